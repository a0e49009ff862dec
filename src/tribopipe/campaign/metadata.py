"""Where a run's labels come from: the manifest, the file name, the export's Test name.

Metadata resolution
-------------------
Each run needs ``pin``, ``disc``, ``normal_force_N`` (nominal, total) and ``temperature_C``
(nominal); ``repeat`` is optional. They come from up to three sources, consulted in this
order: the manifest row (:func:`read_manifest`), the file-name pattern
(:func:`~tribopipe.campaign.patterns.match_pattern`), the export's own Test name. Every
source that gives a field must agree with the others (:func:`merge_metadata`: names
compared after the ``[names]`` aliases, ignoring case and surrounding blanks; numbers
compared exactly); the first source that gives a field defines its spelling. A
disagreement or a missing required field is an error *for that file only*.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import CampaignError, ConfigError, ReadError
from ..frictionmap.records import RunLabels
from ..readers.textio import decode, detect_delimiter
from .patterns import LABEL_FIELDS, REQUIRED_FIELDS, _parse_number

if TYPE_CHECKING:
    from .spec import Campaign

MANIFEST_COLUMNS: tuple[str, ...] = ("file", *LABEL_FIELDS)


@dataclass(frozen=True)
class ManifestRow:
    """One manifest row: the label fields it gives (``None`` cells left out) and its line."""

    line: int
    fields: dict[str, Any]
    problem: str | None = None


def read_manifest(path: str | Path) -> dict[str, ManifestRow]:
    """Read a manifest CSV: one row per file, columns ``file, pin, disc, normal_force_N,
    temperature_C, repeat`` (more allowed, ignored; empty cells mean unknown).

    The encoding and the delimiter are detected as the readers detect them in an export
    (:mod:`tribopipe.readers.textio`): UTF-8 with or without BOM, UTF-16, cp1252; the
    header line decides between TAB, semicolon and comma (semicolon files may use a
    decimal comma). Returns ``{file as written: ManifestRow}``. An unreadable file, a
    missing column or a duplicate file is a :class:`ConfigError` naming the manifest; a
    bad value is recorded as that row's ``problem`` (an error for that file only).
    """
    p = Path(path)
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise ConfigError(f"cannot read manifest: {exc.strerror or exc}", path=p) from None
    if not raw:
        raise ConfigError("manifest is empty", path=p, line=1)
    try:
        text = decode(raw, str(p)).text
    except ReadError as exc:
        raise ConfigError(f"cannot read manifest: {exc.problem}", path=p,
                          hint=exc.hint) from None
    delimiter = detect_delimiter(text.splitlines()[:1]) or ","
    reader = csv.reader(io.StringIO(text, newline=""), delimiter=delimiter)
    try:
        header = [h.strip() for h in next(reader)]
    except StopIteration:
        raise ConfigError("manifest is empty", path=p, line=1) from None
    missing = [c for c in MANIFEST_COLUMNS if c not in header]
    if missing:
        raise ConfigError(
            f"manifest lacks column(s) {', '.join(missing)}; expected "
            f"{', '.join(MANIFEST_COLUMNS)} (more allowed)",
            path=p, line=1,
        )
    index = {name: header.index(name) for name in MANIFEST_COLUMNS}
    rows: dict[str, ManifestRow] = {}
    for lineno, cells in enumerate(reader, start=2):
        if not any(c.strip() for c in cells):
            continue
        cells = cells + [""] * (len(header) - len(cells))
        file = cells[index["file"]].strip()
        if not file:
            raise ConfigError("empty 'file' cell", path=p, line=lineno, column="file")
        key = file.replace("\\", "/")
        if key in rows:
            raise ConfigError(
                f"file {file!r} listed twice (first on line {rows[key].line})",
                path=p, line=lineno, column="file",
            )
        fields: dict[str, Any] = {}
        problem = None
        for name in LABEL_FIELDS:
            raw = cells[index[name]].strip()
            if not raw:
                continue
            try:
                if name == "repeat":
                    number = _parse_number(raw)
                    if not number.is_integer() or number < 0:
                        raise ValueError
                    fields[name] = int(number)
                elif name in ("normal_force_N", "temperature_C"):
                    value = _parse_number(raw)
                    if not math.isfinite(value):
                        raise ValueError
                    fields[name] = value
                else:
                    fields[name] = raw
            except ValueError:
                kind = "a whole number" if name == "repeat" else "a number"
                problem = f"{p}:{lineno}: {raw!r} is not {kind} (column {name!r})"
        rows[key] = ManifestRow(line=lineno, fields=fields, problem=problem)
    return rows


def _same(field_name: str, a: Any, b: Any, campaign: Campaign) -> bool:
    if field_name in ("pin", "disc"):
        return campaign.alias(str(a)).casefold() == campaign.alias(str(b)).casefold()
    return math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=1e-9)


def merge_metadata(
    file: str, sources: Sequence[tuple[str, Mapping[str, Any]]], campaign: Campaign
) -> dict[str, Any]:
    """Merge the label fields of several sources (in priority order) for one file.

    Names get their ``[names]`` alias; the first source giving a field defines its value.
    Raises :class:`CampaignError` naming the file, the field and both sources when two
    sources disagree.
    """
    merged: dict[str, Any] = {}
    origin: dict[str, str] = {}
    for source, fields in sources:
        for key, value in fields.items():
            if value is None:
                continue
            if key in ("pin", "disc"):
                value = campaign.alias(str(value))
            if key in merged:
                if not _same(key, merged[key], value, campaign):
                    raise CampaignError(
                        f"contradictory {key}: {origin[key]} says {merged[key]!r}, "
                        f"{source} says {value!r}",
                        path=file,
                        hint="fix the manifest or rename the file",
                    )
                continue
            merged[key] = value
            origin[key] = source
    return merged


def labels_from(file: str, merged: Mapping[str, Any], *, hints: Sequence[str] = ()) -> RunLabels:
    """Build :class:`RunLabels` from merged fields; :class:`CampaignError` when a required
    field (pin, disc, normal_force_N, temperature_C) is missing."""
    missing = [f for f in REQUIRED_FIELDS if merged.get(f) is None]
    if missing:
        hint = "; ".join(hints) if hints else "add the file to the manifest"
        raise CampaignError(f"metadata missing: {', '.join(missing)}", path=file, hint=hint)
    return RunLabels(
        pin=str(merged["pin"]),
        disc=str(merged["disc"]),
        normal_force_N=float(merged["normal_force_N"]),
        temperature_C=float(merged["temperature_C"]),
        repeat=None if merged.get("repeat") is None else int(merged["repeat"]),
    )
