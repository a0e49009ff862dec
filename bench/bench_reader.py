"""Reader benchmark: ``read_export`` against a bare decode + ``pyarrow.csv`` parse.

Generates long exports (5,000-15,000 rows of the friction interval, plus a 200-row set-up
interval) from the project's synthetic runs (:mod:`generators.synthetic`) in every text
layout the reader knows, plus an Excel twin, and measures per file the CPU time
(``time.process_time``, all threads of the process) of

* ``tribopipe.readers.read_export(path)`` — detection included, nothing forced;
* the **bare parse** of the same file: read the bytes, decode them with the encoding
  given, keep the data lines (a list comprehension over ``splitlines()``), join them and
  parse them with ``pyarrow.csv.read_csv`` (delimiter and decimal mark given, default
  options otherwise). For the ``.xlsx`` file the bare read is ``openpyxl``'s read-only
  ``iter_rows(values_only=True)`` over the sheet, keeping the data rows.

Each file is read ``--repeat`` times by both, back to back in alternating order; the
figures are the medians of the CPU times, the ratio the median of the pairs' ratios
(a pair shares the state of a shared machine; a slow spell hits both of its halves).
Target (issue 10): at most 2 x on every format.

    nice .venv/bin/python bench/bench_reader.py [--repeat 15] [--sizes 5000,10000,15000]

Prints a table and writes ``bench/reader_results.json``.
"""

from __future__ import annotations

import argparse
import io
import json
import math
import platform
import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the generators

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
SIZES = (5_000, 10_000, 15_000)


@dataclass(frozen=True)
class Layout:
    """One export layout: how to write it and how the bare parse reads it."""

    name: str
    suffix: str
    encoding: str
    delimiter: str
    decimal: str
    data_line: Callable[[str], bool]


def _rc_data(line: str) -> bool:
    return line[1:2].isdigit()  # RheoCompass: empty first cell, then the point number


def _first_digit(line: str) -> bool:
    return line[:1].isdigit()  # Rheoplus and plain CSV: the line starts with a number


LAYOUTS: dict[str, Layout] = {
    "utf16-tab-en": Layout("utf16-tab-en", ".csv", "utf-16", "\t", ".", _rc_data),
    "utf16-tab-fr": Layout("utf16-tab-fr", ".csv", "utf-16", "\t", ",", _rc_data),
    "utf8-comma-quoted": Layout("utf8-comma-quoted", ".csv", "utf-8-sig", ",", ".", _rc_data),
    "cp1252-resaved": Layout("cp1252-resaved", ".txt", "cp1252", "\t", ".", _rc_data),
    "rheoplus-thousands": Layout("rheoplus-thousands", ".txt", "utf-8", "\t", ".",
                                 _first_digit),
    "plain-csv": Layout("plain-csv", ".csv", "utf-8", ",", ".", _first_digit),
    "xlsx": Layout("xlsx", ".xlsx", "", "", ".", _rc_data),
}


# --------------------------------------------------------------------------- the files


def _run(rows: int, seed: int):
    from generators.synthetic import SyntheticRun

    return SyntheticRun(mu_s=0.8, mu_k=0.55, normal_force_N=3.0, duration_s=rows / 10.0,
                        noise=0.006, seed=seed)


def _status(k: int) -> str:
    """A status cell as RheoCompass writes them: mostly one flag, sometimes several."""
    return '"ME-,taD,TruStrain™"' if k % 97 == 0 else "Dy_auto"


def _rheocompass_lines(rows: int, seed: int, language: str = "en") -> list[str]:
    from generators.synthetic import rheocompass_text

    text = rheocompass_text(_run(rows, seed), project="bench | DESKTOP-1, 1/1/2026 | 1",
                            test=f"run {seed}", sample="DS30", language=language)
    return text.split("\r\n")[:-1]


def write_utf16(path: Path, rows: int, seed: int, language: str) -> None:
    from generators.synthetic import write_rheocompass_export

    write_rheocompass_export(path, _run(rows, seed), project="bench", test=f"run {seed}",
                             sample="DS30", language=language)


def write_utf8_comma(path: Path, rows: int, seed: int) -> None:
    """UTF-8 + BOM, comma cells, quoted multi-flag status cells (as APRheoPlotR's file)."""
    out = []
    for k, line in enumerate(_rheocompass_lines(rows, seed)):
        cells = line.split("\t")
        if line[1:2].isdigit():
            cells[-1] = _status(k)
        elif "," in line:
            cells = [f'"{c}"' if "," in c else c for c in cells]
        out.append(",".join(cells))
    path.write_bytes(b"\xef\xbb\xbf" + ("\r\n".join(out) + "\r\n").encode("utf-8"))


def write_cp1252(path: Path, rows: int, seed: int) -> None:
    """Re-saved by another program: cp1252, LF, padded label rows, quoted project name."""
    lines = _rheocompass_lines(rows, seed)
    width = max(line.count("\t") for line in lines)
    out = []
    for line in lines:
        if line.startswith("Project:"):
            label, value = line.split("\t", 1)
            line = f'{label}\t"{value}"'
        elif line[1:2].isdigit():
            line = line + "Dy_auto"
        out.append(line + "\t" * (width - line.count("\t")))
    path.write_bytes(("\n".join(out) + "\n").encode("cp1252"))


def write_rheoplus(path: Path, rows: int, seed: int) -> None:
    """Rheoplus "Data Series Information": thousands separators (torque in µNm), ``******``
    columns, a duplicate column name."""
    from generators.synthetic import make_intervals

    head = ["Data Series Information", "Name:\t\t\tDS30 on steel", "Number of Intervals:\t\t\t2",
            "Application:\t\t\tRHEOPLUS/32 V3.62 21006865-33024",
            "Device:\t\t\tMCR302 SN81338429; FW3.71; Slot(8,-1); Adj(7,0)d",
            "Measuring Date/Time:\t\t\t21/03/2022; 15:04 PM", ""]
    names = ("Meas. Pts.\tTime\tTorque\tNormal Force\tDeflection Angle\tSpeed\tTemperature"
             "\tStorage Modulus\tStorage Modulus\tStatus")
    units = "\t[s]\t[µNm]\t[N]\t[mrad]\t[1/min]\t[°C]\t[Pa]\t[Pa]\t[]"
    out = list(head)
    for i, frame in enumerate(make_intervals(_run(rows, seed)), start=1):
        n = len(frame)
        out += [f"Interval:\t\t\t{i}", f"Number of Data Points:\t\t\t{n}", "",
                f"Time Setting:\t\t\t{n} Meas. Pts.", "Measuring Profile:",
                "  Rotational Speed\t\t\tn = 0.005 1/min", "", names, units]
        t = frame["time_s"].to_numpy()
        torque = frame["torque_Nm"].to_numpy() * 1e6
        force = frame["normal_force_N"].to_numpy()
        angle = frame["angle_rad"].to_numpy() * 1e3
        speed = frame["speed_rad_s"].to_numpy() * 60 / (2 * math.pi)
        temp = frame["temperature_C"].to_numpy()
        for k in range(n):
            out.append(f"{k + 1}\t{t[k]:.2f}\t{torque[k]:,.1f}\t{force[k]:.4f}\t{angle[k]:,.3f}"
                       f"\t{speed[k]:.6f}\t{temp[k]:.2f}\t******\t******\tDy_auto")
        out.append("")
    path.write_bytes(("\r\n".join(out) + "\r\n").encode("utf-8"))


def write_plain_csv(path: Path, rows: int, seed: int) -> None:
    """A plain CSV with units in the header (another instrument's export)."""
    from generators.synthetic import make_intervals

    frame = make_intervals(_run(rows, seed))[-1]
    columns = [frame["time_s"].to_numpy(), frame["torque_Nm"].to_numpy() * 1e3,
               frame["normal_force_N"].to_numpy(), frame["angle_rad"].to_numpy() * 1e3,
               frame["speed_rad_s"].to_numpy() * 60 / (2 * math.pi),
               frame["temperature_C"].to_numpy()]
    body = np.column_stack(columns)
    buffer = io.StringIO()
    buffer.write("Time [s],Torque [mN·m],Normal Force [N],Deflection Angle [mrad],"
                 "Rotational Speed [1/min],Temperature [°C]\n")
    np.savetxt(buffer, body, fmt=["%.2f", "%.5f", "%.4f", "%.4f", "%.6f", "%.2f"],
               delimiter=",")
    path.write_bytes(buffer.getvalue().encode("utf-8"))


def write_xlsx(path: Path, rows: int, seed: int) -> None:
    """The RheoCompass layout in an Excel sheet, numbers as numbers."""
    import openpyxl

    workbook = openpyxl.Workbook(write_only=True)
    sheet = workbook.create_sheet("Sheet1")
    for line in _rheocompass_lines(rows, seed):
        cells: list[object] = line.split("\t")
        if line[1:2].isdigit():
            cells = [None, int(cells[1]), *(float(c) for c in cells[2:-1]), "Dy_auto"]
        sheet.append([None if c == "" else c for c in cells])
    workbook.save(path)


def generate(out: Path, sizes: tuple[int, ...], names: list[str]) -> list[tuple[str, Path]]:
    """Write every layout at every size into ``out`` (kept when already there)."""
    out.mkdir(parents=True, exist_ok=True)
    writers = {
        "utf16-tab-en": lambda p, n, s: write_utf16(p, n, s, "en"),
        "utf16-tab-fr": lambda p, n, s: write_utf16(p, n, s, "fr"),
        "utf8-comma-quoted": write_utf8_comma,
        "cp1252-resaved": write_cp1252,
        "rheoplus-thousands": write_rheoplus,
        "plain-csv": write_plain_csv,
        "xlsx": write_xlsx,
    }
    files = []
    for name in names:
        layout = LAYOUTS[name]
        for k, rows in enumerate(sizes):
            path = out / f"{name}_{rows}{layout.suffix}"
            if not path.exists():
                writers[name](path, rows, 100 + k)
            files.append((name, path))
    return files


# --------------------------------------------------------------------------- measuring


def bare_parse(path: Path, layout: Layout) -> int:
    """Decode, keep the data lines, ``pyarrow.csv`` parse; returns the number of rows."""
    import pyarrow.csv as pacsv

    if layout.suffix == ".xlsx":
        return _bare_xlsx(path)
    text = path.read_bytes().decode(layout.encoding)
    data = [line for line in text.splitlines() if layout.data_line(line)]
    table = pacsv.read_csv(
        io.BytesIO("\n".join(data).encode("utf-8")),
        read_options=pacsv.ReadOptions(autogenerate_column_names=True),
        parse_options=pacsv.ParseOptions(delimiter=layout.delimiter),
        convert_options=pacsv.ConvertOptions(decimal_point=layout.decimal),
    )
    return table.num_rows


def _bare_xlsx(path: Path) -> int:
    import openpyxl

    workbook = openpyxl.load_workbook(path, read_only=True, data_only=True)
    try:
        rows = [r for r in workbook.worksheets[0].iter_rows(values_only=True)
                if len(r) > 1 and isinstance(r[1], int)]
    finally:
        workbook.close()
    return len(rows)


def read(path: Path) -> int:
    from tribopipe.readers import read_export

    return sum(len(m.data) for m in read_export(path))


def cpu_ms(fn: Callable[[], object]) -> float:
    t0 = time.process_time()
    fn()
    return (time.process_time() - t0) * 1e3


def measure(files: list[tuple[str, Path]], repeat: int) -> list[dict]:
    """Per file: median CPU [ms] of read_export and of the bare parse, and their ratio."""
    results = []
    for name, path in files:
        layout = LAYOUTS[name]
        n_read, n_bare = read(path), bare_parse(path, layout)  # warm-up, and a sanity check
        if n_read != n_bare:
            raise SystemExit(f"{path}: read_export gives {n_read} rows, the bare parse {n_bare}")
        reader, bare = [], []
        for k in range(repeat):
            # back to back, in alternating order: a pair shares the machine's state
            if k % 2:
                bare.append(cpu_ms(lambda p=path, lay=layout: bare_parse(p, lay)))
                reader.append(cpu_ms(lambda p=path: read(p)))
            else:
                reader.append(cpu_ms(lambda p=path: read(p)))
                bare.append(cpu_ms(lambda p=path, lay=layout: bare_parse(p, lay)))
        r, b = statistics.median(reader), statistics.median(bare)
        ratio = statistics.median(x / y for x, y in zip(reader, bare, strict=True))
        results.append({"layout": name, "file": path.name, "rows": n_read,
                        "bytes": path.stat().st_size, "read_export_ms": round(r, 2),
                        "bare_ms": round(b, 2), "ratio": round(ratio, 2)})
        print(f"{name:<20} {path.name:<32} {n_read:>6} rows  read_export {r:7.1f} ms  "
              f"bare {b:6.1f} ms  ratio {ratio:5.2f}", flush=True)
    return results


def summarise(results: list[dict]) -> dict[str, dict[str, float]]:
    """Per layout: median read_export and bare CPU [ms], median and worst ratio."""
    out: dict[str, dict[str, float]] = {}
    for name in dict.fromkeys(r["layout"] for r in results):
        rows = [r for r in results if r["layout"] == name]
        out[name] = {
            "read_export_ms": round(statistics.median(r["read_export_ms"] for r in rows), 2),
            "bare_ms": round(statistics.median(r["bare_ms"] for r in rows), 2),
            "median_ratio": round(statistics.median(r["ratio"] for r in rows), 2),
            "worst_ratio": round(max(r["ratio"] for r in rows), 2),
        }
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--sizes", default=",".join(map(str, SIZES)))
    parser.add_argument("--layouts", default=",".join(LAYOUTS))
    parser.add_argument("--out", type=Path, default=HERE / "out" / "reader")
    parser.add_argument("--json", type=Path, default=HERE / "reader_results.json")
    args = parser.parse_args(argv)
    sizes = tuple(int(s) for s in args.sizes.split(","))
    names = [n for n in args.layouts.split(",") if n]
    unknown = set(names) - set(LAYOUTS)
    if unknown:
        parser.error(f"unknown layout(s) {', '.join(sorted(unknown))}")
    files = generate(args.out, sizes, names)
    import tribopipe.readers  # noqa: F401 - import cost is not reading

    results = measure(files, args.repeat)
    summary = summarise(results)
    print()
    print(f"{'layout':<20} {'read_export ms':>15} {'bare ms':>8} {'ratio':>6} {'worst':>6}")
    for name, s in summary.items():
        print(f"{name:<20} {s['read_export_ms']:>15.1f} {s['bare_ms']:>8.1f} "
              f"{s['median_ratio']:>6.2f} {s['worst_ratio']:>6.2f}")
    worst = max(s["worst_ratio"] for s in summary.values())
    args.json.write_text(json.dumps({
        "when": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "python": platform.python_version(), "machine": platform.machine(),
        "cpus": __import__("os").cpu_count(), "load_avg": __import__("os").getloadavg(),
        "repeat": args.repeat, "summary": summary, "files": results,
    }, indent=1) + "\n", encoding="utf-8")
    print(f"\nworst ratio {worst:.2f} (target <= 2)")
    return 0 if worst <= 2.0 else 1


if __name__ == "__main__":
    sys.exit(main())
