"""μ at any condition: a pair's group means interpolated by the project's one rule.

A contact pair (pin, disc) is measured at a few nominal contact pressures [kPa] and
temperatures [°C]. :func:`query` returns μ_K (and μ_S where the groups hold it) at any
(pressure, temperature) by the rule of :mod:`tribopipe.interpolation`: linear in
temperature between the two measured temperatures that bracket the request, and at each
of them linear in log p – log μ between the two measured pressures that bracket it (each
temperature keeps its own pressure list, so a pair whose grid has holes still
interpolates); outside the measured range the edge value is held, and the result says so.

The uncertainty (:class:`Estimate`): the groups' combined standard uncertainties u (their
runs' budgets beside the repeat scatter, :mod:`tribopipe.stats`; the repeat scatter alone
where a map holds no budgets, and said so) carried with the interpolation's weights, and
the interpolation's own u (:func:`tribopipe.interpolation.interpolation_u`), combined in
quadrature into u and the expanded U = 2u (k = 2): the headline ± of every output. The
repeats' 95 % CI half-width is carried beside it, for its own labelled column.

Sliding speed: where a pair is measured at several nominal speeds the request names one
(``speed_mm_s``); the value at each of the two measured speeds that bracket it is read as
above and the two are joined linearly in ln v
(:func:`tribopipe.interpolation.speed_bracket`), their U carried with the same weights;
outside the measured speeds the edge value is held, and the result says so. A pair of
one speed needs none.

Inputs are the group-statistics table of :func:`tribopipe.stats.group_statistics`
(columns ``pin, disc, pressure_kPa, temperature_C, mu_k_mean, mu_k_ci95_high, mu_k_sem,
mu_k_u, mu_k_n, mu_s_mean, ...``). Nothing here reads files except :func:`load_groups`.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .config import DEFAULT_TEST_METHOD
from .errors import ExportError
from .frictionmap.snapshot import MapSource, as_snapshot
from .interpolation import (
    EXTRAPOLATED,
    curvature,
    curve,
    densify,
    evaluate,
    held_u,
    interpolation_u,
    speed_bracket,
    stencil,
)
from .numeric import finite_or_none
from .physics import FOUNDING_SLIDING_SPEED_MM_S
from .rounding import decimal_text, known_u, lower_bound, plus_minus
from .stats import (
    GROUP_INPUT_COLUMNS,
    LABS,
    LABS_DISAGREE,
    NOMINAL_SPEED,
    TEST_METHOD,
    group_statistics,
    group_u,
    lab_names,
    select_labs,
)

if TYPE_CHECKING:
    import numpy as np
    import pandas as pd

QUANTITIES = ("mu_k", "mu_s")
#: a requested speed within this fraction of a measured one is that speed
SPEED_MATCH_REL = 0.01


@dataclass(frozen=True)
class UsedPoint:
    """A measured group that contributed to an interpolated value, with its weight (0..1]
    (temperature weight × pressure weight; in a log p – log μ segment the pressure weight
    is the exponent of the point's μ) and ``u``, the standard uncertainty of its mean
    (GUM, k = 1: the group's combined u, or its repeat scatter alone where its runs carry
    no budget; ``None`` when neither is known, e.g. one run without a budget)."""

    pressure_kPa: float
    temperature_C: float | None
    mean: float
    ci95_half_width: float | None
    n: int
    weight: float
    u: float | None = None
    speed_mm_s: float | None = None


#: the notes a result carries, each worded once here (the explorer page receives these
#: texts; ``{n}`` is a count)
NOTES = {
    "left_out": "{n} group(s) without a temperature were left out",
    "mu_s_unknown": "mu_s unknown: no group of this pair holds a static coefficient",
    "mu_s_unknown_speeds": "mu_s unknown: no group of this pair holds a static coefficient"
                           " at every speed used",
    "single_run": "n = 1, no repeat scatter: a group used has a single run",
    "no_budget": "runs of a group used carry no uncertainty budget of their own (e.g. an "
                 "imported map): their u is the stated estimate of the founding cell at the "
                 "run's μ and force",
    "clamped_pressure": "pressure outside the range measured (at a temperature used): edge "
                        "value held",
    "clamped_temperature": "temperature outside the measured range: edge value held",
    "clamped_speed": "sliding speed outside the measured speeds: edge value held",
}
#: what a request out of bounds is told (``{}``: the value asked for, :func:`request_value`)
REQUEST_ERRORS = {
    "pressure": "contact pressure must be a finite number >= 0 kPa, got {}",
    "temperature": "temperature must be a finite number in °C, got {}",
    "speed": "sliding speed must be a finite number > 0 mm/s, got {}",
}
#: why a coefficient is printed without U (:func:`estimate_text`)
WHY_NO_U = {
    "extrapolated": EXTRAPOLATED,
    "single_run": "n = 1, no repeat scatter",
    "unknown": "uncertainty unknown",
}


@dataclass(frozen=True)
class Estimate:
    """One interpolated coefficient with its evidence.

    ``expanded`` is U (k = 2), the headline ±: 2·√(u_groups² + u_interpolation²), with
    ``u_groups`` the weighted sum of the used groups' u (exact for the correlated part that
    dominates it, the friction radius, and conservative for the rest) and
    ``u_interpolation`` the interpolation's own
    (:func:`tribopipe.interpolation.interpolation_u`); ``None`` when a used group's u is
    unknown. ``budgets_known`` is False when a used group's runs carry no uncertainty
    budget of their own (an imported map): their u is then the stated estimate of
    :func:`tribopipe.stats.stated_u`. ``n_min`` is the fewest runs of a used group (1: no
    repeat scatter). ``uncertainty`` is the weighted 95 % CI half-width of the repeats
    (``None`` when a used group has fewer than 2 runs), for its own labelled column;
    ``u_combined`` the weighted groups' combined u where every used group has a budget.
    ``clamped_pressure`` / ``clamped_temperature`` / ``clamped_speed`` say that the
    request lay outside the measured range and the edge
    value was held.
    """

    value: float
    uncertainty: float | None
    used: tuple[UsedPoint, ...]
    clamped_pressure: bool
    clamped_temperature: bool
    u_combined: float | None = None
    u_interpolation: float = 0.0
    u_groups: float | None = None
    expanded: float | None = None
    budgets_known: bool = False
    n_min: int = 1
    clamped_speed: bool = False

    @property
    def lower(self) -> float | None:
        """The lower end of value ± U, bounded at 0 (:func:`tribopipe.rounding.lower_bound`)."""
        return None if self.expanded is None else lower_bound(self.value, self.expanded)

    @property
    def extrapolated(self) -> bool:
        """True when the value was held outside the measured pressures, temperatures or
        speeds: its U is withdrawn (:func:`tribopipe.interpolation.held_u`)."""
        return self.clamped_pressure or self.clamped_temperature or self.clamped_speed

    def text(self, *, ascii_only: bool = False) -> str:
        """``value ± U`` rounded the GUM way (:func:`tribopipe.rounding.plus_minus`), or
        the value with three decimals and why U is unknown."""
        return estimate_text(self.value, self.expanded, self.n_min, ascii_only=ascii_only,
                             extrapolated=self.extrapolated)


@dataclass(frozen=True)
class QueryResult:
    """μ_K (and μ_S when known) for one pair at one condition; see :func:`query`."""

    pin: str
    disc: str
    pressure_kPa: float
    temperature_C: float | None
    mu_k: Estimate
    mu_s: Estimate | None
    pressure_range_kPa: tuple[float, float]
    temperatures_C: tuple[float, ...]
    notes: tuple[str, ...] = field(default=())
    #: the sliding speed [mm/s] of the value: the request, or the pair's one measured
    #: nominal speed when none was given
    speed_mm_s: float | None = None
    #: the pair's measured nominal speeds [mm/s]
    speeds_mm_s: tuple[float, ...] = ()
    #: the test method of every group the value was read from (:func:`one_method`)
    method: str = DEFAULT_TEST_METHOD

    @property
    def clamped(self) -> bool:
        """True when μ_K was held constant outside the measured pressure, temperature or
        speed range."""
        return (self.mu_k.clamped_pressure or self.mu_k.clamped_temperature
                or self.mu_k.clamped_speed)

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict (plain floats, lists, ``None``); each estimate also carries
        ``text`` (value ± U, GUM-rounded) and ``lower`` (value − U bounded at 0)."""
        data = asdict(self)
        for name, est in (("mu_k", self.mu_k), ("mu_s", self.mu_s)):
            if est is not None:
                data[name].update(text=est.text(), lower=est.lower)
        data["clamped"] = self.clamped
        data["pressure_range_kPa"] = list(self.pressure_range_kPa)
        data["temperatures_C"] = list(self.temperatures_C)
        data["speeds_mm_s"] = list(self.speeds_mm_s)
        data["notes"] = list(self.notes)
        return data


# ---------------------------------------------------------------------------- selection


def pairs(groups: pd.DataFrame) -> list[tuple[str, str]]:
    """The (pin, disc) pairs a group table holds, sorted."""
    if groups.empty:
        return []
    unique = groups[["pin", "disc"]].drop_duplicates()
    return sorted((str(p), str(d)) for p, d in unique.itertuples(index=False))


def _held_pairs_text(groups: pd.DataFrame) -> str:
    """One clause listing the pairs a group table holds."""
    held = pairs(groups)
    if not held:
        return "the map holds no groups"
    return "the map holds: " + "; ".join(f"{p} on {d}" for p, d in held)


def name_key(name: object) -> str:
    """A pin or disc name as a request is matched against it: stripped of white space
    (``str.strip``) and casefolded (``str.casefold``); the explorer's script matches a
    link's names by the same rule (its table comes from
    :func:`tribopipe.export.explorer.explorer_data`)."""
    return str(name).strip().casefold()


def select_pair(groups: pd.DataFrame, pin: str, disc: str) -> pd.DataFrame:
    """The groups of one pair (pin and disc matched case-insensitively), as a new frame.

    Raises :class:`ExportError` naming the pairs the map holds when the pair is unknown.
    """
    if groups.empty:
        raise ExportError(
            f"no groups for pin {pin!r} on disc {disc!r}: the friction map is empty",
            hint="reduce runs first (tribopipe reduce / batch) or import the published map",
        )
    pin_key = groups["pin"].map(name_key)
    disc_key = groups["disc"].map(name_key)
    mask = (pin_key == name_key(pin)) & (disc_key == name_key(disc))
    if not mask.any():
        names = [f"{p} on {d}" for p, d in pairs(groups)]
        close = difflib.get_close_matches(f"{pin} on {disc}", names, n=1, cutoff=0.6)
        hint = f"did you mean {close[0]!r}?" if close else None
        raise ExportError(
            f"no groups for pin {pin!r} on disc {disc!r}; {_held_pairs_text(groups)}", hint=hint
        )
    return groups.loc[mask].copy()


# ---------------------------------------------------------------------------- numerics


def pair_methods(pair_groups: pd.DataFrame) -> list[str]:
    """The test methods of a pair's groups, sorted (the founding rheometer cell's where
    the table carries no ``test_method`` column)."""
    if TEST_METHOD not in pair_groups.columns:
        return [DEFAULT_TEST_METHOD]
    return sorted({str(v) if isinstance(v, str) and v else DEFAULT_TEST_METHOD
                   for v in pair_groups[TEST_METHOD]})


def one_method(groups: pd.DataFrame, pin: str, disc: str,
               method: str | None = None) -> tuple[pd.DataFrame, str]:
    """``groups`` with the pair's groups of other test methods left out, and the method
    kept: the one rule by which a value read for one pair (:func:`query`, the simulator
    files) never pools two methods. ``method`` (case-insensitive) chooses; without it a
    pair measured by one method keeps it, and a pair measured by several is refused in
    one :class:`ExportError` listing them (no method is chosen for the user: which one
    a simulation wants is the user's to say). A method the pair lacks is refused too."""
    pair = select_pair(groups, pin, disc)
    held = pair_methods(pair)
    if method is None:
        if len(held) > 1:
            raise ExportError(
                f"pin {pin!r} on disc {disc!r} is measured by {len(held)} test methods "
                f"({'; '.join(held)}), never pooled: give --method with one of them")
        return groups, held[0]
    chosen = [m for m in held if m.casefold() == method.strip().casefold()]
    if not chosen:
        raise ExportError(f"pin {pin!r} on disc {disc!r} has no group measured by "
                          f"{method!r}; its test methods: {'; '.join(held)}")
    if len(held) == 1:
        return groups, chosen[0]
    other = groups.index.isin(pair.index) & (groups[TEST_METHOD].astype(str) != chosen[0])
    return groups.loc[~other].copy(), chosen[0]


def interpolation_weights(
    pressures_kPa: np.ndarray,
    temperatures_C: np.ndarray,
    pressure_kPa: float,
    temperature_C: float | None,
    means: np.ndarray | None = None,
) -> tuple[np.ndarray, bool, bool]:
    """Each measured point's share of a value at (``pressure_kPa``, ``temperature_C``).

    ``pressures_kPa`` and ``temperatures_C`` (shape ``(n,)``) are the coordinates of ``n``
    measured points with unique (pressure, temperature); NaN temperatures mean "unknown"
    and are used only when no point has a temperature; ``means`` (shape ``(n,)``, default
    all 1) decide where a log segment is possible. Returns ``(weights, clamped_pressure,
    clamped_temperature)``: weights of shape ``(n,)``, non-negative, summing to 1, nonzero
    for at most four points (:meth:`tribopipe.interpolation.Stencil.weights`).
    """
    import numpy as np

    mu = np.ones(len(pressures_kPa)) if means is None else means
    st = stencil(pressures_kPa, temperatures_C, mu, pressure_kPa, temperature_C)
    return st.weights(len(pressures_kPa)), st.clamped_pressure, st.clamped_temperature


def _points(pair_groups: pd.DataFrame, quantity: str) -> pd.DataFrame:
    """The pair's measured points for ``quantity``: one row per (pressure, temperature).

    Groups that share a condition (e.g. split by sliding speed) are merged by the
    run-weighted mean of their means and the largest CI half-width and combined standard
    uncertainty, so nothing is dropped.
    """
    import numpy as np

    merged = _merged_points(pair_groups, quantity, np.zeros(len(pair_groups), dtype=np.int64))
    return merged.drop(columns="code") if "code" in merged.columns else merged


def _merged_points(groups: pd.DataFrame, quantity: str, codes: np.ndarray) -> pd.DataFrame:
    """:func:`_points` of the groups of each ``code`` (an integer per row of ``groups``)
    in one pass: one row per (code, pressure, temperature) with a ``code`` column, sorted
    by code, pressure, then temperature (unknown first); the frame of the finite rows
    before merging (without ``code``) where none is finite."""
    import numpy as np
    import pandas as pd

    def column(name: str, default: float) -> pd.Series:
        """A numeric column of the groups, or ``default`` when it is absent."""
        if name not in groups.columns:
            return pd.Series(default, index=groups.index, dtype=float)
        return pd.to_numeric(groups[name], errors="coerce").astype(float)

    mean = column(f"{quantity}_mean", math.nan)
    u, budget = group_u(groups, quantity)
    high = column(f"{quantity}_ci95_high", math.nan)
    n = column(f"{quantity}_n", 1.0)
    frame = pd.DataFrame(
        {
            "pressure_kPa": pd.to_numeric(groups["pressure_kPa"], errors="coerce"),
            "temperature_C": pd.to_numeric(groups["temperature_C"], errors="coerce"),
            "mean": mean,
            # the upper end: the lower one is bounded at 0 (stats.describe_values)
            "half": high - mean,
            # the group's combined u; its repeat scatter alone where its runs have no budget
            "u": u,
            "budget": budget,
            # a finite mean stands for at least one run, whatever the count column says
            "n": n.fillna(1).clip(lower=1).astype(float),
        }
    )
    keep = (np.isfinite(frame["mean"]) & np.isfinite(frame["pressure_kPa"])).to_numpy()
    frame = frame[keep]
    if frame.empty:
        return frame
    code = np.asarray(codes)[keep]
    p = frame["pressure_kPa"].to_numpy(dtype=float)
    t = frame["temperature_C"].to_numpy(dtype=float)
    tkey = np.where(np.isnan(t), -math.inf, t)
    order = np.lexsort((tkey, p, code))  # stable: a condition's groups in table order
    code, p, tkey = code[order], p[order], tkey[order]
    m = frame["mean"].to_numpy(dtype=float)[order]
    w = frame["n"].to_numpy(dtype=float)[order]
    half = frame["half"].to_numpy(dtype=float)[order]
    uu = frame["u"].to_numpy(dtype=float)[order]
    ok = frame["budget"].to_numpy(dtype=bool)[order]
    new = np.ones(len(p), dtype=bool)
    new[1:] = (code[1:] != code[:-1]) | (p[1:] != p[:-1]) | (tkey[1:] != tkey[:-1])
    at = np.flatnonzero(new)

    def largest(values: np.ndarray) -> np.ndarray:
        """The largest value of each point's groups, NaN where one of them is unknown."""
        unknown = np.add.reduceat(np.isnan(values).astype(np.int64), at) > 0
        return np.where(unknown, math.nan, np.fmax.reduceat(values, at))

    def total(values: np.ndarray) -> np.ndarray:
        """The sum of each point's groups' values, summed as ``numpy.sum`` sums (as the
        merge always has: ``reduceat`` may round the last bit otherwise)."""
        out = values[at].copy()
        ends = np.append(at[1:], len(values))
        for i in np.flatnonzero(ends - at > 1):
            out[i] = np.sum(values[at[i]:ends[i]])
        return out

    n_tot = total(w)
    return pd.DataFrame(
        {
            "pressure_kPa": p[at],
            "temperature_C": np.where(np.isinf(tkey[at]), math.nan, tkey[at]),
            "mean": total(m * w) / n_tot,
            "half": largest(half),
            "u": largest(uu),
            "budget": np.logical_and.reduceat(ok, at),
            "n": n_tot.astype(np.int64),
            "code": code[at],
        }
    )


def points_by(groups: pd.DataFrame, codes: np.ndarray, quantity: str = "mu_k") -> pd.DataFrame:
    """:func:`pair_points` of the groups of each ``code`` (an integer per row of
    ``groups``, e.g. one per pair and speed) in one pass, for pages that show every pair:
    the rows of each code equal :func:`pair_points` of that code's groups alone, with a
    ``code`` column, sorted by code (codes with no point have no row)."""
    import numpy as np

    merged = _merged_points(groups, quantity, codes)
    if "code" not in merged.columns:
        return merged.iloc[0:0].assign(code=np.zeros(0, dtype=np.int64))
    known = merged["temperature_C"].notna().to_numpy()
    code = merged["code"].to_numpy()
    any_known = np.zeros(int(code.max()) + 1, dtype=bool)
    any_known[code[known]] = True
    return merged[known | ~any_known[code]].reset_index(drop=True)


def _with_temperature(points: pd.DataFrame) -> pd.DataFrame:
    """The points that have a temperature, or all of them when none has one (a point of
    unknown temperature cannot be placed among measured ones)."""
    known = points["temperature_C"].notna()
    return points[known] if known.any() else points


def pair_points(pair_groups: pd.DataFrame, quantity: str = "mu_k") -> pd.DataFrame:
    """The measured points :func:`query` interpolates ``quantity`` over, for one pair.

    ``pair_groups`` are the pair's groups (:func:`select_pair`). One row per (pressure
    [kPa], temperature [°C]) with ``pressure_kPa, temperature_C, mean, half`` (95 % CI
    half-width, NaN when unknown), ``u`` (combined standard uncertainty of the mean, NaN
    when unknown; the repeat scatter alone where ``budget`` is False) and ``n``, sorted
    by pressure then temperature — the
    row order the interpolation sums in. Points without a temperature are left out when
    others have one, as :func:`query` does. For pages that redo the interpolation (the
    explorer); :func:`query` itself is the reference.
    """
    return _with_temperature(_points(pair_groups, quantity))


def map_curvature(groups: pd.DataFrame, quantity: str = "mu_k") -> float:
    """κ of a group table's ``quantity`` (:func:`tribopipe.interpolation.curvature`): over
    every pair and temperature, the measured points (merged and left out as
    :func:`pair_points` does) in pressure order; μ_K's where ``quantity`` has no interior
    point to estimate it from."""
    import numpy as np

    column = f"{quantity}_mean"
    cells: dict[tuple[str, float, float], list[float]] = {}
    if not groups.empty and column in groups.columns:
        pair = (groups["pin"].astype(str).str.strip().str.casefold() + "\0"
                + groups["disc"].astype(str).str.strip().str.casefold()).to_numpy()
        p = pd_numeric(groups["pressure_kPa"])
        t = pd_numeric(groups["temperature_C"])
        mean = pd_numeric(groups[column])
        n = (pd_numeric(groups[f"{quantity}_n"]) if f"{quantity}_n" in groups.columns
             else np.ones(len(groups)))
        n = np.where(np.isfinite(n), np.maximum(n, 1.0), 1.0)
        ok = np.isfinite(mean) & np.isfinite(p)
        with_t = {k for k, tk, o in zip(pair, t, ok, strict=True) if o and np.isfinite(tk)}
        for k, pk, tk, mk, nk, o in zip(pair, p, t, mean, n, ok, strict=True):
            if not o or (k in with_t and not np.isfinite(tk)):
                continue
            cell = cells.setdefault((k, float(tk) if np.isfinite(tk) else -math.inf, float(pk)),
                                    [0.0, 0.0])
            cell[0] += float(mk) * float(nk)
            cell[1] += float(nk)
    by_series: dict[tuple[str, float], list[tuple[float, float]]] = {}
    for (k, tk, pk), (total, count) in sorted(cells.items()):
        by_series.setdefault((k, tk), []).append((pk, total / count))
    series = [([pk for pk, _ in pts], [m for _, m in pts]) for pts in by_series.values()]
    if not any(len(ps) >= 3 for ps, _ in series) and quantity != "mu_k":
        return map_curvature(groups, "mu_k")
    return curvature(series)


def pd_numeric(column: pd.Series) -> np.ndarray:
    """A column as floats (text that is not a number as NaN)."""
    import pandas as pd

    return pd.to_numeric(column, errors="coerce").to_numpy(dtype=float)


def _estimate(
    points: pd.DataFrame, pressure_kPa: float, temperature_C: float | None, kappa: float
) -> Estimate:
    """Interpolate one quantity's points at (pressure [kPa], temperature [°C]) with the
    map's curvature ``kappa`` (:func:`map_curvature`)."""
    import numpy as np

    means = points["mean"].to_numpy(dtype=float)
    st = stencil(points["pressure_kPa"].to_numpy(), points["temperature_C"].to_numpy(),
                 means, pressure_kPa, temperature_C)
    weights = st.weights(len(points))
    used_idx = np.flatnonzero(weights > 0)
    w = weights[used_idx]
    value = evaluate(st, means)
    halves = points["half"].to_numpy()[used_idx]
    uncertainty = float(np.dot(w, halves)) if np.isfinite(halves).all() else None
    us = points["u"].to_numpy(dtype=float)[used_idx]
    budgets = points["budget"].to_numpy(dtype=bool)[used_idx]
    u_groups = float(np.dot(w, us)) if np.isfinite(us).all() else None
    u_combined = u_groups if budgets.all() else None
    u_interp = interpolation_u(st, means, kappa)
    expanded = None if u_groups is None else 2.0 * math.hypot(u_groups, u_interp)
    if not known_u(expanded):
        expanded = None  # nothing known about the spread: never "± 0"
    expanded = held_u(expanded, st.clamped_pressure or st.clamped_temperature)
    used = tuple(
        UsedPoint(
            pressure_kPa=float(points["pressure_kPa"].iloc[i]),
            temperature_C=finite_or_none(points["temperature_C"].iloc[i]),
            mean=float(points["mean"].iloc[i]),
            ci95_half_width=finite_or_none(points["half"].iloc[i]),
            n=int(points["n"].iloc[i]),
            weight=float(weights[i]),
            u=finite_or_none(points["u"].iloc[i]),
        )
        for i in used_idx
    )
    return Estimate(
        value, uncertainty, used, st.clamped_pressure, st.clamped_temperature, u_combined,
        u_interpolation=u_interp, u_groups=u_groups, expanded=expanded,
        budgets_known=bool(budgets.all()), n_min=min(u.n for u in used),
    )


def request_value(value: float) -> str:
    """A requested value as :data:`REQUEST_ERRORS` quote it: every digit it was given
    (:func:`tribopipe.rounding.decimal_text` to 17 significant digits, the shortest text
    that reads back as it)."""
    return decimal_text(value, digits=17)


def estimate_text(
    value: float, expanded: float | None, n_min: int, *, ascii_only: bool = False,
    extrapolated: bool = False,
) -> str:
    """The headline of a coefficient: ``value ± U`` (:func:`tribopipe.rounding.plus_minus`);
    without a U the value to three decimals and why (:data:`tribopipe.interpolation.EXTRAPOLATED`
    outside the measured range, "n = 1, no repeat scatter" where a group used holds a
    single run), never "± 0"."""
    if expanded is not None and not extrapolated:
        return plus_minus(value, expanded, ascii_only=ascii_only)
    why = WHY_NO_U["extrapolated" if extrapolated else "single_run" if n_min < 2 else
                   "unknown"]
    return f"{decimal_text(value, places=3)} ({why})"


# ---------------------------------------------------------------------------- public API


def pair_speeds(pair_groups: pd.DataFrame) -> list[float]:
    """The nominal sliding speeds [mm/s] of a pair's groups, sorted (the founding speed
    where the group table shows none: every group of a one-speed map)."""
    if NOMINAL_SPEED not in pair_groups.columns:
        return [FOUNDING_SLIDING_SPEED_MM_S]
    values = pd_numeric(pair_groups[NOMINAL_SPEED])
    found = sorted({float(v) for v in values if math.isfinite(v) and v > 0})
    return found or [FOUNDING_SLIDING_SPEED_MM_S]


def groups_at_speed(pair: pd.DataFrame, speed_mm_s: float) -> pd.DataFrame:
    """The pair's groups at one nominal speed [mm/s] (all of them without a speed column)."""
    if NOMINAL_SPEED not in pair.columns:
        return pair
    values = pd_numeric(pair[NOMINAL_SPEED])
    return pair.loc[values == speed_mm_s]


def speed_needed(speeds_mm_s: list[float]) -> str:
    """What a request without a speed is told for a pair measured at several (sorted)
    nominal ``speeds_mm_s`` [mm/s]."""
    listed = ", ".join(f"{v:g}" for v in speeds_mm_s)
    return f"sliding speed needed: this pair is measured at {listed} mm/s"


def speed_weights(
    speeds_mm_s: list[float], speed_mm_s: float | None
) -> tuple[list[tuple[int, float]], bool]:
    """Which of a pair's measured speeds [mm/s] a value at ``speed_mm_s`` [mm/s] is read
    from, with their weights (linear in ln v,
    :func:`tribopipe.interpolation.speed_bracket`), and whether it was held at an end. A
    request within :data:`SPEED_MATCH_REL` of a measured speed is that speed. ``None`` is
    allowed only for a pair of one speed; else an :class:`ExportError` lists the speeds."""
    if speed_mm_s is None:
        if len(speeds_mm_s) > 1:
            raise ExportError(speed_needed(speeds_mm_s), hint="pass --speed")
        return [(0, 1.0)], False
    if not (math.isfinite(speed_mm_s) and speed_mm_s > 0):
        raise ExportError(REQUEST_ERRORS["speed"].format(request_value(speed_mm_s)))
    for i, v in enumerate(speeds_mm_s):
        if abs(math.log(speed_mm_s / v)) <= SPEED_MATCH_REL:
            return [(i, 1.0)], False
    return speed_bracket(speeds_mm_s, speed_mm_s)


def _blend(parts: list[tuple[float, float, Estimate]]) -> Estimate:
    """One estimate from estimates at measured speeds: ``(weight, speed [mm/s],
    estimate)`` with weights summing to 1. Values, CI half-widths, u of the groups and of
    the interpolation are carried with the weights (the groups' u as fully correlated,
    as :class:`Estimate` carries them over pressure and temperature)."""
    def weighted(values: list[float | None]) -> float | None:
        """The weighted sum, ``None`` when a value is unknown."""
        if any(v is None for v in values):
            return None
        return sum(w * float(v) for (w, _, _), v in zip(parts, values, strict=True)
                   if v is not None)

    ests = [e for _, _, e in parts]
    value = sum(w * e.value for w, _, e in parts)
    u_groups = weighted([e.u_groups for e in ests])
    u_interp = sum(w * e.u_interpolation for w, _, e in parts)
    expanded = None if u_groups is None else 2.0 * math.hypot(u_groups, u_interp)
    if not known_u(expanded):
        expanded = None
    expanded = held_u(expanded, any(e.extrapolated for e in ests))
    used = tuple(replace(u, weight=u.weight * w, speed_mm_s=v)
                 for w, v, e in parts for u in e.used)
    return Estimate(
        value, weighted([e.uncertainty for e in ests]), used,
        any(e.clamped_pressure for e in ests), any(e.clamped_temperature for e in ests),
        weighted([e.u_combined for e in ests]), u_interpolation=u_interp, u_groups=u_groups,
        expanded=expanded, budgets_known=all(e.budgets_known for e in ests),
        n_min=min(e.n_min for e in ests),
    )


def _held_speed(est: Estimate, clamped_speed: bool) -> Estimate:
    """``est`` marked held outside the measured speeds, its U withdrawn there
    (:func:`tribopipe.interpolation.held_u`)."""
    return replace(est, clamped_speed=clamped_speed,
                   expanded=held_u(est.expanded, clamped_speed))


def query(
    groups: pd.DataFrame,
    pin: str,
    disc: str,
    pressure_kPa: float,
    temperature_C: float | None = None,
    speed_mm_s: float | None = None,
    method: str | None = None,
    *,
    curvature: Mapping[str, float] | None = None,
) -> QueryResult:
    """μ_K (and μ_S where measured) of a pair at a contact pressure [kPa], temperature [°C]
    and sliding speed [mm/s].

    ``groups`` is a group-statistics table (one row per condition group). The value is
    interpolated over the group means by :mod:`tribopipe.interpolation` (linear in
    temperature, log p – log μ in pressure, linear in ln v between measured speeds) and
    held constant outside the measured range, with U (k = 2) as in the module docstring.
    ``temperature_C`` may be ``None`` only when the pair is measured at a single
    temperature, ``speed_mm_s`` only when it is measured at a single nominal speed.
    Only the groups of one test method are read (``method``, :func:`one_method`: needed
    where the pair is measured by several). ``curvature`` (κ of ``mu_k`` and ``mu_s``,
    :func:`map_curvature` of the whole map) lets ``groups`` be the pair's own groups of a
    larger map, as a writer over every pair hands them (used where no ``method`` leaves
    groups out; else κ is computed from what is left). Raises :class:`ExportError` for an
    unknown pair (listing the pairs held) or a bad request.
    """
    if not math.isfinite(pressure_kPa) or pressure_kPa < 0:
        raise ExportError(REQUEST_ERRORS["pressure"].format(request_value(pressure_kPa)))
    if temperature_C is not None and not math.isfinite(temperature_C):
        raise ExportError(REQUEST_ERRORS["temperature"].format(request_value(temperature_C)))
    chosen, method = one_method(groups, pin, disc, method)
    given = curvature if chosen is groups else None
    groups = chosen

    def kappa(quantity: str) -> float:
        return map_curvature(groups, quantity) if given is None else given[quantity]

    pair = select_pair(groups, pin, disc)
    speeds = pair_speeds(pair)
    brackets, clamped_speed = speed_weights(speeds, speed_mm_s)
    notes: list[str] = []
    k_parts: list[tuple[float, float, Estimate]] = []
    s_parts: list[tuple[float, float, Estimate | None]] = []
    temps: set[float] = set()
    p_range = (math.inf, -math.inf)
    for index, weight in brackets:
        part = groups_at_speed(pair, speeds[index])
        mu_k_points = _points(part, "mu_k")
        if mu_k_points.empty:
            raise ExportError(f"pin {pin!r} on disc {disc!r} has no group with a finite mu_k"
                              + (f" at {speeds[index]:g} mm/s" if len(speeds) > 1 else ""))
        kept = _with_temperature(mu_k_points)
        if len(kept) < len(mu_k_points):
            note = NOTES["left_out"].format(n=len(mu_k_points) - len(kept))
            notes += [] if note in notes else [note]
            mu_k_points = kept
        k_parts.append((weight, speeds[index], _estimate(
            mu_k_points, pressure_kPa, temperature_C, kappa("mu_k"))))
        mu_s_part = None
        if "mu_s_mean" in part.columns:
            mu_s_points = _with_temperature(_points(part, "mu_s"))
            if not mu_s_points.empty:
                mu_s_part = _estimate(mu_s_points, pressure_kPa, temperature_C,
                                      kappa("mu_s"))
        s_parts.append((weight, speeds[index], mu_s_part))
        temps |= {float(t) for t in mu_k_points["temperature_C"] if math.isfinite(t)}
        p_range = (min(p_range[0], float(mu_k_points["pressure_kPa"].min())),
                   max(p_range[1], float(mu_k_points["pressure_kPa"].max())))
    mu_k = _held_speed(_blend(k_parts), clamped_speed)
    mu_s = None
    if all(e is not None for _, _, e in s_parts):
        mu_s = _held_speed(_blend([(w, v, e) for w, v, e in s_parts if e is not None]),
                           clamped_speed)
    if mu_s is None:
        notes.append(NOTES["mu_s_unknown_speeds" if len(speeds) > 1 else "mu_s_unknown"])
    notes += uncertainty_notes(mu_k)
    if mu_k.clamped_pressure:
        notes.append(NOTES["clamped_pressure"])
    if mu_k.clamped_temperature:
        notes.append(NOTES["clamped_temperature"])
    if clamped_speed:
        notes.append(NOTES["clamped_speed"])

    first = pair.iloc[0]
    return QueryResult(
        pin=str(first["pin"]),
        disc=str(first["disc"]),
        pressure_kPa=float(pressure_kPa),
        temperature_C=None if temperature_C is None else float(temperature_C),
        mu_k=mu_k,
        mu_s=mu_s,
        pressure_range_kPa=p_range,
        temperatures_C=tuple(sorted(temps)),
        notes=tuple(notes),
        speed_mm_s=speeds[0] if speed_mm_s is None else float(speed_mm_s),
        speeds_mm_s=tuple(speeds),
        method=method,
    )


def uncertainty_notes(est: Estimate) -> list[str]:
    """What a result says about its μ_K uncertainty: a single run, missing budgets."""
    notes = []
    if est.n_min < 2:
        notes.append(NOTES["single_run"])
    if not est.budgets_known:
        notes.append(NOTES["no_budget"])
    return notes


def friction_table(
    groups: pd.DataFrame,
    pin: str,
    disc: str,
    quantity: str = "mu_k",
    *,
    dense: bool = False,
    curvature: float | None = None,
) -> pd.DataFrame:
    """The pair's full rectangular (pressure × temperature) table of ``quantity``.

    Rows cover every measured pressure [kPa] at every measured temperature [°C] (sorted,
    temperature outer, pressure inner — the order ABAQUS wants). Columns:
    ``pressure_kPa, temperature_C, <quantity>, uncertainty, u_combined, expanded,
    measured, added`` (``uncertainty`` the repeats' CI half-width, ``u_combined`` the
    groups' combined u, ``expanded`` U at k = 2, see :class:`Estimate`). Cells that were
    not measured are filled by :func:`query`'s interpolation (``measured`` False).
    ``dense`` adds pressure rows (``added`` True) by
    :func:`tribopipe.interpolation.densify`, so that an engine reading the table linearly
    in pressure stays within :data:`~tribopipe.interpolation.ENGINE_TOLERANCE` of
    :func:`query` (the union of every temperature's rows: the grid stays rectangular).
    ``temperature_C`` is NaN throughout when the pair has no temperature. ``curvature``:
    κ of ``quantity`` (:func:`map_curvature` of the whole map), which lets ``groups`` be
    the pair's own groups of a larger map (a writer over every pair selects each pair's
    groups and computes κ once); computed from ``groups`` when ``None``.
    """
    import pandas as pd

    if quantity not in QUANTITIES:
        raise ExportError(f"quantity must be one of {', '.join(QUANTITIES)}, got {quantity!r}")
    pair = select_pair(groups, pin, disc)
    points = _points(pair, quantity)
    if points.empty:
        raise ExportError(f"pin {pin!r} on disc {disc!r} has no group with a finite {quantity}")
    points = _with_temperature(points)
    pressures = sorted(set(points["pressure_kPa"]))
    temps: list[float | None] = sorted(set(points["temperature_C"].dropna())) or [None]
    measured = {
        (float(p), None if math.isnan(t) else float(t))
        for p, t in zip(points["pressure_kPa"], points["temperature_C"], strict=True)
    }
    kappa = map_curvature(groups, quantity) if curvature is None else curvature
    measured_p = set(pressures)
    if dense:
        rows_p: set[float] = set(pressures)
        for t in temps:
            rows_p.update(densify(pressures, curve(
                points["pressure_kPa"], points["temperature_C"], points["mean"], t)))
        pressures = sorted(rows_p)
    rows = []
    for t in temps:
        for p in pressures:
            est = _estimate(points, p, t, kappa)
            rows.append(
                {
                    "pressure_kPa": float(p),
                    "temperature_C": math.nan if t is None else float(t),
                    quantity: est.value,
                    "uncertainty": math.nan if est.uncertainty is None else est.uncertainty,
                    "u_combined": math.nan if est.u_combined is None else est.u_combined,
                    "expanded": math.nan if est.expanded is None else est.expanded,
                    "measured": (float(p), t) in measured,
                    "added": float(p) not in measured_p,
                }
            )
    return pd.DataFrame(rows)


#: the map columns ``query`` reads: those of the statistics (where the map stores no
#: groups, or for one lab's runs), whose ``flags`` say which runs are synthetic
QUERY_COLUMNS: tuple[str, ...] = GROUP_INPUT_COLUMNS


def load_groups(map_path: MapSource, labs: Sequence[str] | None = None) -> pd.DataFrame:
    """The group statistics (excluded runs out; with ``labs``, only the runs those labs
    measured) of a friction map: opened (:func:`~tribopipe.frictionmap.snapshot.open_map`),
    or its path; kept with the snapshot."""
    snap = as_snapshot(map_path)
    if not labs:  # every lab's runs: the map's groups (stored in a map folder)
        groups = snap.groups(show_speed=True, show_method=True)
        if groups.empty:
            raise _no_runs(snap.path)
        return groups
    key = ("query.groups", *sorted(labs or ()))
    return snap.derived(key, lambda: groups_of(snap.runs, snap.path, labs))


def groups_of(runs: pd.DataFrame, map_path: str | Path,
              labs: Sequence[str] | None = None) -> pd.DataFrame:
    """Group statistics of friction-map ``runs`` (excluded runs out, the nominal speed
    always shown; with ``labs`` only those labs' runs, :func:`tribopipe.stats.select_labs`);
    an :class:`ExportError` naming ``map_path`` when no run is left."""
    if "excluded" in runs.columns:
        runs = runs[~runs["excluded"].fillna(False).astype(bool)]
    if labs:
        held = sorted(set(lab_names(runs)))
        runs = select_labs(runs, labs)
        if runs.empty:
            raise ExportError(f"no run of lab {', '.join(repr(x) for x in labs)} in the map; "
                              f"it holds runs of {', '.join(repr(x) for x in held)}",
                              path=map_path)
    if runs.empty:
        raise _no_runs(map_path)
    return group_statistics(runs, show_speed=True, show_method=True)


def _no_runs(map_path: str | Path) -> ExportError:
    """The error of a map without an included run to group."""
    return ExportError(
        "the friction map is empty or absent",
        path=map_path,
        hint="reduce runs first (tribopipe reduce / batch) or import the published map",
    )


def query_map(
    map_path: MapSource,
    pin: str,
    disc: str,
    pressure_kPa: float,
    temperature_C: float | None = None,
    speed_mm_s: float | None = None,
    labs: Sequence[str] | None = None,
    method: str | None = None,
) -> QueryResult:
    """:func:`query` on the friction map (Parquet) at ``map_path`` (with ``labs``: on
    those labs' runs only; ``method``: the test method read)."""
    return query(load_groups(map_path, labs), pin, disc, pressure_kPa, temperature_C,
                 speed_mm_s, method)


@dataclass(frozen=True)
class ValueLabs:
    """Which labs a queried value comes from (``labs``, the labs of the groups it was
    read from) and the conditions among them where labs disagree beyond R
    (``disagree``: ``(pressure_kPa, temperature_C)``, :mod:`tribopipe.stats`)."""

    labs: tuple[str, ...]
    disagree: tuple[tuple[float, float | None], ...] = ()

    def lines(self) -> list[str]:
        """What a person reads: the labs, then each disagreement."""
        out = [f"labs: {', '.join(self.labs)}"]
        out += [f"labs disagree beyond R at {p:.4g} kPa"
                + ("" if t is None else f", {t:g} °C") for p, t in self.disagree]
        return out


def value_labs(map_path: MapSource, result: QueryResult,
               labs: Sequence[str] | None = None) -> ValueLabs:
    """The :class:`ValueLabs` of a :func:`query_map` result (the same ``labs``)."""
    groups, _ = one_method(load_groups(map_path, labs), result.pin, result.disc,
                           result.method)
    pair = select_pair(groups, result.pin, result.disc)
    used = {(round(u.pressure_kPa, 6), u.temperature_C) for est in (result.mu_k, result.mu_s)
            if est is not None for u in est.used}
    found: set[str] = set()
    disagree = []
    for row in pair.to_dict(orient="records"):
        temperature = finite_or_none(row["temperature_C"])
        if (round(float(row["pressure_kPa"]), 6), temperature) not in used:
            continue
        found.update(str(row[LABS]).split(";"))
        if bool(row[LABS_DISAGREE]):
            disagree.append((float(row["pressure_kPa"]), temperature))
    return ValueLabs(tuple(sorted(found)), tuple(sorted(set(disagree), key=str)))
