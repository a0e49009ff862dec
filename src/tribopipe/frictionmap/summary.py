"""A readable account of a friction map (``tribopipe map show``)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from ..errors import MapError
from ..stats import group_statistics, repeatability
from .schema import _missing
from .store import read_map


def map_summary(path: str | os.PathLike[str]) -> str:
    """A readable multi-line summary of the map at ``path``: runs, pairs, conditions,
    sources, flags, excluded runs (with reasons) and the pooled repeatability."""
    p = Path(path)
    if not p.exists():
        raise MapError("friction map not found", path=p, hint="pass --map PATH")
    runs = read_map(p)
    lines = [f"friction map {p}"]
    n_ex = int(runs["excluded"].sum())
    lines.append(f"  runs: {len(runs)} ({n_ex} excluded)")
    if runs.empty:
        return "\n".join(lines)
    groups = group_statistics(runs)
    pairs = runs.groupby(["pin", "disc"], sort=True)
    lines.append(f"  contact pairs: {pairs.ngroups}; condition groups: {len(groups)}")
    for source, n in runs["source"].value_counts().sort_index().items():
        lines.append(f"  source {source}: {_runs(n)}")
    for lab, n in runs["lab"].fillna("(this lab)").value_counts().sort_index().items():
        lines.append(f"  lab {lab}: {_runs(n)}")
    lines.append("")
    lines.append("  pin / disc: runs, conditions, force [N], temperature [°C]")
    for (pin, disc), sub in pairs:
        forces = ", ".join(f"{f:g}" for f in sorted(sub["normal_force_N"].dropna().unique()))
        temps = ", ".join(f"{t:g}" for t in sorted(sub["temperature_C"].dropna().unique()))
        n_cond = int(((groups["pin"] == pin) & (groups["disc"] == disc)).sum())
        lines.append(f"    {pin} / {disc}: {_runs(len(sub))}, {n_cond} conditions, "
                     f"F {forces or '-'}, T {temps or '-'}")
    flag_counts: dict[str, int] = {}
    for text in runs["flags"].dropna():
        for f in filter(None, text.split(";")):
            flag_counts[f] = flag_counts.get(f, 0) + 1
    lines.append("")
    if flag_counts:
        lines.append("  flags: " + ", ".join(f"{k} {v}" for k, v in sorted(flag_counts.items())))
    else:
        lines.append("  flags: none")
    flagged = int(groups["qc_flagged"].sum()) if len(groups) else 0
    wide = int(groups["range_exceeds_r"].sum()) if len(groups) else 0
    lines.append(f"  groups with flagged runs: {flagged}; groups with range > r: {wide}")
    for q in ("mu_k", "mu_s"):
        rep = repeatability(groups, q)
        if rep.dof:
            lines.append(f"  repeatability {q}: s_r = {rep.s_r:.4g} ({rep.dof} dof from "
                         f"{rep.n_groups} groups), r = 2.8·s_r = {rep.r:.4g}")
        else:
            lines.append(f"  repeatability {q}: no group with two or more values")
    excluded = runs[runs["excluded"]]
    if len(excluded):
        lines.append("")
        lines.append("  excluded runs:")
        for row in excluded.itertuples(index=False):
            lines.append(f"    {row.measurement_id}  {row.pin} / {row.disc}, "
                         f"{row.normal_force_N:g} N, {_fmt_t(row.temperature_C)}, "
                         f"repeat {_fmt_repeat(row.repeat)}: {row.exclusion_reason}")
    return "\n".join(lines)


def _runs(n: int) -> str:
    return f"{n} run" if n == 1 else f"{n} runs"


def _fmt_t(value: float) -> str:
    return "T ?" if _missing(value) else f"{value:g} °C"


def _fmt_repeat(value: Any) -> str:
    return "?" if _missing(value) else str(value)
