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

Rows without a budget of their own (an imported row, a run reduced before uncertainties were
recorded) carry a stated estimate instead of none (:func:`stated_u`): the GUM budget of the
founding cell (:class:`tribopipe.config.InstrumentConfig` defaults, the T-PID/44 the
founding map was measured with) at the row's μ and nominal force, with its reading term the
resolution of the value as written (0.45: ±0.005, rectangular) and its torque zero unknown;
the group says so (``q_u_estimated``).

Labs: a group's runs are split by the lab that measured them (``lab``; a row naming none is
the map's own lab, :data:`OWN_LAB`). A lab's repeats are never pooled with another's:
within a condition measured by p ≥ 2 labs the statistics are ISO 5725-2's (unbalanced, §7.4):
the repeatability variance s_r² = Σ(nᵢ−1)sᵢ² / Σ(nᵢ−1), the variance of the lab means
s_d² = Σnᵢ(ȳᵢ−ȳ)² / (p−1), n̄ = (Σnᵢ − Σnᵢ²/Σnᵢ)/(p−1), the between-lab variance
s_L² = max(0, (s_d² − s_r²)/n̄), s_R² = s_L² + s_r², r = 2.8·s_r and R = 2.8·s_R. The
pooled value's u holds the between-lab component whole: u² = maxᵢ uᵢ² + s_L², with uᵢ
the lab's own group-mean u; so a second lab's data never make a value look more certain
than either lab alone (the pooled value stands for what a lab measures, not for a mean
over labs that grows more certain the more labs are counted). A condition whose labs'
means differ by more than ISO 5725-6's critical difference
CD = √(R² − r²(1 − 1/2nᵢ − 1/2nⱼ)), with the map's pooled s_r and s_R = √(s_L² + s_r²)
(s_L² pooled over the conditions several labs measured), is flagged ``labs_disagree``.

With two or three repeats per group no statistical outlier test is meaningful (ISO 5725,
ASTM E178). Instead, the within-group standard deviations are pooled over all groups into
a repeatability standard deviation s_r (each lab's repeats apart), and groups in which a
lab's range exceeds the repeatability limit r = 2.8·s_r are flagged, as are groups holding
runs with QC flags. Runs excluded by id (with a recorded reason) are left out of
everything here.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from .config import DEFAULT_TEST_METHOD, InstrumentConfig
from .labels import quality_flags, round_speed
from .physics import FOUNDING_SLIDING_SPEED_MM_S
from .reduction.uncertainty import budget, unknown_offset_u_Nm
from .rounding import lower_bound

if TYPE_CHECKING:
    import pandas as pd

QUANTITIES: tuple[str, ...] = ("mu_k", "mu_s")
STAT_FIELDS: tuple[str, ...] = (
    "n", "mean", "std", "sem", "ci95_low", "ci95_high", "cv", "min", "max", "values",
)
#: The per-group columns of each quantity: the repeat statistics (``n``: the runs that
#: have a value of it), then the uncertainty (``u_run``: mean of the runs' combined
#: standard uncertainties; ``u``: combined standard uncertainty of the group mean, with
#: the between-lab component; ``u_estimated``: some run's u is the stated estimate of
#: :func:`stated_u`), then the labs (``labs``: how many labs measured it; ISO 5725-2's
#: ``s_r``, ``s_L``, ``s_R`` of the condition, ``s_L`` and ``s_R`` NaN with one lab),
#: then the values.
GROUP_FIELDS: tuple[str, ...] = STAT_FIELDS[:-1] + (
    "u_run", "u", "u_estimated", "labs", "s_r", "s_L", "s_R", "values")
#: Repeatability limit factor: r = 2.8·s_r (≈ 1.96·√2, ISO 5725-6); likewise R = 2.8·s_R.
R_FACTOR = 2.8
#: Two nominal pressures of one force group more than this fraction apart are different
#: conditions (e.g. two cells with different pin radii in one map).
PRESSURE_SPLIT = 0.01
FORCE_DECIMALS = 6
TEMPERATURE_DECIMALS = 2
#: the group column of the nominal sliding speed [mm/s]
NOMINAL_SPEED = "nominal_speed_mm_s"
#: how a row that names no lab is shown: the map's own lab
OWN_LAB = "(own lab)"
#: the group column of the labs that measured a group (``;``-joined, sorted)
LABS = "labs"
#: the group column that flags a condition whose labs disagree beyond R
LABS_DISAGREE = "labs_disagree"
#: the group column of a per-lab table (``by_lab``): the one lab of the row
LAB = "lab"
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
    """Student-t 97.5 % quantile for ``dof`` degrees of freedom (two-sided 95 % CI), to
    about 1e-14 relative (``tests/test_stats.py`` holds it to SciPy's ``stdtrit`` for
    1 to 10⁵ degrees of freedom). Computed here, without SciPy, whose import costs a map
    write half a second of CPU: exact for 1 and 2 degrees of freedom, else Newton's
    method on the t distribution's upper tail (:func:`_t_upper_tail`) from the
    Cornish–Fisher expansion."""
    if dof < 1:
        raise ValueError(f"degrees of freedom must be at least 1, not {dof}")
    p = 0.975
    if dof == 1:
        return math.tan(math.pi * (p - 0.5))
    if dof == 2:
        return (2 * p - 1) / math.sqrt(2 * p * (1 - p))
    z = 1.959963984540054  # the standard normal 97.5 % quantile
    nu = float(dof)
    t = (z + (z**3 + z) / (4 * nu) + (5 * z**5 + 16 * z**3 + 3 * z) / (96 * nu**2)
         + (3 * z**7 + 19 * z**5 + 17 * z**3 - 15 * z) / (384 * nu**3))
    log_norm = (math.lgamma((nu + 1) / 2) - math.lgamma(nu / 2)
                - 0.5 * math.log(nu * math.pi))
    for _ in range(50):
        density = math.exp(log_norm - (nu + 1) / 2 * math.log1p(t * t / nu))
        step = (_t_upper_tail(t, nu) - (1 - p)) / density
        t += step
        if abs(step) <= 1e-15 * t:
            break
    return t


def _t_upper_tail(t: float, nu: float) -> float:
    """P(T > t) of Student's t with ``nu`` degrees of freedom, t ≥ 0: half the
    regularised incomplete beta function I_x(ν/2, 1/2) at x = ν/(ν + t²)."""
    return 0.5 * _beta_inc(nu / 2, 0.5, nu / (nu + t * t))


def _beta_inc(a: float, b: float, x: float) -> float:
    """The regularised incomplete beta function I_x(a, b), 0 ≤ x ≤ 1: its continued
    fraction (modified Lentz), on the side of x where it converges fast."""
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    front = math.exp(math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b)
                     + a * math.log(x) + b * math.log1p(-x))
    if x < (a + 1) / (a + b + 2):
        return front * _beta_fraction(a, b, x) / a
    return 1.0 - front * _beta_fraction(b, a, 1.0 - x) / b


def _beta_fraction(a: float, b: float, x: float) -> float:
    """The continued fraction of the incomplete beta function (Lentz's method, to the
    last bit of a double)."""
    tiny = 1e-300
    c, d = 1.0, 1.0 - (a + b) * x / (a + 1)
    d = 1.0 / (d if abs(d) > tiny else tiny)
    h = d
    for m in range(1, 10_000):
        aa = m * (b - m) * x / ((a + 2 * m - 1) * (a + 2 * m))
        for term in (aa, -(a + m) * (a + b + m) * x / ((a + 2 * m) * (a + 2 * m + 1))):
            d = 1.0 + term * d
            d = 1.0 / (d if abs(d) > tiny else tiny)
            c = 1.0 + term / c
            c = c if abs(c) > tiny else tiny
            h *= d * c
        if abs(d * c - 1.0) < 1e-16:
            break
    return h


@functools.lru_cache(maxsize=4096)
def stated_u(mu: float, normal_force_N: float) -> float:
    """The stated standard uncertainty (k = 1) of a μ that carries no budget of its own
    (an imported row): the GUM budget of the founding cell
    (:class:`~tribopipe.config.InstrumentConfig` defaults) at ``mu`` and the nominal
    total force ``normal_force_N`` [N], its reading term the resolution of ``mu`` as
    written (the last decimal of its shortest text, rectangular: 0.45 → 0.01/√12) and its
    torque zero unknown (:func:`~tribopipe.reduction.uncertainty.unknown_offset_u_Nm`).
    NaN for a μ or force that is not finite."""
    if not (math.isfinite(mu) and math.isfinite(normal_force_N) and normal_force_N > 0):
        return math.nan
    instrument = InstrumentConfig()
    text = repr(float(mu))
    decimals = len(text.split(".", 1)[1]) if "." in text and "e" not in text else 0
    resolution = 10.0 ** -decimals if decimals else 1.0
    parts = budget(mu, resolution / math.sqrt(12), normal_force_N=normal_force_N,
                   instrument=instrument, offset_u_Nm=unknown_offset_u_Nm(instrument))
    return parts["combined"]


@dataclass(frozen=True)
class Repeatability:
    """Pooled within-lab standard deviation of one quantity over the groups with repeats.

    ``s_r = sqrt(Σ dofᵢ·s_rᵢ² / Σ dofᵢ)`` with ``dofᵢ = nᵢ − labsᵢ`` (each lab's repeats
    apart; ``nᵢ − 1`` for a one-lab group) and ``dof = Σ dofᵢ``; ``r = 2.8·s_r``.
    NaN when no group has two values from one lab.
    """

    quantity: str
    s_r: float
    r: float
    dof: int
    n_groups: int


def repeatability(groups: pd.DataFrame, quantity: str = "mu_k") -> Repeatability:
    """The pooled repeatability of ``quantity`` ('mu_k' or 'mu_s') from a
    :func:`group_statistics` table (an older table without ``q_labs`` and ``q_s_r``:
    from ``q_n`` and ``q_std``, as one lab)."""
    import numpy as np

    n = groups[f"{quantity}_n"].to_numpy(dtype=float)
    if f"{quantity}_s_r" in groups.columns and f"{quantity}_labs" in groups.columns:
        s = groups[f"{quantity}_s_r"].to_numpy(dtype=float)
        dofs = n - groups[f"{quantity}_labs"].to_numpy(dtype=float)
    else:
        s = groups[f"{quantity}_std"].to_numpy(dtype=float)
        dofs = n - 1
    use = (dofs >= 1) & np.isfinite(s)
    dof = int(np.sum(dofs[use]))
    if dof == 0:
        return Repeatability(quantity, math.nan, math.nan, 0, 0)
    s_r = math.sqrt(float(np.sum(dofs[use] * s[use] ** 2)) / dof)
    return Repeatability(quantity, s_r, R_FACTOR * s_r, dof, int(use.sum()))


@dataclass(frozen=True)
class Reproducibility:
    """ISO 5725-2 precision of one quantity pooled over the map: ``s_r`` (the map's pooled
    repeatability, :func:`repeatability`), ``s_R = √(s_L² + s_r²)`` with the between-lab
    variance s_L² pooled over the conditions several labs measured
    (``Σ (pᵢ−1)·s_Lᵢ² / Σ (pᵢ−1)``), ``r = 2.8·s_r``, ``R = 2.8·s_R``, ``n_conditions``;
    NaN where unknown (no condition measured by two labs)."""

    quantity: str
    s_r: float
    s_R: float
    r: float
    R: float
    n_conditions: int


def reproducibility(groups: pd.DataFrame, quantity: str = "mu_k") -> Reproducibility:
    """The pooled reproducibility of ``quantity`` from a :func:`group_statistics` table."""
    import numpy as np

    rep = repeatability(groups, quantity)
    if f"{quantity}_s_R" not in groups.columns:
        return Reproducibility(quantity, rep.s_r, math.nan, rep.r, math.nan, 0)
    p = groups[f"{quantity}_labs"].to_numpy(dtype=float)
    s_L = groups[f"{quantity}_s_L"].to_numpy(dtype=float)
    use = (p >= 2) & np.isfinite(s_L)
    if not use.any():
        return Reproducibility(quantity, rep.s_r, math.nan, rep.r, math.nan, 0)
    s_L2 = float(np.sum((p[use] - 1) * s_L[use] ** 2) / np.sum(p[use] - 1))
    pooled = math.sqrt(s_L2 + (rep.s_r ** 2 if math.isfinite(rep.s_r) else 0.0))
    return Reproducibility(quantity, rep.s_r, pooled, rep.r, R_FACTOR * pooled,
                           int(use.sum()))


def critical_difference(s_r: float, s_R: float, n_a: int, n_b: int) -> float:
    """ISO 5725-6 §4.2.3: the critical difference of two labs' means of ``n_a`` and
    ``n_b`` results, CD = √(R² − r²(1 − 1/2n_a − 1/2n_b)) with r = 2.8·s_r, R = 2.8·s_R
    (s_r unknown: 0, the two means then compared with R alone). NaN when s_R is."""
    if not math.isfinite(s_R):
        return math.nan
    r = R_FACTOR * (s_r if math.isfinite(s_r) else 0.0)
    R = R_FACTOR * s_R
    return math.sqrt(max(R * R - r * r * (1 - 1 / (2 * n_a) - 1 / (2 * n_b)), 0.0))


def lab_names(runs: pd.DataFrame) -> Any:
    """The lab of each run as the statistics name it (an object array): its ``lab``, or
    :data:`OWN_LAB` where the row names none."""
    import numpy as np

    if "lab" not in runs.columns:
        return np.full(len(runs), OWN_LAB, dtype=object)
    return np.array([OWN_LAB if not isinstance(v, str) or not v.strip() else v
                     for v in runs["lab"].tolist()], dtype=object)


def select_labs(runs: pd.DataFrame, labs: Sequence[str] | None) -> pd.DataFrame:
    """The runs measured by one of ``labs`` (as :func:`lab_names` names them, compared
    without case; ``None``: all runs)."""
    if not labs:
        return runs
    wanted = {lab.strip().casefold() for lab in labs}
    keep = [str(v).casefold() in wanted for v in lab_names(runs)]
    return runs.loc[keep]


def nominal_speeds(runs: pd.DataFrame) -> Any:
    """The nominal sliding speed [mm/s] each run is grouped under (a float array): its
    ``nominal_speed_mm_s`` rounded by :func:`~tribopipe.labels.round_speed`, or
    :data:`~tribopipe.physics.FOUNDING_SLIDING_SPEED_MM_S` where the row has none (a map
    written before schema version 5, an imported row: measured at one speed as far as the
    map can tell, which the published map and tribopipe's default instrument both are)."""
    import numpy as np

    if NOMINAL_SPEED not in runs.columns:
        return np.full(len(runs), FOUNDING_SLIDING_SPEED_MM_S)
    values = runs[NOMINAL_SPEED].to_numpy(dtype=float)
    return np.array([round_speed(float(v)) if math.isfinite(v) and v > 0
                     else FOUNDING_SLIDING_SPEED_MM_S for v in values], dtype=float)


def pairs_with_several_speeds(runs: pd.DataFrame) -> set[tuple[str, str]]:
    """The (pin, disc) pairs whose included runs hold more than one nominal speed."""
    included = runs.loc[~runs["excluded"].astype(bool)]
    speeds: dict[tuple[str, str], set[float]] = {}
    for pin, disc, v in zip(included["pin"], included["disc"], nominal_speeds(included),
                            strict=True):
        speeds.setdefault((str(pin), str(disc)), set()).add(float(v))
    return {pair for pair, found in speeds.items() if len(found) > 1}


def group_keys(runs: pd.DataFrame, by_speed: bool, by_lab: bool = False) -> pd.DataFrame:
    """The rounded grouping keys of each run (a new frame; ``runs`` is not modified):
    pin, disc, force, temperature, nominal speed, test method (and the measured speed
    with ``by_speed``, the lab with ``by_lab``)."""
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
    if by_lab:
        keys[LAB] = lab_names(runs)
    return keys


def condition_keys(runs: pd.DataFrame) -> dict[str, tuple[Any, ...]]:
    """The condition group of each run, by ``measurement_id``: the key
    :func:`group_statistics` groups it under (:func:`group_keys`: pin, disc, nominal force
    [N] and temperature [°C] rounded, nominal speed [mm/s]), unknown values as ``None``.
    What a count of the groups a change touches compares."""
    keys = group_keys(runs, by_speed=False)
    ids = runs["measurement_id"].astype(str).tolist()
    return {mid: tuple(None if isinstance(v, float) and v != v else v for v in key)
            for mid, key in zip(ids, keys.itertuples(index=False, name=None), strict=True)}


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
                     show_speed: bool | None = None, by_lab: bool = False,
                     labs: Sequence[str] | None = None,
                     show_method: bool | None = None) -> pd.DataFrame:
    """Repeat statistics per condition group of a friction map (see module docstring).

    ``runs`` is a map DataFrame (:func:`tribopipe.frictionmap.read_map`); it is not
    modified. Excluded runs are left out, and with ``labs`` the runs of other labs
    (:func:`select_labs`); groups with no remaining run are dropped.
    Groups always split by nominal speed and by test method; ``show_speed`` says whether
    the table shows the speed (default: where some pair holds several nominal speeds),
    ``show_method`` whether it shows ``test_method`` (default: where the map holds several
    methods). With ``by_lab`` each lab's runs of a condition are a group of their own
    (column ``lab``).
    Columns: ``pin, disc, normal_force_N, pressure_kPa, temperature_C``
    (+ ``nominal_speed_mm_s`` when shown, + ``sliding_speed_mm_s``, the measured speed,
    with ``by_speed``, + ``lab`` with ``by_lab``), then for q in ``mu_k``, ``mu_s``:
    ``q_n, q_mean, q_std, q_sem, q_ci95_low, q_ci95_high, q_cv, q_min, q_max, q_u_run,
    q_u, q_u_estimated, q_labs, q_s_r, q_s_L, q_s_R, q_values``,
    then ``labs, range_exceeds_r, labs_disagree, qc_flagged, reviewed, run_ids``
    (``reviewed``: how many of the group's runs a reviewer accepted or re-windowed,
    :mod:`tribopipe.review`; an accepted run's QC flags do not make ``qc_flagged``). Within a group,
    values and ids are in (repeat, measurement_id) order, so the result does not depend
    on the row order. Rows are sorted by pin, disc, temperature, pressure, force, nominal
    speed (measured speed, lab).

    Two steps, each its own function: :func:`group_rows` (each condition's own figures,
    from its runs alone) and :func:`finish_groups` (what needs every group: the map's
    pooled r and the labs' critical difference, the order, the columns shown). A map
    folder keeps the first step's output for every condition
    (:mod:`tribopipe.frictionmap.stored_groups`), brought up to date for the conditions a
    write touches.
    """
    runs = select_labs(runs, labs)
    if show_speed is None:
        show_speed = bool(pairs_with_several_speeds(runs))
    if show_method is None:
        show_method = several_methods(runs)
    return finish_groups(group_rows(runs, by_speed=by_speed, by_lab=by_lab),
                         show_speed=show_speed, show_method=show_method,
                         by_speed=by_speed, by_lab=by_lab)


#: what joins a group's measurement ids in its ``run_ids`` cell (:func:`run_ids_of` reads it)
RUN_IDS_SEPARATOR = ";"


def run_ids_of(cell: object) -> list[str]:
    """The measurement ids a group's ``run_ids`` cell lists, in its order (none for an
    empty or missing cell)."""
    if not isinstance(cell, str) or not cell:
        return []
    return [i for i in cell.split(RUN_IDS_SEPARATOR) if i]


#: the map columns :func:`group_rows` reads (with ``sliding_speed_mm_s`` for ``by_speed``)
GROUP_INPUT_COLUMNS: tuple[str, ...] = (
    "measurement_id", "pin", "disc", "normal_force_N", "pressure_kPa", "temperature_C",
    NOMINAL_SPEED, TEST_METHOD, "excluded", "repeat", "flags", "review", "lab",
    "mu_k", "mu_s", "u_mu_k", "u_mu_s")
#: the condition key of :func:`group_rows`' rows (rounded as :func:`group_keys` rounds):
#: the rows of one key are the pressure clusters of one condition
CONDITION_KEY: tuple[str, ...] = ("pin", "disc", "normal_force_N", "temperature_C",
                                  NOMINAL_SPEED, TEST_METHOD)
#: the version of :func:`group_rows`' output: a stored copy of another version is not
#: used (raise it whenever what a group row holds, or how it is computed, changes)
GROUP_ROWS_VERSION = 1


def group_rows(runs: pd.DataFrame, *, by_speed: bool = False,
               by_lab: bool = False) -> pd.DataFrame:
    """Each condition group's own figures (the first step of :func:`group_statistics`),
    unsorted: one row per group of the included runs of ``runs``, with every key column
    (:data:`CONDITION_KEY`, the median nominal pressure [kPa]; the measured speed with
    ``by_speed``, the lab with ``by_lab``), the statistics of each quantity, ``labs``,
    ``qc_flagged``, ``reviewed``, ``run_ids``, and the private ``_q_lab_range`` and
    ``_q_lab_means`` (each lab's range and (mean, n)) that :func:`finish_groups` compares
    across groups. A row depends only on the runs of its own condition."""
    import numpy as np

    included = runs.loc[~runs["excluded"].astype(bool)]
    keys = group_keys(included, by_speed, by_lab)
    key_cols = list(keys.columns)
    # plain arrays once; per-group pandas slicing is what makes large maps slow
    data = {
        "pressure_kPa": included["pressure_kPa"].to_numpy(dtype=float),
        "normal_force_N": included["normal_force_N"].to_numpy(dtype=float),
        "repeat": included["repeat"].astype("Float64").to_numpy(dtype=float, na_value=np.nan),
        "measurement_id": included["measurement_id"].astype(str).to_numpy(dtype=object),
        "flags": included["flags"].fillna("").astype(str).to_numpy(dtype=object),
        "review": (included["review"].fillna("").astype(str).to_numpy(dtype=object)
                   if "review" in included else np.full(len(included), "", dtype=object)),
        "lab": lab_names(included),
    }
    for q in QUANTITIES:
        data[q] = included[q].to_numpy(dtype=float)
        data[f"u_{q}"] = (included[f"u_{q}"].to_numpy(dtype=float) if f"u_{q}" in included
                          else np.full(len(included), np.nan))
    rows = _Columns()
    for key, members in _condition_members(keys, data["pressure_kPa"]):
        rows.append(_group_row(dict(zip(key_cols, key, strict=True)), members, data))
    return rows.frame()


def _condition_members(keys: pd.DataFrame, pressures: Any
                       ) -> Iterator[tuple[tuple[Any, ...], Any]]:
    """The condition groups of the runs whose grouping keys are the rows of ``keys``
    (:func:`group_keys`) and nominal pressures [kPa] ``pressures``: per group its key (a
    value per column of ``keys``) and its members (positions into ``keys``, an integer
    array), one group per pressure cluster of a key, in the order :func:`group_rows`
    makes its rows."""
    import numpy as np

    if not len(keys):
        return
    grouped = keys.groupby(list(keys.columns), dropna=False, sort=False).indices
    for key, positions in grouped.items():
        key = key if isinstance(key, tuple) else (key,)
        if len(positions) == 1:  # one run, one cluster
            yield key, np.asarray(positions)
            continue
        clusters = _pressure_clusters([float(p) for p in pressures[positions]])
        for c in sorted(set(clusters)):
            # .indices holds integer arrays (typed as array, Index or list)
            yield key, np.asarray(positions)[[i for i, k in enumerate(clusters) if k == c]]


#: the columns of :func:`group_mu_k`'s table
GROUP_MU_K_COLUMNS: tuple[str, ...] = (
    "pin", "disc", "normal_force_N", "pressure_kPa", "temperature_C", NOMINAL_SPEED,
    "mu_k_n", "mu_k_mean", "run_ids")
#: the run columns :func:`group_mu_k` reads
GROUP_MU_K_INPUT: tuple[str, ...] = (
    "measurement_id", "pin", "disc", "normal_force_N", "pressure_kPa", "temperature_C",
    NOMINAL_SPEED, TEST_METHOD, "excluded", "repeat", "mu_k")


def group_mu_k(runs: pd.DataFrame) -> pd.DataFrame:
    """The columns :data:`GROUP_MU_K_COLUMNS` of :func:`group_statistics` (``show_speed``,
    every lab): per condition group of the included runs its key, median nominal pressure
    [kPa], μ_K count and mean, and its runs' ids, in the same row order, dtypes and values
    (each computed as :func:`group_rows` and :func:`finish_groups` compute it), without the
    other statistics (what a package's group table is checked against; some ten times
    less work at 10⁵ groups). ``runs`` needs the columns :data:`GROUP_MU_K_INPUT` only
    (``nominal_speed_mm_s`` and ``test_method`` may be absent)."""
    import numpy as np

    included = runs.loc[~runs["excluded"].astype(bool),
                        [c for c in GROUP_MU_K_INPUT if c in runs.columns]]
    keys = group_keys(included, by_speed=False)
    key_cols = list(keys.columns)
    pressures = included["pressure_kPa"].to_numpy(dtype=float)
    repeats: Any = included["repeat"].astype("Float64").to_numpy(dtype=float,
                                                                 na_value=np.nan)
    ids = included["measurement_id"].astype(str).to_numpy(dtype=object)
    mu_k = included["mu_k"].to_numpy(dtype=float)
    rows = _Columns()
    for key, members in _condition_members(keys, pressures):
        row: dict[str, Any] = dict(zip(key_cols, key, strict=True))
        if len(members) == 1:  # the median and mean of one value are the value
            i = int(members[0])
            row["pressure_kPa"] = float(pressures[i])
            finite = bool(np.isfinite(mu_k[i]))
            row["mu_k_n"] = int(finite)
            row["mu_k_mean"] = float(mu_k[i]) if finite else math.nan
            row["run_ids"] = str(ids[i])
        else:  # as _group_row and describe_values compute them
            order = sorted(members, key=lambda i: (_repeat_key(repeats[i]), ids[i]))
            row["pressure_kPa"] = float(np.median(pressures[order]))
            values = mu_k[order]
            values = values[np.isfinite(values)]
            row["mu_k_n"] = int(values.size)
            row["mu_k_mean"] = float(np.mean(values)) if values.size else math.nan
            row["run_ids"] = RUN_IDS_SEPARATOR.join(ids[order])
        rows.append(row)
    if not rows.n:
        return _empty_groups(GROUP_MU_K_COLUMNS)
    groups = _sorted_groups(rows.frame(), by_speed=False, by_lab=False)
    columns = list(GROUP_MU_K_COLUMNS)
    non_float = {c: _dtype(c) for c in columns if _dtype(c) != "float64"}
    return groups.astype(non_float).loc[:, columns]


def _empty_groups(columns: Sequence[str]) -> pd.DataFrame:
    """An empty group table of ``columns``, each of its group-table dtype."""
    import pandas as pd

    return pd.DataFrame({c: pd.Series(dtype=_dtype(c)) for c in columns})


class _Columns:
    """Rows (dicts) gathered as columns as they come: ``pd.DataFrame`` of the list of
    rows (a key a row lacks is NaN there, the columns in the order their keys first
    appear), without holding a dict per row (10⁵ groups of some 60 figures each)."""

    def __init__(self) -> None:
        self.columns: dict[str, list[Any]] = {}
        self.n = 0

    def append(self, row: Mapping[str, Any]) -> None:
        for name, value in row.items():
            column = self.columns.get(name)
            if column is None:
                column = self.columns[name] = [math.nan] * self.n
            column.append(value)
        self.n += 1
        if len(row) != len(self.columns):
            for column in self.columns.values():
                if len(column) < self.n:
                    column.append(math.nan)

    def frame(self) -> pd.DataFrame:
        import pandas as pd

        if not self.n:
            return pd.DataFrame([])
        return pd.DataFrame(self.columns, index=pd.RangeIndex(self.n))


def shown_columns(rows: pd.DataFrame) -> tuple[bool, bool]:
    """Whether a group table of the rows of :func:`group_rows` shows the nominal speed
    (some pair holds several) and the test method (the groups hold several): what
    :func:`pairs_with_several_speeds` and :func:`several_methods` say of the included
    runs, read from their groups."""
    if rows.empty:
        return False, False
    speeds = rows.groupby([rows["pin"].astype(str), rows["disc"].astype(str)])[
        NOMINAL_SPEED].nunique(dropna=False)
    return bool((speeds > 1).any()), rows[TEST_METHOD].nunique(dropna=False) > 1


def finish_groups(rows: pd.DataFrame, *, show_speed: bool, show_method: bool,
                  by_speed: bool = False, by_lab: bool = False) -> pd.DataFrame:
    """The group table of :func:`group_statistics` from the rows of :func:`group_rows`
    (any order): sorted, ``range_exceeds_r`` and ``labs_disagree`` decided from every
    group (the map's pooled r, the labs' critical difference), the columns shown."""
    import numpy as np

    condition_cols = ["pin", "disc", "normal_force_N", "pressure_kPa", "temperature_C"]
    if show_speed:
        condition_cols.append(NOMINAL_SPEED)
    if show_method:
        condition_cols.append(TEST_METHOD)
    if by_speed:
        condition_cols.append("sliding_speed_mm_s")
    if by_lab:
        condition_cols.append(LAB)
    stat_cols = [f"{q}_{f}" for q in QUANTITIES for f in GROUP_FIELDS]
    columns = condition_cols + stat_cols + [LABS, "range_exceeds_r", LABS_DISAGREE,
                                            "qc_flagged", "reviewed", "run_ids"]
    if rows.empty:
        return _empty_groups(columns)
    groups = _sorted_groups(rows, by_speed=by_speed, by_lab=by_lab)
    flagged = np.zeros(len(groups), dtype=bool)
    disagree = np.zeros(len(groups), dtype=bool)
    for q in QUANTITIES:
        rep = repeatability(groups, q)
        if math.isfinite(rep.r):
            spread = groups[f"_{q}_lab_range"].to_numpy(dtype=float)
            flagged |= np.nan_to_num(spread, nan=0.0) > rep.r
        disagree |= _labs_disagree(groups, q, reproducibility(groups, q))
    groups["range_exceeds_r"] = flagged
    groups[LABS_DISAGREE] = disagree
    # the types of _dtype, as for an empty table; numeric columns are left as computed
    non_float = {c: _dtype(c) for c in columns if _dtype(c) != "float64"}
    return groups.astype(non_float).loc[:, columns]


def _sorted_groups(rows: pd.DataFrame, *, by_speed: bool, by_lab: bool) -> pd.DataFrame:
    """Group rows in the group table's order: by pin, disc, temperature, pressure, force,
    nominal speed, test method (measured speed, lab), missing values last, ties as
    given; a new frame, indexed from 0."""
    return rows.sort_values(
        ["pin", "disc", "temperature_C", "pressure_kPa", "normal_force_N", NOMINAL_SPEED,
         TEST_METHOD] + (["sliding_speed_mm_s"] if by_speed else []) + ([LAB] if by_lab else []),
        na_position="last",
        kind="mergesort",
    ).reset_index(drop=True)


def _labs_disagree(groups: pd.DataFrame, q: str, rep: Reproducibility) -> Any:
    """Per group: two of its labs' means of ``q`` differ by more than their critical
    difference (:func:`critical_difference`, with the map's pooled s_r and s_R)."""
    import numpy as np

    out = np.zeros(len(groups), dtype=bool)
    if not math.isfinite(rep.s_R):
        return out
    for i, lab_means in enumerate(groups[f"_{q}_lab_means"]):
        means = list(lab_means)
        for a in range(len(means)):
            for b in range(a + 1, len(means)):
                (m_a, n_a), (m_b, n_b) = means[a], means[b]
                cd = critical_difference(rep.s_r, rep.s_R, n_a, n_b)
                if math.isfinite(cd) and abs(m_a - m_b) > cd:
                    out[i] = True
    return out


def _dtype(column: str) -> str:
    if column in ("pin", "disc", "run_ids", LABS, LAB, TEST_METHOD) or \
            column.endswith("_values"):
        return "str"
    if column.endswith("_n") or column.endswith("_labs") or column == "reviewed":
        return "int64"
    if column in ("range_exceeds_r", "qc_flagged", LABS_DISAGREE) or \
            column.endswith("_u_estimated"):
        return "bool"
    return "float64"


def _group_row(
    key: dict[str, Any], members: Any, data: dict[str, Any]
) -> dict[str, Any]:
    """One output row (``range_exceeds_r`` and ``labs_disagree`` come later, from all
    groups, through the private ``_q_lab_range`` and ``_q_lab_means``): ``members`` are
    positions into the per-run arrays of ``data``."""
    import numpy as np

    order = sorted(
        members,
        key=lambda i: (_repeat_key(data["repeat"][i]), data["measurement_id"][i]),
    )
    row: dict[str, Any] = dict(key)
    row["pressure_kPa"] = float(np.median(data["pressure_kPa"][order]))
    labs_of = data["lab"][order]
    for q in QUANTITIES:
        values = data[q][order]
        finite = np.isfinite(values)
        stats = describe_values(values[finite])
        row.update({f"{q}_{f}": v for f, v in stats.items()})
        u_runs = data[f"u_{q}"][order][finite]
        forces = data["normal_force_N"][order][finite]
        estimated = ~np.isfinite(u_runs)
        u_runs = np.where(estimated, [stated_u(float(m), float(f)) for m, f in
                                      zip(values[finite], forces, strict=True)], u_runs)
        row.update(_lab_precision(values[finite], u_runs, labs_of[finite], q))
        row[f"{q}_u_estimated"] = bool(estimated.any())
    row[LABS] = ";".join(sorted(set(labs_of.tolist())))
    # a reviewer who accepted a run has judged its flags: they no longer count
    row["qc_flagged"] = any(quality_flags(f) for f, r in zip(data["flags"][order],
                            data["review"][order], strict=True) if r != "accept")
    row["reviewed"] = sum(1 for r in data["review"][order] if r)
    row["run_ids"] = RUN_IDS_SEPARATOR.join(data["measurement_id"][order])
    return row


def _lab_precision(values: Any, u_runs: Any, labs: Any, q: str) -> dict[str, Any]:
    """The uncertainty and ISO 5725-2 columns of ``q`` for one condition group: its runs'
    ``values``, standard uncertainties ``u_runs`` (a budget or the stated estimate) and
    ``labs``, all in the group's order (module docstring)."""
    import numpy as np

    out: dict[str, Any] = {f"{q}_u_run": math.nan, f"{q}_u": math.nan, f"{q}_labs": 0,
                           f"{q}_s_r": math.nan, f"{q}_s_L": math.nan, f"{q}_s_R": math.nan,
                           f"_{q}_lab_range": math.nan, f"_{q}_lab_means": ()}
    if values.size == 0:
        return out
    names = sorted(set(labs.tolist()))
    per_lab = []
    for lab in names:
        sel = labs == lab
        x, u = values[sel], u_runs[sel]
        n = int(x.size)
        mean = float(np.mean(x))
        s = float(np.std(x, ddof=1)) if n > 1 else math.nan
        u_run = float(np.mean(u)) if np.isfinite(u).all() else math.nan
        sem = s / math.sqrt(n) if n > 1 else 0.0
        per_lab.append((n, mean, s, u_run, math.hypot(sem, u_run),
                        float(np.ptp(x)) if n > 1 else math.nan))
    n_i = np.array([p[0] for p in per_lab], dtype=float)
    means = np.array([p[1] for p in per_lab])
    s_i = np.array([p[2] for p in per_lab])
    u_i = np.array([p[4] for p in per_lab])
    dof = n_i - 1
    with_dof = dof > 0
    s_r = (math.sqrt(float(np.sum(dof[with_dof] * s_i[with_dof] ** 2) / np.sum(dof[with_dof])))
           if with_dof.any() else math.nan)
    out.update({
        f"{q}_u_run": float(np.mean(u_runs)) if np.isfinite(u_runs).all() else math.nan,
        f"{q}_labs": len(names),
        f"{q}_s_r": s_r,
        f"_{q}_lab_range": float(np.nanmax([p[5] for p in per_lab]))
        if any(math.isfinite(p[5]) for p in per_lab) else math.nan,
        f"_{q}_lab_means": tuple((float(m), int(n)) for m, n in zip(means, n_i, strict=True)),
    })
    p = len(names)
    if p == 1:
        out[f"{q}_u"] = float(u_i[0])
        return out
    total = float(np.sum(n_i))
    grand = float(np.sum(n_i * means) / total)
    s_d2 = float(np.sum(n_i * (means - grand) ** 2) / (p - 1))
    n_bar = (total - float(np.sum(n_i ** 2)) / total) / (p - 1)
    # no repeats in any lab: the spread of the means is all the map can tell
    s_r2 = s_r ** 2 if math.isfinite(s_r) else 0.0
    s_L2 = max(0.0, (s_d2 - s_r2) / n_bar)
    out[f"{q}_s_L"] = math.sqrt(s_L2)
    out[f"{q}_s_R"] = math.sqrt(s_L2 + s_r2)
    out[f"{q}_u"] = math.sqrt(float(np.max(u_i ** 2)) + s_L2)
    return out


def _repeat_key(value: float) -> tuple[int, int]:
    return (1, 0) if math.isnan(value) else (0, int(value))


def group_u(groups: pd.DataFrame, quantity: str = "mu_k") -> tuple[pd.Series, pd.Series]:
    """``(u, budget)`` per group of ``quantity``: the standard uncertainty of the group mean
    (GUM, k = 1) that every output's U = 2u reads, and whether it holds only the runs' own
    budgets (False where some run's u is the stated estimate of :func:`stated_u`).

    ``u`` is the group's combined ``q_u`` (runs' budgets or stated estimates beside the
    repeat scatter and the between-lab component); a table without it (written before
    it existed) gives its repeat scatter, ``q_sem``; NaN where neither is known. Columns
    that are absent count as unknown.
    """
    import pandas as pd

    def column(name: str) -> pd.Series:
        """A numeric column of ``groups`` (all NaN when absent)."""
        if name not in groups.columns:
            return pd.Series(math.nan, index=groups.index, dtype=float)
        return pd.to_numeric(groups[name], errors="coerce").astype(float)

    u_group = column(f"{quantity}_u")
    known = u_group.notna()
    if f"{quantity}_u_estimated" in groups.columns:
        estimated = groups[f"{quantity}_u_estimated"].astype(str).str.lower().isin(
            ["true", "1"])
        budget = known & ~estimated
    else:
        budget = known
    return u_group.where(known, column(f"{quantity}_sem")), budget


#: the columns of :func:`lab_comparison`, after the condition's
COMPARE_FIELDS: tuple[str, ...] = (
    "lab_a", "n_a", "mean_a", "U_a", "lab_b", "n_b", "mean_b", "U_b", "difference",
    "U_difference", "En", "z_a", "z_b", "labs_disagree")


def lab_comparison(runs: pd.DataFrame, quantity: str = "mu_k") -> pd.DataFrame:
    """Labs side by side at every condition two of them measured (``map compare``): one
    row per condition and pair of labs, the condition's columns, then
    :data:`COMPARE_FIELDS`: each lab's number of runs, mean and expanded uncertainty of
    its mean (U = 2u, k = 2, its own budget), the difference a − b and its
    U = √(U_a² + U_b²), ISO 13528's En number (difference / U_difference; |En| > 1: the
    two disagree beyond their stated uncertainties) and each lab's z score
    (ISO 13528 §9.4: z = (x − x_pt)/σ_pt, with x_pt the condition's pooled mean over its
    labs and σ_pt the map's pooled reproducibility s_R, :func:`reproducibility`; NaN where
    no condition gives s_R), and the condition's ``labs_disagree``."""
    import numpy as np
    import pandas as pd

    # the test method is part of the condition: two methods are never compared as one
    by_lab = group_statistics(runs, by_lab=True, show_speed=True, show_method=True)
    pooled = group_statistics(runs, show_speed=True, show_method=True)
    keys = ["pin", "disc", "normal_force_N", "temperature_C", NOMINAL_SPEED, TEST_METHOD]
    sigma = reproducibility(pooled, quantity).s_R
    rows = []
    pooled_rows = {tuple(_key_value(g[k]) for k in keys): g
                   for g in pooled.to_dict(orient="records")}
    grouped: dict[tuple[Any, ...], list[dict[Any, Any]]] = {}
    for g in by_lab.to_dict(orient="records"):
        if g[f"{quantity}_n"] > 0:
            grouped.setdefault(tuple(_key_value(g[k]) for k in keys), []).append(g)
    for key, labs in grouped.items():
        if len(labs) < 2:
            continue
        condition = pooled_rows[key]
        centre = float(condition[f"{quantity}_mean"])
        for i in range(len(labs)):
            for j in range(i + 1, len(labs)):
                a, b = labs[i], labs[j]
                u_a, u_b = 2 * float(a[f"{quantity}_u"]), 2 * float(b[f"{quantity}_u"])
                diff = float(a[f"{quantity}_mean"]) - float(b[f"{quantity}_mean"])
                u_diff = math.hypot(u_a, u_b)
                rows.append({
                    **{k: condition[k] for k in ("pin", "disc", "normal_force_N",
                                                 "pressure_kPa", "temperature_C",
                                                 NOMINAL_SPEED, TEST_METHOD)},
                    "lab_a": a[LAB], "n_a": int(a[f"{quantity}_n"]),
                    "mean_a": float(a[f"{quantity}_mean"]), "U_a": u_a,
                    "lab_b": b[LAB], "n_b": int(b[f"{quantity}_n"]),
                    "mean_b": float(b[f"{quantity}_mean"]), "U_b": u_b,
                    "difference": diff, "U_difference": u_diff,
                    "En": diff / u_diff if u_diff > 0 else math.nan,
                    "z_a": (float(a[f"{quantity}_mean"]) - centre) / sigma
                    if sigma > 0 else math.nan,
                    "z_b": (float(b[f"{quantity}_mean"]) - centre) / sigma
                    if sigma > 0 else math.nan,
                    "labs_disagree": bool(condition[LABS_DISAGREE]),
                })
    columns = ["pin", "disc", "normal_force_N", "pressure_kPa", "temperature_C",
               NOMINAL_SPEED, TEST_METHOD, *COMPARE_FIELDS]
    if not rows:
        return pd.DataFrame({c: pd.Series(dtype=object) for c in columns})
    out = pd.DataFrame(rows, columns=columns)
    out["En"] = out["En"].astype(float)
    return out.replace({np.inf: np.nan})


def _key_value(value: Any) -> Any:
    """A grouping key as compared across tables (floats rounded, NaN as ``None``)."""
    if isinstance(value, float):
        return None if math.isnan(value) else round(value, 6)
    return value
