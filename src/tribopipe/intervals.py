"""The friction interval of an export, and the torque offset its set-up interval measured.

An export holds several intervals (of one or more tests and results): typically a
normal-force set-up with the disc at rest, then the friction interval with the disc
turning. :func:`select_friction_interval` picks the interval with rotation; when the
interval right before it is verified at rest, its robust mean torque is the instrument's
torque zero offset (with the disc at rest the true friction torque is zero), attached as
``meta.torque_offset`` for :func:`tribopipe.reduce.reduce_measurement`.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from .errors import MissingQuantityError, ReductionError
from .measurement import ANGLE, NORMAL_FORCE, SPEED, TIME, TORQUE, Measurement, TorqueOffset

if TYPE_CHECKING:
    from collections.abc import Sequence

#: an interval "rotates" when its deflection angle travels at least this far [rad]
#: (0.002 rad ≈ 0.027 mm at R = 13.37 mm, ~4 s at 0.005 rpm) ...
ROTATION_MIN_ANGLE_RAD = 2e-3
#: ... or its median |rotational speed| reaches this [rad/s] (0.005 rpm = 5.2e-4 rad/s)
ROTATION_MIN_SPEED_RAD_S = 5e-5


def robust_mean(values: Any) -> float:
    """Mean of the values (shape (n,)) within 4 robust standard deviations (1.4826·MAD)
    of their median: as efficient as the mean on Gaussian noise, deaf to spikes."""
    v = np.asarray(values, dtype=float)
    centre = float(np.median(v))
    spread = 1.4826 * float(np.median(np.abs(v - centre)))
    if spread == 0:
        return centre
    return float(np.mean(v[np.abs(v - centre) <= 4 * spread]))


def _column(m: Measurement, name: str) -> np.ndarray | None:
    if name not in m.data.columns:
        return None
    values = np.array(m.data[name], dtype=float)
    return values if np.isfinite(values).any() else None


def _rotation_known(m: Measurement) -> bool:
    return _column(m, ANGLE) is not None or _column(m, SPEED) is not None


def _rotates(m: Measurement) -> bool:
    angle = _column(m, ANGLE)
    if angle is not None:
        finite = angle[np.isfinite(angle)]
        if finite.size >= 2 and abs(finite[-1] - finite[0]) >= ROTATION_MIN_ANGLE_RAD:
            return True
    speed = _column(m, SPEED)
    if speed is not None:
        finite = speed[np.isfinite(speed)]
        if finite.size and float(np.median(np.abs(finite))) >= ROTATION_MIN_SPEED_RAD_S:
            return True
    return False


def _angle_travel(m: Measurement) -> float:
    angle = _column(m, ANGLE)
    if angle is not None:
        finite = angle[np.isfinite(angle)]
        return float(abs(finite[-1] - finite[0]))
    speed = _column(m, SPEED)
    time = _column(m, TIME)
    if speed is None or time is None:
        return 0.0
    ok = np.isfinite(speed) & np.isfinite(time)
    return float(abs(np.trapezoid(speed[ok], time[ok]))) if ok.sum() >= 2 else 0.0


def setup_torque_offset_Nm(setup: Measurement) -> float | None:
    """Robust mean torque [N·m] of a set-up interval (disc not rotating), or ``None``
    without torque values. With the disc at rest the true friction torque is zero, so this is the
    instrument's torque zero offset."""
    torque = _column(setup, TORQUE)
    if torque is None:
        return None
    return robust_mean(torque[np.isfinite(torque)])


def select_friction_interval(measurements: Sequence[Measurement]) -> Measurement:
    """The friction interval of an export: the interval with rotation.

    Among the intervals having time, torque and normal force, the one whose disc rotates
    (deflection angle travels ≥ ``ROTATION_MIN_ANGLE_RAD`` or median speed ≥
    ``ROTATION_MIN_SPEED_RAD_S``) is chosen; if several rotate, the one travelling
    farthest. Without any angle or speed column the interval with the largest median
    |torque| is taken (a normal-force set-up interval carries almost none).

    When the interval right before it in the same test and result is verified at rest
    (a normal-force set-up), its mean torque is attached to the returned measurement's
    ``meta.torque_offset`` (a :class:`~tribopipe.measurement.TorqueOffset` naming the
    set-up interval) for :func:`reduce_measurement`. The input measurements are not
    modified.

    Raises :class:`ReductionError` when no interval has the quantities or none rotates.
    """
    items = list(measurements)
    if not items:
        raise ReductionError("no intervals to choose the friction interval from")
    usable = [i for i, m in enumerate(items) if m.has(TIME, TORQUE, NORMAL_FORCE)]
    source = items[0].meta.source_file
    if not usable:
        found = sorted({c for m in items for c in m.data.columns})
        absent = [c for c in (TIME, TORQUE, NORMAL_FORCE) if not any(m.has(c) for m in items)]
        lacking = ", ".join(absent) if absent else "all three together"
        raise MissingQuantityError(
            f"no interval has time, torque and normal force (missing: {lacking}); "
            "columns found: " + (", ".join(found) or "none"),
            path=source,
            hint="check the column names or pass an alias table",
        )
    known = [i for i in usable if _rotation_known(items[i])]
    if known:
        rotating = [i for i in known if _rotates(items[i])]
        if not rotating:
            raise ReductionError(
                f"no rotation in any of the {len(known)} interval(s) with an angle or speed: "
                "the disc never turned, so there is no friction interval",
                path=source,
            )
        chosen = max(rotating, key=lambda i: (_angle_travel(items[i]), -i))
    else:
        chosen = max(usable, key=lambda i: (_median_abs_torque(items[i]), -i))
    picked = items[chosen]
    previous = chosen - 1
    if previous >= 0:
        before = items[previous]
        same_run = (before.meta.test, before.meta.result) == (picked.meta.test, picked.meta.result)
        if same_run and _rotation_known(before) and not _rotates(before):
            offset = setup_torque_offset_Nm(before)
            if offset is not None:
                where = f"set-up interval {before.meta.interval}" if before.meta.interval else (
                    "set-up interval"
                )
                picked = Measurement(data=picked.data, meta=replace(
                    picked.meta, torque_offset=TorqueOffset(torque_Nm=offset, source=where)))
    return picked


def _median_abs_torque(m: Measurement) -> float:
    torque = _column(m, TORQUE)
    return float(np.nanmedian(np.abs(torque))) if torque is not None else 0.0
