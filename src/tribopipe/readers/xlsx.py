"""Excel workbooks (.xlsx): the RheoCompass table layout saved to Excel.

The cells of the first sheet that holds a RheoCompass label are turned into the same rows
of text cells a text export gives (numbers written with a decimal point), so one parser
serves both and the two read to identical tables.
"""

from __future__ import annotations

import zipfile

from ..errors import ReadError
from .rheocompass import looks_like

XLSX_MAGIC = b"PK\x03\x04"


def _cell_text(value: object) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    return str(value).strip()


def workbook_rows(path: str) -> list[tuple[int, list[str]]]:
    """The rows of the first sheet whose first column holds a RheoCompass label, as
    ``(1-based row number, text cells)``."""
    import openpyxl

    try:
        workbook = openpyxl.load_workbook(path, read_only=True, data_only=True)
    except (zipfile.BadZipFile, KeyError, OSError, ValueError) as exc:
        raise ReadError(f"not a readable Excel workbook: {exc}", path=path) from None
    except Exception as exc:  # openpyxl raises many types for a damaged workbook
        raise ReadError(
            f"not a readable Excel workbook ({type(exc).__name__})", path=path
        ) from None
    try:
        names = []
        for sheet in workbook.worksheets:
            names.append(sheet.title)
            rows = [
                (k, [_cell_text(v) for v in values])
                for k, values in enumerate(sheet.iter_rows(values_only=True), start=1)
            ]
            if looks_like(rows):
                return rows
    except Exception as exc:  # noqa: BLE001 - a damaged sheet (bad CRC, bad XML) read lazily
        raise ReadError(
            f"not a readable Excel workbook ({type(exc).__name__}: "
            f"{str(exc).splitlines()[0][:120] if str(exc) else 'damaged'})",
            path=path,
        ) from None
    finally:
        workbook.close()
    raise ReadError(
        f"no sheet holds a RheoCompass table (sheets: {', '.join(names) or 'none'})",
        path=path,
        hint="expected 'Project:', 'Test:', 'Interval data:' labels in the first column",
    )
