"""Repeat statistics per condition group of the friction map, and the pooled repeatability.

A condition group is one contact pair (pin, disc) at one nominal normal force [N] (hence
one nominal pressure [kPa]), one nominal temperature [°C] and one nominal sliding speed
[mm/s] (:func:`nominal_speeds`: a row written before nominal speeds were recorded counts
as the founding paper's speed); optionally (``by_speed``) also one measured sliding speed.
Nominal values are rounded before grouping (force to 1e-6 N, temperature to 0.01 °C,
speeds to two significant digits, :func:`tribopipe.labels.round_speed`) so 11.79 vs
11.7893 kPa never splits a group. A map whose pairs were each measured at one speed has
groups without a speed column, as before speeds were recorded; where a pair holds several
nominal speeds the groups carry ``nominal_speed_mm_s``.

Test methods are never pooled: the instrument kind and test method (``test_method``, one
of :data:`tribopipe.config.TEST_METHODS`; a row that names none was measured on the
founding rheometer cell) is part of every condition group's key, and where a map holds
several methods the groups carry a ``test_method`` column (a sled's μ on a film and a
rheometer's μ on the same pair are two groups, side by side).

Beside the repeat statistics each group carries its combined standard uncertainty (GUM,
k = 1) from the runs' own budgets (:mod:`tribopipe.reduction.uncertainty`): ``u_run`` is the mean of
the runs' combined standard uncertainties, and the group mean's is
``u = √(sem² + u_run²)``: the repeat scatter (sem, which already holds each run's noise)
plus the runs' uncertainty counted as fully correlated between the runs (its largest
part, the friction radius, is the same for every run of a cell; counting the rest so is
conservative). With one run u = u_run; when a run has no uncertainty (an imported row, a
run reduced before uncertainties were recorded) the group's is unknown (NaN).

With two or three repeats per group no statistical outlier test is meaningful (ISO 5725,
ASTM E178). Instead, the within-group standard deviations are pooled over all groups into
a repeatability standard deviation s_r, and groups whose range exceeds the repeatability
limit r = 2.8·s_r are flagged, as are groups holding runs with QC flags. Runs excluded by
id (with a recorded reason) are left out of everything here.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from .config import DEFAULT_TEST_METHOD
from .labels import FOUNDING_NOMINAL_SPEED_MM_S, quality_flags, round_speed
from .rounding import lower_bound

if TYPE_CHECKING:
    import pandas as pd

QUANTITIES: tuple[str, ...] = ("mu_k", "mu_s")
STAT_FIELDS: tuple[str, ...] = (
    "n", "mean", "std", "sem", "ci95_low", "ci95_high", "cv", "min", "max", "values",
)
#: The per-group columns of each quantity: the repeat statistics, then the uncertainty
#: (``u_run``: mean of the runs' combined standard uncertainties; ``u``: combined standard
#: uncertainty of the group mean), then the values.
GROUP_FIELDS: tuple[str, ...] = STAT_FIELDS[:-1] + ("u_run", "u", "values")
#: Repeatability limit factor: r = 2.8·s_r (≈ 1.96·√2, ISO 5725-6).
R_FACTOR = 2.8
#: Two nominal pressures of one force group more than this fraction apart are different
#: conditions (e.g. two cells with different pin radii in one map).
PRESSURE_SPLIT = 0.01
FORCE_DECIMALS = 6
TEMPERATURE_DECIMALS = 2
#: the group column of the nominal sliding speed [mm/s]
NOMINAL_SPEED = "nominal_speed_mm_s"
#: the group column of the instrument kind and test method
TEST_METHOD = "test_method"


def test_methods(runs: pd.DataFrame) -> Any:
    """The test method each run is grouped under (an object array of text): its
    ``test_method``, or :data:`~tribopipe.config.DEFAULT_TEST_METHOD` where the row names
    none (a map older than schema version 6, an imported row)."""
    import numpy as np

    if TEST_METHOD not in runs.columns:
        return np.full(len(runs), DEFAULT_TEST_METHOD, dtype=object)
    return np.array([v if isinstance(v, str) and v else DEFAULT_TEST_METHOD
                     for v in runs[TEST_METHOD].tolist()], dtype=object)


def several_methods(runs: pd.DataFrame) -> bool:
    """Whether the included runs of a map hold more than one test method."""
    included = runs.loc[~runs["excluded"].astype(bool)]
    return len(set(test_methods(included).tolist())) > 1


def describe_values(values: Sequence[float]) -> dict[str, Any]:
    """Statistics of one group's values (finite floats; missing ones already removed).

    Returns ``n, mean, std`` (sample, n−1), ``sem`` (std/√n), ``ci95_low, ci95_high``
    (mean ∓ t₀.₉₇₅,ₙ₋₁·sem, Student t; the lower end bounded at 0, since a coefficient of
    friction is never negative: with n = 2, t = 12.7 would otherwise reach far below),
    ``cv`` (std/mean), ``min, max`` and ``values`` (``;``-joined shortest round-trip
    text, in the given order). With n = 1, std, sem, CI and cv are NaN (unknown, not
    zero); with n = 0 everything but n is NaN.
    """
    import numpy as np

    x = np.asarray(values, dtype=float)
    n = int(x.size)
    out: dict[str, Any] = dict.fromkeys(STAT_FIELDS, math.nan)
    out["n"] = n
    out["values"] = ";".join(repr(float(v)) for v in x)
    if n == 0:
        return out
    mean = float(np.mean(x))
    out.update(mean=mean, min=float(np.min(x)), max=float(np.max(x)))
    if n < 2:
        return out
    std = float(np.std(x, ddof=1))
    sem = std / math.sqrt(n)
    half = t975(n - 1) * sem
    out.update(
        std=std,
        sem=sem,
        ci95_low=lower_bound(mean, half),
        ci95_high=mean + half,
        cv=std / mean if mean != 0 else math.nan,
    )
    return out


@functools.lru_cache(maxsize=256)
def t975(dof: int) -> float:
    """Student-t 97.5 % quantile for ``dof`` degrees of freedom (two-sided 95 % CI)."""
    # scipy.special's inverse of the t CDF: the value of scipy.stats.t.ppf, without
    # importing scipy.stats (seconds on a first run)
    from scipy.special import stdtrit

    return float(stdtrit(dof, 0.975))


@dataclass(frozen=True)
class Repeatability:
    """Pooled within-group standard deviation of one quantity over the groups with n ≥ 2.

    ``s_r = sqrt(Σ (nᵢ−1)·sᵢ² / Σ (nᵢ−1))`` with ``dof = Σ (nᵢ−1)``; ``r = 2.8·s_r``.
    NaN when no group has two values.
    """

    quantity: str
    s_r: float
    r: float
    dof: int
    n_groups: int


def repeatability(groups: pd.DataFrame, quantity: str = "mu_k") -> Repeatability:
    """The pooled repeatability of ``quantity`` ('mu_k' or 'mu_s') from a
    :func:`group_statistics` table."""
    import numpy as np

    n = groups[f"{quantity}_n"].to_numpy(dtype=float)
    s = groups[f"{quantity}_std"].to_numpy(dtype=float)
    use = (n >= 2) & np.isfinite(s)
    dof = int(np.sum(n[use] - 1))
    if dof == 0:
        return Repeatability(quantity, math.nan, math.nan, 0, 0)
    s_r = math.sqrt(float(np.sum((n[use] - 1) * s[use] ** 2)) / dof)
    return Repeatability(quantity, s_r, R_FACTOR * s_r, dof, int(use.sum()))


def nominal_speeds(runs: pd.DataFrame) -> Any:
    """The nominal sliding speed [mm/s] each run is grouped under (a float array): its
    ``nominal_speed_mm_s`` rounded by :func:`~tribopipe.labels.round_speed`, or
    :data:`~tribopipe.labels.FOUNDING_NOMINAL_SPEED_MM_S` where the row has none (a map
    written before schema version 5, an imported row: measured at one speed as far as the
    map can tell, which the published map and tribopipe's default instrument both are)."""
    import numpy as np

    if NOMINAL_SPEED not in runs.columns:
        return np.full(len(runs), FOUNDING_NOMINAL_SPEED_MM_S)
    values = runs[NOMINAL_SPEED].to_numpy(dtype=float)
    return np.array([round_speed(float(v)) if math.isfinite(v) and v > 0
                     else FOUNDING_NOMINAL_SPEED_MM_S for v in values], dtype=float)


def pairs_with_several_speeds(runs: pd.DataFrame) -> set[tuple[str, str]]:
    """The (pin, disc) pairs whose included runs hold more than one nominal speed."""
    included = runs.loc[~runs["excluded"].astype(bool)]
    speeds: dict[tuple[str, str], set[float]] = {}
    for pin, disc, v in zip(included["pin"], included["disc"], nominal_speeds(included),
                            strict=True):
        speeds.setdefault((str(pin), str(disc)), set()).add(float(v))
    return {pair for pair, found in speeds.items() if len(found) > 1}


def group_keys(runs: pd.DataFrame, by_speed: bool) -> pd.DataFrame:
    """The rounded grouping keys of each run (a new frame; ``runs`` is not modified):
    pin, disc, force, temperature, nominal speed, test method (and the measured speed
    with ``by_speed``)."""
    import pandas as pd

    keys = pd.DataFrame(
        {
            "pin": runs["pin"].to_numpy(dtype=object),
            "disc": runs["disc"].to_numpy(dtype=object),
            "normal_force_N": runs["normal_force_N"].round(FORCE_DECIMALS).to_numpy(),
            "temperature_C": runs["temperature_C"].round(TEMPERATURE_DECIMALS).to_numpy(),
            NOMINAL_SPEED: nominal_speeds(runs),
            TEST_METHOD: test_methods(runs),
        },
        index=runs.index,
    )
    if by_speed:
        keys["sliding_speed_mm_s"] = [
            round_speed(float(v)) for v in runs["sliding_speed_mm_s"]
        ]
    return keys


def _pressure_clusters(pressures: Sequence[float]) -> list[int]:
    """Cluster numbers for the nominal pressures of one force group: sorted, a new cluster
    starts where a pressure is more than :data:`PRESSURE_SPLIT` above the previous one."""
    order = sorted(range(len(pressures)), key=lambda i: (math.isnan(pressures[i]), pressures[i]))
    labels = [0] * len(pressures)
    cluster = 0
    previous = None
    for i in order:
        p = pressures[i]
        same = previous is not None and (
            math.isclose(p, previous, rel_tol=PRESSURE_SPLIT)
            or (math.isnan(p) and math.isnan(previous))
        )
        if previous is not None and not same:
            cluster += 1
        labels[i] = cluster
        previous = p
    return labels


def group_statistics(runs: pd.DataFrame, *, by_speed: bool = False,
                     show_speed: bool | None = None,
                     show_method: bool | None = None) -> pd.DataFrame:
    """Repeat statistics per condition group of a friction map (see module docstring).

    ``runs`` is a map DataFrame (:func:`tribopipe.frictionmap.read_map`); it is not
    modified. Excluded runs are left out; groups with no remaining run are dropped.
    Groups always split by nominal speed and by test method; ``show_speed`` says whether
    the table shows the speed (default: where some pair holds several nominal speeds),
    ``show_method`` whether it shows ``test_method`` (default: where the map holds several
    methods).
    Columns: ``pin, disc, normal_force_N, pressure_kPa, temperature_C``
    (+ ``nominal_speed_mm_s`` when shown, + ``sliding_speed_mm_s``, the measured speed,
    with ``by_speed``), then for q in ``mu_k``, ``mu_s``:
    ``q_n, q_mean, q_std, q_sem, q_ci95_low, q_ci95_high, q_cv, q_min, q_max, q_u_run,
    q_u, q_values``,
    then ``range_exceeds_r, qc_flagged, run_ids``. Within a group, values and ids are in
    (repeat, measurement_id) order, so the result does not depend on the row order.
    Rows are sorted by pin, disc, temperature, pressure, force, nominal speed (and
    measured speed).
    """
    import numpy as np
    import pandas as pd

    if show_speed is None:
        show_speed = bool(pairs_with_several_speeds(runs))
    if show_method is None:
        show_method = several_methods(runs)
    condition_cols = ["pin", "disc", "normal_force_N", "pressure_kPa", "temperature_C"]
    if show_speed:
        condition_cols.append(NOMINAL_SPEED)
    if show_method:
        condition_cols.append(TEST_METHOD)
    if by_speed:
        condition_cols.append("sliding_speed_mm_s")
    stat_cols = [f"{q}_{f}" for q in QUANTITIES for f in GROUP_FIELDS]
    columns = condition_cols + stat_cols + ["range_exceeds_r", "qc_flagged", "run_ids"]

    included = runs.loc[~runs["excluded"].astype(bool)]
    keys = group_keys(included, by_speed)
    key_cols = list(keys.columns)
    # plain arrays once; per-group pandas slicing is what makes large maps slow
    data = {
        "pressure_kPa": included["pressure_kPa"].to_numpy(dtype=float),
        "repeat": included["repeat"].astype("Float64").to_numpy(dtype=float, na_value=np.nan),
        "measurement_id": included["measurement_id"].astype(str).to_numpy(dtype=object),
        "flags": included["flags"].fillna("").astype(str).to_numpy(dtype=object),
    }
    for q in QUANTITIES:
        data[q] = included[q].to_numpy(dtype=float)
        data[f"u_{q}"] = (included[f"u_{q}"].to_numpy(dtype=float) if f"u_{q}" in included
                          else np.full(len(included), np.nan))
    rows: list[dict[str, Any]] = []
    if len(included):
        grouped = keys.groupby(key_cols, dropna=False, sort=False).indices
        for key, positions in grouped.items():
            key = key if isinstance(key, tuple) else (key,)
            clusters = _pressure_clusters([float(p) for p in data["pressure_kPa"][positions]])
            for c in sorted(set(clusters)):
                # .indices holds integer arrays (typed as array, Index or list)
                members = np.asarray(positions)[[i for i, k in enumerate(clusters) if k == c]]
                rows.append(_group_row(dict(zip(key_cols, key, strict=True)), members, data))
    if not rows:
        return pd.DataFrame({c: pd.Series(dtype=_dtype(c)) for c in columns})
    groups = pd.DataFrame(rows)
    groups = groups.sort_values(
        ["pin", "disc", "temperature_C", "pressure_kPa", "normal_force_N", NOMINAL_SPEED,
         TEST_METHOD] + (["sliding_speed_mm_s"] if by_speed else []),
        na_position="last",
        kind="mergesort",
    ).reset_index(drop=True)
    flagged = np.zeros(len(groups), dtype=bool)
    for q in QUANTITIES:
        rep = repeatability(groups, q)
        if math.isfinite(rep.r):
            spread = (groups[f"{q}_max"] - groups[f"{q}_min"]).to_numpy(dtype=float)
            flagged |= np.nan_to_num(spread, nan=0.0) > rep.r
    groups["range_exceeds_r"] = flagged
    # the types of _dtype, as for an empty table; numeric columns are left as computed
    non_float = {c: _dtype(c) for c in columns if _dtype(c) != "float64"}
    return groups.astype(non_float).loc[:, columns]


def _dtype(column: str) -> str:
    if column in ("pin", "disc", "run_ids", TEST_METHOD) or column.endswith("_values"):
        return "str"
    if column.endswith("_n"):
        return "int64"
    if column in ("range_exceeds_r", "qc_flagged"):
        return "bool"
    return "float64"


def _group_row(
    key: dict[str, Any], members: Any, data: dict[str, Any]
) -> dict[str, Any]:
    """One output row (``range_exceeds_r`` comes later, from all groups): ``members`` are
    positions into the per-run arrays of ``data``."""
    import numpy as np

    order = sorted(
        members,
        key=lambda i: (_repeat_key(data["repeat"][i]), data["measurement_id"][i]),
    )
    row: dict[str, Any] = dict(key)
    row["pressure_kPa"] = float(np.median(data["pressure_kPa"][order]))
    for q in QUANTITIES:
        values = data[q][order]
        finite = np.isfinite(values)
        stats = describe_values(values[finite])
        row.update({f"{q}_{f}": v for f, v in stats.items()})
        row.update(_group_uncertainty(data[f"u_{q}"][order][finite], stats["sem"], q))
    row["qc_flagged"] = any(quality_flags(f) for f in data["flags"][order])
    row["run_ids"] = ";".join(data["measurement_id"][order])
    return row


def _group_uncertainty(u_runs: Any, sem: float, q: str) -> dict[str, float]:
    """``q_u_run`` and ``q_u`` of a group (module docstring) from its runs' standard
    uncertainties (the runs with a value of q) and the standard error of their mean."""
    import numpy as np

    u = np.asarray(u_runs, dtype=float)
    if u.size == 0 or not np.isfinite(u).all():
        return {f"{q}_u_run": math.nan, f"{q}_u": math.nan}
    u_run = float(np.mean(u))
    scatter = sem if math.isfinite(sem) else 0.0
    return {f"{q}_u_run": u_run, f"{q}_u": math.hypot(scatter, u_run)}


def _repeat_key(value: float) -> tuple[int, int]:
    return (1, 0) if math.isnan(value) else (0, int(value))


def group_u(groups: pd.DataFrame, quantity: str = "mu_k") -> tuple[pd.Series, pd.Series]:
    """``(u, budget)`` per group of ``quantity``: the standard uncertainty of the group mean
    (GUM, k = 1) that every output's U = 2u reads, and whether it holds the runs' budgets.

    ``u`` is the group's combined ``q_u`` (runs' budgets beside the repeat scatter) where
    its runs carry budgets (``budget`` True); else its repeat scatter alone, ``q_sem``
    (e.g. an imported map); NaN where neither is known (one run without a budget). Columns
    that are absent count as unknown.
    """
    import pandas as pd

    def column(name: str) -> pd.Series:
        """A numeric column of ``groups`` (all NaN when absent)."""
        if name not in groups.columns:
            return pd.Series(math.nan, index=groups.index, dtype=float)
        return pd.to_numeric(groups[name], errors="coerce").astype(float)

    u_budget = column(f"{quantity}_u")
    budget = u_budget.notna()
    return u_budget.where(budget, column(f"{quantity}_sem")), budget
