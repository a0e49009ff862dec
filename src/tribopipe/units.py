"""Unit strings as instrument software writes them → SI factor, offset and column suffix.

A value ``v`` in a parsed unit becomes ``v * factor + offset`` in SI (temperatures in °C,
which is what the friction map uses). Unit strings are read the way Anton Paar software
writes them (``[mN·m]``, ``[µNm]``, ``[°]``, ``[1/min]``, ``[°C]``), including the micro
sign as U+00B5 or U+03BC, the middle dot U+00B7 and the forms a cp1252/UTF-8 mix-up leaves
behind (``Âµ``, ``Â·``, ``Â°``).

Rotational speed is special: Anton Paar writes it in revolutions (``[1/min]``), so a speed
column converts revolutions to rad/s, while a generic ``[1/s]`` (a shear rate) stays 1/s.
"""

from __future__ import annotations

import functools
import math
import re
import unicodedata
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import ReadError


@dataclass(frozen=True)
class UnitSpec:
    """A parsed unit: ``si = value * factor + offset``; ``suffix`` names the SI unit in a
    column name (``"Nm"`` → ``torque_Nm``; ``""`` for dimensionless quantities)."""

    factor: float
    suffix: str
    offset: float = 0.0

    def to_si(self, values: ArrayLike) -> NDArray[np.float64]:
        """Convert an array of values in this unit to SI (a new float array)."""
        out = np.asarray(values, dtype=float) * self.factor
        if self.offset:
            out = out + self.offset
        return out


_REV_PER_MIN = 2 * math.pi / 60  # one revolution per minute in rad/s
#: standard gravity [m/s²] (CGPM 1901): 1 gf = 9.80665 mN, 1 kgf = 9.80665 N
STANDARD_GRAVITY_M_S2 = 9.80665
#: one pound-force [N]: 0.45359237 kg × standard gravity (exact by definition)
POUND_FORCE_N = 0.45359237 * STANDARD_GRAVITY_M_S2
#: one inch [m] (exact by definition)
INCH_M = 0.0254

#: normalised unit (see :func:`normalize_unit`) → (factor, SI suffix[, offset])
_GENERIC: dict[str, tuple[float, str] | tuple[float, str, float]] = {
    # time
    "s": (1.0, "s"),
    "ms": (1e-3, "s"),
    "µs": (1e-6, "s"),
    "us": (1e-6, "s"),
    "min": (60.0, "s"),
    "h": (3600.0, "s"),
    # torque
    "Nm": (1.0, "Nm"),
    "mNm": (1e-3, "Nm"),
    "µNm": (1e-6, "Nm"),
    "nNm": (1e-9, "Nm"),
    # force
    "N": (1.0, "N"),
    "mN": (1e-3, "N"),
    "µN": (1e-6, "N"),
    "kN": (1e3, "N"),
    # force in mass units (standard gravity, 9.80665 m/s²) and pound-force
    "gf": (STANDARD_GRAVITY_M_S2 * 1e-3, "N"),
    "kgf": (STANDARD_GRAVITY_M_S2, "N"),
    "lbf": (POUND_FORCE_N, "N"),
    # angle
    "rad": (1.0, "rad"),
    "mrad": (1e-3, "rad"),
    "µrad": (1e-6, "rad"),
    "rev": (2 * math.pi, "rad"),  # whole revolutions (laps of a rotary tribometer)
    "°": (math.pi / 180, "rad"),  # also "deg" (normalize_unit)
    # angular velocity, frequency, rates
    "rad/s": (1.0, "rad_s"),
    "mrad/s": (1e-3, "rad_s"),
    "°/s": (math.pi / 180, "rad_s"),
    "Hz": (1.0, "Hz"),
    "1/s": (1.0, "1_s"),
    "1/min": (1 / 60, "1_s"),
    # temperature (°C is the map's unit)
    "°C": (1.0, "C"),
    "C": (1.0, "C"),
    "K": (1.0, "C", -273.15),
    "°F": (5 / 9, "C", -32 * 5 / 9),
    # stress, pressure
    "Pa": (1.0, "Pa"),
    "mPa": (1e-3, "Pa"),
    "kPa": (1e3, "Pa"),
    "MPa": (1e6, "Pa"),
    "bar": (1e5, "Pa"),
    # viscosity
    "Pas": (1.0, "Pa_s"),
    "mPas": (1e-3, "Pa_s"),
    # length
    "m": (1.0, "m"),
    "mm": (1e-3, "m"),
    "cm": (1e-2, "m"),
    "µm": (1e-6, "m"),
    "um": (1e-6, "m"),
    "in": (INCH_M, "m"),
    "mm/s": (1e-3, "m_s"),
    "mm/min": (1e-3 / 60, "m_s"),
    "m/s": (1.0, "m_s"),
    # dimensionless
    "%": (1.0, "pct"),
    "1": (1.0, ""),
    "": (1.0, ""),
}

#: rotational speed: Anton Paar's [1/min] and [1/s] count revolutions
_SPEED: dict[str, tuple[float, str]] = {
    "1/min": (_REV_PER_MIN, "rad_s"),
    "rpm": (_REV_PER_MIN, "rad_s"),
    "U/min": (_REV_PER_MIN, "rad_s"),
    "tr/min": (_REV_PER_MIN, "rad_s"),
    "1/s": (2 * math.pi, "rad_s"),
    "rps": (2 * math.pi, "rad_s"),
    "rad/s": (1.0, "rad_s"),
    "mrad/s": (1e-3, "rad_s"),
    "°/s": (math.pi / 180, "rad_s"),
}

# cp1252 reading of UTF-8 bytes, and look-alike characters, mapped to what we expect
_MOJIBAKE = (
    ("Âµ", "µ"),
    ("Î¼", "µ"),
    ("Â·", "·"),
    ("Â°", "°"),
    ("\u03bc", "µ"),  # Greek mu
    ("\u00ba", "°"),  # masculine ordinal, often typed for a degree
    ("\u02da", "°"),  # ring above
    ("\u2219", "·"),  # bullet operator
    ("\u22c5", "·"),  # dot operator
)


def normalize_unit(text: str) -> str:
    """Strip brackets/spaces and unify the micro sign, middle dot and degree sign.

    Products lose their dot (``mN·m``, ``mN.m``, ``mN*m`` → ``mNm``); ``µ`` is U+00B5.
    """
    unit = unicodedata.normalize("NFC", text).strip()
    for bad, good in _MOJIBAKE:
        unit = unit.replace(bad, good)
    if len(unit) >= 2 and unit[0] in "[(" and unit[-1] in "])":
        unit = unit[1:-1]
    unit = unit.replace(" ", "")
    # a product dot between two letters: mN·m, Pa.s, N*m
    unit = re.sub(r"(?<=[A-Za-zµ])[·.*](?=[A-Za-z])", "", unit)
    if unit.lower() == "rpm":
        unit = "rpm"
    if unit in ("revs", "revolutions", "laps"):
        unit = "rev"
    return "°" if unit == "deg" else unit


@functools.lru_cache(maxsize=1024)
def parse_unit(text: str, quantity: str | None = None) -> UnitSpec | None:
    """Parse a unit string such as ``"[mN·m]"``; ``None`` when the unit is not known.

    ``quantity`` is a canonical quantity name (``"speed"`` changes the meaning of
    ``[1/min]`` and ``[1/s]`` from a rate to revolutions).
    """
    unit = normalize_unit(text)
    table: Mapping[str, tuple[float, str] | tuple[float, str, float]] = (
        _SPEED if quantity == "speed" and unit in _SPEED else _GENERIC)
    entry = table.get(unit)
    if entry is None:
        return None
    factor, suffix, *rest = entry
    offset = float(rest[0]) if rest else 0.0
    return UnitSpec(factor=float(factor), suffix=str(suffix), offset=offset)


def sanitize_suffix(text: str) -> str:
    """A column-name-safe suffix for a unit we do not know (``[Pa/mNm]`` → ``Pa_mNm``)."""
    unit = normalize_unit(text)
    unit = unit.replace("µ", "u").replace("°", "deg").replace("%", "pct")
    unit = unicodedata.normalize("NFKD", unit).encode("ascii", "ignore").decode()
    return re.sub(r"[^A-Za-z0-9]+", "_", unit).strip("_")


#: SI suffix each canonical quantity must end up in
CANONICAL_SUFFIX: dict[str, str] = {
    "time": "s",
    "torque": "Nm",
    "normal_force": "N",
    "angle": "rad",
    "speed": "rad_s",
    "temperature": "C",
    "friction_force": "N",
    "position": "m",
}


def canonical_unit(
    quantity: str, unit_text: str, *, column: str, path: str | None = None
) -> UnitSpec:
    """The conversion of a canonical quantity's column; raises :class:`ReadError` when its
    unit is missing, unknown or of the wrong dimension (we never guess)."""
    expected = CANONICAL_SUFFIX[quantity]
    spec = parse_unit(unit_text, quantity)
    if spec is None or spec.suffix != expected:
        shown = unit_text.strip() or "no unit"
        what = "unknown unit" if spec is None else "unit of the wrong kind"
        raise ReadError(
            f"{what} {shown!r} for {quantity.replace('_', ' ')}",
            path=path,
            column=column,
            hint=f"expected a unit convertible to {expected} (add it to tribopipe.units "
            "or convert the column)",
        )
    return spec
