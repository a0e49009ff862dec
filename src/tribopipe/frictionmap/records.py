"""A reduced run as a friction-map row, and its identity.

:func:`make_record` builds a run's row (:data:`~tribopipe.frictionmap.schema.RUN_COLUMNS`)
from a :class:`~tribopipe.reduction.reduce.ReductionResult` and the run's
:class:`~tribopipe.labels.RunVerdict` (its labels, nominal force and flags, decided once by
:func:`tribopipe.labels.decide_run`, never here); :func:`measurement_id` and
:func:`imported_id` are the stable ids that make appending idempotent.
"""

from __future__ import annotations

import hashlib
import math
from pathlib import Path
from typing import TYPE_CHECKING

from .. import __version__
from ..errors import MapError, RowError
from ..labels import RunVerdict, flags_text
from ..numeric import finite_or_nan, finite_or_none
from .schema import SOURCE_REDUCED, MapRow, checked_row, utc_now

if TYPE_CHECKING:
    from ..config import Settings
    from ..measurement import MeasurementMeta
    from ..reduction.reduce import ReductionResult

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


def stored_file_name(path: str | Path) -> str:
    """The name a map row keeps of the file at ``path`` (its ``source_file``): the file's
    own name, raw (a U+202E or a newline stays what it is: outputs escape it where they
    write it). Only bytes that were not UTF-8 (lone surrogates), which no stored text can
    hold, are kept as ``\\xNN``. Every comparison with a stored name goes through here."""
    name = Path(path).name
    if not any(0xD800 <= ord(ch) <= 0xDFFF for ch in name):
        return name
    return "".join(f"\\x{ord(ch) - 0xDC00:02x}" if 0xDC80 <= ord(ch) <= 0xDCFF
                   else f"\\u{ord(ch):04x}" if 0xD800 <= ord(ch) <= 0xDFFF else ch
                   for ch in name)


def _num_key(value: float) -> str:
    # 1.0 and 1.0000000001 are the same nominal condition; NaN (unknown) keeps its own key.
    return "nan" if value is None or not math.isfinite(value) else format(round(value, 6), ".6f")


def make_record(
    *,
    result: ReductionResult,
    meta: MeasurementMeta,
    file_hash: str,
    settings: Settings,
    verdict: RunVerdict,
    occurrence: int = 1,
) -> MapRow:
    """One friction-map row (a checked :class:`~tribopipe.frictionmap.schema.MapRow`) for a
    reduced run.

    ``verdict`` is the run's labels, nominal force and flags as
    :func:`tribopipe.labels.decide_run` decided them (the pipeline passes the one every
    other output of the run shows: nothing is decided here). The nominal pressure [kPa]
    follows from the nominal force and ``settings.instrument``. ``occurrence`` is the
    run's place among runs of the export with the same test/result/interval
    (:func:`measurement_id`).

    Raises :class:`MapError` when pin or disc is unknown, μ_K is not a finite number, the
    run has neither a nominal nor a measured normal force, or the row would break a rule
    of :func:`~tribopipe.frictionmap.schema.check_runs` (e.g. a measured sliding speed
    beyond any instrument).
    """
    labels = verdict.labels
    pin, disc = labels.pin, labels.disc
    if not (pin and disc):
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
    force = verdict.normal_force_N
    if force is None:
        raise MapError(
            "run has neither a nominal nor a measured normal force",
            path=meta.source_file,
            hint="pass --force",
        )
    temperature = finite_or_none(labels.temperature_C)
    k_start_mm, k_end_mm = result.mu_k_window_mm
    k_start_s, k_end_s = result.mu_k_window_s
    row = MapRow(
        measurement_id=measurement_id(file_hash, meta, occurrence),
        source=SOURCE_REDUCED,
        lab=None,
        pin=pin,
        disc=disc,
        normal_force_N=force,
        pressure_kPa=settings.instrument.pressure_kPa(force),
        normal_force_measured_N=finite_or_none(result.normal_force_mean_N),
        pressure_measured_kPa=finite_or_none(result.pressure_kPa),
        temperature_C=temperature,
        temperature_measured_C=finite_or_none(result.temperature_C),
        sliding_speed_mm_s=finite_or_none(result.sliding_speed_mm_s),
        nominal_speed_mm_s=verdict.nominal_speed_mm_s,
        repeat=labels.repeat,
        mu_s=finite_or_none(result.mu_s),
        mu_k=mu_k,
        u_mu_s=finite_or_none(result.u_mu_s),
        u_mu_k=finite_or_none(result.u_mu_k),
        mu_s_distance_mm=finite_or_none(result.mu_s_distance_mm),
        mu_s_time_s=finite_or_none(result.mu_s_time_s),
        mu_k_window_start_mm=finite_or_none(k_start_mm),
        mu_k_window_end_mm=finite_or_none(k_end_mm),
        mu_k_window_start_s=finite_or_none(k_start_s),
        mu_k_window_end_s=finite_or_none(k_end_s),
        plateau_std=finite_or_none(result.plateau_std),
        plateau_drift_per_mm=finite_or_none(result.plateau_drift_per_mm),
        flags=flags_text(verdict.flags),
        method=result.method,
        test_method=settings.instrument.test_method,
        source_file=stored_file_name(meta.source_file),
        file_hash=file_hash,
        test=meta.test,
        result=meta.result,
        interval=meta.interval,
        config_hash=settings.config_hash,
        tribopipe_version=__version__,
        reduced_at=utc_now(),
        excluded=False,
        exclusion_reason=None,
        pin_as_given=labels.pin_as_given,
        disc_as_given=labels.disc_as_given,
        **labels.report.columns(),
    )
    try:
        # the rules every map row keeps, checked here, once, so a bad run fails alone (in
        # a batch, before the one map update that holds every run's record); the store
        # takes the checked record without checking it again
        return checked_row(row)
    except RowError as exc:
        raise MapError(f"the run cannot be recorded: {exc.row_problem}", path=meta.source_file,
                       column=exc.column) from None
