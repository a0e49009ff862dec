"""The reader's exact output, locked to the bit.

Every real export (``tests/data``, ``../shared/real-exports``) and a family of synthetic
exports in every layout the reader knows must read to exactly the tables recorded in
``tests/golden/reader_digests.json``: the same columns in the same order, the same dtypes,
the same values bit for bit (a SHA-256 of each column's bytes: float64 bits including NaN
payloads, int64 values, text cells), the same metadata; and the same one-line error for
each broken export. The expectations were written by the row-by-row reader before the
column-wise fast path (``readers/cells.py``) existed, so this test holds the fast path to
the old results.

The synthetic exports are written here from ``random.Random(seed)`` (stable across Python
versions), long enough (>= 300 rows) to take the fast path, with the quirks the reader
handles: UTF-16/UTF-8/cp1252, TAB/comma/semicolon, decimal comma, quoted status cells with
commas, padded cells, ``(invalid)`` points, raw-waveform sub-rows, ``******``, thousands
separators, duplicate column names, the 20000 loss-factor placeholder, E notation, a
``nan`` cell, Excel damage, a unit row in a plain CSV.

Regenerate the expectations only for an intended change of the reader's output:
``.venv/bin/python tests/test_readers_golden.py --write``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import random
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from conftest import DATA, SHARED

GOLDEN = Path(__file__).resolve().parent / "golden" / "reader_digests.json"
REAL = sorted(p.name for p in DATA.iterdir() if p.suffix in (".csv", ".txt", ".xlsx"))
SHARED_ONLY = ["rheocompass_fr_utf16_laos.csv", "rheocompass_en_utf8_comma.csv"]


# --------------------------------------------------------------------------- digests


def _sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()[:24]


def digest(result: list | Exception, path: Path) -> dict:
    """A JSON-ready fingerprint of what ``read_export`` gave: per interval its rows, its
    columns (name and dtype), a SHA-256 over the values' bytes of every column, one over
    the whole metadata, and the metadata a reader of this file checks by eye; or the
    error's class and message (the file's path replaced by its name)."""
    if isinstance(result, Exception):
        return {"error": type(result).__name__,
                "message": str(result).replace(str(path), path.name)}
    out = []
    for m in result:
        columns, hashes = [], []
        for name in m.data.columns:
            series = m.data[name]
            if isinstance(series.dtype, np.dtype):
                raw = np.ascontiguousarray(series.to_numpy()).tobytes()
            else:
                raw = "\x1f".join("\x00NA" if v is pd.NA else v for v in series).encode()
            dtype = series.dtype
            if not isinstance(dtype, np.dtype):  # text: where it is stored, what marks NA
                dtype = f"{dtype.name}[{getattr(dtype, 'storage', '')}, {dtype.na_value}]"
            columns.append(f"{name}:{dtype}")
            hashes.append(_sha(raw))
        meta = dataclasses.asdict(m.meta)
        meta["source_file"] = Path(meta["source_file"]).name
        out.append({
            "rows": len(m.data),
            "index": type(m.data.index).__name__,
            "columns": ", ".join(columns),
            "values": _sha(" ".join(hashes).encode()),
            "meta": _sha(json.dumps(meta, ensure_ascii=False).encode()),
            "where": [m.meta.test, m.meta.result, m.meta.interval, m.meta.header_line],
            "skipped": [m.meta.n_invalid_points, m.meta.n_waveform_rows],
            "notes": dict(m.meta.extra),
        })
    return json.loads(json.dumps({"intervals": out}))


def outcome(read: Callable, path: Path, **kwargs: object) -> dict:
    try:
        return digest(read(path, **kwargs), path)
    except Exception as exc:  # the digest records which error, and its message
        return digest(exc, path)


# --------------------------------------------------------------------------- exports


def _num(rng: random.Random, scale: float, decimals: int) -> str:
    return f"{rng.uniform(-scale, scale):.{decimals}f}"


def rheocompass_lines(seed: int, n: int, *, sep: str = "\t", comma: bool = False,
                      french: bool = False, status: Callable[[int], str] | None = None,
                      loss_factor: bool = False) -> list[str]:
    """One test, two results (a short set-up interval, then ``n`` rows), RheoCompass
    layout; numbers from ``random.Random(seed)``."""
    rng = random.Random(seed)
    labels = (("Projet:", "Test:", "Résultat:", "Intervalle et points de données:",
               "Interval données:") if french else
              ("Project:", "Test:", "Result:", "Interval and data points:", "Interval data:"))
    names = (["Point No.", "Temps", "Couple", "Force Normale", "Angle de Déflexion",
              "Température"] if french else
             ["Point No.", "Time", "Torque", "Normal Force", "Deflection Angle",
              "Temperature"])
    units = ["", "[s]", "[mN·m]", "[N]", "[mrad]", "[°C]"]
    if loss_factor:
        names.append("Loss Factor")
        units.append("[1]")
    names.append("Etat" if french else "Status")
    units.append("")
    status = status or (lambda k: "Dy_auto")
    lines = [f"{labels[0]}{sep}golden | LAB-PC, 1/2/2026 | 1", "", f"{labels[1]}{sep}DS30 pin",
             ""]
    for result, rows in ((1, 40), (2, n)):
        lines += [f"{labels[2]}{sep}Friction {result}", "",
                  f"{labels[3]}{sep}1{sep}{rows}",
                  labels[4] + sep + sep.join(names), sep * len(names),
                  sep + sep.join(units)]
        for k in range(1, rows + 1):
            cells = [str(k), f"{k / 10:.2f}", _num(rng, 30, 5), f"{3 + rng.random():.4f}",
                     _num(rng, 900, 3), f"{20 + rng.random():.2f}"]
            if rng.random() < 0.01:
                cells[2] = f"{rng.uniform(1, 9):.3E}"
            if loss_factor:
                cells.append("20000.000" if k % 7 == 0 else f"{rng.random():.3f}")
            cells.append(status(k))
            if comma:
                cells = [c.replace(".", ",") for c in cells]
            lines.append(sep + sep.join(cells))
        lines.append("")
    return lines


def _write(path: Path, lines: list[str], encoding: str, newline: str = "\r\n") -> Path:
    path.write_bytes((newline.join(lines) + newline).encode(encoding))
    return path


def en_utf16(path: Path) -> Path:
    flags = {17: "ME-,taD,TruStrain™", 101: "TruStrain™"}
    return _write(path, rheocompass_lines(1, 300, status=lambda k: flags.get(k, "Dy_auto"),
                                          loss_factor=True), "utf-16")


def fr_utf16(path: Path) -> Path:
    lines = rheocompass_lines(2, 320, comma=True, french=True,
                              status=lambda k: "M- " if k % 50 == 0 else "")
    out = []
    for line in lines:
        cells = line.split("\t")
        if len(cells) > 2 and cells[1] in ("5", "6", "7"):  # invalid points
            line = "\t" + cells[1] + "  (invalide)" + "\t" * (len(cells) - 2)
        out.append(line)
        if len(cells) > 2 and cells[1] in ("30", "31"):  # raw-waveform sub-rows
            out += ["\t\t" + "\t".join(["0,125"] * (len(cells) - 2))] * 3
    return _write(path, out, "utf-16")


def utf8_comma(path: Path) -> Path:
    lines = rheocompass_lines(3, 310, status=lambda k: '"ME-,WMa,taD"' if k % 9 == 0 else
                              "Dy_auto")
    out = []
    for line in lines:
        cells = line.split("\t")
        if cells[0].startswith("Project"):
            cells[1] = f'"{cells[1]}"'
        out.append(",".join(cells))
    return _write(path, out, "utf-8-sig")


def cp1252_resaved(path: Path) -> Path:
    lines = rheocompass_lines(4, 305, loss_factor=True)
    width = max(line.count("\t") for line in lines)
    out = []
    for line in lines:
        if line.startswith("Project:"):
            label, value = line.split("\t", 1)
            line = f'{label}\t"{value}"'
        out.append(line + "\t" * (width - line.count("\t")))
    return _write(path, out, "cp1252", "\n")


def rheoplus(path: Path, *, sep: str = "\t", header: bool = True) -> Path:
    rng = random.Random(6)
    lines = []
    if header:
        lines += ["Data Series Information", f"Name:{sep * 3}DS30 sample 1",
                  f"Number of Intervals:{sep * 3}2",
                  f"Application:{sep * 3}RHEOPLUS/32 V3.62 21006865-33024",
                  f"Device:{sep * 3}MCR302 SN81338429; FW3.71", ""]
    names = ["Meas. Pts.", "Time", "Torque", "Normal Force", "Storage Modulus",
             "Storage Modulus", "Temperature", "Status"]
    units = ["", "[s]", "[µNm]", "[N]", "[Pa]", "[Pa]", "[°C]", "[]"]
    for interval, rows in ((1, 300), (2, 180)):
        if header:
            lines += [f"Interval:{sep * 3}{interval}",
                      f"Number of Data Points:{sep * 3}{rows}", "",
                      "Measuring Profile:", f"  Strain{sep * 3}gamma = 1 %", ""]
        else:
            lines += ["#NAME?", ""]
        lines += [sep.join(names), sep.join(units)]
        for k in range(1, rows + 1):
            if k == 12:
                lines.append(f"{k}{sep}invalid point" + sep * (len(names) - 2))
                continue
            torque = rng.uniform(-30000, 30000)
            torque_cell = f"{torque:,.1f}" if sep == "\t" else f"{torque:.1f}"
            modulus = "******" if k % 3 else f"{rng.uniform(1e3, 9e3):.4E}"
            cells = [str(k), f"{k * 0.5:.2f}", torque_cell, f"{rng.random():.4f}", modulus,
                     modulus, f"{37 + rng.random():.2f}", "Dy_auto" if k % 4 else ""]
            lines.append(sep.join(cells))
        lines.append("")
    return _write(path, lines, "utf-8" if header else "cp1252")


def rheoplus_excel(path: Path) -> Path:
    return rheoplus(path, sep=",", header=False)


def plain_semicolon(path: Path) -> Path:
    rng = random.Random(7)
    lines = ["Time;Torque;Normal Force;Angle;Speed", "[s];[µN·m];[mN];[°];[rpm]"]
    for k in range(400):
        lines.append(f"{k / 10:.1f};{rng.uniform(-2e3, 2e3):.2f};{rng.uniform(2e3, 4e3):.1f};"
                     f"{k * 0.01:.2f};0,005".replace(".", ","))
        if k == 150:
            lines.append("")
    return _write(path, lines, "utf-8", "\n")


def plain_units_in_header(path: Path) -> Path:
    rng = random.Random(8)
    lines = ["time_s,torque_mNm,normal_force_N,temperature_C"]
    lines += [f"{k / 10:.1f},{_num(rng, 5, 4)},{3 + rng.random():.3f},{20 + rng.random():.2f}"
              for k in range(350)]
    return _write(path, lines, "utf-8")


def short_rheocompass(path: Path) -> Path:
    return _write(path, rheocompass_lines(9, 60), "utf-16")


def _edited(seed: int, edit: Callable[[list[str]], None]) -> Callable[[Path], Path]:
    def write(path: Path) -> Path:
        lines = rheocompass_lines(seed, 300)
        edit(lines)
        return _write(path, lines, "utf-16")

    return write


def _cell(row: int, column: int, value: str) -> Callable[[list[str]], None]:
    """Set one cell of the second result's data row ``row`` (1-based)."""
    def edit(lines: list[str]) -> None:
        k = next(i for i, ln in enumerate(lines) if ln.startswith("Result:\tFriction 2")) + 5
        cells = lines[k + row].split("\t")
        cells[column] = value
        lines[k + row] = "\t".join(cells)

    return edit


def _declare(rows: int) -> Callable[[list[str]], None]:
    def edit(lines: list[str]) -> None:
        k = [i for i, ln in enumerate(lines) if ln.startswith("Interval and data")][-1]
        lines[k] = f"Interval and data points:\t1\t{rows}"

    return edit


SYNTHETIC: dict[str, Callable[[Path], Path]] = {
    "en_utf16.csv": en_utf16,
    "fr_utf16.csv": fr_utf16,
    "utf8_comma.csv": utf8_comma,
    "cp1252_resaved.txt": cp1252_resaved,
    "nan_cell.csv": _edited(5, _cell(260, 4, "nan")),
    "rheoplus.txt": rheoplus,
    "rheoplus_excel.csv": rheoplus_excel,
    "plain_semicolon.csv": plain_semicolon,
    "plain_units.csv": plain_units_in_header,
    "short.csv": short_rheocompass,
    "word_in_torque.csv": _edited(10, _cell(250, 3, "oops")),
    "excel_error.csv": _edited(11, _cell(120, 4, "#NAME?")),
    "truncated.csv": _edited(12, _declare(400)),
    "short_row.csv": _edited(13, lambda lines: lines.__setitem__(-100, "\t2\t0.3")),
    "extra_cell.csv": _edited(14, _cell(200, 7, "Dy_auto\tsurplus")),
    "bad_point.csv": _edited(15, _cell(77, 1, "7b")),
    "padded_number.csv": _edited(16, _cell(33, 3, " 1.25 ")),
    "thousands_in_torque.csv": _edited(17, _cell(90, 3, "1,250.5")),
}


def synthetic_outcomes(read: Callable, folder: Path) -> dict[str, dict]:
    return {name: outcome(read, write(folder / name)) for name, write in SYNTHETIC.items()}


def real_outcomes(read: Callable) -> dict[str, dict]:
    out = {name: outcome(read, DATA / name) for name in REAL}
    for name in SHARED_ONLY:
        if (SHARED / "real-exports" / name).exists():
            out[name] = outcome(read, SHARED / "real-exports" / name)
    return out


# --------------------------------------------------------------------------- the tests


@pytest.fixture(scope="module")
def expected() -> dict:
    return json.loads(GOLDEN.read_text(encoding="utf-8"))


@pytest.mark.parametrize("name", REAL)
def test_real_export_reads_to_the_recorded_tables(expected: dict, name: str) -> None:
    from tribopipe.readers import read_export

    assert outcome(read_export, DATA / name) == expected["real"][name]


@pytest.mark.parametrize("name", SHARED_ONLY)
def test_shared_real_export_reads_to_the_recorded_tables(
    expected: dict, shared_dir: Path, name: str
) -> None:
    from tribopipe.readers import read_export

    path = shared_dir / "real-exports" / name
    assert outcome(read_export, path) == expected["real"][name]


@pytest.mark.parametrize("name", list(SYNTHETIC))
def test_synthetic_export_reads_to_the_recorded_tables(
    expected: dict, tmp_path: Path, name: str
) -> None:
    from tribopipe.readers import read_export

    got = outcome(read_export, SYNTHETIC[name](tmp_path / name))
    assert got == expected["synthetic"][name]


def test_the_recorded_outcomes_cover_both_paths_and_errors(expected: dict) -> None:
    """The family is what it claims: long tables, errors with line numbers, and the
    quirks named above (a check on the expectations file itself)."""
    synthetic = expected["synthetic"]
    errors = {k: v["message"] for k, v in synthetic.items() if "error" in v}
    assert set(errors) == {"word_in_torque.csv", "excel_error.csv", "truncated.csv",
                           "short_row.csv", "extra_cell.csv", "bad_point.csv"}
    assert "word_in_torque.csv:" in errors["word_in_torque.csv"]
    assert "expected a number" in errors["word_in_torque.csv"]
    rows = [i["rows"] for v in synthetic.values() for i in v.get("intervals", [])]
    assert max(rows) >= 300 and min(rows) < 150
    assert synthetic["fr_utf16.csv"]["intervals"][1]["skipped"] == [3, 6]
    plus = synthetic["rheoplus.txt"]["intervals"][0]
    assert plus["skipped"] == [1, 0]
    starred = sum(1 for k in range(1, 301) if k % 3 and k != 12)  # see rheoplus()
    assert plus["notes"]["missing_cells"] == str(2 * starred)
    assert "storage_modulus_2_Pa:" in plus["columns"]
    assert expected["synthetic"]["en_utf16.csv"]["intervals"][1]["notes"] == {
        "loss_factor_placeholders": str(300 // 7)}


def dump(data: dict) -> str:
    """The expectations as JSON, one interval per line."""
    lines = ["{"]
    for g, (group, outcomes) in enumerate(data.items()):
        lines.append(f" {json.dumps(group)}: {{")
        for k, (name, result) in enumerate(outcomes.items()):
            end = "," if k < len(outcomes) - 1 else ""
            if "error" in result:
                lines.append(f"  {json.dumps(name)}: {json.dumps(result, ensure_ascii=False)}{end}")
                continue
            lines.append(f"  {json.dumps(name)}: {{\"intervals\": [")
            items = [json.dumps(i, ensure_ascii=False) for i in result["intervals"]]
            lines += [f"   {item}," for item in items[:-1]] + [f"   {items[-1]}"]
            lines.append(f"  ]}}{end}")
        lines.append(" }" + ("," if g < len(data) - 1 else ""))
    lines.append("}")
    return "\n".join(lines) + "\n"


def main(argv: list[str]) -> int:
    """``--write``: record what the current reader gives as the expectations."""
    import tempfile

    from tribopipe.readers import read_export

    if argv != ["--write"]:
        print(__doc__)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        data = {"real": real_outcomes(read_export),
                "synthetic": synthetic_outcomes(read_export, Path(tmp))}
    GOLDEN.write_text(dump(data), encoding="utf-8")
    print(f"wrote {GOLDEN}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
