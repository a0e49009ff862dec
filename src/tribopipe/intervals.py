"""The friction interval of an export: which one, its complete samples, its torque offset.

An export holds several intervals (of one or more tests and results): typically a
normal-force set-up with the disc at rest, then the friction interval with the disc
turning. :func:`select_friction_interval` picks the interval with rotation; when the
interval right before it is verified at rest, its robust mean torque is the instrument's
torque zero offset (with the disc at rest the true friction torque is zero), attached as
``meta.torque_offset`` for :func:`tribopipe.reduce.reduce_measurement`.

What the reduction reads of the chosen interval is prepared here too:
:func:`interval_samples` (the complete samples as new float arrays, time-ordered, force
positive in compression) and :func:`choose_torque_offset` (given > set-up interval >
the at-rest start of the interval, :func:`leading_rest` and
:func:`estimate_torque_offset_Nm` > none).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from .config import ReductionParams
from .errors import MissingQuantityError, ReductionError
from .measurement import (
    ANGLE,
    NORMAL_FORCE,
    SPEED,
    TEMPERATURE,
    TIME,
    TORQUE,
    Measurement,
    TorqueOffset,
)

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


# ------------------------------------------------------------------ what the reduction reads


@dataclass(frozen=True)
class IntervalSamples:
    """The complete samples of one interval, time-ordered, as new float arrays."""

    t: np.ndarray
    torque: np.ndarray
    force: np.ndarray  # made positive in compression
    angle: np.ndarray | None
    speed: np.ndarray | None
    temperature: np.ndarray | None
    n_total: int
    n_dropped: int
    force_sign: float


def interval_samples(m: Measurement, params: ReductionParams) -> IntervalSamples:
    """Validate and copy the quantities of ``m`` (raises ReductionError for bad input)."""
    label = m.meta.label
    data = m.data
    t = np.array(data[TIME], dtype=float)
    torque = np.array(data[TORQUE], dtype=float)
    force = np.array(data[NORMAL_FORCE], dtype=float)
    n_total = int(t.size)
    for name, values in ((TORQUE, torque), (NORMAL_FORCE, force)):
        missing = int((~np.isfinite(values)).sum())
        if missing > params.max_missing_fraction * n_total:
            raise ReductionError(
                f"{label}: {missing} of {n_total} {name} values are missing "
                f"(more than {params.max_missing_fraction:.0%}); cannot reduce"
            )
    keep = np.isfinite(t) & np.isfinite(torque) & np.isfinite(force)
    order = np.argsort(t[keep], kind="stable")

    def pick(values: np.ndarray) -> np.ndarray:
        return values[keep][order]

    def optional(name: str) -> np.ndarray | None:
        if name not in data.columns:
            return None
        values = pick(np.array(data[name], dtype=float))
        return values if np.isfinite(values).any() else None

    t, torque, force = pick(t), pick(torque), pick(force)
    if t.size < params.min_contact_samples:
        raise ReductionError(
            f"{label}: only {t.size} complete samples (time, torque and normal force); "
            f"need at least {params.min_contact_samples}"
        )
    force_sign = -1.0 if np.median(force) < 0 else 1.0
    return IntervalSamples(
        t=t,
        torque=torque,
        force=force_sign * force,
        angle=optional(ANGLE),
        speed=optional(SPEED),
        temperature=optional(TEMPERATURE),
        n_total=n_total,
        n_dropped=int(n_total - t.size),
        force_sign=force_sign,
    )


def _offset_from_meta(m: Measurement) -> tuple[float | None, str | None]:
    offset = m.meta.torque_offset
    if offset is None or not math.isfinite(offset.torque_Nm):
        return None, None
    return offset.torque_Nm, offset.source


def leading_rest(s_mm: Any, motion_tol_mm: float) -> np.ndarray:
    """Boolean mask (shape (n,)) of the samples before the disc first moves
    ``motion_tol_mm`` [mm] along ``s_mm``; a stop later in the run is not "rest"."""
    s = np.asarray(s_mm, dtype=float)
    moved = s >= motion_tol_mm
    first = int(np.argmax(moved)) if moved.any() else s.size
    return np.arange(s.size) < first


def estimate_torque_offset_Nm(
    torque_Nm: Any, at_rest: Any, min_samples: int
) -> tuple[float | None, int]:
    """Robust mean torque [N·m] of the at-rest samples (boolean mask), or ``None`` when fewer
    than ``min_samples`` are at rest; and the number of samples used."""
    torque = np.asarray(torque_Nm, dtype=float)
    rest = np.asarray(at_rest, dtype=bool)
    n = int(rest.sum())
    if n < min_samples:
        return None, n
    return robust_mean(torque[rest]), n


def choose_torque_offset(
    m: Measurement, x: IntervalSamples, at_rest: np.ndarray, given_Nm: float | None,
    params: ReductionParams,
) -> tuple[float, str]:
    """The torque zero offset [N·m] and where it came from: given > set-up interval >
    at-rest start of this interval > none (0)."""
    meta_offset, meta_source = _offset_from_meta(m)
    rest_offset, n_rest = estimate_torque_offset_Nm(x.torque, at_rest, params.offset_min_samples)
    if given_Nm is not None:
        offset, offset_source = float(given_Nm), "given"
    elif meta_offset is not None:
        offset, offset_source = meta_offset, str(meta_source)
    elif rest_offset is not None:
        offset, offset_source = rest_offset, f"at-rest start ({n_rest} samples)"
    else:
        offset = 0.0
        offset_source = "not estimated (no set-up interval, no at-rest samples): 0 assumed"
    return offset, offset_source
