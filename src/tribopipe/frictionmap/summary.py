"""A readable account of a friction map (``tribopipe map show``)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from ..errors import MapError
from ..escape import display_path, printable
from ..labels import flag_list
from ..materials import Vocabulary, shipped_vocabulary
from ..measurement import run_name
from ..stats import GROUP_INPUT_COLUMNS, repeatability
from .checks import validate_runs
from .schema import RUN_COLUMNS, MapRow, frame_rows, is_missing
from .snapshot import MapSource, as_snapshot
from .store import verify_map
from .synthetic_rows import synthetic_note

if TYPE_CHECKING:
    import pandas as pd

#: the columns :func:`map_summary` reads of every run (the condition groups' inputs, for
#: a map without stored groups, and the sources); the runs it shows whole (excluded and
#: reviewed ones) are read whole apart
SUMMARY_COLUMNS: tuple[str, ...] = tuple(
    c for c in RUN_COLUMNS if c in {*GROUP_INPUT_COLUMNS, "source"})


def map_summary(path: MapSource, *, runs_listed: bool = False) -> str:
    """A readable multi-line summary of the map at ``path``: runs, pairs, conditions,
    sources, flags, excluded runs (with reasons and where each came from) and the pooled
    repeatability; with ``runs_listed``, then one line per run (:func:`run_line`).
    ``path``: the map opened (:func:`~tribopipe.frictionmap.snapshot.open_map`: with
    :data:`SUMMARY_COLUMNS` at least, every column for ``runs_listed``), or its path
    (opened so)."""
    snap = as_snapshot(path, None if runs_listed else SUMMARY_COLUMNS)
    p = snap.path
    if not snap.exists:
        raise MapError("friction map not found", path=p, hint="pass --map PATH")
    runs = snap.runs
    lines = [f"friction map {display_path(p)}"]
    n_ex = int(runs["excluded"].sum())
    lines.append(f"  runs: {len(runs)} ({n_ex} excluded)")
    if runs.empty:
        return "\n".join(lines)
    note = synthetic_note(runs)
    if note is not None:
        lines.append(f"  {note}")
    groups = snap.groups()
    # per pair, the columns it prints only (not every column of each pair's rows)
    pairs = runs.loc[:, ["pin", "disc", "normal_force_N", "temperature_C"]].groupby(
        ["pin", "disc"], sort=True)
    lines.append(f"  contact pairs: {pairs.ngroups}; condition groups: {len(groups)}")
    for source, n in runs["source"].value_counts().sort_index().items():
        lines.append(f"  source {source}: {_runs(n)}")
    for lab, n in runs["lab"].fillna("(this lab)").value_counts().sort_index().items():
        lines.append(f"  lab {_text(lab)}: {_runs(n)}")
    lines.append("")
    lines.append("  pin / disc: runs, conditions, force [N], temperature [°C]")
    n_runs = pairs.size()
    force_values = pairs["normal_force_N"].unique()
    temp_values = pairs["temperature_C"].unique()
    conditions = (groups.groupby(["pin", "disc"]).size().to_dict() if len(groups)
                  else {})
    for key, n, f_values, t_values in zip(
            n_runs.index, n_runs, force_values.loc[n_runs.index],
            temp_values.loc[n_runs.index], strict=True):
        pin, disc = cast("tuple[Any, Any]", key)
        forces = ", ".join(f"{f:g}" for f in _sorted_values(f_values))
        temps = ", ".join(f"{t:g}" for t in _sorted_values(t_values))
        n_cond = int(conditions.get((pin, disc), 0))
        lines.append(f"    {_text(pin)} / {_text(disc)}: {_runs(int(n))}, {n_cond} conditions, "
                     f"F {forces or '-'}, T {temps or '-'}")
    flag_counts: dict[str, int] = {}
    # each distinct flags text once (a map holds few), counted by its rows
    for text, n in runs["flags"].fillna("").value_counts(sort=False).items():
        for f in flag_list(str(text)):
            flag_counts[f] = flag_counts.get(f, 0) + int(n)
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
    # the excluded and reviewed runs are shown whole: every column of those rows only
    shown = runs["excluded"]
    if "review" in runs.columns:
        shown = shown | runs["review"].notna()
    whole = snap.rows_of(runs.loc[shown, "measurement_id"]) if shown.any() else None
    excluded = whole[whole["excluded"]] if whole is not None else runs.iloc[:0]
    if len(excluded):
        lines.append("")
        lines.append("  excluded runs:")
        for row in frame_rows(excluded):
            lines.append(f"    {row.measurement_id}  {_text(row.pin)} / "
                         f"{_text(row.disc)}, {row.normal_force_N:g} N, "
                         f"{_fmt_t(row.temperature_C)}, repeat {_fmt_repeat(row.repeat)}"
                         f", from {run_origin(row)}: {_text(row.exclusion_reason)}")
    lines += _review_lines(whole, groups) if whole is not None else []
    if runs_listed:
        snap.require(RUN_COLUMNS)
        lines.append("")
        lines.append("  runs: id, from (file [test / result / interval]), pin / disc, "
                     "nominal F and T, repeat, mu_k, mu_s, flags")
        ordered = runs.sort_values(["source_file", "test", "result", "interval",
                                    "measurement_id"], kind="mergesort", na_position="first")
        lines += ["    " + run_line(row) for row in frame_rows(ordered)]
    return "\n".join(lines)


def _sorted_values(values: Any) -> list[float]:
    """The distinct numbers of one pair's column, sorted, missing ones left out."""
    return sorted(float(v) for v in values if not is_missing(v))


def _review_lines(runs: Any, groups: Any) -> list[str]:
    """The reviewed runs (a lab's ``review.csv``, :mod:`tribopipe.review`): how many by
    decision and per condition group, and one line per run with the automatic μ beside
    the reviewed one, who, when and why."""
    if "review" not in runs.columns or not runs["review"].notna().any():
        return []
    done = runs[runs["review"].notna()]
    counts = done["review"].astype(str).value_counts().sort_index()
    lines = ["", f"  reviewed runs: {len(done)} ("
             + ", ".join(f"{a} {n}" for a, n in counts.items()) + ")"]
    in_groups = groups[groups["reviewed"] > 0] if "reviewed" in groups else groups.iloc[:0]
    for g in in_groups.to_dict(orient="records", into=dict):
        lines.append(f"    group {_text(g['pin'])} / {_text(g['disc'])}, "
                     f"{g['normal_force_N']:g} N, {_fmt_t(g['temperature_C'])}: "
                     f"{g['reviewed']} of {g['mu_k_n']} runs reviewed")
    for row in frame_rows(done):
        what = _text(row.review)
        if row.review == "window":
            what += (f" {_num(row.mu_k_window_start_mm, '.4g')}–"
                     f"{_num(row.mu_k_window_end_mm, '.4g')} mm: "
                     f"mu_k {row.mu_k:.4f} (automatic {_num(row.auto_mu_k, '.4f')})")
            if row.review_static_peak_mm is not None:
                what += (f", mu_s {_num(row.mu_s, '.4f')} "
                         f"(automatic {_num(row.auto_mu_s, '.4f')})")
        who = ", ".join(_text(v) for v in (row.review_by, row.review_date) if v is not None)
        why = "" if row.review_reason is None else f": {_text(row.review_reason)}"
        lines.append(f"    {row.measurement_id}  {what}" + (f" [{who}]" if who else "") + why)
    return lines


def _text(value: Any) -> str:
    """A text cell of the map as one printable line (:func:`~tribopipe.escape.printable`:
    a merged map's names are data, never terminal commands)."""
    if is_missing(value):
        return "?"
    return printable(str(value))


def run_origin(row: MapRow) -> str:
    """Where a map row came from: ``file [test / result / interval i]`` (the parts the row
    knows; a row of a map older than schema version 4 names no test or result)."""
    test, result = (None if v is None else _text(v) for v in (row.test, row.result))
    return run_name(_text(row.source_file), test, result, row.interval)


def run_line(row: MapRow) -> str:
    """One run of the map on one line: the first 16 digits of its id, where it came from,
    pin / disc, nominal force [N] and temperature [°C], repeat, μ_K, μ_S and flags."""
    mu_s = "" if row.mu_s is None else f", mu_s {row.mu_s:.3f}"
    flags = printable(", ".join(flag_list(row.flags))) or "-"
    excluded = " (excluded)" if row.excluded else ""
    if row.review is not None:
        excluded += f" (reviewed: {_text(row.review)})"
    return (f"{row.measurement_id}  {run_origin(row)}  {_text(row.pin)} / "
            f"{_text(row.disc)}, {row.normal_force_N:g} N, {_fmt_t(row.temperature_C)}"
            f", repeat {_fmt_repeat(row.repeat)}: mu_k {row.mu_k:.3f}{mu_s}; flags "
            f"{flags}{excluded}")


def _num(value: float | None, spec: str) -> str:
    """A number of a row as ``format(value, spec)``; ``?`` where the row holds none."""
    return "?" if value is None else format(value, spec)


def _runs(n: int) -> str:
    return f"{n} run" if n == 1 else f"{n} runs"


def _fmt_t(value: float | None) -> str:
    return "T ?" if is_missing(value) else f"{value:g} °C"


def _fmt_repeat(value: int | None) -> str:
    return "?" if value is None else str(value)


def unresolved_names(runs: pd.DataFrame, vocabulary: Vocabulary) -> list[str]:
    """One line per pin or disc name of ``runs`` that is not a canonical name of
    ``vocabulary``, with how many rows hold it and the fix: the canonical name it
    resolves to (re-import or merge it again, or relabel), or a did-you-mean and how to
    add the material."""
    lines = []
    for what in ("pin", "disc"):
        counts: dict[str, int] = {}
        for value in runs[what].dropna().astype(str):
            counts[value] = counts.get(value, 0) + 1
        for name, n in sorted(counts.items()):
            if name in vocabulary:
                continue
            found = vocabulary.candidates(name)
            rows = f"{n} row(s)"
            if len(found) == 1:
                lines.append(f"{what} {name!r} ({rows}) is not a canonical name: it is "
                             f"{found[0]!r}; merge or import the rows again (names are "
                             "resolved on the way in), or reduce them again")
            else:
                problem = vocabulary.problem(name, what)
                lines.append(f"{problem} ({rows}); add it to the lab's materials.toml "
                             f"(`tribopipe materials add`) or relabel the runs")
    return lines


def check_map_file(path: str | os.PathLike[str], vocabulary: Vocabulary | None = None
                   ) -> tuple[list[str], str, dict[str, Any]]:
    """Check the friction map (Parquet) at ``path`` as ``map publish`` would before
    writing a package: every row against the map's rules
    (:func:`~tribopipe.frictionmap.checks.validate_runs`), and every pin and disc name
    against the materials ``vocabulary`` (default: the shipped one,
    :func:`unresolved_names`). Returns one line per problem, a verdict line and the
    map's metadata as the check read it (:func:`~tribopipe.frictionmap.store.verify_map`:
    its schema version among them; nothing is read twice). Raises :class:`MapError` for
    a file that is absent or not a friction map."""
    p = Path(path)
    if not os.path.lexists(p):  # read_map takes an absent map as empty: no file to pass
        raise MapError("file not found, expected a friction map (Parquet) or a data "
                       "package", path=p)
    runs, info = verify_map(p)  # every check there is: parts, checksums, every row
    problems = [problem.line(display_path(p)) for problem in validate_runs(runs)]
    problems += [f"{display_path(p)}: {line}" for line in
                 unresolved_names(runs, vocabulary or shipped_vocabulary())]
    note = synthetic_note(runs)
    verdict = (f"friction map {display_path(p)}: {_runs(len(runs))}, "
               + (f"{len(problems)} problem(s)" if problems else "every row passes the checks")
               + (f"; {note}" if note else ""))
    return problems, verdict, info
