"""Load and validate instrument configs (``configs/instruments/*.toml``) into frozen dataclasses.

An instrument config has two tables:

``[instrument]``
    the measuring cell's geometry (:class:`InstrumentConfig`);
``[reduction]``
    the parameters of the μ_S / μ_K detection (:class:`ReductionParams`, used by
    :mod:`tribopipe.reduce`).

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

from .errors import ConfigError
from .physics import (  # noqa: F401 - the founding constants are importable from here too
    FOUNDING_FRICTION_RADIUS_MM,
    FOUNDING_SLIDING_SPEED_MM_S,
    FOUNDING_SPEED_RPM,
    sliding_speed_mm_s,
)

#: the tables of a config that a reduction depends on
SECTIONS: tuple[str, ...] = ("instrument", "reduction")


@dataclass(frozen=True)
class InstrumentConfig:
    """Geometry of a pin-on-disc measuring cell.

    Defaults are the founding setup: Anton Paar MCR 302e with the T-PID/44 cell, three
    silicone pins of radius 3 mm (A = 28.27 mm² each), friction radius 13.37 mm.
    """

    name: str = "Anton Paar MCR 302e, T-PID/44 pin-on-disc, 3 pins"
    pin_radius_mm: float = 3.0
    n_pins: int = 3
    friction_radius_mm: float = FOUNDING_FRICTION_RADIUS_MM
    nominal_speed_rpm: float = FOUNDING_SPEED_RPM
    contact_threshold_N: float = 0.2

    def __post_init__(self) -> None:
        for name in ("pin_radius_mm", "friction_radius_mm", "nominal_speed_rpm"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise ConfigError(f"[instrument] {name} must be a positive number, got {value!r}")
        if not (isinstance(self.n_pins, int) and self.n_pins >= 1):
            raise ConfigError(
                f"[instrument] n_pins must be a whole number >= 1, got {self.n_pins!r}"
            )
        if not (math.isfinite(self.contact_threshold_N) and self.contact_threshold_N >= 0):
            raise ConfigError(
                f"[instrument] contact_threshold_N must be >= 0, got {self.contact_threshold_N!r}"
            )

    @property
    def pin_area_mm2(self) -> float:
        """Contact area of one pin, π r² [mm²]."""
        return math.pi * self.pin_radius_mm**2

    @property
    def nominal_sliding_speed_mm_s(self) -> float:
        """Nominal sliding speed at the friction radius, ω·R_eff [mm/s]."""
        return sliding_speed_mm_s(self.nominal_speed_rpm, self.friction_radius_mm)


@dataclass(frozen=True)
class ReductionParams:
    """Parameters of the μ_S / μ_K detection (the ``[reduction]`` table of a config).

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
    static_search_mm
        The static peak is searched within this sliding distance from the start [mm].
    run_in_mm
        The μ_K plateau never starts before this sliding distance (ASTM D2534 run-in) [mm].
    plateau_min_mm
        Shortest acceptable plateau [mm]; shorter → ``no_steady_state``/``short_trace``.
    block_mm
        Block length of the settling test that finds the plateau start [mm].
    settle_tol
        Smallest tolerance of the settling test [COF].
    max_drift_per_mm
        Largest plateau slope of μ over s still called steady [1/mm].
    static_min_prominence
        μ_S is distinct when it exceeds the plateau's highs by more than this [COF] ...
    static_prominence_sigma
        ... and by more than this many standard deviations of the smoothed noise [-].
    stick_slip_average_s
        Averaging time before the stick-slip test [s] (removes white noise, keeps slips).
    stick_slip_ratio
        Stick-slip when the averaged plateau scatter exceeds white noise by this factor [-] ...
    stick_slip_min_std
        ... and is larger than this [COF].
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
    static_search_mm: float = 0.5
    run_in_mm: float = 0.25
    plateau_min_mm: float = 0.3
    block_mm: float = 0.05
    settle_tol: float = 0.006
    max_drift_per_mm: float = 0.02
    static_min_prominence: float = 0.02
    static_prominence_sigma: float = 3.0
    stick_slip_average_s: float = 1.0
    stick_slip_ratio: float = 3.0
    stick_slip_min_std: float = 0.01
    normal_force_cv_max: float = 0.05
    min_contact_samples: int = 20
    min_plateau_samples: int = 30
    min_travel_mm: float = 0.01
    motion_tol_mm: float = 1e-3
    offset_min_samples: int = 5
    max_missing_fraction: float = 0.5

    def __post_init__(self) -> None:
        for f_name, value in asdict(self).items():
            if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0):
                raise ConfigError(f"[reduction] {f_name} must be a number >= 0, got {value!r}")
        if not (isinstance(self.median_window, int) and self.median_window >= 1):
            raise ConfigError(
                f"[reduction] median_window must be a whole number >= 1, "
                f"got {self.median_window!r}"
            )
        if self.block_mm <= 0 or self.peak_window_mm <= 0 or self.cliff_window_mm <= 0:
            raise ConfigError(
                "[reduction] block_mm, peak_window_mm and cliff_window_mm must be > 0"
            )


@dataclass(frozen=True)
class Settings:
    """Everything a reduction depends on: instrument geometry and detection parameters."""

    instrument: InstrumentConfig
    reduction: ReductionParams
    source: str | None = None

    @functools.cached_property
    def config_hash(self) -> str:
        """A stable 16-hex-digit hash of the instrument and reduction parameters (computed
        once per settings object: every run of a batch asks for it)."""
        payload = {"instrument": asdict(self.instrument), "reduction": asdict(self.reduction)}
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
        with p.open("rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise ConfigError("config file not found", path=p) from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"not valid TOML: {exc}", path=p) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"cannot read config: {exc}", path=p) from None


def load_settings(path: str | Path | None = None) -> Settings:
    """Load an instrument config file; ``None`` gives the founding T-PID/44 defaults."""
    if path is None:
        return settings_from_dict({}, source=None)
    return settings_from_dict(read_toml(path), source=str(path))
