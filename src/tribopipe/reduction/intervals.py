"""The friction interval of an export: which one, its complete samples, its torque offset.

An export holds several intervals (of one or more tests and results): typically a
normal-force set-up with the disc at rest, then the friction interval with the disc
turning; a test whose method holds force or speed steps has several friction intervals,
and a session export holds several tests. :func:`friction_intervals` finds every friction
interval of every test and result (the rule is in its docstring); the nearest interval
before each in the same test and result that is verified at rest is its set-up, whose
robust mean torque is the instrument's torque zero offset (with the disc at rest the true
friction torque is zero), attached as ``meta.torque_offset`` for
:func:`tribopipe.reduction.reduce.reduce_measurement`. :func:`select_friction_interval` is the
single choice among them (the one travelling farthest).

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

from ..config import ReductionParams
from ..errors import MissingQuantityError, NotFrictionTestError, ReductionError, TribopipeError
from ..measurement import (
    ANGLE,
    FRICTION_FORCE,
    NORMAL_FORCE,
    POSITION,
    SPEED,
    TEMPERATURE,
    TIME,
    TORQUE,
    Measurement,
    TorqueOffset,
    interval_label,
)
from ..validate import FORCE_N
from .uncertainty import zero_offset_standard_error

if TYPE_CHECKING:
    from collections.abc import Sequence

#: the largest magnitude a sample of each quantity may have (in its SI unit): no
#: instrument measures beyond these, and larger values would overflow the statistics
SAMPLE_LIMITS: dict[str, float] = {
    TIME: 1e10, TORQUE: 1e6, NORMAL_FORCE: FORCE_N.high, ANGLE: 1e9, SPEED: 1e6,
    TEMPERATURE: 1e4, FRICTION_FORCE: FORCE_N.high, POSITION: 1e6,
}
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


def tangential_column(m: Measurement) -> str:
    """The column holding ``m``'s tangential reading: ``torque_Nm`` (a rheometer) when it
    has torque values, else ``friction_force_N`` (a force-based tribometer)."""
    return TORQUE if m.has(TORQUE) or not m.has(FRICTION_FORCE) else FRICTION_FORCE


def _usable(m: Measurement) -> bool:
    """Time and a tangential reading, and a normal force (a force-based run may lack it:
    a sled's weight gives it, see ``InstrumentConfig.sled_mass_g``)."""
    if m.has(TIME, TORQUE, NORMAL_FORCE):
        return True
    return not m.has(TORQUE) and m.has(TIME, FRICTION_FORCE)


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


#: A sliding interval turns one way: its net angle is at least this share of the angle's
#: range, and its speed has one sign (an oscillation goes back and forth: a net near 0).
ONE_WAY_MIN_SHARE = 0.8
#: What a rheological test that is not pin-on-disc sliding carries: (columns, what it is).
_NOT_SLIDING: tuple[tuple[tuple[str, ...], str], ...] = (
    # the most telling first: a relaxation export lists the oscillation moduli too
    (("relaxation_modulus_Pa",), "a stress relaxation test (relaxation modulus)"),
    (("storage_modulus_Pa", "loss_modulus_Pa", "frequency_Hz"),
     "an oscillation test (storage and loss moduli, frequency)"),
    (("viscosity_Pa_s", "shear_rate_1_s"), "a flow curve (viscosity over shear rate)"),
)
#: the hint of every refusal of a test that is not pin-on-disc sliding
NOT_FRICTION_HINT = ("tribopipe reduces pin-on-disc friction tests: the disc turns one way "
                     "at constant speed under a normal force (e.g. an Anton Paar T-PID test); "
                     "export such a test")


def _one_way(m: Measurement) -> bool:
    """True unless the measured angle or speed shows the disc turning back and forth."""
    angle = _column(m, ANGLE)
    if angle is not None:
        finite = angle[np.isfinite(angle)]
        # the range, not the summed steps: sensor jitter adds path, not range (Python
        # floats: a wild sample's overflow is an infinite span, not a numeric warning)
        span = float(finite.max()) - float(finite.min()) if finite.size >= 2 else 0.0
        if span >= ROTATION_MIN_ANGLE_RAD and \
                abs(float(finite[-1]) - float(finite[0])) < ONE_WAY_MIN_SHARE * span:
            return False
    speed = _column(m, SPEED)
    if speed is not None:
        moving = speed[np.isfinite(speed) & (np.abs(speed) >= ROTATION_MIN_SPEED_RAD_S)]
        if moving.size and min((moving > 0).mean(), (moving < 0).mean()) > 1 - ONE_WAY_MIN_SHARE:
            return False
    return True


def not_sliding(m: Measurement) -> str | None:
    """What an interval is when it is not pin-on-disc sliding (steady rotation in one
    direction): a rheological test its columns name (oscillation, relaxation, flow curve)
    unless a measured angle or speed shows one-way rotation under a normal force, or "an
    oscillation" when the measured angle or speed goes back and forth; ``None`` for a
    sliding interval (and for one that names none of these: plain time, torque, force)."""
    if not _one_way(m):
        return "an oscillation (the disc turns back and forth)"
    if _rotation_known(m) and _rotates(m) and m.has(NORMAL_FORCE):
        return None
    for columns, what in _NOT_SLIDING:
        if any(c in m.data.columns for c in columns):
            return what
    return None


def _most_telling(kinds: Sequence[str]) -> str:
    """Of the kinds of a result's intervals (:func:`not_sliding`), the one listed first in
    :data:`_NOT_SLIDING` (an oscillation test's intervals may carry a shear rate too)."""
    order = [what for _, what in _NOT_SLIDING]
    return min(kinds, key=lambda k: order.index(k) if k in order else -1)


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


def group_results(measurements: Sequence[Measurement]) -> list[list[Measurement]]:
    """The intervals cut into their tests and results, in file order: a new group starts
    where the test or result name changes or the interval numbering restarts (two tests
    of one export may carry the same names)."""
    groups: list[list[Measurement]] = []
    previous: Measurement | None = None
    for m in measurements:
        restarted = (
            previous is not None and m.meta.interval is not None
            and previous.meta.interval is not None and m.meta.interval <= previous.meta.interval
        )
        same = previous is not None and \
            (m.meta.test, m.meta.result) == (previous.meta.test, previous.meta.result)
        if not groups or not same or restarted:
            groups.append([])
        groups[-1].append(m)
        previous = m
    return groups


@dataclass(frozen=True)
class ResultIntervals:
    """One test/result of an export: its friction intervals, in file order, each carrying
    its set-up interval's torque offset (``meta.torque_offset``), or ``problem``, why it
    holds none (then ``friction`` is empty)."""

    test: str | None
    result: str | None
    friction: tuple[Measurement, ...]
    problem: TribopipeError | None = None

    @property
    def label(self) -> str:
        """``test / result`` (``""`` when the export names neither)."""
        return interval_label(self.test, self.result, None)


def friction_intervals(measurements: Sequence[Measurement]) -> list[ResultIntervals]:
    """Every friction interval of an export, by test and result (:func:`group_results`).

    The rule, applied to each test/result on its own:

    * only intervals with time, torque and normal force count;
    * where any of them has a deflection angle or a rotational speed, every interval
      whose disc rotates (angle travels ≥ ``ROTATION_MIN_ANGLE_RAD`` or median speed ≥
      ``ROTATION_MIN_SPEED_RAD_S``) is a friction interval: one for a plain test, one
      per step where a test's method holds force or speed steps; none rotating is a
      ``problem`` (the disc never turned);
    * without any angle or speed, rest and sliding cannot be told apart: the one
      interval with the largest median |torque| is taken (a normal-force set-up carries
      almost none).

    Set-up interval: for each friction interval, the nearest interval before it in the
    same test and result that is verified at rest (it has an angle or speed, and the disc
    does not rotate). Its robust mean torque is the instrument's torque zero offset for
    that friction interval, attached as ``meta.torque_offset`` (a
    :class:`~tribopipe.measurement.TorqueOffset` naming the set-up interval); a set-up is
    never borrowed from another test or result. The input measurements are not modified.

    Messages name the test and result when the export holds several.
    """
    groups = group_results(measurements)
    several = len(groups) > 1
    return [_result_intervals(items, several) for items in groups]


def _result_intervals(items: list[Measurement], several: bool) -> ResultIntervals:
    """The friction intervals of one test/result (see :func:`friction_intervals`)."""
    first = items[0].meta
    where = interval_label(first.test, first.result, None)
    prefix = f"{where}: no friction interval: " if several and where else (
        "no friction interval: " if several else "")
    source = first.source_file
    kinds = [not_sliding(m) for m in items]
    # judged on the intervals that hold samples (an export may list empty ones)
    held = [k for m, k in zip(items, kinds, strict=True) if len(m.data)]
    named = [k for k in held if k is not None]
    if held and len(named) == len(held):
        return ResultIntervals(first.test, first.result, (), NotFrictionTestError(
            f"{prefix}not a pin-on-disc friction test: it looks like {_most_telling(named)}",
            looks_like=_most_telling(named), path=source, hint=NOT_FRICTION_HINT))
    usable = [i for i, m in enumerate(items) if _usable(m) and kinds[i] is None]
    if not usable:
        found = sorted({c for m in items for c in m.data.columns})
        absent = [c for c in (TIME, TORQUE, NORMAL_FORCE) if not any(m.has(c) for m in items)]
        lacking = ", ".join(absent) if absent else "all three together"
        return ResultIntervals(first.test, first.result, (), MissingQuantityError(
            f"{prefix}no interval has time, torque and normal force (missing: {lacking}); "
            "columns found: " + (", ".join(found) or "none"),
            path=source,
            hint="if the export names a quantity otherwise, add that column name to "
                 "configs/aliases.toml in the folder you run tribopipe from (`tribopipe "
                 "inspect FILE` lists the columns read)",
        ))
    known = [i for i in usable if _rotation_known(items[i])]
    if known:
        chosen = [i for i in known if _rotates(items[i])]
        if not chosen:
            return ResultIntervals(first.test, first.result, (), ReductionError(
                f"{prefix}no rotation in any of the {len(known)} interval(s) with an angle or "
                "speed: the disc never turned, so there is no friction interval",
                path=source,
            ))
    else:
        chosen = [max(usable, key=lambda i: (_median_abs_torque(items[i]), -i))]
    try:
        friction = tuple(_with_setup_offset(items, i) for i in chosen)
    except ReductionError as exc:          # a set-up torque beyond any measurement
        return ResultIntervals(first.test, first.result, (), exc)
    return ResultIntervals(first.test, first.result, friction)


def _with_setup_offset(items: list[Measurement], chosen: int) -> Measurement:
    """``items[chosen]`` with the torque offset of its set-up interval: the nearest
    interval before it (same test/result) verified at rest. Raises
    :class:`ReductionError` when that interval holds a sample beyond any measurement
    (:data:`SAMPLE_LIMITS`): its torque cannot be the instrument's zero."""
    picked = items[chosen]
    for before in reversed(items[:chosen]):
        if not _rotation_known(before) or _rotates(before):
            continue
        _check_magnitudes(before)
        offset = setup_torque_offset_Nm(before)
        if offset is None:
            continue
        where = f"set-up interval {before.meta.interval}" if before.meta.interval else (
            "set-up interval"
        )
        # NaN when the set-up holds too few samples to show its own scatter
        u = zero_offset_standard_error(_column(before, TORQUE))
        return Measurement(data=picked.data, meta=replace(
            picked.meta, torque_offset=TorqueOffset(torque_Nm=offset, source=where, u_Nm=u)))
    return picked


def all_friction_intervals(measurements: Sequence[Measurement]) -> list[Measurement]:
    """The friction intervals of every test and result (:func:`friction_intervals`), in
    file order. Raises the first test/result's ``problem`` when the export holds none."""
    found = friction_intervals(measurements)
    if not found:
        raise ReductionError("no intervals to choose the friction interval from")
    out = [m for r in found for m in r.friction]
    if not out:
        problem = next(r.problem for r in found if r.problem is not None)
        raise problem
    return out


def select_friction_interval(measurements: Sequence[Measurement]) -> Measurement:
    """The one friction interval of an export that travels farthest (ties: the first).

    Of the friction intervals of every test and result (:func:`friction_intervals`:
    every interval whose disc rotates; without any angle or speed, the interval with the
    largest median |torque|), the one whose disc travels farthest, else the one with the
    largest median |torque|, carrying its set-up interval's torque offset. A reduction of
    the whole export reads them all (:func:`tribopipe.pipeline.read_runs`); this is the
    single choice for a one-run export.

    Raises :class:`ReductionError` (:class:`MissingQuantityError`) when no interval has
    the quantities or none rotates.
    """
    items = all_friction_intervals(measurements)
    best = max(range(len(items)),
               key=lambda i: (_angle_travel(items[i]), _median_abs_torque(items[i]), -i))
    return items[best]


def _median_abs_torque(m: Measurement) -> float:
    torque = _column(m, tangential_column(m))
    return float(np.nanmedian(np.abs(torque))) if torque is not None else 0.0


# ------------------------------------------------------------------ what the reduction reads


@dataclass(frozen=True)
class IntervalSamples:
    """The complete samples of one interval, time-ordered, as new float arrays."""

    t: np.ndarray
    #: the tangential reading: torque [N·m], or a force-based instrument's friction force [N]
    torque: np.ndarray
    force: np.ndarray  # made positive in compression
    angle: np.ndarray | None
    speed: np.ndarray | None
    temperature: np.ndarray | None
    n_total: int
    n_dropped: int
    force_sign: float
    #: linear position, crosshead travel or sliding distance [m] (``None`` without one)
    position: np.ndarray | None = None


def interval_samples(
    m: Measurement, params: ReductionParams, tangential: str = TORQUE
) -> IntervalSamples:
    """Validate and copy the quantities of ``m`` (raises ReductionError for bad input);
    ``tangential`` names the column of the tangential reading (torque or friction force)."""
    meta = m.meta
    data = m.data
    t = np.array(data[TIME], dtype=float)
    torque = np.array(data[tangential], dtype=float)
    force = np.array(data[NORMAL_FORCE], dtype=float)
    n_total = int(t.size)
    for name, values in ((tangential, torque), (NORMAL_FORCE, force)):
        missing = int((~np.isfinite(values)).sum())
        if missing > params.max_missing_fraction * n_total:
            raise ReductionError(
                f"{missing} of {n_total} {name} values are missing "
                f"(more than {params.max_missing_fraction:.0%}); cannot reduce",
                path=meta.source_file, place=meta.place,
            )
    keep = np.isfinite(t) & np.isfinite(torque) & np.isfinite(force)
    _check_magnitudes(m)
    _check_time(m, t, keep)
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
            f"only {t.size} complete samples (time, {tangential} and normal force); "
            f"need at least {params.min_contact_samples}",
            path=meta.source_file, place=meta.place,
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
        position=optional(POSITION),
    )


def _point(m: Measurement, row: int) -> Any:
    """The instrument's point number of ``m``'s sample ``row`` (0-based), or ``row + 1``
    when the export numbers no points."""
    return m.data["point_no"].iloc[row] if "point_no" in m.data.columns else row + 1


def _check_magnitudes(m: Measurement) -> None:
    """Refuse (:class:`ReductionError`) a sample beyond :data:`SAMPLE_LIMITS`: a column
    holding such values is not what its name and unit say."""
    meta = m.meta
    for name, limit in SAMPLE_LIMITS.items():
        if name not in m.data.columns:
            continue
        values = np.abs(np.asarray(m.data[name], dtype=float))
        beyond = np.flatnonzero(values > limit)  # NaN compares False: missing is no error
        if beyond.size:
            row = int(beyond[0])
            point = _point(m, row)
            raise ReductionError(
                f"{name} is {float(m.data[name].iloc[row]):.4g} at point "
                f"{point}, beyond any measurement (|value| <= {limit:g}): the column is not "
                "what its name and unit say",
                hint="check the export's columns and units",
                path=meta.source_file, place=meta.place,
            )


def _check_time(m: Measurement, t: np.ndarray, keep: np.ndarray) -> None:
    """Refuse (:class:`ReductionError`, naming the point) a time column that goes
    backwards between complete samples or never advances: the samples of an interval are
    written in the order they were taken, so either means the column is not the time."""
    meta = m.meta
    t_kept = t[keep]
    if t_kept.size < 2:
        return
    back = np.flatnonzero(np.diff(t_kept) < 0)
    if back.size:
        k = int(back[0]) + 1
        row = int(np.flatnonzero(keep)[k])
        point = _point(m, row)
        raise ReductionError(
            f"time goes backwards at point {point} ({t_kept[k]:g} s after "
            f"{t_kept[k - 1]:g} s): expected increasing time",
            hint="check the time column (or its unit)",
            path=meta.source_file, place=meta.place,
        )
    if t_kept[-1] == t_kept[0]:
        raise ReductionError(
            f"time is constant ({t_kept[0]:g} s) over all {t_kept.size} "
            "complete samples: expected increasing time",
            hint="check the time column (or its unit)",
            path=meta.source_file, place=meta.place,
        )


def _offset_from_meta(m: Measurement) -> tuple[float | None, str | None, float]:
    offset = m.meta.torque_offset
    if offset is None or not math.isfinite(offset.torque_Nm):
        return None, None, 0.0
    return offset.torque_Nm, offset.source, offset.u_Nm


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


def trailing_rest(s_mm: Any, motion_tol_mm: float) -> np.ndarray:
    """Boolean mask (shape (n,)) of the samples after the last movement: from the first
    sample from which ``s_mm`` [mm] stays within ``motion_tol_mm`` of its final value."""
    s = np.asarray(s_mm, dtype=float)
    if s.size == 0:
        return np.zeros(0, dtype=bool)
    away = np.flatnonzero(np.abs(s - s[-1]) > motion_tol_mm)
    first = int(away[-1]) + 1 if away.size else 0
    return np.arange(s.size) >= first


def end_stop(t_s: Any, s_mm: Any, moving: Any, fraction: float) -> np.ndarray:
    """Boolean mask (shape (n,)) of a stop at the end of a record: the last samples over
    which the sliding speed [mm/s] stays below ``fraction`` of the median speed of the
    ``moving`` samples (a motor slowing down, then at rest). The speed is read over
    windows of 1 % of the record (at least 2 samples each side), so that a distance
    column's noise is not taken for a stop; nothing is marked when the record ends
    sliding."""
    t = np.asarray(t_s, dtype=float)
    s = np.asarray(s_mm, dtype=float)
    n = s.size
    stop = np.zeros(n, dtype=bool)
    h = max(2, n // 100)
    if n < 4 * h + 1 or fraction <= 0:
        return stop
    lo, hi = np.arange(n) - h, np.arange(n) + h
    lo, hi = np.clip(lo, 0, n - 1), np.clip(hi, 0, n - 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        speed = np.abs(s[hi] - s[lo]) / (t[hi] - t[lo])
    move = np.asarray(moving, dtype=bool) & np.isfinite(speed)
    if move.sum() < 4 * h:
        return stop
    typical = float(np.median(speed[move]))
    if not typical > 0:
        return stop
    slow = ~(speed >= fraction * typical)
    if not slow[-1]:
        return stop
    fast = np.flatnonzero(~slow)
    if fast.size == 0:
        return stop
    # the window of the last fast sample still reaches into the slowing: start past it
    first = min(n, int(fast[-1]) + 1)
    stop[first:] = True
    return stop


@dataclass(frozen=True)
class ZeroChoice:
    """The tangential channel's zero [N·m, or N for a friction force] and what it rests
    on: ``source`` (words), ``u`` its standard uncertainty, ``known`` whether it was
    estimated or given, ``under_load`` whether at-rest samples that carry a tangential load
    were refused as a zero, ``disagree`` whether a second zero (a rest after sliding)
    disagrees with the first, ``load_fraction`` the refused samples' level over the
    sliding level above it, ``second`` the second zero (``None`` without one)."""

    offset: float
    source: str
    u: float
    known: bool = True
    under_load: bool = False
    disagree: bool = False
    load_fraction: float | None = None
    second: float | None = None


def load_fraction(zero: float, sliding_level: float) -> float:
    """How much of a tangential load an at-rest level ``zero`` carries: ``|zero|`` over
    the sliding level above it, ``|sliding_level − zero|`` (inf when that is 0). A
    transducer's zero offset is small beside the friction it measures; a pull or a shear
    already applied at rest is as large as the friction."""
    above = abs(sliding_level - zero)
    return abs(zero) / above if above > 0 else math.inf


def choose_zero(
    m: Measurement, x: IntervalSamples, at_rest: np.ndarray, given: float | str | None,
    params: ReductionParams, *, unknown_u: float = 0.0, sliding: np.ndarray | None = None,
    after: np.ndarray | None = None, lever_N_per_unit: float = 1.0,
    force_N: float = 1.0,
) -> ZeroChoice:
    """The zero of the tangential channel (torque [N·m] or friction force [N]).

    ``given``: a number (used as it is, u = 0), ``"off"`` (0, u = 0), or ``"auto"`` /
    ``None``: estimated where the instrument is known unloaded, in this order: the set-up
    interval before the friction interval; the samples before the first movement
    (``at_rest``, at least ``offset_min_samples``). An estimate whose level is more than
    ``zero_load_max_fraction`` of the sliding level above it (:func:`load_fraction`;
    ``sliding`` masks the sliding samples) carries a load: it is refused and
    ``under_load`` set. ``after`` masks a rest after sliding that the protocol unloads
    (``InstrumentConfig.rest_after_sliding``): a second zero. With two zeros the mean is
    used (a drift between them counts half each way) and ``disagree`` is set when they
    differ by more than 3 combined standard errors and by more than ``settle_tol`` in μ
    (``lever_N_per_unit`` converts the channel to newtons, ``force_N`` is the mean normal
    force). Nothing estimable: 0, with ``unknown_u``."""
    if isinstance(given, int | float) and not isinstance(given, bool):
        return ZeroChoice(float(given), "given", 0.0)
    if given == "off":
        return ZeroChoice(0.0, "off (switched off: 0 taken)", 0.0)
    level = (float(np.median(x.torque[sliding])) if sliding is not None and sliding.any()
             else math.nan)
    refused: list[tuple[str, float]] = []

    def loaded(value: float) -> float | None:
        if not math.isfinite(level):
            return None
        fraction = load_fraction(value, level)
        return fraction if fraction > params.zero_load_max_fraction else None

    first: ZeroChoice | None = None
    meta_offset, meta_source, meta_u = _offset_from_meta(m)
    rest_offset, n_rest = estimate_torque_offset_Nm(x.torque, at_rest, params.offset_min_samples)
    if meta_offset is not None:
        frac = loaded(meta_offset)
        if frac is not None:
            refused.append((str(meta_source), frac))
        elif not math.isfinite(meta_u):
            first = ZeroChoice(meta_offset, f"{meta_source} (too few samples for its scatter: "
                               "the unknown offset's uncertainty applies)", unknown_u)
        else:
            first = ZeroChoice(meta_offset, str(meta_source), meta_u)
    if first is None and rest_offset is not None:
        frac = loaded(rest_offset)
        if frac is not None:
            refused.append((f"at-rest start ({n_rest} samples)", frac))
        else:
            u = zero_offset_standard_error(x.torque[at_rest])
            first = ZeroChoice(rest_offset, f"at-rest start ({n_rest} samples)",
                               u if math.isfinite(u) else 0.0)
    second: ZeroChoice | None = None
    if after is not None and int(after.sum()) >= params.offset_min_samples:
        value = robust_mean(x.torque[after])
        frac = loaded(value)
        if frac is not None:
            refused.append((f"rest after sliding ({int(after.sum())} samples)", frac))
        else:
            u = zero_offset_standard_error(x.torque[after])
            second = ZeroChoice(value, f"rest after sliding ({int(after.sum())} samples)",
                                u if math.isfinite(u) else 0.0)
    under = bool(refused)
    worst = max((f for _, f in refused), default=None)
    note = ("; refused as under load: " + ", ".join(
        f"{where} at {f:.0%} of the sliding level" for where, f in refused)) if refused else ""
    if first is not None and second is not None:
        delta = abs(first.offset - second.offset)
        se = math.hypot(first.u, second.u)
        in_mu = delta * lever_N_per_unit / force_N if force_N > 0 else math.inf
        disagree = delta > 3 * se and in_mu > params.settle_tol
        u = math.sqrt((first.u**2 + second.u**2) / 4 + (delta / 2) ** 2 / 3)
        return ZeroChoice(0.5 * (first.offset + second.offset),
                          f"mean of {first.source} and {second.source}{note}", u,
                          under_load=under, disagree=disagree, load_fraction=worst,
                          second=second.offset)
    chosen = first or second
    if chosen is not None:
        return replace(chosen, source=chosen.source + note, under_load=under,
                       load_fraction=worst,
                       second=None if second is None else second.offset)
    if under:
        return ZeroChoice(0.0, "not subtracted (the at-rest samples carry a tangential "
                          f"load){note}: 0 assumed", unknown_u, known=False,
                          under_load=True, load_fraction=worst)
    return ZeroChoice(0.0, "not estimated (no set-up interval, no at-rest samples): 0 assumed",
                      unknown_u, known=False)
