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
from dataclasses import asdict, dataclass, fields, replace
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
from .units import STANDARD_GRAVITY_M_S2
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


#: The test methods a run can come from: the instrument kind and the method it follows.
#: One truth: the map's ``test_method`` column, the statistics' condition key, the tables'
#: and the explorer's filter read this tuple. The first is the founding rheometer cell.
TEST_METHODS: tuple[str, ...] = (
    "rheometer pin-on-disc",   # Anton Paar MCR + T-PID/44: torque and angle at R_eff
    "sled D1894",              # a sled pulled over a plane (ASTM D1894 / ISO 8295)
    "linear reciprocating",    # a pin or ball stroking back and forth (ASTM G133)
    "rotary pin-on-disc",      # a force-based pin-on-disc tribometer (ASTM G99)
)
#: the method a row that names none was measured with (every map before schema 6)
DEFAULT_TEST_METHOD = TEST_METHODS[0]
#: the zero settings of a tangential channel besides a number: estimate it, or take 0
ZERO_MODES: tuple[str, ...] = ("auto", "off")

#: most pins a cell may carry
MAX_PINS = 1000
#: the contact threshold [N]: from 0 up to the largest force a run may carry
_CONTACT_THRESHOLD_N = Range(0.0, FORCE_N.high, "N")
#: a sled's mass [g]: from a milligram to a tonne
_SLED_MASS_G = Range(1e-3, 1e6, "g", low_open=True)
#: a linear instrument's set speed [mm/s]: from 1 nm/s to 10 m/s
_LINEAR_SPEED_MM_S = Range(1e-6, 1e4, "mm/s", low_open=True)
#: the largest zero a user may give [N·m or N]
_ZERO_LIMIT = 1e5


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

    Force-based instruments (``test_method`` other than ``"rheometer pin-on-disc"``)
    measure the friction force itself: ``friction_force_u_rel``,
    ``friction_force_resolution_N`` [N] and ``friction_force_offset_unknown_N`` [N] are
    that channel's uncertainties, and ``friction_radius_mm`` is the wear track's radius of
    a rotary tribometer (distance from its angle or speed). A sled (ASTM D1894) has no
    normal-force sensor: ``sled_mass_g`` [g] (F_N = m·g) or ``sled_weight_N`` [N] gives the
    normal force of a run without a normal-force column. ``nominal_speed_mm_s`` [mm/s] is
    a linear instrument's set speed (150 mm/min = 2.5 mm/s for D1894).

    ``zero_offset``: the tangential channel's zero — ``"auto"`` (estimated where the
    instrument is known unloaded, see :mod:`tribopipe.reduction`), ``"off"`` (0, not
    estimated) or a number [N·m for torque, N for a friction force].
    ``rest_after_sliding``: the protocol ends with the tangential load released and the
    instrument at rest, so a rest after sliding is a second zero.
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
    test_method: str = DEFAULT_TEST_METHOD
    sled_mass_g: float | None = None
    sled_weight_N: float | None = None
    nominal_speed_mm_s: float | None = None
    friction_force_u_rel: float = 0.005
    friction_force_resolution_N: float = 1e-4
    friction_force_offset_unknown_N: float = 0.01
    zero_offset: str | float = "auto"
    rest_after_sliding: bool = False

    def __post_init__(self) -> None:
        self._check_uncertainties()
        self._check_force_instrument()

    def _check_uncertainties(self) -> None:
        for name in (
            "friction_radius_u_mm", "torque_u_rel", "torque_resolution_Nm",
            "normal_force_u_rel", "normal_force_u_N", "normal_force_resolution_N",
            "torque_offset_unknown_Nm", "friction_force_u_rel",
            "friction_force_resolution_N", "friction_force_offset_unknown_N",
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

    def _check_force_instrument(self) -> None:
        if self.test_method not in TEST_METHODS:
            raise ConfigError(f"[instrument] test_method: expected one of "
                              f"{', '.join(repr(m) for m in TEST_METHODS)}, got "
                              f"{self.test_method!r}")
        if self.sled_mass_g is not None and self.sled_weight_N is not None:
            raise ConfigError("[instrument] give sled_mass_g or sled_weight_N, not both")
        try:
            if self.sled_mass_g is not None:
                check_number(self.sled_mass_g, _SLED_MASS_G, "sled_mass_g")
            if self.sled_weight_N is not None:
                check_number(self.sled_weight_N, FORCE_N, "sled_weight_N")
            if self.nominal_speed_mm_s is not None:
                check_number(self.nominal_speed_mm_s, _LINEAR_SPEED_MM_S, "nominal_speed_mm_s")
        except ValidationError as exc:
            raise ConfigError(f"[instrument] {exc.problem}") from None
        zero = self.zero_offset
        numeric = isinstance(zero, int | float) and not isinstance(zero, bool)
        if not (zero in ZERO_MODES if isinstance(zero, str) else
                numeric and math.isfinite(zero) and abs(zero) <= _ZERO_LIMIT):
            raise ConfigError(f"[instrument] zero_offset: expected \"auto\", \"off\" or a "
                              f"number (N·m for torque, N for a friction force), got {zero!r}")
        if not isinstance(self.rest_after_sliding, bool):
            raise ConfigError("[instrument] rest_after_sliding: expected true or false, got "
                              f"{self.rest_after_sliding!r}")

    @property
    def force_based(self) -> bool:
        """Whether the instrument measures the friction force (not a torque)."""
        return self.test_method != "rheometer pin-on-disc"

    @property
    def sled_normal_force_N(self) -> float | None:
        """The normal force [N] a sled's mass or weight gives (``None`` when neither is
        set): ``m · g`` with standard gravity, m in g."""
        if self.sled_weight_N is not None:
            return float(self.sled_weight_N)
        if self.sled_mass_g is not None:
            return float(self.sled_mass_g) * 1e-3 * STANDARD_GRAVITY_M_S2
        return None

    @property
    def pin_area_mm2(self) -> float:
        """Contact area of one pin, π r² [mm²]."""
        return math.pi * self.pin_radius_mm**2

    @property
    def nominal_sliding_speed_mm_s(self) -> float:
        """Nominal sliding speed [mm/s]: ``nominal_speed_mm_s`` where set (a linear
        instrument), else ω·R_eff at the friction radius."""
        if self.nominal_speed_mm_s is not None:
            return float(self.nominal_speed_mm_s)
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
    zero_load_max_fraction
        At-rest samples whose mean tangential reading exceeds this fraction of the
        sliding level above it are under load, not a zero (flag ``zero_under_load``) [-].
    stop_speed_fraction
        The end of a record where the sliding speed stays below this fraction of the
        run's median speed is a stop, trimmed before the plateau search [-].
    stroke_core_fraction
        Of each stroke of a reciprocating run, the central fraction of its length whose
        mean friction force is that stroke's (ASTM G133: away from the reversals) [-].
    run_out_tolerance
        An oscillation whose period lies within this relative distance of one revolution
        or a harmonic (1/2, 1/3) is run-out, not stick-slip (plus the periodogram's own
        resolution) [-].

    Every window is a distance along the sliding path [mm] or a number of samples, and
    its bounds fit a tribometer's metres as well as a rheometer's millimetres (up to
    1 km); windows wider than the run act as the whole run.
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
    zero_load_max_fraction: float = 0.5
    stop_speed_fraction: float = 0.5
    stroke_core_fraction: float = 0.5
    run_out_tolerance: float = 0.05

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
#: in its unit, or ``(low, high)`` for a whole number. The bounds are generous and fit a
#: tribometer's metres of sliding as well as a rheometer's millimetres, but no setting may
#: make a reduction allocate without bound (``block_mm`` ≥ 1 µm: a block needs samples;
#: windows ≤ 1 km, capped at the run's own length in samples by the detection).
REDUCTION_BOUNDS: dict[str, Range | tuple[int, int]] = {
    "median_window": (1, 1001),
    "peak_window_mm": Range(0.0, 1e6, "mm", low_open=True),
    "cliff_window_mm": Range(0.0, 1e6, "mm", low_open=True),
    "cliff_sigma": Range(0.0, 1e3),
    "peak_ici_gamma": Range(0.0, 1e3),
    "static_search_mm": Range(0.0, 1e7, "mm", low_open=True),
    "run_in_mm": Range(0.0, 1e7, "mm"),
    "plateau_min_mm": Range(0.0, 1e7, "mm"),
    "plateau_confirm_mm": Range(0.0, 1e7, "mm"),
    "block_mm": Range(1e-3, 1e6, "mm"),
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
    "min_travel_mm": Range(0.0, 1e7, "mm"),
    "motion_tol_mm": Range(0.0, 1e7, "mm"),
    "offset_min_samples": (1, 10_000_000),
    "max_missing_fraction": Range(0.0, 1.0),
    "zero_load_max_fraction": Range(0.0, 1e3, low_open=True),
    "stop_speed_fraction": Range(0.0, 1.0),
    "stroke_core_fraction": Range(0.0, 1.0, low_open=True),
    "run_out_tolerance": Range(0.0, 1.0),
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
        payload = {"method": REDUCTION_METHOD,
                   "instrument": _hashed(asdict(self.instrument), InstrumentConfig),
                   "reduction": _hashed(asdict(self.reduction), ReductionParams)}
        text = json.dumps(payload, sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


#: keys added after the hash was first defined: left out of it while at their default, so
#: that a config that does not use them keeps its hash (and a batch its reduced runs)
_LATER_KEYS = frozenset({
    "test_method", "sled_mass_g", "sled_weight_N", "nominal_speed_mm_s",
    "friction_force_u_rel", "friction_force_resolution_N", "friction_force_offset_unknown_N",
    "zero_offset", "rest_after_sliding", "zero_load_max_fraction", "stop_speed_fraction",
    "stroke_core_fraction", "run_out_tolerance",
})


def _hashed(values: dict[str, Any], cls: type) -> dict[str, Any]:
    """``values`` without the :data:`_LATER_KEYS` that hold ``cls``'s default."""
    defaults = {f.name: f.default for f in fields(cls)}
    return {k: v for k, v in values.items()
            if not (k in _LATER_KEYS and v == defaults.get(k))}


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


def with_zero(settings: Settings, text: str) -> Settings:
    """``settings`` with the instrument's ``zero_offset`` from a command-line word:
    ``auto``, ``off`` or a number (N·m for torque, N for a friction force);
    :class:`ConfigError` in one line otherwise."""
    value: str | float = text.strip().lower()
    if value not in ZERO_MODES:
        try:
            value = float(text)
        except ValueError:
            raise ConfigError(f"--zero: expected auto, off or a number (N·m for torque, N "
                              f"for a friction force), got {text[:40]!r}") from None
    try:
        instrument = replace(settings.instrument, zero_offset=value)
    except ConfigError as exc:
        raise ConfigError(f"--zero: {exc.problem.removeprefix('[instrument] ')}") from None
    return Settings(instrument=instrument, reduction=settings.reduction,
                    source=settings.source)


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
