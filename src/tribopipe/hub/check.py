"""``hub check``: a package checked as a contribution to a hub.

:func:`check_against_hub` runs, in order, and lists every problem one line each:

1. the package's own checks and the recompute of every μ from its evidence
   (:func:`tribopipe.evidence.recompute_package`: schema, row rules, checksums, μ_S and
   μ_K re-derived);
2. the materials: every pin and disc must be a canonical name of the materials
   vocabulary (:mod:`tribopipe.materials`, extended by the hub's own ``materials.toml``;
   :func:`material_problems`);
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

from ..errors import ConfigError
from ..escape import printable
from ..evidence import Recompute, recompute_package
from ..frictionmap.package import PackageInvalid, package_runs
from ..frictionmap.schema import SOURCE_REDUCED
from ..materials import (
    LAB_FILE,
    Material,
    Vocabulary,
    lab_files,
    load_vocabulary,
    material_line,
)
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


def hub_vocabulary(hub: Path) -> Vocabulary:
    """The hub's materials vocabulary: the shipped one, extended by the hub's own
    ``materials.toml`` (added to by pull request) when it has one."""
    return load_vocabulary(lab_files(hub))


def material_problems(runs: pd.DataFrame, vocabulary: Vocabulary) -> list[str]:
    """One line per pin or disc name of ``runs`` that is not a canonical name of
    ``vocabulary``: an unknown name with a did-you-mean, an ambiguous one with its
    choices, an alias with the canonical name to write."""
    out = []
    for column in ("pin", "disc"):
        for name in sorted(set(runs[column].dropna().astype(str))):
            if name in vocabulary:
                continue
            found = vocabulary.candidates(name)
            problem = (f"{column} {name!r} is written as an alias; the hub stores the "
                       f"canonical name {found[0]!r}" if len(found) == 1
                       else vocabulary.problem(name, column))
            fix = f"a new material is one line in its {LAB_FILE}" + (
                "" if found else f", e.g. {material_line(Material(name, 'CLASS'))}")
            out.append(f"data/runs.csv: {printable(str(problem))} (the hub's materials "
                       f"vocabulary; {printable(fix)})")
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
    try:
        vocabulary = hub_vocabulary(Path(hub))
    except ConfigError as exc:
        result.problems.append(f"{LAB_FILE}: {exc.problem}")
    else:
        result.problems += material_problems(runs, vocabulary)
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
