"""The unit systems of simulator files, and numbers written as the solvers read them.

The map stores contact pressure in kPa and sliding speed in mm/s; a file is written in one
of these unit systems (``units``):

==========  ===================  ==============  ======================
``units``   contact pressure     slip rate       decay coefficient d_c
==========  ===================  ==============  ======================
mm-N-s      MPa (kPa × 1e-3)     mm/s (× 1)      s/mm (× 1)
m-N-s       Pa  (kPa × 1e3)      m/s (× 1e-3)    s/m  (× 1e3)
==========  ===================  ==============  ======================

Light: the standard library only, so that the command line can offer the unit systems
without loading numpy or pandas.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import ExportError
from ..rounding import FILE_DIGITS, decimal_text


@dataclass(frozen=True)
class UnitSystem:
    """Conversion factors from the map's units (kPa, mm/s, s/mm) to a simulator's."""

    name: str
    pressure_unit: str
    pressure_per_kPa: float
    speed_unit: str
    speed_per_mm_s: float
    decay_unit: str
    decay_per_s_per_mm: float


UNIT_SYSTEMS: dict[str, UnitSystem] = {
    "mm-N-s": UnitSystem("mm-N-s", "MPa", 1e-3, "mm/s", 1.0, "s/mm", 1.0),
    "m-N-s": UnitSystem("m-N-s", "Pa", 1e3, "m/s", 1e-3, "s/m", 1e3),
}


def unit_system(units: str) -> UnitSystem:
    """The :class:`UnitSystem` named ``units`` (``mm-N-s`` or ``m-N-s``)."""
    try:
        return UNIT_SYSTEMS[units]
    except KeyError:
        raise ExportError(
            f"unknown unit system {units!r}; expected one of {', '.join(UNIT_SYSTEMS)}"
        ) from None


def convert_pressure_kPa(pressure_kPa: float, units: str) -> float:
    """Contact pressure [kPa] in the unit system's pressure unit (MPa or Pa)."""
    return pressure_kPa * unit_system(units).pressure_per_kPa


def num(value: float) -> str:
    """A number as the solvers read it: up to :data:`~tribopipe.rounding.FILE_DIGITS` (10)
    significant digits, no separators.

    10 digits keep the grid's pressures exact enough that a solver's interpolation
    between them matches ours; short values (0.01179) stay short. Rounded by the one
    rule for computed numbers (:func:`tribopipe.rounding.decimal_text`), which the
    explorer's copied snippets share.
    """
    return decimal_text(value, digits=FILE_DIGITS)
