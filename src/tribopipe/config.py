"""Load and validate instrument configs (``configs/instruments/*.toml``) into frozen dataclasses.

An instrument config has two tables:

``[instrument]``
    the measuring cell's geometry (:class:`InstrumentConfig`);
``[reduction]``
    the parameters of the μ_S / μ_K detection (:class:`tribopipe.reduce.ReductionParams`).

Both are optional: a missing key keeps the founding setup's default. Unknown keys are an
error (a typo must not silently fall back to a default).
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import tomllib
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .errors import ConfigError
from .physics import (  # noqa: F401 - the founding constants are importable from here too
    FOUNDING_FRICTION_RADIUS_MM,
    FOUNDING_SLIDING_SPEED_MM_S,
    FOUNDING_SPEED_RPM,
    sliding_speed_mm_s,
)

if TYPE_CHECKING:
    from .reduce import ReductionParams

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


def settings_from_dict(data: dict[str, Any], *, source: str | None = None) -> Settings:
    """Build :class:`Settings` from a parsed TOML document with optional
    ``[instrument]`` and ``[reduction]`` tables (other top-level tables are ignored)."""
    from .reduce import ReductionParams

    for section in ("instrument", "reduction"):
        if section in data and not isinstance(data[section], dict):
            raise ConfigError(f"[{section}] must be a table", path=source)
    instrument = _build(InstrumentConfig, data.get("instrument", {}), "instrument", source)
    reduction = _build(ReductionParams, data.get("reduction", {}), "reduction", source)
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
