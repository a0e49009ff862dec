"""Merging another lab's friction data into the map: a Parquet map or a data package.

:func:`merge_map` takes either another friction map (Parquet, as ``map merge`` always did)
or a data package (its folder or ``datapackage.json``, as ``tribopipe map publish`` writes
it). A package is checked first (:func:`tribopipe.frictionmap.package.package_runs`) and
refused whole, the map untouched, when it has any problem. Each row keeps its provenance:
``lab`` names the laboratory that measured it (every row of a valid package has one),
``source`` how it was made. A Parquet map may hold rows without a ``lab`` (a lab's own
runs before it publishes them): merged as they are, they read as this map's own lab's, so
``lab`` names the laboratory that measured them (``map merge --lab``); rows naming a lab
keep it. A run already in the map with the same content is left alone;
one with the same id and other values is a conflict, reported per row with both values
(:meth:`~tribopipe.frictionmap.store.AppendReport.conflict_lines`) and replaced only with
``replace``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import MapError
from ..materials import Vocabulary, shipped_vocabulary
from ..validate import text_problem
from .datapackage import DESCRIPTOR
from .package import package_runs
from .parts import MANIFEST
from .schema import is_missing
from .store import AppendReport, append_frame, read_map

if TYPE_CHECKING:
    import pandas as pd


@dataclass(frozen=True)
class MergeReport:
    """What a merge did: the map's :class:`AppendReport`, the rows of the other map that
    were given the ``lab`` passed (``labelled``) and those left naming no lab
    (``without_lab``: they now read as this map's own lab's)."""

    report: AppendReport
    labelled: int = 0
    without_lab: int = 0
    lab: str | None = None
    #: names the materials vocabulary resolved (given → canonical, rows)
    resolved: tuple[tuple[str, str, int], ...] = ()

    def notes(self, other: str) -> list[str]:
        """One line per thing to know about the rows' labs and names (nothing when all
        named a lab and every name was canonical)."""
        lines = [f"{n} row(s) of {other} name {given!r}: stored as {name!r} (the given name "
                 f"kept in pin_as_given/disc_as_given)" for given, name, n in self.resolved]
        if self.labelled:
            lines.append(f"{self.labelled} row(s) of {other} named no lab: recorded as "
                         f"measured by {self.lab!r}")
        if self.without_lab:
            lines.append(f"note: {self.without_lab} row(s) of {other} name no lab and now "
                         "read as this map's own; if another lab measured them, merge with "
                         "--lab NAME")
        return lines


def is_package(path: str | os.PathLike[str]) -> bool:
    """True when ``path`` names a data package: a folder (not a map folder of parts, which
    holds a manifest), or a ``.json`` descriptor."""
    p = Path(path)
    if p.is_dir():
        return not (p / MANIFEST).exists()
    return p.name == DESCRIPTOR or p.suffix.lower() == ".json"


def merge_map(
    path: str | os.PathLike[str], other: str | os.PathLike[str], *, replace: bool = False,
    lab: str | None = None, vocabulary: Vocabulary | None = None,
) -> MergeReport:
    """Fold ``other`` — a friction map (Parquet) or a data package (folder or
    ``datapackage.json``) — into the map at ``path``.

    Runs with the same id are stored once; rows whose content differs are reported as
    conflicting (and replaced only with ``replace``). ``lab`` names the laboratory that
    measured the rows of a Parquet map that name none (a package names its own lab: a
    ``lab`` given with one is refused). A package with any problem is a
    :class:`~tribopipe.frictionmap.package.PackageInvalid` naming the first and counting
    the others; a missing ``other``, a map merged into itself or a ``lab`` that is not
    one line of text a :class:`MapError`. Every pin and disc name is resolved through
    the materials ``vocabulary`` (default: the shipped one) on the way in
    (:func:`resolve_names`); a name it does not know refuses the merge whole, the map
    untouched, in one :class:`~tribopipe.materials.MaterialError` naming every such name
    with the fix (``tribopipe materials add``, or a line for the lab's
    ``materials.toml``).
    """
    if lab is not None:
        lab = _lab_name(lab)
    if not Path(other).exists():
        raise MapError("file not found, expected a friction map (Parquet) or a data package "
                       "(folder or datapackage.json) to merge", path=other)
    vocabulary = vocabulary or shipped_vocabulary()
    if is_package(other):
        runs, package_lab = package_runs(other)
        if lab is not None:
            raise MapError(f"a data package names its lab ({package_lab!r}); --lab is for a "
                           "Parquet map whose rows name none", path=other)
        runs, resolved = resolve_names(runs, vocabulary, other)
        return MergeReport(append_frame(path, runs, replace=replace), resolved=resolved)
    if os.path.realpath(other) == os.path.realpath(path):
        raise MapError("cannot merge a friction map into itself", path=other)
    runs = read_map(other)  # validated: a damaged or foreign file is refused before any write
    unnamed = runs["lab"].map(is_missing).astype(bool)
    if lab is not None:
        runs.loc[unnamed, "lab"] = lab
    runs, resolved = resolve_names(runs, vocabulary, other)
    report = append_frame(path, runs, replace=replace)
    n = int(unnamed.sum())
    return MergeReport(report, labelled=n if lab else 0, without_lab=0 if lab else n, lab=lab,
                       resolved=resolved)


def resolve_names(runs: pd.DataFrame, vocabulary: Vocabulary,
                  where: str | os.PathLike[str] | None = None) -> tuple[
        pd.DataFrame, tuple[tuple[str, str, int], ...]]:
    """``runs`` (a copy) with every pin and disc name stored under its canonical name
    (:meth:`~tribopipe.materials.Vocabulary.resolve_all`), the given one kept in
    ``pin_as_given``/``disc_as_given`` (unless the row already keeps one), and the names
    resolved (given, canonical, rows). A name the vocabulary does not resolve refuses
    the rows: one :class:`~tribopipe.materials.MaterialError` about ``where`` naming
    every such name, with the fix."""
    runs = runs.copy()
    named = [(what, name) for what in ("pin", "disc")
             for name in sorted(set(runs[what].astype(str)))]
    canonical = vocabulary.resolve_all(named, where)
    resolved: list[tuple[str, str, int]] = []
    for what in ("pin", "disc"):
        given_column = f"{what}_as_given"
        if given_column not in runs.columns:  # rows of an older schema
            runs[given_column] = None
        names = runs[what].astype(str)
        for name in sorted(set(names)):
            to = canonical[(what, name)]
            if to == name:
                continue
            rows = names == name
            keep = rows & runs[given_column].map(is_missing).astype(bool)
            runs.loc[keep, given_column] = name
            runs.loc[rows, what] = to
            resolved.append((name, to, int(rows.sum())))
    return runs, tuple(resolved)


def _lab_name(lab: str) -> str:
    """``--lab`` as stored: one line of text (:func:`~tribopipe.validate.text_problem`,
    what the map's ``lab`` column keeps) of at most 300 characters, stripped (a name from
    the command line)."""
    text = lab.strip()
    if not text:
        raise MapError("--lab is empty; expected the name of the lab that measured the rows")
    if text_problem(text, max_chars=300) is not None:
        raise MapError("--lab holds a line break or control character, or is longer than "
                       "300 characters; expected one line of text")
    return text
