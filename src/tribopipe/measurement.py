"""The in-memory measurement: one interval of one export, in SI units, with its metadata.

A reader returns a list of :class:`Measurement` objects (one per interval of every test and
result in a file). ``data`` is a DataFrame whose columns are snake_case and unit-suffixed.
The canonical quantities, when present, use exactly these names:

==================  =====================================================
``time_s``          time since the start of the interval or test [s]
``torque_Nm``       torque [N·m]
``normal_force_N``  normal force [N]
``angle_rad``       deflection angle [rad]
``speed_rad_s``     rotational speed [rad/s]
``temperature_C``   temperature [°C]
``friction_force_N`` friction (tangential) force of a force-based tribometer [N]
``position_m``      linear position, crosshead travel or sliding distance [m]
==================  =====================================================

A rheometer export carries torque and angle or speed; a force-based tribometer (a sled on
a universal testing machine, a linear or rotary tribometer) carries the friction force and
a position or distance, or an angle or speed of its disc.

Any other column keeps a snake_case name with its (converted where known) unit suffix,
e.g. ``shear_stress_Pa``. ``point_no`` holds the instrument's point number.

Nothing downstream of a reader knows which instrument or software wrote the file.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from .errors import MissingQuantityError

if TYPE_CHECKING:
    import pandas as pd

TIME = "time_s"
TORQUE = "torque_Nm"
NORMAL_FORCE = "normal_force_N"
ANGLE = "angle_rad"
SPEED = "speed_rad_s"
TEMPERATURE = "temperature_C"
FRICTION_FORCE = "friction_force_N"
POSITION = "position_m"
#: what a rheometer export holds
RHEOMETER_COLUMNS: tuple[str, ...] = (TIME, TORQUE, NORMAL_FORCE, ANGLE, SPEED, TEMPERATURE)
#: every canonical quantity: the rheometer's and a force-based instrument's
CANONICAL_COLUMNS: tuple[str, ...] = (*RHEOMETER_COLUMNS, FRICTION_FORCE, POSITION)


def interval_label(test: str | None, result: str | None, interval: int | None,
                   occurrence: int = 1) -> str:
    """``test / result / interval i``, leaving out what is unknown (``""`` when all are);
    `` #n`` added for the n-th run of an export at the same place (``occurrence`` > 1)."""
    parts = [p for p in (test, result) if p]
    if interval is not None:
        parts.append(f"interval {interval}")
    text = " / ".join(parts)
    if occurrence > 1:
        return f"{text} #{occurrence}" if text else f"#{occurrence}"
    return text


def run_name(file: str, test: str | None = None, result: str | None = None,
             interval: int | None = None, occurrence: int = 1) -> str:
    """The one way a run is named in messages, tables, plots and the map's account:
    ``file [test / result / interval i]`` (:func:`interval_label` of the parts known), the
    file alone where none is (or where the caller leaves them out: an export with one
    run)."""
    label = interval_label(test, result, interval, occurrence)
    return f"{file} [{label}]" if label else file


@dataclass(frozen=True)
class TorqueOffset:
    """The instrument's torque zero offset [N·m] measured outside a friction interval, and
    where (e.g. ``"set-up interval 1"``: the disc at rest under load before sliding), with
    the standard error of that estimate ``u_Nm`` [N·m] (NaN when the samples cannot show it)."""

    torque_Nm: float
    source: str
    u_Nm: float = 0.0


@dataclass(frozen=True)
class MeasurementMeta:
    """Where a measurement came from and how it was read.

    ``original_columns`` and ``original_units`` are the names and unit strings exactly as
    the file wrote them, in file order; ``column_map`` maps each original column name to
    the DataFrame column it became (absent when the column was dropped).
    """

    source_file: str
    file_format: str
    encoding: str | None = None
    delimiter: str | None = None
    decimal: str | None = None
    project: str | None = None
    test: str | None = None
    result: str | None = None
    interval: int | None = None
    sample: str | None = None
    original_columns: tuple[str, ...] = ()
    original_units: tuple[str, ...] = ()
    column_map: tuple[tuple[str, str], ...] = ()
    n_points_declared: int | None = None
    n_invalid_points: int = 0
    n_waveform_rows: int = 0
    header_line: int | None = None
    extra: tuple[tuple[str, str], ...] = field(default=())
    #: set by :func:`tribopipe.reduction.intervals.select_friction_interval` from the
    #: set-up interval before a friction interval; read by the reduction (``None``: not measured)
    torque_offset: TorqueOffset | None = None

    @property
    def label(self) -> str:
        """A short human label: ``file [test / result / interval i]`` (:func:`run_name`)."""
        return run_name(self.source_file, self.test, self.result, self.interval)

    @property
    def place(self) -> str | None:
        """Where the interval sits in its export, ``test / result / interval i``
        (:func:`interval_label`; ``None`` when the export names none of them)."""
        return interval_label(self.test, self.result, self.interval) or None


@dataclass(frozen=True)
class Measurement:
    """One interval's data (SI, unit-suffixed columns) with its metadata."""

    data: pd.DataFrame
    meta: MeasurementMeta

    def has(self, *columns: str) -> bool:
        """True when every named column exists and holds at least one finite value."""
        import numpy as np

        for col in columns:
            if col not in self.data.columns:
                return False
            values = np.asarray(self.data[col], dtype=float)
            if not np.isfinite(values).any():
                return False
        return True


def require_columns(measurement: Measurement, *columns: str) -> None:
    """Raise :class:`MissingQuantityError` unless every column exists with a finite value.

    The message names the file, the interval and the columns that were found, e.g.
    ``run.csv: interval 2 has no torque_Nm column (columns found: Time [s] → time_s, ...)``.
    """
    missing = [c for c in columns if not measurement.has(c)]
    if not missing:
        return
    meta = measurement.meta
    found = ", ".join(
        f"{orig} → {new}" for orig, new in meta.column_map
    ) or ", ".join(measurement.data.columns)
    where = interval_label(meta.test, meta.result, meta.interval)
    raise MissingQuantityError(
        f"{where} has no {' or '.join(missing)} values (columns found: {found or 'none'})",
        path=meta.source_file,
        line=meta.header_line,
        hint="add the column's name to configs/aliases.toml if it is there under another name",
    )
