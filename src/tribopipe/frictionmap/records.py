"""A reduced run as a friction-map row: its labels, its identity and its QC flags.

:class:`RunLabels` say what a run is (pair and nominal conditions); :func:`make_record`
builds its row (:data:`~tribopipe.frictionmap.schema.RUN_COLUMNS`) from a
:class:`~tribopipe.reduction.reduce.ReductionResult`, with the off-nominal flags of
:func:`qc_flags` under :class:`Tolerances`; :func:`measurement_id` and
:func:`imported_id` are the stable ids that make appending idempotent.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .. import __version__
from ..errors import MapError
from ..escape import display_path
from ..numeric import finite_or_nan
from ..physics import contact_pressure_kPa
from ..validate import FORCE_N, MAX_REPEAT, TEMPERATURE_C, check_count, check_name, check_number
from .schema import SOURCE_REDUCED, records_frame, utc_now

if TYPE_CHECKING:
    from ..config import InstrumentConfig, Settings
    from ..measurement import MeasurementMeta
    from ..reduction.reduce import ReductionResult

#: Flag added when the nominal force was not given and the measured mean was used.
FLAG_FORCE_ESTIMATED = "nominal_force_estimated"
#: Flags added by :func:`make_record` when a run strays from its nominal conditions.
FLAG_FORCE_OFF = "normal_force_off_nominal"
FLAG_TEMPERATURE_OFF = "temperature_off_nominal"


@dataclass(frozen=True)
class RunLabels:
    """What a run is: contact pair and nominal conditions (not measured values).

    ``normal_force_N`` is the nominal total normal force on the three pins [N] and
    ``temperature_C`` the nominal chamber temperature [°C]; both define the condition
    group in the friction map. ``None`` means unknown.

    Every given label is checked where it is made (:mod:`tribopipe.validate`): names are
    one line of printable text, the force is in :data:`~tribopipe.validate.FORCE_N`, the
    temperature in :data:`~tribopipe.validate.TEMPERATURE_C`, the repeat a whole number;
    otherwise :class:`~tribopipe.errors.ValidationError` names the label.
    """

    pin: str | None = None
    disc: str | None = None
    normal_force_N: float | None = None
    temperature_C: float | None = None
    repeat: int | None = None

    def __post_init__(self) -> None:
        for name in ("pin", "disc"):
            value = getattr(self, name)
            if value is not None:
                check_name(value, name)
        if self.normal_force_N is not None:
            check_number(self.normal_force_N, FORCE_N, "nominal normal force")
        if self.temperature_C is not None:
            check_number(self.temperature_C, TEMPERATURE_C, "nominal temperature")
        if self.repeat is not None:
            check_count(self.repeat, "repeat", high=MAX_REPEAT)

    @property
    def complete(self) -> bool:
        """True when pin and disc are known (the minimum for a friction-map row)."""
        return bool(self.pin) and bool(self.disc)


@dataclass(frozen=True)
class Tolerances:
    """How far a run's measured conditions may stray from nominal before it is flagged.

    The normal force limit is ``max(force_N, force_rel · F_nominal)`` [N]; the temperature
    limit is ``temperature_C`` [K, as a difference in °C]. Defaults: 10 % of the nominal
    force, 2 K (a campaign config may state its own).
    """

    force_N: float = 0.0
    force_rel: float = 0.10
    temperature_C: float = 2.0

    def force_limit_N(self, nominal_N: float) -> float:
        """Allowed |F_measured − F_nominal| [N] at a nominal total force [N]."""
        return max(self.force_N, self.force_rel * abs(nominal_N))


def qc_flags(labels: RunLabels, normal_force_measured_N: float | None,
             temperature_measured_C: float | None, tolerances: Tolerances) -> list[str]:
    """The off-nominal QC flags of a run: ``normal_force_off_nominal`` when the measured
    mean normal force [N] strays more than the tolerance from nominal,
    ``temperature_off_nominal`` likewise for the temperature [°C]. Unknown nominal or
    measured values (``None`` or NaN) raise no flag."""
    flags: list[str] = []
    if labels.normal_force_N is not None and normal_force_measured_N is not None and \
            math.isfinite(normal_force_measured_N):
        if abs(normal_force_measured_N - labels.normal_force_N) > \
                tolerances.force_limit_N(labels.normal_force_N):
            flags.append(FLAG_FORCE_OFF)
    if labels.temperature_C is not None and temperature_measured_C is not None and \
            math.isfinite(temperature_measured_C):
        if abs(temperature_measured_C - labels.temperature_C) > tolerances.temperature_C:
            flags.append(FLAG_TEMPERATURE_OFF)
    return flags


def nominal_pressure_kPa(force_N: float, instrument: InstrumentConfig) -> float:
    """Nominal contact pressure per pin [kPa] for a total normal force [N].

    p = (F / n_pins) / (π r²); with F in N and r in mm, N/mm² = MPa, hence × 1000 → kPa.
    The founding cell (3 pins, r = 3 mm) gives 1 N → 11.79 kPa.
    """
    return float(contact_pressure_kPa(force_N, instrument.n_pins, instrument.pin_radius_mm))


def measurement_id(file_hash: str, meta: MeasurementMeta, occurrence: int = 1) -> str:
    """Stable id of a run: 16 hex digits of SHA-256 over the raw file's content hash and
    the test / result / interval the run was taken from. ``occurrence`` counts runs of one
    export that carry the same test, result and interval (two tests of the same name):
    the second and later get it in their key, the first keeps the id it always had."""
    parts = ["run", file_hash, meta.test or "", meta.result or "", str(meta.interval)]
    if occurrence > 1:
        parts.append(f"#{occurrence}")
    return hashlib.sha256("|".join(parts).encode()).hexdigest()[:16]


def imported_id(source: str, pin: str, disc: str, force_N: float, temperature_C: float,
                repeat: int | None) -> str:
    """Stable id of an imported row: 16 hex digits of SHA-256 over its origin and
    conditions, so importing the same table twice (or as .mat and as CSV) is idempotent."""
    key = "|".join(
        ["import", source, pin, disc, _num_key(force_N), _num_key(temperature_C), str(repeat)]
    )
    return hashlib.sha256(key.encode()).hexdigest()[:16]


def _num_key(value: float) -> str:
    # 1.0 and 1.0000000001 are the same nominal condition; NaN (unknown) keeps its own key.
    return "nan" if value is None or not math.isfinite(value) else format(round(value, 6), ".6f")


def _join_flags(flags: Iterable[str]) -> str:
    # Sorted and unique so the same run always gets the same string.
    return ";".join(sorted({f for f in flags if f}))


def make_record(
    *,
    result: ReductionResult,
    labels: RunLabels,
    meta: MeasurementMeta,
    file_hash: str,
    settings: Settings,
    tolerances: Tolerances | None = None,
    occurrence: int = 1,
) -> dict[str, Any]:
    """One friction-map row (a dict keyed by :data:`RUN_COLUMNS`) for a reduced run.

    The nominal force comes from ``labels``; when absent, the measured mean rounded to
    0.1 N is used and the run is flagged ``nominal_force_estimated``. The nominal pressure
    [kPa] follows from the nominal force and ``settings.instrument``. Runs whose measured
    force or temperature stray from nominal by more than ``tolerances`` (default
    :class:`Tolerances`: 10 %, 2 K) are flagged (:func:`qc_flags`). ``occurrence`` is the
    run's place among runs of the export with the same test/result/interval
    (:func:`measurement_id`).

    Raises :class:`MapError` when pin or disc is unknown, μ_K is not a finite number, or
    the row would break a rule of :func:`~tribopipe.frictionmap.schema.check_runs`
    (e.g. a measured sliding speed beyond any instrument).
    """
    if not labels.complete:
        raise MapError(
            "run has no pin and/or disc material: it cannot be recorded in the friction map",
            path=meta.source_file,
            hint="pass --pin and --disc (or --no-map)",
        )
    mu_k = finite_or_nan(result.mu_k)
    if math.isnan(mu_k):
        raise MapError(
            f"mu_k is {result.mu_k!r}, expected a finite number: the run cannot be recorded",
            path=meta.source_file,
        )
    flags = list(result.flags)
    measured_force = finite_or_nan(result.normal_force_mean_N)
    measured_temperature = finite_or_nan(result.temperature_C)
    flags += qc_flags(labels, measured_force, measured_temperature, tolerances or Tolerances())
    if labels.normal_force_N is not None:
        force = float(labels.normal_force_N)
    elif math.isfinite(measured_force):
        force = round(measured_force, 1)
        flags.append(FLAG_FORCE_ESTIMATED)
    else:
        raise MapError(
            "run has neither a nominal nor a measured normal force",
            path=meta.source_file,
            hint="pass --force",
        )
    temperature = finite_or_nan(labels.temperature_C)
    k_start_mm, k_end_mm = result.mu_k_window_mm
    k_start_s, k_end_s = result.mu_k_window_s
    record = {
        "measurement_id": measurement_id(file_hash, meta, occurrence),
        "source": SOURCE_REDUCED,
        "lab": None,
        "pin": labels.pin,
        "disc": labels.disc,
        "normal_force_N": force,
        "pressure_kPa": nominal_pressure_kPa(force, settings.instrument),
        "normal_force_measured_N": measured_force,
        "pressure_measured_kPa": finite_or_nan(result.pressure_kPa),
        "temperature_C": temperature,
        "temperature_measured_C": measured_temperature,
        "sliding_speed_mm_s": finite_or_nan(result.sliding_speed_mm_s),
        "repeat": labels.repeat,
        "mu_s": finite_or_nan(result.mu_s),
        "mu_k": mu_k,
        "u_mu_s": finite_or_nan(result.u_mu_s),
        "u_mu_k": finite_or_nan(result.u_mu_k),
        "mu_s_distance_mm": finite_or_nan(result.mu_s_distance_mm),
        "mu_s_time_s": finite_or_nan(result.mu_s_time_s),
        "mu_k_window_start_mm": finite_or_nan(k_start_mm),
        "mu_k_window_end_mm": finite_or_nan(k_end_mm),
        "mu_k_window_start_s": finite_or_nan(k_start_s),
        "mu_k_window_end_s": finite_or_nan(k_end_s),
        "plateau_std": finite_or_nan(result.plateau_std),
        "plateau_drift_per_mm": finite_or_nan(result.plateau_drift_per_mm),
        "flags": _join_flags(flags),
        "method": result.method,
        "source_file": display_path(Path(meta.source_file).name),
        "file_hash": file_hash,
        "test": meta.test,
        "result": meta.result,
        "interval": meta.interval,
        "config_hash": settings.config_hash,
        "tribopipe_version": __version__,
        "reduced_at": utc_now(),
        "excluded": False,
        "exclusion_reason": None,
    }
    try:
        # the rules every map row keeps, checked here so a bad run fails alone (in a
        # batch, before the one map update that holds every run's record)
        records_frame([record])
    except MapError as exc:
        problem = exc.problem.split(": ", 1)[-1]
        raise MapError(f"the run cannot be recorded: {problem}", path=meta.source_file,
                       column=exc.column) from None
    return record
