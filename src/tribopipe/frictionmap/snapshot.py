"""A friction map opened once: one checked, immutable snapshot of its rows.

A command turns a path into a :class:`MapSnapshot` with :func:`open_map` (the one read
and check of the map it makes); every library function it calls takes the snapshot, never
the path, so nothing reads or checks the same map twice. What is derived from the rows
(the condition groups, the groups' runs, the fits, the labs, notes) is computed on demand
and kept with the snapshot: the rows cannot change under it.

The model is sqlite-utils' ``Database``: open once, then ask the handle.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from ..errors import MapError
from ..stats import (
    GROUP_INPUT_COLUMNS,
    finish_groups,
    group_statistics,
    run_ids_of,
    shown_columns,
)
from .schema import RUN_COLUMNS, empty_map
from .store import committed_groups_info, load_map, rows_by_id, stored_groups

if TYPE_CHECKING:
    import pandas as pd

T = TypeVar("T")

#: the columns that identify a run's condition group (the statistics' key, before rounding)
GROUP_KEY_COLUMNS: tuple[str, ...] = ("pin", "disc", "normal_force_N", "temperature_C")


@dataclass(frozen=True, eq=False)
class MapSnapshot:
    """A friction map as one read found it: ``path``, the rows (:attr:`runs`, the map's
    ``columns`` only) and the metadata (:attr:`info`: schema, version, ``n_runs``,
    ``sources``, ``format`` ``"parts"`` or ``"file"``, and the writing tribopipe).

    Immutable: :attr:`runs` gives a copy-on-write view (pandas ≥ 3), so a caller that
    changes it changes its own copy. Derived tables are computed on first use and kept.
    """

    path: Path
    _runs: pd.DataFrame = field(repr=False)
    info: Mapping[str, Any] = field(repr=False)
    columns: tuple[str, ...] = RUN_COLUMNS
    _derived: dict[Any, Any] = field(default_factory=dict, repr=False, compare=False)

    def __fspath__(self) -> str:
        """The map's path: a snapshot names its map where a message or a default folder
        needs the path."""
        return os.fspath(self.path)

    def __str__(self) -> str:
        return str(self.path)

    @property
    def runs(self) -> pd.DataFrame:
        """The rows of the map (a copy-on-write view: changing it leaves the snapshot)."""
        return self._runs.copy(deep=False)

    @property
    def n_runs(self) -> int:
        """The number of rows."""
        return len(self._runs)

    @property
    def empty(self) -> bool:
        """True for a map without rows (or no map at the path)."""
        return len(self._runs) == 0

    @property
    def exists(self) -> bool:
        """True when a map was found at :attr:`path` (an absent map reads as empty)."""
        return self.info.get("format") != "none"

    @cached_property
    def ids(self) -> frozenset[str]:
        """The measurement ids of the map's runs."""
        self.require(["measurement_id"])
        return frozenset(self._runs["measurement_id"].astype(str))

    def require(self, columns: Sequence[str]) -> None:
        """Raise :class:`MapError` unless the snapshot holds ``columns`` (a function asked
        for more than the command opened the map with: a programming error, named)."""
        missing = [c for c in columns if c not in self.columns]
        if missing:
            raise MapError(f"the map was opened without column(s) {', '.join(missing)}",
                           path=self.path)

    def groups(self, *, by_speed: bool = False, show_speed: bool | None = None,
               show_method: bool | None = None) -> pd.DataFrame:
        """The condition groups' repeat statistics
        (:func:`tribopipe.stats.group_statistics` of every run, with its ``by_speed``,
        ``show_speed`` and ``show_method``), once per snapshot. A map folder's stored
        groups (:mod:`~tribopipe.frictionmap.stored_groups`) are finished
        (:func:`~tribopipe.stats.finish_groups`) instead of grouping every run; a map
        without them (a single file, an older folder), or ``by_speed``, groups its runs
        (the snapshot must hold :data:`~tribopipe.stats.GROUP_INPUT_COLUMNS`)."""
        def compute() -> pd.DataFrame:
            rows = None if by_speed else self.stored_group_rows()
            if rows is None:
                self.require((*GROUP_INPUT_COLUMNS, "sliding_speed_mm_s") if by_speed
                             else GROUP_INPUT_COLUMNS)
                return group_statistics(self._runs, by_speed=by_speed,
                                        show_speed=show_speed, show_method=show_method)
            speed, method = shown_columns(rows)
            return finish_groups(
                rows, show_speed=speed if show_speed is None else show_speed,
                show_method=method if show_method is None else show_method)

        return self.derived(("groups", by_speed, show_speed, show_method), compute)

    def stored_group_rows(self) -> pd.DataFrame | None:
        """The map folder's stored group rows as this snapshot's commit holds them
        (:func:`~tribopipe.frictionmap.store.stored_groups`), read once; ``None`` for a
        map without them."""
        return self.derived(("stored_group_rows",),
                            lambda: stored_groups(self.path, self.info))

    def group_members(self, *, by_speed: bool = False) -> pd.DataFrame:
        """Which run belongs to which condition group: one row per (group, run), columns
        ``group`` (the row of :meth:`groups` with the same ``by_speed``) and
        ``measurement_id``, in the groups' order; computed once per snapshot. The
        membership as its own table: no cell grows with the number of runs."""
        import pandas as pd

        def members() -> pd.DataFrame:
            groups = self.groups(by_speed=by_speed)
            ids = ([run_ids_of(cell) for cell in groups["run_ids"]]
                   if "run_ids" in groups.columns else [])
            return pd.DataFrame({
                "group": [g for g, run_ids in enumerate(ids) for _ in run_ids],
                "measurement_id": [m for run_ids in ids for m in run_ids]})

        return self.derived(("group_members", by_speed), members)

    def group_runs(self, group: int, *, by_speed: bool = False) -> pd.DataFrame:
        """The runs (rows of :attr:`runs`) of condition group ``group`` (a row number of
        :meth:`groups`), in the group's order."""
        index = self.derived(("run_index",), lambda: {
            m: i for i, m in enumerate(self._runs["measurement_id"].astype(str))})
        members = self.group_members(by_speed=by_speed)
        ids = members.loc[members["group"] == group, "measurement_id"]
        return self._runs.iloc[[index[m] for m in ids]].copy(deep=False)

    def rows_of(self, ids: Iterable[str]) -> pd.DataFrame:
        """Every column of the runs ``ids`` (measurement ids), in the map's order: taken
        from this snapshot when it holds every column, else read from the commit it was
        opened at (:func:`~tribopipe.frictionmap.store.rows_by_id`: only the parts that
        hold them are read whole). For a command that opened a few columns and shows
        some rows whole."""
        wanted = set(ids)
        if set(RUN_COLUMNS) <= set(self.columns):
            return self._runs[self._runs["measurement_id"].isin(wanted)].copy(deep=False)
        if self.info.get("format") == "rows":
            self.require(RUN_COLUMNS)  # rows in memory, without them: named
        if not wanted:
            return empty_map()
        return rows_by_id(self.path, self.info, wanted)

    def derived(self, key: Any, compute: Callable[[], T]) -> T:
        """The value ``compute()`` gives for this snapshot, computed once per ``key``: the
        place where rooms above the map keep what they derive from it (fits, labs …)."""
        if key not in self._derived:
            self._derived[key] = compute()
        return self._derived[key]

    def select(self, columns: Sequence[str]) -> MapSnapshot:
        """A snapshot of the same read with fewer columns (nothing is read again)."""
        self.require(columns)
        keep = tuple(c for c in RUN_COLUMNS if c in set(columns))
        return MapSnapshot(self.path, self._runs.loc[:, list(keep)], self.info, keep)


def open_map(path: str | os.PathLike[str], columns: Sequence[str] | None = None
             ) -> MapSnapshot:
    """Read and check the map at ``path`` once (:func:`~tribopipe.frictionmap.store.load_map`:
    the ``columns`` asked for, all when ``None``; an absent map is empty) and return it as
    a snapshot. Raises :class:`~tribopipe.errors.MapError` in one line."""
    runs, info = load_map(path, columns)
    kept = tuple(runs.columns)
    return MapSnapshot(Path(path), runs, info, kept)


def open_groups(path: str | os.PathLike[str]) -> MapSnapshot:
    """The map at ``path`` opened for its condition groups (:meth:`MapSnapshot.groups`)
    and no more: a map folder with stored groups as its manifest names them
    (:func:`~tribopipe.frictionmap.store.committed_groups_info`), no part read (a
    snapshot of its number of rows and none of its columns); any other map with the
    statistics' inputs (:data:`~tribopipe.stats.GROUP_INPUT_COLUMNS`), which it
    groups."""
    import pandas as pd

    info = committed_groups_info(path)
    if "groups" not in info:
        return open_map(path, GROUP_INPUT_COLUMNS)
    rows = pd.DataFrame(index=pd.RangeIndex(int(info["n_runs"])))
    return MapSnapshot(Path(path), rows, info, ())


def snapshot_of(runs: pd.DataFrame, path: str | os.PathLike[str] = "<rows>",
                info: Mapping[str, Any] | None = None) -> MapSnapshot:
    """A snapshot of rows already in memory (checked rows of a map, e.g. a package's
    ``runs.parquet`` read, or rows a test built): library functions take it like an
    opened map."""
    return MapSnapshot(Path(path), runs, dict(info or {"format": "rows",
                                                        "n_runs": len(runs)}),
                       tuple(runs.columns))


#: what a library function takes for a map: a snapshot (a command opened it once), or a
#: path that it opens once itself (callers not moved to snapshots yet)
MapSource = MapSnapshot | str | os.PathLike[str]


def as_snapshot(source: MapSource, columns: Sequence[str] | None = None) -> MapSnapshot:
    """``source`` itself when it is a snapshot, else the map at that path opened once.
    Library functions call this at their top so that a command that passes the snapshot
    reads the map once, and older callers that pass a path still work."""
    if isinstance(source, MapSnapshot):
        return source
    return open_map(source, columns)
