"""``hub check``: a package checked as a contribution to a hub.

:func:`check_against_hub` runs, in order, and lists every problem one line each:

1. the package's own checks and the recompute of every μ from its evidence
   (:func:`tribopipe.evidence.recompute_package`: schema, row rules, checksums, μ_S and
   μ_K re-derived);
2. the materials: every pin and disc must be a canonical name of the materials
   vocabulary (:func:`material_problems`);
3. the hub: a run whose raw content (its ``file_hash``) the hub holds under another lab
   is refused (one measurement cannot be two labs'), and so is a run the hub holds with
   the same id but other values (a conflict). The same lab's earlier releases may hold the
   same runs with the same values: a release is a new version of the lab's map.

The package's own folder, when it already sits in the hub (a pull request), is left out
of the comparison.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..escape import printable
from ..evidence import Recompute, recompute_package
from ..frictionmap.package import PackageInvalid, package_runs
from ..frictionmap.published import published_csv_path, read_frictionmap_table
from ..frictionmap.schema import SOURCE_REDUCED
from .folder import HubPackage, hub_packages

if TYPE_CHECKING:
    import pandas as pd

#: the values that must agree where two packages hold the same run
COMPARED = ("mu_s", "mu_k", "pin", "disc", "normal_force_N", "temperature_C")


@dataclass
class HubCheck:
    """What :func:`check_against_hub` found: the package, the recompute, and every
    problem line (the recompute's first)."""

    path: Path
    recompute: Recompute
    problems: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """True when nothing is wrong."""
        return not self.problems

    def verdict(self) -> str:
        """The line for a package without problems."""
        n = 0 if self.recompute.check.runs is None else len(self.recompute.check.runs)
        return (f"{self.path}: ready for the hub: {n} runs from {self.recompute.check.lab}, "
                "every re-derived μ within its U, no duplicate or conflict")


def known_materials(hub_runs: Iterable[pd.DataFrame]) -> set[str]:
    """The material names the hub knows: the founding map's and those of the hub's rows."""
    founding = read_frictionmap_table(published_csv_path())
    names = set(founding["pin"].astype(str)) | set(founding["disc"].astype(str))
    for runs in hub_runs:
        names.update(runs["pin"].dropna().astype(str))
        names.update(runs["disc"].dropna().astype(str))
    return names


def material_problems(runs: pd.DataFrame, known: set[str]) -> list[str]:
    """One line per pin or disc name of ``runs`` that ``known`` lacks, with a
    did-you-mean."""
    import difflib

    out = []
    folded = {k.casefold(): k for k in known}
    for column in ("pin", "disc"):
        for name in sorted(set(runs[column].dropna().astype(str))):
            if name in known:
                continue
            near = difflib.get_close_matches(name.casefold(), list(folded), n=2, cutoff=0.6)
            hint = ("; did you mean " + " or ".join(repr(folded[n]) for n in near) + "?"
                    if near else "; a new material is added to the hub's vocabulary by "
                    "a pull request")
            out.append(f"data/runs.csv: {column} {printable(name)!r} is not a material of "
                       f"the hub's vocabulary{hint}")
    return out


def check_against_hub(package: str | os.PathLike[str], hub: str | os.PathLike[str],
                      *, before: Iterable[HubPackage] | None = None) -> HubCheck:
    """Check ``package`` (module docstring) against the packages of ``hub`` (or only
    ``before``, as :func:`check_hub` does). Never raises for a bad package."""
    path = Path(package)
    again = recompute_package(path)
    result = HubCheck(path, again, list(again.lines()))
    runs = again.check.runs
    if runs is None:
        return result
    own = path.resolve()
    others: list[tuple[HubPackage, pd.DataFrame]] = []
    for other in (hub_packages(Path(hub)) if before is None else before):
        if other.path.resolve() == own:
            continue
        try:
            other_runs, _ = package_runs(other.path)
        except PackageInvalid as exc:
            result.problems.append(f"{other.where}: a package of the hub does not validate "
                                   f"({exc.problem})")
            continue
        others.append((other, other_runs))
    result.problems += material_problems(runs, known_materials(r for _, r in others))
    result.problems += hub_conflicts(runs, others)
    return result


def hub_conflicts(runs: pd.DataFrame,
                  others: list[tuple[HubPackage, pd.DataFrame]]) -> list[str]:
    """The duplicates of raw content under another lab and the conflicts with the hub's
    rows, one line each (module docstring)."""
    by_hash: dict[str, tuple[str, str]] = {}
    by_id: dict[str, tuple[str, dict[str, Any]]] = {}
    for other, other_runs in others:
        for row in _records(other_runs):
            if row["source"] == SOURCE_REDUCED and isinstance(row.get("file_hash"), str):
                by_hash.setdefault(row["file_hash"], (str(row["lab"]), other.where))
            by_id.setdefault(str(row["measurement_id"]), (other.where, row))
    out = []
    for row in _records(runs):
        mid = str(row["measurement_id"])
        name = printable(str(row.get("source_file") or mid))
        owner = by_hash.get(str(row.get("file_hash")))
        if row["source"] == SOURCE_REDUCED and owner is not None and owner[0] != row["lab"]:
            out.append(f"run {mid} ({name}): its raw content (SHA-256 "
                       f"{str(row['file_hash'])[:12]}…) is in the hub already under "
                       f"{printable(owner[0])!r} ({owner[1]}); one measurement cannot be "
                       "two labs'")
            continue
        seen = by_id.get(mid)
        if seen is None:
            continue
        where, theirs = seen
        differs = [c for c in COMPARED if not _same(row.get(c), theirs.get(c))]
        if differs:
            shown = ", ".join(f"{c} {_show(row.get(c))} here, {_show(theirs.get(c))} there"
                              for c in differs)
            out.append(f"run {mid} ({name}): conflicts with {where}: {shown}")
    return out


def _records(runs: pd.DataFrame) -> list[dict[str, Any]]:
    return [{str(k): v for k, v in r.items()} for r in runs.to_dict("records")]


def _same(a: Any, b: Any) -> bool:
    import math

    if isinstance(a, float) and isinstance(b, float):
        return (math.isnan(a) and math.isnan(b)) or math.isclose(a, b, rel_tol=1e-12,
                                                                 abs_tol=1e-12)
    return bool(a == b)


def _show(value: Any) -> str:
    return f"{value:.6g}" if isinstance(value, float) else printable(repr(value))


def check_hub(hub: str | os.PathLike[str]) -> list[HubCheck]:
    """Every package of ``hub`` checked against those filed before it (release date, then
    lab): what the pull-request workflow runs."""
    packages = hub_packages(Path(hub))
    return [check_against_hub(p.path, hub, before=packages[:i])
            for i, p in enumerate(packages)]
