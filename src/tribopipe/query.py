"""μ at any condition: interpolation over a pair's group means, the way ABAQUS reads a table.

A contact pair (pin, disc) is measured at a few nominal contact pressures [kPa] and
temperatures [°C]. :func:`query` returns μ_K (and μ_S where the groups hold it) at any
(pressure, temperature) by linear interpolation between the measured group means:

* temperature first: the two measured temperatures that bracket the request;
* then, at each of those temperatures, the two measured pressures that bracket the
  request (each temperature keeps its own pressure list, so a pair whose grid has holes
  still interpolates);
* outside the measured range the value is held constant at the edge (clamped), which is
  what ABAQUS and Ansys do with a friction table; the result says when that happened.

On a full rectangular grid this is exactly bilinear interpolation. The weights of the
measured points are returned with the result, and the uncertainty is the same weighted
sum of the groups' 95 % confidence-interval half-widths (an interpolated half-width, not a
propagated one: it is what the neighbouring measurements support, no more).

Inputs are the group-statistics table of :func:`tribopipe.stats.group_statistics`
(columns ``pin, disc, pressure_kPa, temperature_C, mu_k_mean, mu_k_ci95_low,
mu_k_ci95_high, mu_k_n, mu_s_mean, ...``). Nothing here reads files except
:func:`load_groups`.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .errors import ExportError
from .frictionmap import read_map
from .numeric import finite_or_none
from .stats import group_statistics

if TYPE_CHECKING:
    import numpy as np
    import pandas as pd

QUANTITIES = ("mu_k", "mu_s")


@dataclass(frozen=True)
class UsedPoint:
    """A measured group that contributed to an interpolated value, with its weight (0..1]
    and ``u``, the combined standard uncertainty of its mean (GUM, k = 1; ``None`` when
    unknown, see :mod:`tribopipe.stats`)."""

    pressure_kPa: float
    temperature_C: float | None
    mean: float
    ci95_half_width: float | None
    n: int
    weight: float
    u: float | None = None


@dataclass(frozen=True)
class Estimate:
    """One interpolated coefficient with its evidence.

    ``uncertainty`` is the weighted 95 % CI half-width of the groups used (``None`` when a
    used group has no CI, e.g. a single run): what the repeats support. ``u_combined`` is
    the weighted combined standard uncertainty of the groups' means (GUM, k = 1: their
    runs' budgets beside the repeat scatter; ``None`` when a used group's is unknown); the
    same weighted sum, which is exact for the correlated part that dominates it (the
    friction radius) and conservative for the rest. ``clamped_pressure`` /
    ``clamped_temperature`` say that the request lay outside the measured range and the
    edge value was held.
    """

    value: float
    uncertainty: float | None
    used: tuple[UsedPoint, ...]
    clamped_pressure: bool
    clamped_temperature: bool
    u_combined: float | None = None


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

    @property
    def clamped(self) -> bool:
        """True when μ_K was held constant outside the measured pressure or temperature range."""
        return self.mu_k.clamped_pressure or self.mu_k.clamped_temperature

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict (plain floats, lists, ``None``)."""
        data = asdict(self)
        data["clamped"] = self.clamped
        data["pressure_range_kPa"] = list(self.pressure_range_kPa)
        data["temperatures_C"] = list(self.temperatures_C)
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


def select_pair(groups: pd.DataFrame, pin: str, disc: str) -> pd.DataFrame:
    """The groups of one pair (pin and disc matched case-insensitively), as a new frame.

    Raises :class:`ExportError` naming the pairs the map holds when the pair is unknown.
    """
    if groups.empty:
        raise ExportError(
            f"no groups for pin {pin!r} on disc {disc!r}: the friction map is empty",
            hint="reduce runs first (tribopipe reduce / batch) or import the published map",
        )
    pin_key = groups["pin"].astype(str).str.strip().str.casefold()
    disc_key = groups["disc"].astype(str).str.strip().str.casefold()
    mask = (pin_key == pin.strip().casefold()) & (disc_key == disc.strip().casefold())
    if not mask.any():
        names = [f"{p} on {d}" for p, d in pairs(groups)]
        close = difflib.get_close_matches(f"{pin} on {disc}", names, n=1, cutoff=0.6)
        hint = f"did you mean {close[0]!r}?" if close else None
        raise ExportError(
            f"no groups for pin {pin!r} on disc {disc!r}; {_held_pairs_text(groups)}", hint=hint
        )
    return groups.loc[mask].copy()


# ---------------------------------------------------------------------------- numerics


def _bracket(xs: np.ndarray, x: float) -> tuple[list[tuple[int, float]], bool]:
    """Indices into sorted unique ``xs`` with linear weights for ``x``, clamped at the ends.

    Returns ``([(i, w), ...], clamped)``; the weights are positive and sum to 1.
    """
    import numpy as np

    if len(xs) == 1:
        return [(0, 1.0)], bool(x != xs[0])
    if x <= xs[0]:
        return [(0, 1.0)], bool(x < xs[0])
    if x >= xs[-1]:
        return [(len(xs) - 1, 1.0)], bool(x > xs[-1])
    hi = int(np.searchsorted(xs, x, side="right"))
    lo = hi - 1
    if x == xs[lo]:
        return [(lo, 1.0)], False
    w_hi = float((x - xs[lo]) / (xs[hi] - xs[lo]))
    return [(lo, 1.0 - w_hi), (hi, w_hi)], False


def interpolation_weights(
    pressures_kPa: np.ndarray,
    temperatures_C: np.ndarray,
    pressure_kPa: float,
    temperature_C: float | None,
) -> tuple[np.ndarray, bool, bool]:
    """Weights of measured points for a value at (``pressure_kPa``, ``temperature_C``).

    ``pressures_kPa`` and ``temperatures_C`` (shape ``(n,)``) are the coordinates of ``n``
    measured points with unique (pressure, temperature); NaN temperatures mean "unknown"
    and are used only when no point has a temperature. Returns ``(weights, clamped_pressure,
    clamped_temperature)``: weights of shape ``(n,)``, non-negative, summing to 1, nonzero
    for at most four points. ``temperature_C=None`` is allowed when at most one temperature
    is measured.
    """
    import numpy as np

    p = np.asarray(pressures_kPa, dtype=float)
    t = np.asarray(temperatures_C, dtype=float)
    weights = np.zeros(len(p))
    known_t = np.isfinite(t)
    # (points at one temperature, weight of that temperature); no temperature known: one set
    t_sets = [(np.ones(len(p), dtype=bool), 1.0)]
    clamped_t = False
    if known_t.any():
        temps = np.unique(t[known_t])
        if temperature_C is None:
            if len(temps) > 1:
                listed = ", ".join(f"{v:g}" for v in temps)
                raise ExportError(
                    f"temperature needed: this pair is measured at {listed} °C",
                    hint="pass --temperature",
                )
            t_brackets = [(0, 1.0)]
        else:
            t_brackets, clamped_t = _bracket(temps, float(temperature_C))
        t_sets = [(t == temps[ti], wt) for ti, wt in t_brackets]

    clamped_p = False
    for at_t, wt in t_sets:
        idx = np.flatnonzero(at_t)
        idx = idx[np.argsort(p[idx])]
        p_brackets, c = _bracket(p[idx], float(pressure_kPa))
        clamped_p = clamped_p or c
        for pi, wp in p_brackets:
            weights[idx[pi]] += wt * wp
    return weights, clamped_p, clamped_t


def _points(pair_groups: pd.DataFrame, quantity: str) -> pd.DataFrame:
    """The pair's measured points for ``quantity``: one row per (pressure, temperature).

    Groups that share a condition (e.g. split by sliding speed) are merged by the
    run-weighted mean of their means and the largest CI half-width and combined standard
    uncertainty, so nothing is dropped.
    """
    import numpy as np
    import pandas as pd

    def column(name: str, default: float) -> pd.Series:
        """A numeric column of the pair's groups, or ``default`` when it is absent."""
        if name not in pair_groups.columns:
            return pd.Series(default, index=pair_groups.index, dtype=float)
        return pd.to_numeric(pair_groups[name], errors="coerce").astype(float)

    mean = column(f"{quantity}_mean", math.nan)
    u = column(f"{quantity}_u", math.nan)
    low = column(f"{quantity}_ci95_low", math.nan)
    high = column(f"{quantity}_ci95_high", math.nan)
    n = column(f"{quantity}_n", 1.0)
    frame = pd.DataFrame(
        {
            "pressure_kPa": pd.to_numeric(pair_groups["pressure_kPa"], errors="coerce"),
            "temperature_C": pd.to_numeric(pair_groups["temperature_C"], errors="coerce"),
            "mean": mean,
            "half": (high - low) / 2.0,
            "u": u,
            # a finite mean stands for at least one run, whatever the count column says
            "n": n.fillna(1).clip(lower=1).astype(float),
        }
    )
    frame = frame[np.isfinite(frame["mean"]) & np.isfinite(frame["pressure_kPa"])]
    if frame.empty:
        return frame
    rows = []
    keys = frame["temperature_C"].fillna(-math.inf)
    for (pk, _tk), grp in frame.groupby([frame["pressure_kPa"], keys], sort=True):
        n_tot = float(grp["n"].sum())
        rows.append(
            {
                "pressure_kPa": float(pk),
                "temperature_C": float(grp["temperature_C"].iloc[0]),
                "mean": float((grp["mean"] * grp["n"]).sum() / n_tot),
                "half": float(grp["half"].max()) if grp["half"].notna().all() else math.nan,
                "u": float(grp["u"].max()) if grp["u"].notna().all() else math.nan,
                "n": int(n_tot),
            }
        )
    return pd.DataFrame(rows)


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
    when unknown) and ``n``, sorted by pressure then temperature — the
    row order the interpolation sums in. Points without a temperature are left out when
    others have one, as :func:`query` does. For pages that redo the interpolation (the
    explorer); :func:`query` itself is the reference.
    """
    return _with_temperature(_points(pair_groups, quantity))


def _estimate(points: pd.DataFrame, pressure_kPa: float, temperature_C: float | None) -> Estimate:
    """Interpolate one quantity's points at (pressure [kPa], temperature [°C])."""
    import numpy as np

    weights, clamped_p, clamped_t = interpolation_weights(
        points["pressure_kPa"].to_numpy(), points["temperature_C"].to_numpy(),
        pressure_kPa, temperature_C,
    )
    used_idx = np.flatnonzero(weights > 0)
    value = float(np.dot(weights[used_idx], points["mean"].to_numpy()[used_idx]))
    halves = points["half"].to_numpy()[used_idx]
    uncertainty = (
        float(np.dot(weights[used_idx], halves)) if np.isfinite(halves).all() else None
    )
    us = points["u"].to_numpy()[used_idx] if "u" in points else np.full(used_idx.size, np.nan)
    u_combined = float(np.dot(weights[used_idx], us)) if np.isfinite(us).all() else None
    used = tuple(
        UsedPoint(
            pressure_kPa=float(points["pressure_kPa"].iloc[i]),
            temperature_C=finite_or_none(points["temperature_C"].iloc[i]),
            mean=float(points["mean"].iloc[i]),
            ci95_half_width=finite_or_none(points["half"].iloc[i]),
            n=int(points["n"].iloc[i]),
            weight=float(weights[i]),
            u=finite_or_none(points["u"].iloc[i]) if "u" in points else None,
        )
        for i in used_idx
    )
    return Estimate(value, uncertainty, used, clamped_p, clamped_t, u_combined)


# ---------------------------------------------------------------------------- public API


def query(
    groups: pd.DataFrame,
    pin: str,
    disc: str,
    pressure_kPa: float,
    temperature_C: float | None = None,
) -> QueryResult:
    """μ_K (and μ_S where measured) of a pair at a contact pressure [kPa] and temperature [°C].

    ``groups`` is a group-statistics table (one row per condition group). The value is
    interpolated linearly in temperature, then in pressure, over the group means and held
    constant outside the measured range (see the module docstring). ``temperature_C`` may
    be ``None`` only when the pair is measured at a single temperature. Raises
    :class:`ExportError` for an unknown pair (listing the pairs held) or a bad request.
    """
    if not math.isfinite(pressure_kPa) or pressure_kPa < 0:
        raise ExportError(f"contact pressure must be a finite number >= 0 kPa, got {pressure_kPa}")
    if temperature_C is not None and not math.isfinite(temperature_C):
        raise ExportError(f"temperature must be a finite number in °C, got {temperature_C}")
    pair = select_pair(groups, pin, disc)
    mu_k_points = _points(pair, "mu_k")
    if mu_k_points.empty:
        raise ExportError(f"pin {pin!r} on disc {disc!r} has no group with a finite mu_k")
    notes: list[str] = []
    kept = _with_temperature(mu_k_points)
    if len(kept) < len(mu_k_points):
        notes.append(f"{len(mu_k_points) - len(kept)} group(s) without a temperature were left out")
        mu_k_points = kept
    mu_k = _estimate(mu_k_points, pressure_kPa, temperature_C)

    mu_s = None
    if "mu_s_mean" in pair.columns:
        mu_s_points = _with_temperature(_points(pair, "mu_s"))
        if not mu_s_points.empty:
            mu_s = _estimate(mu_s_points, pressure_kPa, temperature_C)
    if mu_s is None:
        notes.append("mu_s unknown: no group of this pair holds a static coefficient")
    if mu_k.uncertainty is None:
        notes.append("uncertainty unknown: a group used has fewer than 2 runs")
    if mu_k.clamped_pressure:
        notes.append(
            "pressure outside the range measured (at a temperature used): edge value held"
        )
    if mu_k.clamped_temperature:
        notes.append("temperature outside the measured range: edge value held")

    temps = sorted({float(t) for t in mu_k_points["temperature_C"] if math.isfinite(t)})
    first = pair.iloc[0]
    return QueryResult(
        pin=str(first["pin"]),
        disc=str(first["disc"]),
        pressure_kPa=float(pressure_kPa),
        temperature_C=None if temperature_C is None else float(temperature_C),
        mu_k=mu_k,
        mu_s=mu_s,
        pressure_range_kPa=(
            float(mu_k_points["pressure_kPa"].min()),
            float(mu_k_points["pressure_kPa"].max()),
        ),
        temperatures_C=tuple(temps),
        notes=tuple(notes),
    )


def friction_table(
    groups: pd.DataFrame,
    pin: str,
    disc: str,
    quantity: str = "mu_k",
) -> pd.DataFrame:
    """The pair's full rectangular (pressure × temperature) table of ``quantity``.

    Rows cover every measured pressure [kPa] at every measured temperature [°C] (sorted,
    temperature outer, pressure inner — the order ABAQUS wants). Columns:
    ``pressure_kPa, temperature_C, <quantity>, uncertainty, u_combined, measured`` (bool;
    ``uncertainty`` the CI half-width, ``u_combined`` the combined standard uncertainty,
    see :class:`Estimate`). Cells that
    were not measured are filled by :func:`query`'s interpolation (``measured`` False).
    ``temperature_C`` is NaN throughout when the pair has no temperature.
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
    rows = []
    for t in temps:
        for p in pressures:
            est = _estimate(points, p, t)
            rows.append(
                {
                    "pressure_kPa": float(p),
                    "temperature_C": math.nan if t is None else float(t),
                    quantity: est.value,
                    "uncertainty": math.nan if est.uncertainty is None else est.uncertainty,
                    "u_combined": math.nan if est.u_combined is None else est.u_combined,
                    "measured": (float(p), t) in measured,
                }
            )
    return pd.DataFrame(rows)


def load_groups(map_path: str | Path) -> pd.DataFrame:
    """Read a friction map (Parquet) and return its group statistics (excluded runs out)."""
    return groups_of(read_map(map_path), map_path)


def groups_of(runs: pd.DataFrame, map_path: str | Path) -> pd.DataFrame:
    """Group statistics of friction-map ``runs`` (excluded runs out); an
    :class:`ExportError` naming ``map_path`` when no run is left."""
    if "excluded" in runs.columns:
        runs = runs[~runs["excluded"].fillna(False).astype(bool)]
    if runs.empty:
        raise ExportError(
            "the friction map is empty or absent",
            path=map_path,
            hint="reduce runs first (tribopipe reduce / batch) or import the published map",
        )
    return group_statistics(runs)


def query_map(
    map_path: str | Path,
    pin: str,
    disc: str,
    pressure_kPa: float,
    temperature_C: float | None = None,
) -> QueryResult:
    """:func:`query` on the friction map (Parquet) at ``map_path``."""
    return query(load_groups(map_path), pin, disc, pressure_kPa, temperature_C)


def format_result(res: QueryResult) -> str:
    """A short human-readable report of a query (several lines, no trailing newline)."""

    def est_text(name: str, est: Estimate | None) -> str:
        """One line for an estimate: value ± uncertainty, or 'unknown'."""
        if est is None:
            return f"{name} = unknown (no group of this pair holds it)"
        unc = "" if est.uncertainty is None else f" ± {est.uncertainty:.3f} (95 % CI, interpolated)"
        comb = ("" if est.u_combined is None else
                f"; combined u = {est.u_combined:.3f}, U = {2 * est.u_combined:.3f} (k = 2)")
        return f"{name} = {est.value:.3f}{unc}{comb}"

    t = "" if res.temperature_C is None else f", {res.temperature_C:g} °C"
    lines = [
        f"{res.pin} on {res.disc} at {res.pressure_kPa:g} kPa{t}",
        "  " + est_text("mu_k", res.mu_k),
        "  " + est_text("mu_s", res.mu_s),
        "  from measured groups (pressure, temperature, mean, n, weight):",
    ]
    for u in res.mu_k.used:
        t_u = "?" if u.temperature_C is None else f"{u.temperature_C:g} °C"
        lines.append(
            f"    {u.pressure_kPa:g} kPa, {t_u}, {u.mean:.3f}, n={u.n}, w={u.weight:.3f}"
        )
    lo, hi = res.pressure_range_kPa
    temps = ", ".join(f"{v:g}" for v in res.temperatures_C) or "unknown"
    lines.append(f"  measured: {lo:g}–{hi:g} kPa at {temps} °C")
    lines.append(f"  clamped: {'yes' if res.clamped else 'no'}")
    lines += [f"  note: {n}" for n in res.notes]
    return "\n".join(lines)
