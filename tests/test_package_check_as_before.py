"""The package check made lighter for packages of 10⁵ condition groups says what it said
before: each changed step is held equal to the code it replaced (kept here, as it was),
run on the same real package, clean and broken in each way the step compares (a changed
cell of ``groups.csv``, a missing group, an extra group, a group differing in one figure,
a group number twice, ``runs.csv`` against ``runs.parquet``, the linking table, the
7-column table, the group table's Parquet copy): the same problems, the same lines, in the
same order, the same verdict; and so does the check that keeps no runs but their labs
(``check_package(keep_runs=False)``, what ``map publish`` and ``map validate`` call)."""

from __future__ import annotations

import csv
import io
import math
import shutil
from pathlib import Path
from typing import Any, cast

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from reduced_runs import make_processed
from test_package_groups import rehash
from tribopipe import frictionmap as fm
from tribopipe.cli import main
from tribopipe.frictionmap import package as P
from tribopipe.frictionmap.datapackage import GROUP_ID
from tribopipe.frictionmap.profile import LINKED_GROUPS_VERSION
from tribopipe.frictionmap.published import published_csv_path
from tribopipe.frictionmap.schema import is_missing
from tribopipe.frictionmap.store import same_value
from tribopipe.stats import (
    GROUP_MU_K_COLUMNS,
    NOMINAL_SPEED,
    group_mu_k,
    group_statistics,
    run_ids_of,
)

# --------------------------------------------------------------------------- as it was


def _records_before(columns: dict[str, Any]) -> list[dict[str, Any]]:
    names = list(columns)
    values = [[None if is_missing(v) else v for v in columns[n].tolist()] for n in names]
    return [dict(zip(names, row, strict=True)) for row in zip(*values, strict=True)]


def _key_before(row: dict[str, Any], keys: tuple[str, ...]) -> tuple[Any, ...]:
    out = []
    for k in keys:
        v = row[k]
        if isinstance(v, float) and math.isnan(v):
            v = None
        out.append(round(float(v), 9) if isinstance(v, int | float) and v is not None else v)
    return tuple(out)


def _check_groups_before(check: Any, res: dict[str, Any], columns: dict[str, Any],
                         runs: pd.DataFrame) -> dict[int, frozenset[str]] | None:
    """package._check_groups as it was: every group's statistics, rows as dicts."""
    shown = str(res.get("path"))
    fields = cast("list[dict[str, Any]]", P._group_fields(res))
    keys: tuple[str, ...] = ("pin", "disc", "normal_force_N", "temperature_C")
    names = {f["name"] for f in fields}
    if not {*keys, "mu_k_n", "mu_k_mean"} <= names:
        check.add(shown, "schema: expected the fields pin, disc, normal_force_N, "
                  "temperature_C, mu_k_n and mu_k_mean")
        return None
    linked = check.result.profile_version >= LINKED_GROUPS_VERSION
    if linked and not any(f["name"] == GROUP_ID and f.get("type") == "integer"
                          for f in fields):
        check.add(shown, f"schema: expected the field {GROUP_ID!r} (integer), the group's "
                  f"number, which package profile version {check.result.profile_version} "
                  "requires")
        return None
    if "nominal_speed_mm_s" in names:
        keys += ("nominal_speed_mm_s",)
    used = (*keys, "mu_k_n", "mu_k_mean", GROUP_ID)
    rows = _records_before({name: columns[name] for name in columns if name in used})
    groups = group_statistics(runs, show_speed=True)
    computed = {_key_before(g, keys): g for g in groups.loc[:, [
        c for c in groups.columns if c in (*keys, "mu_k_n", "mu_k_mean", "run_ids")]].to_dict(
        orient="records", into=dict)}
    del groups
    if len(rows) != len(computed):
        check.add(shown, f"{len(rows)} groups, the runs make {len(computed)}")
    members: dict[int, frozenset[str]] = {}
    first: dict[int, int] = {}
    for n, row in enumerate(rows, 1):
        number = row.get(GROUP_ID) if linked else None
        if isinstance(number, int) and number < 1:
            check.add(shown, f"row {n}, field {GROUP_ID}: {number} is not a group number "
                      "(expected 1 or more)")
            number = None
        if isinstance(number, int):
            if number in first:
                check.add(shown, f"row {n}, field {GROUP_ID}: group {number} appears twice "
                          f"(first in row {first[number]})")
                number = None
            else:
                first[number] = n
        g = computed.get(_key_before(row, keys))
        if g is None:
            check.add(shown, f"row {n}: no runs of this group in the runs table")
            continue
        for name in ("mu_k_n", "mu_k_mean"):
            if not same_value(row[name], g[name]):
                check.add(shown, f"row {n}, field {name}: {row[name]!r} does not follow "
                          f"from the runs ({g[name]!r})")
        if isinstance(number, int):
            members[number] = frozenset(run_ids_of(g["run_ids"]))
    return members if linked else None


def _check_groups_copy_before(check: Any, res: dict[str, Any], path: Path,
                              columns: dict[str, Any]) -> None:
    """package._check_groups_copy as it was: a frame of the CSV's columns."""
    import pyarrow as pa

    shown = str(res.get("path"))
    parquet = P._open_parquet(check, path, shown)
    if parquet is None:
        return
    try:
        copy = parquet.read().to_pandas()
    except (pa.ArrowException, OSError, ValueError) as exc:
        check.add(shown, f"not a readable Parquet file ({str(exc)[:120]})")
        return
    names = list(columns)
    if list(copy.columns) != names:
        check.add(shown, f"columns {list(map(str, copy.columns))} differ from the CSV's "
                  f"{names}")
        return
    n = len(next(iter(columns.values()))) if columns else 0
    if len(copy) != n:
        check.add(shown, f"{len(copy)} rows, the CSV has {n}")
        return
    csv_frame = pd.DataFrame({name: pd.Series(columns[name]) for name in names})
    # a CSV cannot tell an empty text from a missing one: neither can the comparison
    for frame in (csv_frame, copy):
        for name in names:
            if frame[name].dtype.kind in "OUT" or str(frame[name].dtype) == "str":
                frame[name] = frame[name].mask(frame[name].astype(object) == "")
    try:
        differs = np.column_stack([~P._same_values(csv_frame[name], copy[name])
                                   for name in names]) if names else np.zeros((n, 0), bool)
    except (TypeError, ValueError) as exc:
        check.add(shown, f"not comparable with the CSV ({str(exc)[:120]})")
        return
    P._name_differences(check, shown, differs, names, csv_frame, copy)


def _check_group_runs_before(check: Any, res: dict[str, Any], path: Path,
                             members: dict[int, frozenset[str]], groups_shown: str) -> None:
    """package._check_group_runs as it was: each group's runs a frozenset."""
    shown = str(res.get("path"))
    fields = P._check_fields(check, (res.get("schema") or {}), list(P.GROUP_RUNS_FIELDS),
                             shown)
    if fields is None:
        return
    columns = P._table(check, path, fields, shown)
    if columns is None:
        return
    owner = {mid: number for number, ids in members.items() for mid in ids}
    seen: dict[str, int] = {}
    listed: dict[int, set[str]] = {number: set() for number in members}
    pairs = zip(columns[GROUP_ID].tolist(), columns["measurement_id"].tolist(), strict=True)
    for n, (number, mid) in enumerate(pairs, 1):
        if is_missing(number) or is_missing(mid):
            continue  # said by the cell check
        if mid in seen:
            check.add(shown, f"row {n}, field measurement_id: run {mid[:40]!r} is listed "
                      f"twice (first in row {seen[mid]})")
            continue
        seen[mid] = n
        if number not in members:
            check.add(shown, f"row {n}, field {GROUP_ID}: {number} is not a group of "
                      f"{groups_shown}")
        elif mid not in owner:
            check.add(shown, f"row {n}, field measurement_id: {mid[:40]!r} is not an "
                      "included run of the runs table")
        else:
            listed[number].add(mid)
    for number in sorted(members):
        got, expected = listed[number], members[number]
        if got != expected:
            check.add(shown, f"group {number}: lists {len(got)} run(s), the group's "
                      f"conditions in the runs table make {len(expected)} "
                      f"({len(expected - got)} of them not listed, {len(got - expected)} "
                      "listed that belong to another group)")


# --------------------------------------------------------------------------- inputs


def _variants(runs: pd.DataFrame) -> dict[str, pd.DataFrame]:
    """The runs as they are and changed where the grouping branches."""
    out = {"as they are": runs}
    blank = runs.copy()
    blank.loc[blank.index[::3], "repeat"] = pd.NA
    blank.loc[blank.index[1::7], "excluded"] = True
    blank.loc[blank.index[2::11], "mu_k"] = math.nan  # a run without μ_K is not counted
    out["repeats missing, runs excluded, μ_K missing"] = blank
    no_t = runs.copy()
    no_t.loc[no_t.index[::5], "temperature_C"] = math.nan
    out["temperatures missing"] = no_t
    speeds = runs.copy()
    speeds[NOMINAL_SPEED] = np.where(np.arange(len(runs)) % 2 == 0, 5.0, 10.0)
    out["two speeds"] = speeds
    out["a run in four"] = runs.iloc[::4]
    out["all excluded"] = runs.assign(excluded=True)
    every = np.arange(len(runs))
    out["two test methods"] = runs.assign(
        test_method=np.where(every % 3 == 0, "pin-on-disc", "rheometer"))
    out["two labs"] = runs.assign(lab=np.where(every % 2 == 0, "Lab B", "Lab A"))
    odd = runs.copy()
    odd.loc[odd.index[::4], "pressure_kPa"] = math.nan
    odd.loc[odd.index[1::6], "normal_force_N"] = math.nan
    odd.loc[odd.index[::3], "repeat"] = 1  # ties in the members' order
    odd.loc[odd.index[2::5], "mu_k"] = math.inf
    out["pressures and forces missing, repeats tied, μ_K infinite"] = odd
    reordered = runs.iloc[::-1].copy()
    reordered.index = np.arange(len(runs)) * 2 + 7
    out["rows reversed, indexed from 7 by 2"] = reordered
    return out


VARIANTS = ["as they are", "repeats missing, runs excluded, μ_K missing",
            "temperatures missing", "two speeds", "a run in four", "all excluded",
            "two test methods", "two labs",
            "pressures and forces missing, repeats tied, μ_K infinite",
            "rows reversed, indexed from 7 by 2"]


@pytest.fixture(scope="module")
def package(tmp_path_factory) -> Path:
    """A real package: six reduced runs (with traces) and the 169 published rows, whose
    condition groups hold one to several runs at several pressures."""
    root = tmp_path_factory.mktemp("asbefore")
    map_path, _ = make_processed(root / "lab")
    fm.import_table(map_path)
    out = root / "pkg"
    result = CliRunner().invoke(main, ["map", "publish", "-o", str(out), "--lab", "Lab A",
                                       "--map", str(map_path)], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    return out


def _rows(path: Path) -> list[list[str]]:
    return list(csv.reader(io.StringIO(path.read_text(encoding="utf-8"))))


def _write_rows(path: Path, table: list[list[str]]) -> None:
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerows(table)
    path.write_text(buf.getvalue(), encoding="utf-8")


def _edit(pkg: Path, path: str, change: Any) -> None:
    """``change(table)`` on the CSV rows of ``path`` (header first), written back and
    re-hashed in the descriptor."""
    table = _rows(pkg / path)
    change(table)
    _write_rows(pkg / path, table)
    rehash(pkg, path)


def _cell(table: list[list[str]], row: int, name: str, value: str) -> None:
    table[row][table[0].index(name)] = value


def _reverse_rows(table: list[list[str]]) -> None:
    table[1:] = table[:0:-1]


GROUPS_CSV, RUNS_CSV = "data/groups.csv", "data/runs.csv"
GROUP_RUNS_CSV = "data/group_runs.csv"
BREAKS: dict[str, tuple[str, Any]] = {
    "a μ_K mean changed": (GROUPS_CSV, lambda t: _cell(t, 3, "mu_k_mean", "0.123")),
    "a μ_K n changed": (GROUPS_CSV, lambda t: _cell(t, 5, "mu_k_n", "7")),
    "a key cell changed": (GROUPS_CSV, lambda t: _cell(t, 2, "normal_force_N", "99.5")),
    "a group missing": (GROUPS_CSV, lambda t: t.pop(4)),
    "an extra group": (GROUPS_CSV, lambda t: t.append(
        [*t[1][:t[0].index("pin")], "Ecoflex 00-30", *t[1][t[0].index("pin") + 1:]])),
    "a group number twice": (GROUPS_CSV, lambda t: _cell(t, 6, GROUP_ID, t[2][
        t[0].index(GROUP_ID)])),
    "a group number zero": (GROUPS_CSV, lambda t: _cell(t, 7, GROUP_ID, "0")),
    "the groups reversed": (GROUPS_CSV, lambda t: _reverse_rows(t)),
    "a run's μ_K changed in runs.csv": (RUNS_CSV, lambda t: _cell(t, 9, "mu_k", "0.4321")),
    "a run's force changed in runs.csv": (RUNS_CSV, lambda t: _cell(t, 12, "normal_force_N",
                                                                    "2.5")),
    "a link missing": (GROUP_RUNS_CSV, lambda t: t.pop(3)),
    "a link twice": (GROUP_RUNS_CSV, lambda t: t.append(t[5])),
    "a link to another group": (GROUP_RUNS_CSV, lambda t: _cell(t, 4, GROUP_ID, "9")),
    "a link to no group": (GROUP_RUNS_CSV, lambda t: _cell(t, 4, GROUP_ID, "9999")),
    "a link to an unknown run": (GROUP_RUNS_CSV, lambda t: _cell(t, 6, "measurement_id",
                                                                 "0123456789abcdef")),
    "a cof changed": ("data/frictionmap.csv", lambda t: _cell(t, 2, "cof", "0.77")),
}


def _edit_copy(pkg: Path, change: Any) -> None:
    """``change(frame)`` on the group table's Parquet copy, written back and re-hashed."""
    path = pkg / GROUPS_PARQUET
    frame = pd.read_parquet(path)
    frame = change(frame)
    frame.to_parquet(path, index=False)
    rehash(pkg, GROUPS_PARQUET)


def _set(frame: pd.DataFrame, row: int, name: str, value: Any) -> pd.DataFrame:
    frame.loc[row, name] = value
    return frame


GROUPS_PARQUET = "data/groups.parquet"
COPY_BREAKS: dict[str, Any] = {
    "a mean changed": lambda f: _set(f, 0, "mu_k_mean", 0.987),
    "two cells changed": lambda f: _set(_set(f, 3, "pin", "Ecoflex 00-30"), 9, "mu_k_n", 9),
    "a text emptied": lambda f: _set(f, 2, "labs", ""),
    "a text missing": lambda f: _set(f, 2, "labs", None),
    "a row dropped": lambda f: f.iloc[1:],
    "a column dropped": lambda f: f.drop(columns=["mu_k_mean"]),
    "columns swapped": lambda f: f[[*f.columns[1:], f.columns[0]]],
    "every number a text": lambda f: f.astype(str),
    "every mean changed": lambda f: f.assign(mu_k_mean=f["mu_k_mean"] + 0.5),
    "rows reversed": lambda f: f.iloc[::-1].reset_index(drop=True),
}


# --------------------------------------------------------------------------- tests


@pytest.mark.parametrize("variant", VARIANTS)
def test_group_mu_k_is_group_statistics_columns(package, variant):
    """``stats.group_mu_k`` gives the columns of ``group_statistics(show_speed=True)`` it
    names, value for value, dtype for dtype, row for row."""
    runs = _variants(fm.read_map(package / "data" / "runs.parquet"))[variant]
    before = group_statistics(runs, show_speed=True)
    after = group_mu_k(runs)
    assert list(after.columns) == list(GROUP_MU_K_COLUMNS)
    pd.testing.assert_frame_equal(after, before.loc[:, list(GROUP_MU_K_COLUMNS)],
                                  check_exact=True)
    for a, b in zip(after.to_dict(orient="records"),
                    before.loc[:, list(GROUP_MU_K_COLUMNS)].to_dict(orient="records"),
                    strict=True):  # the same plain values, as the check prints them
        assert [repr(v) for v in a.values()] == [repr(v) for v in b.values()]


def test_group_mu_k_of_the_published_map_is_as_before(tmp_path):
    """The same on the founding paper's published map (many runs per group)."""
    map_path = tmp_path / "published.parquet"
    fm.import_table(map_path, published_csv_path())
    for runs in _variants(fm.read_map(map_path)).values():
        pd.testing.assert_frame_equal(
            group_mu_k(runs),
            group_statistics(runs, show_speed=True).loc[:, list(GROUP_MU_K_COLUMNS)],
            check_exact=True)


def _both(pkg: Path, monkeypatch: pytest.MonkeyPatch) -> tuple[list[str], list[str], str]:
    """The check's lines (and verdict) by today's code, keeping the runs or not (as
    publish checks), and with the replaced steps as they were."""
    after = P.check_package(pkg)
    lean = P.check_package(pkg, keep_runs=False)
    with monkeypatch.context() as m:
        m.setattr(P, "_check_groups", _check_groups_before)
        m.setattr(P, "_check_groups_copy", _check_groups_copy_before)
        m.setattr(P, "_check_group_runs", _check_group_runs_before)
        before = P.check_package(pkg)
    for other in (lean, before):
        assert (after.ok, after.more, after.verdict(), after.notes, after.lines()) == (
            other.ok, other.more, other.verdict(), other.notes, other.lines())
    if after.runs is not None:
        assert before.runs is not None and lean.runs is not None
        pd.testing.assert_frame_equal(after.runs, before.runs)
        pd.testing.assert_frame_equal(lean.runs, after.runs.loc[:, ["lab"]])
    return after.lines(), before.lines(), after.verdict()


def test_a_clean_package_checks_as_before(package, monkeypatch):
    after, before, verdict = _both(package, monkeypatch)
    assert after == before == []
    assert "valid friction-map package from Lab A, 175 runs" in verdict


@pytest.mark.parametrize("broken", list(BREAKS))
def test_a_broken_package_is_said_as_before(package, tmp_path, monkeypatch, broken):
    """Each way of breaking the package gives the lines it gave before, and some."""
    pkg = tmp_path / "pkg"
    shutil.copytree(package, pkg)
    path, change = BREAKS[broken]
    _edit(pkg, path, change)
    after, before, _ = _both(pkg, monkeypatch)
    assert after == before
    assert after, f"{broken}: no problem found"


@pytest.mark.parametrize("broken", list(COPY_BREAKS))
def test_a_broken_group_copy_is_said_as_before(package, tmp_path, monkeypatch, broken):
    """The group table's Parquet copy, compared a column at a time, is said as it was
    when compared as one frame beside a frame of the CSV's columns."""
    pkg = tmp_path / "pkg"
    shutil.copytree(package, pkg)
    _edit_copy(pkg, COPY_BREAKS[broken])
    after, before, _ = _both(pkg, monkeypatch)
    assert after == before
    assert after and all(line.startswith(GROUPS_PARQUET) or "more problem(s)" in line
                         for line in after), after


@pytest.mark.parametrize("broken", [None, "a μ_K mean changed", "a run's μ_K changed in runs.csv"])
def test_map_validate_prints_what_the_full_check_says(package, tmp_path, broken):
    """``map validate`` (which keeps no runs but the labs) prints the notes, the lines and
    the verdict of the check that keeps every run, and fails where it fails."""
    pkg = tmp_path / "pkg"
    shutil.copytree(package, pkg)
    if broken is not None:
        _edit(pkg, *BREAKS[broken])
    full = P.check_package(pkg)
    result = CliRunner().invoke(main, ["map", "validate", str(pkg)], catch_exceptions=False)
    expected = [f"note: {n}" for n in full.notes] + full.lines()
    if full.ok:
        expected.append(full.verdict())
    assert result.output.splitlines() == expected
    assert result.exit_code == (0 if full.ok else 1)
