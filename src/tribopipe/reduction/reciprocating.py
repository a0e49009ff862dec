"""A linear reciprocating run (ASTM G133): strokes, cycles, μ per stroke and per cycle.

The method is described in the docstring of :mod:`tribopipe.reduction` ("Reciprocating
runs"); :func:`reduce_reciprocating` carries it out on the samples of one run, and
:func:`split_strokes` is the split into strokes by direction. Everything here is pure.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..errors import ReductionError
from .intervals import IntervalSamples, leading_rest

#: a reversal is where the position turns back by more than this share of the stroke
#: amplitude (the position's full range): smaller wiggles are noise, not a new stroke
REVERSAL_HYSTERESIS = 0.1
#: a stroke shorter than this share of the amplitude is not a full stroke (a partial
#: first or last stroke, a stop)
FULL_STROKE_SHARE = 0.5


@dataclass(frozen=True)
class Stroke:
    """One stroke: samples ``start`` to ``stop`` (inclusive indices), its direction of
    travel (+1 or −1), and its span along the position [mm]."""

    start: int
    stop: int
    direction: int
    span_mm: float


def reversals(position_mm: Any, hysteresis_mm: float) -> list[int]:
    """Sample indices where the position (shape (n,)) turns back: the extremes from which
    it retreats by more than ``hysteresis_mm`` [mm]."""
    p = np.asarray(position_mm, dtype=float)
    turns: list[int] = []
    if p.size < 3:
        return turns
    direction = 0
    extreme = 0
    for i in range(1, p.size):
        if direction >= 0 and p[i] >= p[extreme]:
            extreme = i if direction > 0 or p[i] > p[extreme] else extreme
        if direction <= 0 and p[i] <= p[extreme]:
            extreme = i if direction < 0 or p[i] < p[extreme] else extreme
        if direction == 0:
            if p[i] - p[0] > hysteresis_mm:
                direction, extreme = 1, int(np.argmax(p[: i + 1]))
            elif p[0] - p[i] > hysteresis_mm:
                direction, extreme = -1, int(np.argmin(p[: i + 1]))
            continue
        if direction > 0 and p[extreme] - p[i] > hysteresis_mm:
            turns.append(extreme)
            direction, extreme = -1, i
        elif direction < 0 and p[i] - p[extreme] > hysteresis_mm:
            turns.append(extreme)
            direction, extreme = 1, i
    return turns


def split_strokes(position_mm: Any) -> list[Stroke]:
    """The full strokes of a reciprocating position trace [mm] (shape (n,)): the pieces
    between reversals (:func:`reversals` at :data:`REVERSAL_HYSTERESIS` of the range) at
    least :data:`FULL_STROKE_SHARE` of the range long, in time order."""
    p = np.asarray(position_mm, dtype=float)
    amplitude = float(np.ptp(p)) if p.size else 0.0
    if amplitude <= 0:
        return []
    turns = reversals(p, REVERSAL_HYSTERESIS * amplitude)
    strokes = []
    for a, b in zip(turns[:-1], turns[1:], strict=True):
        span = float(p[b] - p[a])
        if abs(span) >= FULL_STROKE_SHARE * amplitude:
            strokes.append(Stroke(a, b, 1 if span > 0 else -1, abs(span)))
    return strokes


def _core(p: NDArray[np.float64], stroke: Stroke, fraction: float) -> NDArray[np.intp]:
    """Indices of a stroke's central ``fraction`` of its span (away from the reversals,
    where the pin stops and turns)."""
    idx = np.arange(stroke.start, stroke.stop + 1)
    lo, hi = sorted((float(p[stroke.start]), float(p[stroke.stop])))
    margin = 0.5 * (1.0 - fraction) * (hi - lo)
    inside = (p[idx] >= lo + margin) & (p[idx] <= hi - margin)
    return idx[inside]


class StrokeMean(NamedTuple):
    """One stroke's core averaged: its ``direction`` (±1), the raw channel ``raw_N`` [N],
    its ``mu`` with the zero subtracted, the normal force ``force_N`` [N], and where and
    when the stroke ends (``end_mm`` [mm] along the path, ``t_end_s`` [s])."""

    direction: int
    raw_N: float
    mu: float
    force_N: float
    end_mm: float
    t_end_s: float


@dataclass(frozen=True)
class Cycle:
    """One cycle of a reciprocating run (a stroke forward and one back): its number
    ``cycle`` (from 1), ``mu`` = (forward − backward)/2 of the raw channel over the normal
    force, each stroke's own μ (``mu_forward``, ``mu_backward``), where and when it ends
    (``distance_mm`` [mm], ``time_s`` [s]) and its mean ``normal_force_N`` [N]."""

    cycle: int
    mu: float
    mu_forward: float
    mu_backward: float
    distance_mm: float
    time_s: float
    normal_force_N: float

    def to_json(self) -> dict[str, float]:
        """The cycle as JSON (the run's summary)."""
        return {"cycle": self.cycle, "mu": self.mu, "mu_forward": self.mu_forward,
                "mu_backward": self.mu_backward, "distance_mm": self.distance_mm,
                "time_s": self.time_s, "normal_force_N": self.normal_force_N}


@dataclass(frozen=True)
class Cycles:
    """What a reciprocating run's strokes give (arrays over the run's samples, shape (n,),
    or over its cycles, shape (c,)).

    ``s_mm`` the sliding path of every sample [mm] (each stroke's travel adds);
    ``friction_N`` the friction force [N] with the zero subtracted, positive against the
    motion; ``mu`` μ of every sample (NaN out of contact); ``sign`` the instrument's
    sign convention (+1: the force reads positive when the pin moves forward);
    ``n_strokes`` the full strokes used; ``table`` one :class:`Cycle` per cycle;
    ``s_cycle_mm``, ``t_cycle_s``, ``mu_cycle`` the cycles' end distance [mm], end time
    [s] and μ; ``stroke_length_mm`` the median stroke; ``first_stroke`` the indices of the
    first full stroke's first half (where the static peak is read) and ``first_level``
    that stroke's μ; ``at_rest`` the samples before the first movement."""

    s_mm: NDArray[np.float64]
    friction_N: NDArray[np.float64]
    mu: NDArray[np.float64]
    sign: float
    n_strokes: int
    table: tuple[Cycle, ...]
    s_cycle_mm: NDArray[np.float64]
    t_cycle_s: NDArray[np.float64]
    mu_cycle: NDArray[np.float64]
    stroke_length_mm: float
    first_stroke: NDArray[np.intp]
    first_level: float
    at_rest: NDArray[np.bool_]


def stroke_path(x: IntervalSamples, label: str, motion_tol_mm: float
                ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """The position [mm], the sliding path [mm] (every stroke's travel adds) and the
    samples at rest before the first movement of a reciprocating run;
    :class:`ReductionError` without a position column."""
    if x.position is None or np.isfinite(x.position).sum() < 2:
        raise ReductionError(
            f"{label}: a linear reciprocating run needs a position column (the stroke "
            "position) to split its strokes",
            hint="name the column 'Position [mm]' (or add its name to configs/aliases.toml)",
        )
    ok = np.isfinite(x.position)
    p = (np.interp(x.t, x.t[ok], x.position[ok]) if not ok.all() else x.position) * 1e3
    s = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(p)))])
    return p, s, leading_rest(s, motion_tol_mm)


def reciprocating_cycles(
    x: IntervalSamples, p_mm: NDArray[np.float64], s_mm: NDArray[np.float64],
    at_rest: NDArray[np.bool_], in_contact: NDArray[np.bool_], zero_N: float,
    lever_m: float, core_fraction: float, label: str,
) -> Cycles:
    """Split a reciprocating run into strokes and cycles (see the module docstring of
    :mod:`tribopipe.reduction`): ``p_mm`` the position, ``s_mm`` the path [mm];
    ``zero_N`` the channel's zero and ``lever_m`` its lever (1 m for a force channel:
    ``x.torque / lever_m`` is the force [N]); ``core_fraction`` of each stroke is
    averaged. :class:`ReductionError` with fewer than 2 strokes or 3 cycles."""
    strokes = [st for st in split_strokes(p_mm)
               if in_contact[st.start : st.stop + 1].mean() > 0.5]
    if len(strokes) < 2:
        raise ReductionError(
            f"{label}: {len(strokes)} full stroke(s) found in the position: a reciprocating "
            "run needs at least one cycle (a stroke forward and one back)",
        )
    raw_n = x.torque / lever_m
    corrected = raw_n - zero_N / lever_m
    # friction opposes the motion: its sign relative to the direction of travel is the
    # instrument's convention, read from the strokes themselves
    signed = [st.direction * float(np.mean(raw_n[_core(p_mm, st, core_fraction)]))
              for st in strokes]
    sign = -1.0 if float(np.median(signed)) < 0 else 1.0
    rows: list[StrokeMean] = []
    for st in strokes:
        core = _core(p_mm, st, core_fraction)
        core = core[in_contact[core]]
        if core.size < 3:
            continue
        fn = float(np.mean(x.force[core]))
        rows.append(StrokeMean(
            direction=st.direction, raw_N=float(np.mean(raw_n[core])),
            mu=sign * st.direction * float(np.mean(corrected[core])) / fn, force_N=fn,
            end_mm=float(s_mm[st.stop]), t_end_s=float(x.t[st.stop])))
    first_dir = rows[0].direction if rows else 1
    cycles: list[Cycle] = []
    k = 0
    while k + 1 < len(rows):
        a, b = rows[k], rows[k + 1]
        if a.direction == b.direction:
            k += 1
            continue
        fwd, bwd = (a, b) if a.direction == first_dir else (b, a)
        n_mean = 0.5 * (a.force_N + b.force_N)
        # forward and backward means: the zero cancels in their difference
        mu_cycle = sign * first_dir * (fwd.raw_N - bwd.raw_N) / (2.0 * n_mean)
        cycles.append(Cycle(cycle=len(cycles) + 1, mu=mu_cycle, mu_forward=fwd.mu,
                            mu_backward=bwd.mu, distance_mm=b.end_mm, time_s=b.t_end_s,
                            normal_force_N=n_mean))
        k += 2
    if len(cycles) < 3:
        raise ReductionError(
            f"{label}: {len(cycles)} complete cycle(s): a reciprocating run needs at "
            "least 3 to find a plateau over cycles",
        )
    direction = np.sign(np.gradient(p_mm))
    friction = sign * direction * corrected
    with np.errstate(divide="ignore", invalid="ignore"):
        mu = np.where(in_contact, friction / x.force, np.nan)
    first = strokes[0]
    head = np.arange(first.start, first.start + max(3, (first.stop - first.start) // 2))
    return Cycles(
        s_mm=s_mm, friction_N=friction, mu=mu, sign=sign, n_strokes=len(rows),
        table=tuple(cycles),
        s_cycle_mm=np.array([c.distance_mm for c in cycles]),
        t_cycle_s=np.array([c.time_s for c in cycles]),
        mu_cycle=np.array([c.mu for c in cycles]),
        stroke_length_mm=float(np.median([st.span_mm for st in strokes])),
        first_stroke=head[np.isfinite(mu[head])], first_level=float(rows[0].mu),
        at_rest=at_rest,
    )
