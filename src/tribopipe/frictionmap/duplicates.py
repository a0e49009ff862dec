"""The same raw content under two file names: a duplicate, or a conflict of labels.

A run's ``measurement_id`` hashes the raw file's content, not its name, so a byte-identical
copy yields the same runs. When the copy's runs carry the same labels (pin, disc, nominal
force and temperature, repeat) it is a *duplicate*: stored once, under the first name.
When the labels differ it is a *conflict*: the two names claim different conditions for
one measurement, and the second is refused rather than overwrite the first.
:func:`compare_labels` decides between the two; :func:`map_files_by_hash` tells which
files a map already holds, by content; :class:`ContentOwners` is the one check both
``tribopipe reduce`` and the batch make, under the map's lock. :func:`repeat_clashes`
finds one repeat number used by several runs of one condition.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ..stats import FORCE_DECIMALS, TEMPERATURE_DECIMALS, group_statistics, run_ids_of
from .records import stored_file_name
from .schema import MapRow, unvalidated_frame

if TYPE_CHECKING:
    import pandas as pd

#: the columns that say what a run is (its condition group and repeat)
LABEL_COLUMNS: tuple[str, ...] = ("pin", "disc", "normal_force_N", "temperature_C", "repeat")

#: {file_hash: {source_file: {measurement_id: labels}}}
FilesByHash = Mapping[str, dict[str, dict[str, dict[str, Any]]]]

#: the map columns the duplicate and conflict check reads (:func:`map_files_by_hash`,
#: :func:`repeat_clashes`): what a locked append reads of every row
CHECK_COLUMNS: tuple[str, ...] = ("measurement_id", "file_hash", "source_file",
                                  *LABEL_COLUMNS, "excluded")
#: what :func:`repeat_clashes` reads besides, of the rows of the pairs it reports on (the
#: statistics' condition groups)
GROUP_COLUMNS: tuple[str, ...] = ("pressure_kPa", "nominal_speed_mm_s", "test_method", "lab",
                                  "flags", "review", "mu_s", "mu_k", "u_mu_s", "u_mu_k")


def _value(column: str, value: Any) -> Any:
    """A label as compared: unknown (``None``, NaN, pandas NA) as ``None``, numbers as float."""
    if value is None:
        return None
    try:
        if value != value:  # NaN
            return None
    except TypeError:  # pandas NA refuses a truth value
        return None
    if column in ("normal_force_N", "temperature_C", "repeat"):
        return float(value)
    return str(value)


def labels_of(row: MapRow | Mapping[str, Any] | None) -> dict[str, Any]:
    """The :data:`LABEL_COLUMNS` of a map row or a ``RunLabels`` dict, with unknown values
    as ``None`` and numbers as float."""
    if isinstance(row, MapRow):
        return {c: _value(c, getattr(row, c)) for c in LABEL_COLUMNS}
    return {c: _value(c, (row or {}).get(c)) for c in LABEL_COLUMNS}


def same_label(column: str, a: Any, b: Any) -> bool:
    """True when two values of a label column agree: names ignoring case and surrounding
    blanks, numbers within 1e-9, unknown equal only to unknown."""
    a, b = _value(column, a), _value(column, b)
    if a is None or b is None:
        return a is b
    if isinstance(a, float):
        return math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-9)
    return a.strip().casefold() == b.strip().casefold()


@dataclass(frozen=True)
class SameContent:
    """A file whose content (SHA-256) was already seen under another name: a duplicate
    when the labels of their runs agree, else a conflict (the second is refused)."""

    file: str
    other: str
    differences: tuple[str, ...] = ()

    @property
    def conflict(self) -> bool:
        """True when the two files' runs carry different labels."""
        return bool(self.differences)

    def message(self) -> str:
        """One line naming both files (and, for a conflict, the labels that differ)."""
        if self.conflict:
            return (f"{self.file}: same content as {self.other} but other labels "
                    f"({'; '.join(self.differences)}): refused as a conflict, the map keeps "
                    f"{self.other}'s")
        return (f"{self.file}: same content as {self.other} (a duplicate): its runs are "
                f"{self.other}'s, stored once")


def compare_labels(file: str, other: str, new: Mapping[str, Mapping[str, Any]],
                   old: Mapping[str, Mapping[str, Any]]) -> SameContent:
    """Compare the labels of two same-content files, run by run: ``new`` and ``old`` map
    measurement ids to labels (:data:`LABEL_COLUMNS`). Runs only one side holds are not
    compared (another version may have found other runs in the same bytes)."""
    differences: list[str] = []
    for mid in sorted(set(new) & set(old)):
        for col in LABEL_COLUMNS:
            a, b = old[mid].get(col), new[mid].get(col)
            if not same_label(col, a, b):
                differences.append(f"{col} {_shown(col, a)} vs {_shown(col, b)}")
    return SameContent(file=file, other=other, differences=tuple(dict.fromkeys(differences)))


def _shown(column: str, value: Any) -> str:
    value = _value(column, value)
    if value is None:
        return "unknown"
    return f"{value:g}" if isinstance(value, float) else repr(value)


def map_files_by_hash(runs: Any) -> FilesByHash:
    """``{file_hash: {source_file: {measurement_id: labels}}}`` of a map's reduced rows
    (a DataFrame with :data:`CHECK_COLUMNS`): which files the map holds, by content. The
    entry of one content is built when it is asked for, so a check of a few files costs
    what they add, not what the map holds."""
    return _FilesIndex(runs)


class _FilesIndex(Mapping[str, dict[str, dict[str, dict[str, Any]]]]):
    """:func:`map_files_by_hash`'s mapping: the rows of one content found through a hash
    index of the column, its entry built on first use."""

    def __init__(self, runs: Any) -> None:
        import pandas as pd

        columns = ["file_hash", "source_file", "measurement_id", *LABEL_COLUMNS]
        rows = runs.loc[:, columns].reset_index(drop=True)
        self._rows = rows.loc[rows["file_hash"].notna() & rows["source_file"].notna()
                              & (rows["file_hash"].astype(str) != "")
                              ].reset_index(drop=True)
        self._index = pd.Index(self._rows["file_hash"].astype(str))
        self._built: dict[str, dict[str, dict[str, dict[str, Any]]]] = {}

    def __getitem__(self, sha: str) -> dict[str, dict[str, dict[str, Any]]]:
        if sha in self._built:
            return self._built[sha]
        if not isinstance(sha, str):
            raise KeyError(sha)
        positions = self._index.get_indexer_non_unique([sha])[0]
        positions = positions[positions >= 0]
        if not len(positions):
            raise KeyError(sha)
        out: dict[str, dict[str, dict[str, Any]]] = {}
        for row in self._rows.iloc[positions].itertuples(index=False, name=None):
            _, source, mid, *values = row
            labels = {c: _value(c, v) for c, v in zip(LABEL_COLUMNS, values, strict=True)}
            out.setdefault(str(source), {})[str(mid)] = labels
        self._built[sha] = out
        return out

    def __iter__(self) -> Iterator[str]:
        return iter(self._index.unique())

    def __len__(self) -> int:
        return len(self._index.unique())


class ContentOwners:
    """Which file brought each content (SHA-256) to the map, and its runs' labels: the
    one duplicate and conflict check of ``tribopipe reduce`` and the batch, made from the
    map as read under its lock (:func:`tribopipe.frictionmap.store.update_map_with`).

    ``in_map``: :func:`map_files_by_hash` of that map; ``known``: contents already owned
    before the map is asked (a campaign's state: ``{sha: (file, {id: labels})}``);
    ``renamed``: map source names of files that left the folder, with the file and its
    content (``{name: (file, sha)}``): the same content under a new name is that file
    renamed, not a duplicate.
    """

    def __init__(self, in_map: FilesByHash,
                 known: Mapping[str, tuple[str, dict[str, dict[str, Any]]]] | None = None,
                 renamed: Mapping[str, tuple[str, str | None]] | None = None) -> None:
        self.in_map = in_map
        self.first: dict[str, tuple[str, dict[str, dict[str, Any]]]] = dict(known or {})
        self.renamed = dict(renamed or {})

    def check(self, file: str, sha: str | None, runs: Mapping[str, Mapping[str, Any]]
              ) -> tuple[SameContent | None, str | None]:
        """The same content (``sha``) seen before under another name than ``file`` (or
        ``None``), and a note when the other name is a file that left the folder with this
        content (taken as renamed). ``runs``: the file's runs, measurement id → labels."""
        sha = sha or ""
        if sha in self.first and self.first[sha][0] != file:
            other, old = self.first[sha]
            return compare_labels(file, other, runs, old), None
        name = stored_file_name(file)  # as the map keeps it: raw
        for source, old in sorted(self.in_map.get(sha, {}).items()):
            if source == name:
                continue
            gone = self.renamed.get(source)
            if gone is not None and gone[1] == sha:
                return None, (f"{file}: same content as {gone[0]}, which left the folder: "
                              "taken as renamed")
            return compare_labels(file, source, runs, old), None
        return None, None

    def landed(self, file: str, sha: str | None, runs: Mapping[str, Mapping[str, Any]]) -> None:
        """Record that ``file``'s runs land: later files with its content are duplicates."""
        if sha and runs:
            self.first.setdefault(sha, (file, {k: dict(v) for k, v in runs.items()}))


def _coarse_key(pin: Any, disc: Any, force: Any, temperature: Any, repeat: Any
                ) -> tuple[Any, ...] | None:
    """A run's pair, nominal force and temperature rounded as the statistics round them,
    and repeat: runs of one condition group with one repeat number share it (the groups
    only split it further, by nominal pressure). ``None`` without a repeat number."""
    number = _value("repeat", repeat)
    if number is None:
        return None
    force_N, temperature_C = _value("normal_force_N", force), _value("temperature_C",
                                                                      temperature)
    return (pin, disc, None if force_N is None else round(force_N, FORCE_DECIMALS),
            None if temperature_C is None else round(temperature_C, TEMPERATURE_DECIMALS),
            number)


def repeat_clashes(current: pd.DataFrame, records: Sequence[MapRow],
                   drop_ids: Collection[str] = ()) -> list[str]:
    """The repeat numbers that more than one run of one condition group would carry once
    ``records`` are folded into the map ``current`` (rows ``drop_ids`` gone), where one of
    ``records`` takes part: one line each, naming the condition, the repeat and the files.

    The condition groups are those of the map's statistics
    (:func:`tribopipe.stats.group_statistics`: pin, disc, nominal force and temperature,
    nominal pressure; excluded runs left out). A repeat number is a run's place among the
    repeats of its condition: two runs with one number are a labelling mistake (or one
    run under two names), reported, never refused. The statistics are asked only when
    two runs share the pair, rounded conditions and repeat number.
    """
    import pandas as pd

    columns = ("pin", "disc", "normal_force_N", "temperature_C", "repeat")
    new_ids = {r.measurement_id for r in records}
    # only the map's runs of the records' pairs can share a record's condition (the
    # pairs filtered first, on whole columns)
    pins = {r.pin for r in records}
    discs = {r.disc for r in records}
    old = current.loc[current["pin"].isin(sorted(pins)) & current["disc"].isin(sorted(discs))]
    old = old.loc[~old["measurement_id"].isin(new_ids | set(drop_ids))
                  & ~old["excluded"].fillna(False).astype(bool)]
    # and only those with a record's repeat number can share its key
    repeats = sorted({int(r.repeat) for r in records if r.repeat is not None})
    seen: dict[tuple[Any, ...], int] = {}
    for values in old.loc[old["repeat"].isin(repeats), list(columns)].itertuples(
            index=False, name=None):
        key = _coarse_key(*values)
        if key is not None:
            seen[key] = seen.get(key, 0) + 1
    clash = False
    for record in records:
        key = _coarse_key(*(getattr(record, c) for c in columns))
        if key is not None:
            clash = clash or key in seen
            seen[key] = seen.get(key, 0) + 1
    if not clash:
        return []
    # the records' rules are the store's to check, once, as it folds them in: here only
    # their columns and dtypes are needed
    new = unvalidated_frame(records)
    pairs = set(zip(new["pin"], new["disc"], strict=True))
    old = old.loc[[(p, d) in pairs for p, d in zip(old["pin"], old["disc"], strict=True)]]
    runs = pd.concat([old, new], ignore_index=True) if len(old) else new
    by_id = runs.set_index(runs["measurement_id"].astype(str))
    lines: list[str] = []
    for group in group_statistics(runs).to_dict(orient="records"):
        ids = run_ids_of(group["run_ids"])
        if not new_ids.intersection(ids):
            continue
        by_repeat: dict[int, list[str]] = {}
        for mid in ids:
            repeat = _value("repeat", by_id.at[mid, "repeat"])
            if repeat is not None:
                by_repeat.setdefault(int(repeat), []).append(mid)
        for repeat, same in sorted(by_repeat.items()):
            if len(same) < 2 or not new_ids.intersection(same):
                continue
            files = ", ".join(sorted({str(by_id.at[mid, "source_file"]) for mid in same}))
            temperature = _value("temperature_C", group["temperature_C"])
            where = f"{group['normal_force_N']:g} N, " + (
                "temperature unknown" if temperature is None else f"{temperature:g} °C")
            lines.append(
                f"repeat {repeat} used by {len(same)} runs of {group['pin']} on "
                f"{group['disc']}, {where} ({files}): give each run of a condition its own "
                "repeat number")
    return lines
