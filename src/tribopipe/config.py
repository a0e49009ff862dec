"""Load and validate instrument configs (``configs/instruments/*.toml``) into frozen dataclasses.

An instrument config has two tables:

``[instrument]``
    the measuring cell's geometry (:class:`InstrumentConfig`);
``[reduction]``
    the parameters of the μ_S / μ_K detection (:class:`ReductionParams`, used by
    :mod:`tribopipe.reduction.reduce`).

Both are optional: a missing key keeps the founding setup's default. Unknown keys are an
error (a typo must not silently fall back to a default). A campaign config may override
the ``[reduction]`` table of its instrument file key by key: :func:`merge_tables` is the
one merge both use.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import tomllib
from collections.abc import Mapping
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

from .errors import ConfigError, ReadError, ValidationError
from .files import read_regular
from .physics import (
    FOUNDING_FRICTION_RADIUS_MM,
    FOUNDING_SPEED_RPM,
    contact_pressure_kPa,
    sliding_speed_mm_s,
)
from .validate import (
    FORCE_N,
    FRICTION_RADIUS_MM,
    PIN_RADIUS_MM,
    SPEED_RPM,
    Range,
    check_count,
    check_name,
    check_number,
)

#: the largest config file read [bytes]
MAX_CONFIG_BYTES = 16 * 1024 * 1024
#: the tables of a config that a reduction depends on
SECTIONS: tuple[str, ...] = ("instrument", "reduction")


#: The name and version of the reduction method (:mod:`tribopipe.reduction.reduce`): part of every
#: config hash, so a batch re-reduces its runs when the method changes.
REDUCTION_METHOD = "tribopipe-v2"

#: R_eff from "0.007 mm/s", one significant figure: the speed lies in [0.0065, 0.0075),
#: so R_eff in [12.41, 14.32) mm; rectangular, u = half-width/√3 = 0.55 mm (4.1 %).
FOUNDING_FRICTION_RADIUS_U_MM = round(
    0.0005 / (FOUNDING_SPEED_RPM * 2 * math.pi / 60) / math.sqrt(3), 2
)


#: most pins a cell may carry
MAX_PINS = 1000
#: the contact threshold [N]: from 0 up to the largest force a run may carry
_CONTACT_THRESHOLD_N = Range(0.0, FORCE_N.high, "N")


@dataclass(frozen=True)
class InstrumentConfig:
    """Geometry of a pin-on-disc measuring cell and the standard uncertainties (k = 1) of
    what it measures.

    Defaults are the founding setup: Anton Paar MCR 302e with the T-PID/44 cell, three
    silicone pins of radius 3 mm (A = 28.27 mm² each), friction radius 13.37 mm.

    Uncertainties (see ``configs/instruments/t-pid44.toml`` for where each default comes
    from): ``friction_radius_u_mm`` [mm]; ``torque_u_rel`` (relative, of the torque
    transducer's calibration); ``torque_resolution_Nm`` [N·m]; ``normal_force_u_rel``
    (relative) and ``normal_force_u_N`` [N] of the normal-force sensor;
    ``normal_force_resolution_N`` [N]; ``torque_offset_unknown_Nm`` [N·m], the plausible
    size (rectangular half-width) of a torque zero offset that could not be estimated.
    """

    name: str = "Anton Paar MCR 302e, T-PID/44 pin-on-disc, 3 pins"
    pin_radius_mm: float = 3.0
    n_pins: int = 3
    friction_radius_mm: float = FOUNDING_FRICTION_RADIUS_MM
    nominal_speed_rpm: float = FOUNDING_SPEED_RPM
    contact_threshold_N: float = 0.2
    friction_radius_u_mm: float = FOUNDING_FRICTION_RADIUS_U_MM
    torque_u_rel: float = 0.005
    torque_resolution_Nm: float = 5e-11
    normal_force_u_rel: float = 0.005
    normal_force_u_N: float = 0.005
    normal_force_resolution_N: float = 5e-4
    torque_offset_unknown_Nm: float = 5e-4

    def __post_init__(self) -> None:
        for name in (
            "friction_radius_u_mm", "torque_u_rel", "torque_resolution_Nm",
            "normal_force_u_rel", "normal_force_u_N", "normal_force_resolution_N",
            "torque_offset_unknown_Nm",
        ):
            value = getattr(self, name)
            if not (
                isinstance(value, int | float) and not isinstance(value, bool)
                and math.isfinite(value) and value >= 0
            ):
                raise ConfigError(
                    f"[instrument] {name} must be a number >= 0 (a standard uncertainty), "
                    f"got {value!r}"
                )
        try:
            check_name(self.name, "name")
            check_number(self.pin_radius_mm, PIN_RADIUS_MM, "pin_radius_mm")
            check_number(self.friction_radius_mm, FRICTION_RADIUS_MM, "friction_radius_mm")
            check_number(self.nominal_speed_rpm, SPEED_RPM, "nominal_speed_rpm")
            check_count(self.n_pins, "n_pins", low=1, high=MAX_PINS)
            check_number(self.contact_threshold_N, _CONTACT_THRESHOLD_N, "contact_threshold_N")
        except ValidationError as exc:
            raise ConfigError(f"[instrument] {exc.problem}") from None

    @property
    def pin_area_mm2(self) -> float:
        """Contact area of one pin, π r² [mm²]."""
        return math.pi * self.pin_radius_mm**2

    @property
    def nominal_sliding_speed_mm_s(self) -> float:
        """Nominal sliding speed at the friction radius, ω·R_eff [mm/s]."""
        return sliding_speed_mm_s(self.nominal_speed_rpm, self.friction_radius_mm)

    def pressure_kPa(self, normal_force_N: float) -> float:
        """The contact pressure per pin [kPa] of a total normal force [N] on these pins:
        the one force → pressure conversion (:func:`tribopipe.physics.contact_pressure_kPa`,
        F / n / (π r²)); the founding cell (3 pins, r = 3 mm) gives 1 N → 11.79 kPa."""
        return float(contact_pressure_kPa(normal_force_N, self.n_pins, self.pin_radius_mm))


@dataclass(frozen=True)
class ReductionParams:
    """Parameters of the μ_S / μ_K detection (the ``[reduction]`` table of a config); the
    steps they tune are described in the docstring of :mod:`tribopipe.reduction`.

    Attributes
    ----------
    median_window
        Width of the light median filter on μ [samples, odd]; removes spikes.
    peak_window_mm
        Width of the quadratic Savitzky–Golay smoothing used to read the static peak [mm].
    cliff_window_mm
        Length of the one-sided quadratic fits that read a peak ending in a sudden slip [mm].
    cliff_sigma
        A sudden slip (cliff) is a drop between the fits left and right of a sample larger
        than this many standard deviations of their difference [-].
    peak_ici_gamma
        A rounded peak is re-read by quadratics over widening windows while their readings
        agree within this many standard deviations [-].
    static_search_mm
        Optional cap [mm]: the static peak is searched no farther than this from the start
        of sliding. ``None`` (the default): no cap, the search ends where the plateau
        begins.
    run_in_mm
        The μ_K plateau never starts before this sliding distance (ASTM D2534 run-in) [mm].
    plateau_min_mm
        Shortest acceptable plateau [mm]; shorter → ``no_steady_state``/``short_trace``.
    plateau_confirm_mm
        A settled plateau shorter than this ends with the trace before a second minimum
        plateau could confirm it → ``plateau_at_trace_end`` [mm].
    block_mm
        Block length of the settling test that finds the plateau start [mm].
    settle_tol
        Smallest tolerance of the settling test [COF].
    settle_alpha
        Probability that a settled plateau of pure noise fails the settling test [-]: the
        noise allowance is the two-sided normal quantile at ``settle_alpha / (2·blocks)``
        times a block mean's standard error (3.4 for 35 blocks, 3.9 for 200).
    max_drift_per_mm
        Largest plateau slope of μ over s still called steady [1/mm].
    static_min_prominence
        μ_S is distinct when it exceeds the plateau's highs by more than this [COF] ...
    static_prominence_sigma
        ... and by more than this many standard deviations of the smoothed noise [-].
    stick_slip_min_cycles
        A stick-slip oscillation repeats at least this often within the plateau [-].
    stick_slip_false_alarm
        Probability that noise alone passes the stick-slip line test on one run [-] ...
    stick_slip_min_std
        ... and the smallest standard deviation the oscillation must add to μ [COF].
    normal_force_cv_max
        Largest coefficient of variation of F_N over sliding still called stable [-].
    min_contact_samples
        Fewer samples in contact than this is an error, not a result [samples].
    min_plateau_samples
        A plateau with fewer samples than this is flagged ``short_trace`` [samples].
    min_travel_mm
        A measured sliding distance below this means "no rotation" (an error) [mm].
    motion_tol_mm
        Samples before the disc has moved this far count as "at rest" [mm].
    offset_min_samples
        At-rest samples needed to estimate a torque offset from the friction interval.
    max_missing_fraction
        More missing torque or normal-force values than this fraction is an error [-].
    """

    median_window: int = 3
    peak_window_mm: float = 0.015
    cliff_window_mm: float = 0.045
    cliff_sigma: float = 4.0
    peak_ici_gamma: float = 2.0
    static_search_mm: float | None = None
    run_in_mm: float = 0.25
    plateau_min_mm: float = 0.3
    plateau_confirm_mm: float = 0.6
    block_mm: float = 0.05
    settle_tol: float = 0.006
    settle_alpha: float = 0.01
    max_drift_per_mm: float = 0.02
    static_min_prominence: float = 0.02
    static_prominence_sigma: float = 3.0
    stick_slip_min_cycles: float = 4.0
    stick_slip_false_alarm: float = 1e-4
    stick_slip_min_std: float = 0.001
    normal_force_cv_max: float = 0.05
    min_contact_samples: int = 20
    min_plateau_samples: int = 30
    min_travel_mm: float = 0.01
    motion_tol_mm: float = 1e-3
    offset_min_samples: int = 5
    max_missing_fraction: float = 0.5

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if value is None and f.name in OPTIONAL_REDUCTION_KEYS:
                continue
            bounds = REDUCTION_BOUNDS[f.name]
            try:
                if isinstance(bounds, Range):
                    check_number(value, bounds, f.name)
                else:
                    check_count(value, f.name, low=bounds[0], high=bounds[1])
            except ValidationError as exc:
                raise ConfigError(f"[reduction] {exc.problem}") from None
        for name in ("settle_alpha", "stick_slip_false_alarm"):
            if not getattr(self, name) < 1:
                raise ConfigError(f"[reduction] {name} must be a probability in (0, 1), got "
                                  f"{getattr(self, name)!r}")
        if self.median_window % 2 == 0:
            raise ConfigError(
                f"[reduction] median_window: expected an odd number of samples, "
                f"got {self.median_window}"
            )


#: the ``[reduction]`` keys that may be left out or set to nothing (``None``)
OPTIONAL_REDUCTION_KEYS = frozenset({"static_search_mm"})
#: what each ``[reduction]`` key may hold: a :class:`~tribopipe.validate.Range` of numbers
#: in its unit, or ``(low, high)`` for a whole number. The bounds are generous, but no
#: setting may make a reduction allocate without bound (``block_mm`` ≥ 1 µm: a block
#: needs samples; windows ≤ 100 mm).
REDUCTION_BOUNDS: dict[str, Range | tuple[int, int]] = {
    "median_window": (1, 1001),
    "peak_window_mm": Range(0.0, 100.0, "mm", low_open=True),
    "cliff_window_mm": Range(0.0, 100.0, "mm", low_open=True),
    "cliff_sigma": Range(0.0, 1e3),
    "peak_ici_gamma": Range(0.0, 1e3),
    "static_search_mm": Range(0.0, 1e4, "mm", low_open=True),
    "run_in_mm": Range(0.0, 1e4, "mm"),
    "plateau_min_mm": Range(0.0, 1e4, "mm"),
    "plateau_confirm_mm": Range(0.0, 1e4, "mm"),
    "block_mm": Range(1e-3, 100.0, "mm"),
    "settle_tol": Range(0.0, 100.0),
    "settle_alpha": Range(0.0, 1.0, low_open=True),
    "max_drift_per_mm": Range(0.0, 1e6, "1/mm"),
    "static_min_prominence": Range(0.0, 100.0),
    "static_prominence_sigma": Range(0.0, 1e3),
    "stick_slip_min_cycles": Range(0.0, 1e6),
    "stick_slip_false_alarm": Range(0.0, 1.0, low_open=True),
    "stick_slip_min_std": Range(0.0, 100.0),
    "normal_force_cv_max": Range(0.0, 1e3),
    "min_contact_samples": (1, 10_000_000),
    "min_plateau_samples": (0, 10_000_000),
    "min_travel_mm": Range(0.0, 1e4, "mm"),
    "motion_tol_mm": Range(0.0, 1e4, "mm"),
    "offset_min_samples": (1, 10_000_000),
    "max_missing_fraction": Range(0.0, 1.0),
}


@dataclass(frozen=True)
class Settings:
    """Everything a reduction depends on: instrument geometry and uncertainties, and
    detection parameters (and, through :attr:`config_hash`, the method's version)."""

    instrument: InstrumentConfig
    reduction: ReductionParams
    source: str | None = None

    @functools.cached_property
    def config_hash(self) -> str:
        """A stable 16-hex-digit hash of the reduction method's name, the instrument and
        the reduction parameters (computed once per settings object: every run of a batch
        asks for it)."""
        payload = {"method": REDUCTION_METHOD, "instrument": asdict(self.instrument),
                   "reduction": asdict(self.reduction)}
        text = json.dumps(payload, sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def reject_unknown_keys(
    table: dict[str, Any], known: set[str] | frozenset[str], section: str,
    path: str | Path | None,
) -> None:
    """Raise :class:`ConfigError` naming the file, the table and the keys a typo produced."""
    unknown = sorted(set(table) - set(known))
    if unknown:
        raise ConfigError(
            f"unknown key(s) {', '.join(unknown)} in [{section}]; expected some of "
            f"{', '.join(sorted(known))}",
            path=path,
        )


def _build(cls: type, table: dict[str, Any], section: str, path: str | None) -> Any:
    reject_unknown_keys(table, {f.name for f in fields(cls)}, section, path)
    try:
        return cls(**table)
    except ConfigError as exc:
        raise ConfigError(exc.problem, path=path) from None
    except TypeError as exc:
        raise ConfigError(f"[{section}]: {exc}", path=path) from None


def settings_tables(
    data: Mapping[str, Any], source: str | Path | None
) -> dict[str, dict[str, Any]]:
    """The :data:`SECTIONS` tables of a parsed TOML document (an absent one is empty);
    :class:`ConfigError` naming ``source`` when one is not a table."""
    tables: dict[str, dict[str, Any]] = {}
    for section in SECTIONS:
        table = data.get(section, {})
        if not isinstance(table, dict):
            raise ConfigError(f"[{section}] must be a table", path=source)
        tables[section] = dict(table)
    return tables


def merge_tables(
    base: Mapping[str, Mapping[str, Any]], override: Mapping[str, Mapping[str, Any]]
) -> dict[str, dict[str, Any]]:
    """``base``'s :data:`SECTIONS` tables with ``override``'s keys on top, key by key (the
    one merge of an instrument file and a campaign config's overrides)."""
    return {section: {**base.get(section, {}), **override.get(section, {})}
            for section in SECTIONS}


def settings_from_dict(data: Mapping[str, Any], *, source: str | None = None) -> Settings:
    """Build :class:`Settings` from a parsed TOML document with optional
    ``[instrument]`` and ``[reduction]`` tables (other top-level tables are ignored)."""
    tables = settings_tables(data, source)
    instrument = _build(InstrumentConfig, tables["instrument"], "instrument", source)
    reduction = _build(ReductionParams, tables["reduction"], "reduction", source)
    return Settings(instrument=instrument, reduction=reduction, source=source)


def read_toml(path: str | Path) -> dict[str, Any]:
    """Parse a TOML file, turning any problem into a :class:`ConfigError` naming it."""
    p = Path(path)
    try:
        raw = read_regular(p, max_bytes=MAX_CONFIG_BYTES, what="a config file (TOML)")
    except ReadError as exc:
        problem = "config file not found" if exc.problem.startswith("file not found") \
            else f"cannot read config: {exc.problem}"
        raise ConfigError(problem, path=p) from None
    try:
        return tomllib.loads(raw.decode("utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"not valid TOML: {exc}", path=p) from None
    except UnicodeDecodeError as exc:
        raise ConfigError(f"cannot read config: not UTF-8 text (byte {exc.start})",
                          path=p) from None


def load_settings(path: str | Path | None = None) -> Settings:
    """Load an instrument config file; ``None`` gives the founding T-PID/44 defaults."""
    if path is None:
        return settings_from_dict({}, source=None)
    return settings_from_dict(read_toml(path), source=str(path))
