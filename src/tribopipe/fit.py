"""The fits of the map's μ_K: its power-law pressure dependence μ = k·p^(n−1), fitted per
pair and temperature (:func:`fit_power_law`), and its speed dependence as an exponential
decay μ(v) = FD + (FS − FD)·exp(−DC·v) over a pair's measured speeds (:func:`fit_decay`,
what LS-DYNA's friction card holds).

Elastomer friction falls with contact pressure; a Hertz-type contact gives
n − 1 ≈ −1/3. We fit on the individual runs (not the group means) as a straight line in
log–log space,

    ln μ = ln k + (n − 1)·ln p,        p in kPa,

by ordinary least squares. Why log–log rather than ``curve_fit`` on μ: the scatter of μ
between repeats grows with μ (multiplicative error), the problem is then linear (no
starting values, no convergence failures), and the 95 % confidence intervals follow
exactly from the t-distribution with N − 2 degrees of freedom. ``k`` is μ at 1 kPa; its
interval is the exponentiated interval of ln k (so it is asymmetric). ``r_squared`` is the
coefficient of determination of the log–log regression.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from .errors import MapError
from .frictionmap.snapshot import MapSource, as_snapshot
from .stats import NOMINAL_SPEED, nominal_speeds, pairs_with_several_speeds, t975

if TYPE_CHECKING:
    import numpy as np
    import pandas as pd
    from numpy.typing import ArrayLike, NDArray

FIT_COLUMNS: tuple[str, ...] = (
    "pin",
    "disc",
    "temperature_C",
    "k",
    "k_ci95_low",
    "k_ci95_high",
    "exponent",
    "exponent_ci95_low",
    "exponent_ci95_high",
    "r_squared",
    "n_points",
    "n_pressures",
    "pressure_min_kPa",
    "pressure_max_kPa",
    "note",
)

MIN_POINTS = 3


def power_law(pressure_kPa: ArrayLike, k: float, exponent: float) -> NDArray[np.float64]:
    """μ = k·p^exponent for contact pressure(s) ``pressure_kPa`` [kPa] (same shape out)."""
    import numpy as np

    return k * np.power(np.asarray(pressure_kPa, dtype=float), exponent)


def fit_one(pressure_kPa: ArrayLike, mu: ArrayLike) -> dict[str, float]:
    """Fit μ = k·p^exponent to paired arrays (shape ``(N,)``, p in kPa, μ > 0).

    Returns ``k, k_ci95_low, k_ci95_high, exponent, exponent_ci95_low,
    exponent_ci95_high, r_squared`` (floats). Needs N ≥ 3 points at ≥ 2 pressures; the
    caller checks that. With a perfect fit the intervals collapse to the estimate.
    """
    import numpy as np

    x = np.log(np.asarray(pressure_kPa, dtype=float))
    y = np.log(np.asarray(mu, dtype=float))
    n = len(x)
    x_mean = x.mean()
    sxx = float(((x - x_mean) ** 2).sum())
    slope = float(((x - x_mean) * (y - y.mean())).sum() / sxx)
    intercept = float(y.mean() - slope * x_mean)
    resid = y - (intercept + slope * x)
    ss_res = float((resid**2).sum())
    ss_tot = float(((y - y.mean()) ** 2).sum())
    dof = n - 2
    s2 = ss_res / dof
    se_slope = math.sqrt(s2 / sxx)
    se_intercept = math.sqrt(s2 * (1.0 / n + x_mean**2 / sxx))
    t = t975(dof)
    # ss_tot == 0: every μ equal, the flat line explains everything there is
    r2 = 1.0 - ss_res / ss_tot if ss_tot > 0 else 1.0
    return {
        "k": math.exp(intercept),
        "k_ci95_low": math.exp(intercept - t * se_intercept),
        "k_ci95_high": math.exp(intercept + t * se_intercept),
        "exponent": slope,
        "exponent_ci95_low": slope - t * se_slope,
        "exponent_ci95_high": slope + t * se_slope,
        "r_squared": r2,
    }


def fit_power_law(runs: pd.DataFrame, *, quantity: str = "mu_k") -> pd.DataFrame:
    """Fit μ = k·p^(n−1) per (pin, disc, temperature, nominal speed) on the individual runs.

    ``runs`` has the friction-map run columns ``pin, disc, pressure_kPa`` (nominal, kPa),
    ``temperature_C`` (nominal, °C; NaN = unknown, fitted as its own set) and ``quantity``
    (default ``mu_k``); runs with ``excluded`` True and rows with a missing or
    non-positive μ or pressure are left out. Returns one row per set with the columns
    :data:`FIT_COLUMNS`; a set with fewer than 3 runs or a single pressure keeps NaN
    parameters and says why in ``note`` (empty when fitted). Runs at different nominal
    sliding speeds are never fitted together; where a pair holds several speeds the
    table has ``nominal_speed_mm_s`` after ``temperature_C`` (as the group table).
    ``runs`` is not modified.
    """
    import numpy as np
    import pandas as pd

    if runs.empty:
        return pd.DataFrame(columns=list(FIT_COLUMNS))
    columns = list(FIT_COLUMNS)
    if "excluded" in runs.columns and pairs_with_several_speeds(runs):
        columns.insert(columns.index("temperature_C") + 1, NOMINAL_SPEED)
    data = pd.DataFrame(
        {
            "pin": runs["pin"].astype(str),
            "disc": runs["disc"].astype(str),
            "temperature_C": pd.to_numeric(runs["temperature_C"], errors="coerce"),
            "p": pd.to_numeric(runs["pressure_kPa"], errors="coerce"),
            "mu": pd.to_numeric(runs[quantity], errors="coerce"),
            "v": nominal_speeds(runs),
        }
    )
    keep = np.isfinite(data["p"]) & np.isfinite(data["mu"]) & (data["p"] > 0) & (data["mu"] > 0)
    if "excluded" in runs.columns:
        keep &= ~runs["excluded"].fillna(False).astype(bool).to_numpy()
    data = data[keep]
    rows = []
    t_key = data["temperature_C"].fillna(-math.inf)
    # each set's rows in the order of its key (the groupby's sorted order), each set's
    # own in map order: one stable sort, then plain arrays per set (never a frame per set)
    codes = data.groupby([data["pin"], data["disc"], t_key, data["v"]],
                         sort=True).ngroup().to_numpy(dtype=np.int64)
    order = np.argsort(codes, kind="stable")
    starts = np.flatnonzero(np.diff(codes[order], prepend=-1)).tolist()
    ends = [*starts[1:], len(order)] if starts else []
    pins, discs = (data[c].to_numpy(dtype=object)[order] for c in ("pin", "disc"))
    t, p, mu, v = (data[c].to_numpy(dtype=float)[order]
                   for c in ("temperature_C", "p", "mu", "v"))
    for start, end in zip(starts, ends, strict=True):
        p_set, n = p[start:end], end - start
        n_pressures = len(np.unique(p_set))
        row: dict[str, Any] = {
            "pin": pins[start],
            "disc": discs[start],
            "temperature_C": float(t[start]),
            NOMINAL_SPEED: float(v[start]),
            "n_points": n,
            "n_pressures": n_pressures,
            "pressure_min_kPa": float(p_set.min()),
            "pressure_max_kPa": float(p_set.max()),
            "note": "",
        }
        if n < MIN_POINTS or n_pressures < 2:
            row["note"] = (
                f"not fitted: {n} run(s) at {n_pressures} pressure(s); "
                f"need >= {MIN_POINTS} runs at >= 2 pressures"
            )
            row.update({c: math.nan for c in FIT_COLUMNS if c not in row})
        else:
            row.update(fit_one(p_set, mu[start:end]))
        rows.append(row)
    return pd.DataFrame(rows, columns=columns)


def fit_map(map_path: MapSource) -> pd.DataFrame:
    """:func:`fit_power_law` on the runs of the friction map (Parquet) at ``map_path``."""
    runs = as_snapshot(map_path).runs
    if runs.empty:
        raise MapError(
            "the friction map is empty or absent",
            path=map_path,
            hint="reduce runs first (tribopipe reduce / batch) or import the published map",
        )
    return fit_power_law(runs)


# ---------------------------------------------------------------------------- speed decay


@dataclass(frozen=True)
class DecayFit:
    """μ(v) = FD + (FS − FD)·exp(−DC·v) fitted to μ_K at the measured speeds: ``fs``,
    ``fd``, ``dc_s_per_mm`` [s/mm]; ``rms`` and ``max_abs`` the residuals (in μ) at the
    ``n`` speeds; ``rising`` when μ grows with speed (FS < FD: elastomers below their
    loss peak)."""

    fs: float
    fd: float
    dc_s_per_mm: float
    rms: float
    max_abs: float
    n: int

    @property
    def rising(self) -> bool:
        """True when μ rises with speed (FS < FD)."""
        return self.fs < self.fd


def fit_decay(curve: list[tuple[float, float]]) -> DecayFit | None:
    """:class:`DecayFit` of ``[(v [mm/s], μ)]`` by least squares (DC ≥ 0, started at the
    inverse middle speed); ``None`` with fewer than 3 speeds (three parameters)."""
    import numpy as np
    from scipy.optimize import least_squares

    if len(curve) < 3:
        return None
    v = np.array([c[0] for c in curve], dtype=float)
    mu = np.array([c[1] for c in curve], dtype=float)

    def model(theta: np.ndarray) -> np.ndarray:
        return theta[1] + (theta[0] - theta[1]) * np.exp(-theta[2] * v)

    start = np.array([mu[0], mu[-1], 1.0 / float(np.exp(np.mean(np.log(v))))])
    best = None
    for scale in (0.1, 1.0, 10.0):
        theta0 = start.copy()
        theta0[2] *= scale
        sol = least_squares(lambda t: model(t) - mu, theta0,
                            bounds=([-np.inf, -np.inf, 0.0], [np.inf, np.inf, np.inf]))
        if best is None or sol.cost < best.cost:
            best = sol
    assert best is not None
    res = model(best.x) - mu
    return DecayFit(float(best.x[0]), float(best.x[1]), float(best.x[2]),
                    float(np.sqrt(np.mean(res**2))), float(np.max(np.abs(res))), len(curve))
