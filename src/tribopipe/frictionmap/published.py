"""The founding paper's published friction map, and any table in its 7-column schema.

:func:`read_frictionmap_table` reads the MATLAB ``FrictionMap.mat`` (with mat-io) or its CSV
form; :func:`import_records` turns the rows into map records (published rows keep the
paper's sliding speed); :func:`import_table` folds them into a map. The published CSV ships
with tribopipe (:func:`published_csv_path`).
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypedDict

from .. import __version__
from ..errors import MapError, ReadError, RowError
from ..escape import csv_uncell
from ..files import file_sha256, regular_file
from ..materials import Vocabulary, shipped_vocabulary
from ..physics import FOUNDING_SLIDING_SPEED_MM_S
from ..validate import name_problem
from .records import imported_id
from .schema import SOURCE_PUBLISHED, MapRow, is_missing, records_frame, utc_now
from .store import AppendReport, append_records

if TYPE_CHECKING:
    import pandas as pd

#: ``lab`` of the published rows: the founding paper's authors measured them.
PUBLISHED_LAB = "Berthold et al. (founding paper)"


class Paper(TypedDict):
    """A paper as cited: authors as (family name, given names), title, year, data URL."""

    authors: tuple[tuple[str, str], ...]
    title: str
    year: int
    data: str


#: The founding paper, cited wherever its rows are published again.
FOUNDING_PAPER: Paper = {
    # (family name, given names as published)
    "authors": (("Berthold", "R."), ("Burgner-Kahrs", "J."), ("Wangenheim", "M."),
                ("Kahms", "S.")),
    "title": "Investigating frictional contact behavior for soft material robot simulations",
    "year": 2023,
    "data": "https://github.com/RebeccaBerthold/FrictionMap",
}
#: The published map's 7-column schema (RebeccaBerthold/FrictionMap).
FRICTIONMAP_COLUMNS: tuple[str, ...] = (
    "pin",
    "disc",
    "contactForce",
    "contactPressure",
    "temperature",
    "measurementNo",
    "cof",
)


def read_frictionmap_table(path: str | os.PathLike[str]) -> pd.DataFrame:
    """Read a table in the published 7-column schema (:data:`FRICTIONMAP_COLUMNS`) from the
    MATLAB ``FrictionMap.mat`` (a MATLAB ``table``, read with mat-io) or a CSV file.

    Returns the 7 columns (text, then floats). Raises :class:`MapError` naming the file and
    the line (CSV) or row (``.mat``) and column of a missing or non-numeric value.
    """
    import pandas as pd

    p = Path(path)
    try:
        regular_file(p, what="a FrictionMap .mat or CSV")
    except ReadError as exc:
        raise MapError(exc.problem, path=p) from None
    if p.suffix.lower() == ".mat":
        table = _read_mat_table(p)
        first_line = None
    else:
        try:
            table = pd.read_csv(p, dtype=str, keep_default_na=False, skipinitialspace=True)
        except (ValueError, UnicodeDecodeError, OSError) as exc:
            raise MapError(
                f"cannot read as CSV ({exc})",
                path=p,
                hint=f"expected columns {', '.join(FRICTIONMAP_COLUMNS)}",
            ) from None
        first_line = 2  # line 1 is the header
    table.columns = [str(c).strip() for c in table.columns]
    absent = [c for c in FRICTIONMAP_COLUMNS if c not in table.columns]
    if absent:
        raise MapError(
            f"missing column(s) {', '.join(absent)}; expected the FrictionMap schema "
            f"{', '.join(FRICTIONMAP_COLUMNS)}",
            path=p,
            line=1 if first_line else None,
            column=absent[0],
        )
    out: dict[str, Any] = {}
    for col in FRICTIONMAP_COLUMNS:
        values = table[col].tolist()
        if col in ("pin", "disc"):
            # a cell we wrote safe for spreadsheets ('=x) reads back as what it was
            texts = ["" if is_missing(v) else csv_uncell(str(v).strip()) for v in values]
            for i, text in enumerate(texts):
                if not text:
                    raise _where(p, first_line, i, col, "empty, expected a material name")
                problem = name_problem(text)
                if problem is not None:
                    raise _where(p, first_line, i, col, f"expected a material name: {problem}")
            out[col] = texts
            continue
        numbers = []
        for i, v in enumerate(values):
            text = "" if is_missing(v) else str(v).strip()
            if text == "" and col == "temperature":
                numbers.append(math.nan)  # unknown temperature is allowed, unknown μ is not
                continue
            try:
                number = float(text) if isinstance(v, str) else float(v)
            except (TypeError, ValueError):
                number = math.nan
            if not math.isfinite(number):
                raise _where(p, first_line, i, col, f"{text!r} is not a finite number")
            numbers.append(number)
        out[col] = numbers
    return pd.DataFrame(out, columns=list(FRICTIONMAP_COLUMNS))


def _where(path: Path, first_line: int | None, i: int, col: str, problem: str) -> MapError:
    if first_line is None:
        return MapError(f"row {i + 1}: {problem}", path=path, column=col)
    return MapError(problem, path=path, line=first_line + i, column=col)


def _read_mat_table(path: Path) -> pd.DataFrame:
    import warnings

    import pandas as pd

    with warnings.catch_warnings():
        # mat-io sets a pandas option that pandas 3 deprecates; not our users' concern
        warnings.simplefilter("ignore", DeprecationWarning)
        try:
            import matio
        except ImportError:  # pragma: no cover - mat-io is a dependency
            raise MapError("reading .mat files needs the mat-io package", path=path,
                           hint="pip install mat-io") from None
        try:
            contents = matio.load_from_mat(str(path))
        except Exception as exc:  # mat-io raises many types for foreign files
            raise MapError(f"not a readable MATLAB file ({type(exc).__name__}: {exc})",
                           path=path) from None
    tables = [v for v in contents.values() if isinstance(v, pd.DataFrame)]
    if not tables:
        raise MapError(
            f"holds no MATLAB table (variables: {', '.join(contents) or 'none'})",
            path=path,
            hint="expected the FrictionMap.mat 'frictionMap' table",
        )
    table = contents.get("frictionMap")
    if not isinstance(table, pd.DataFrame):
        table = tables[0]
    return table.astype({c: object for c in table.columns if str(c) in ("pin", "disc")})


def _is_published(table: pd.DataFrame) -> bool:
    """True when every row of ``table`` is a row of the shipped published map."""
    published = read_frictionmap_table(published_csv_path())
    def keys(t: pd.DataFrame) -> set[tuple[Any, ...]]:
        return set(t.itertuples(index=False, name=None))
    return len(table) > 0 and keys(table) <= keys(published)


def published_csv_path() -> Path:
    """The published map shipped with tribopipe (``tribopipe/data/frictionmap_published.csv``)."""
    from importlib.resources import files

    return Path(str(files("tribopipe") / "data" / "frictionmap_published.csv"))


def import_records(
    path: str | os.PathLike[str], *, source: str | None = None,
    vocabulary: Vocabulary | None = None,
) -> list[MapRow]:
    """Friction-map rows for a table in the published 7-column schema (.mat or CSV).

    ``source`` labels where the rows came from; by default ``published:Berthold2023`` when
    every row is one of the published map's rows (whatever the file's name or format),
    else ``import:<file name>``. Ids hash the source and the conditions, so importing the
    same rows again is idempotent. μ_S and the measured values are missing; published rows
    record the paper's sliding speed (0.007 mm/s), others leave it missing. Every pin and
    disc name is resolved through the materials ``vocabulary`` (default: the shipped
    one): stored under its canonical name, the given one kept in ``pin_as_given``/
    ``disc_as_given``; a name it does not know refuses the table in one
    :class:`~tribopipe.materials.MaterialError` naming every such name, with the fix.
    """
    p = Path(path)
    table = read_frictionmap_table(p)
    canonical = (vocabulary or shipped_vocabulary()).resolve_all(
        [(what, str(name)) for what in ("pin", "disc") for name in table[what]], p)
    if source is None:
        source = SOURCE_PUBLISHED if _is_published(table) else f"import:{p.name}"
    published = source == SOURCE_PUBLISHED
    file_hash = file_sha256(p)
    stamp = utc_now()
    records = []
    for pin, disc, force, pressure, temperature, number, cof in table.itertuples(
        index=False, name=None
    ):
        repeat = int(number) if float(number).is_integer() else None
        records.append(
            MapRow(
                # the id from the names as the table writes them, as it always was:
                # importing the same table again stays a no-op
                measurement_id=imported_id(source, str(pin), str(disc), force,
                                           temperature, repeat),
                source=source,
                lab=PUBLISHED_LAB if published else None,
                pin=canonical[("pin", str(pin))],
                disc=canonical[("disc", str(disc))],
                pin_as_given=None if canonical[("pin", str(pin))] == pin else pin,
                disc_as_given=None if canonical[("disc", str(disc))] == disc else disc,
                normal_force_N=force,
                pressure_kPa=pressure,
                temperature_C=temperature,
                sliding_speed_mm_s=FOUNDING_SLIDING_SPEED_MM_S if published else None,
                repeat=repeat,
                mu_k=cof,
                flags="",
                method="published" if published else "imported",
                source_file=p.name,
                file_hash=file_hash,
                tribopipe_version=__version__,
                reduced_at=stamp,
                excluded=False,
            )
        )
    _validate_rows(p, records)
    seen: set[str] = set()
    for row, rec in enumerate(records):
        if rec.measurement_id not in seen:
            seen.add(rec.measurement_id)
            continue
        raise MapError(
            "two rows have the same pin, disc, force, temperature and measurementNo",
            path=p,
            line=row + 2 if p.suffix.lower() != ".mat" else None,
            column="measurementNo",
        )
    return records


def _validate_rows(path: Path, records: list[MapRow]) -> None:
    """Check the records of an imported table as every map row is checked
    (:func:`~tribopipe.frictionmap.checks.validate_runs`: force > 0, temperature above
    −273.15 °C, 0 ≤ μ ≤ 10 ...); :class:`MapError` naming the file, the line (CSV) or
    row (``.mat``) and the column of the first bad one."""
    try:
        records_frame(records)
    except MapError:
        pass
    else:
        return
    for row, rec in enumerate(records):
        try:
            records_frame([rec])
        except RowError as exc:
            problem = exc.row_problem
            csv_line = row + 2 if path.suffix.lower() != ".mat" else None
            where = "" if csv_line else f"row {row + 1}: "
            raise MapError(where + problem, path=path, line=csv_line,
                           column=exc.column) from None


def import_table(
    path: str | os.PathLike[str],
    file: str | os.PathLike[str] | None = None,
    *,
    source: str | None = None,
    replace: bool = False,
    vocabulary: Vocabulary | None = None,
) -> AppendReport:
    """Import a 7-column FrictionMap table (.mat or CSV; default: the shipped published
    map) into the map at ``path``; see :func:`import_records`."""
    records = import_records(published_csv_path() if file is None else file, source=source,
                             vocabulary=vocabulary)
    return append_records(path, records, replace=replace)
