"""Merging another lab's friction data into the map: a Parquet map or a data package.

:func:`merge_map` takes either another friction map (Parquet, as ``map merge`` always did)
or a data package (its folder or ``datapackage.json``, as ``tribopipe map publish`` writes
it). A package is checked first (:func:`tribopipe.frictionmap.package.package_runs`) and
refused whole, the map untouched, when it has any problem. Each row keeps its provenance:
``lab`` names the laboratory that measured it (every row of a valid package has one),
``source`` how it was made. A run already in the map with the same content is left alone;
one with the same id and other values is a conflict, reported per row with both values
(:meth:`~tribopipe.frictionmap.store.AppendReport.conflict_lines`) and replaced only with
``replace``.
"""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import MapError
from .datapackage import DESCRIPTOR
from .package import package_runs
from .schema import frame_records
from .store import AppendReport, append_records, merge_map_file


def is_package(path: str | os.PathLike[str]) -> bool:
    """True when ``path`` names a data package: a folder, or a ``.json`` descriptor."""
    p = Path(path)
    return p.is_dir() or p.name == DESCRIPTOR or p.suffix.lower() == ".json"


def merge_map(
    path: str | os.PathLike[str], other: str | os.PathLike[str], *, replace: bool = False
) -> AppendReport:
    """Fold ``other`` — a friction map (Parquet) or a data package (folder or
    ``datapackage.json``) — into the map at ``path``.

    Runs with the same id are stored once; rows whose content differs are reported as
    conflicting (and replaced only with ``replace``). A package with any problem is a
    :class:`~tribopipe.frictionmap.package.PackageInvalid` naming the first and counting
    the others; a missing ``other`` a :class:`MapError`.
    """
    if not Path(other).exists():
        raise MapError("file not found, expected a friction map (Parquet) or a data package "
                       "(folder or datapackage.json) to merge", path=other)
    if not is_package(other):
        return merge_map_file(path, other, replace=replace)
    runs, _lab = package_runs(other)
    return append_records(path, frame_records(runs), replace=replace)
