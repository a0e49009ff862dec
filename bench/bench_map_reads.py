"""How many times each command reads and checks the friction map.

Counts the calls of the store's row conversion (``frictionmap.store._from_arrow``), which
every read of a map's rows passes through once (a single-file map, or a map folder's
parts together), while each command runs through the real CLI (``click.testing``) on a
map of the shipped example campaign (48 synthetic exports, 96 runs) plus the published
map. A command that reads the map once shows 1; one that appends shows 1 more for the
locked read-modify-write (the read under the lock).

    PYTHONPATH=src .venv/bin/python bench/bench_map_reads.py [--single-file]

``--single-file`` runs on a map in the format before map folders (one Parquet file).
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--single-file", action="store_true")
    parser.add_argument("--trace", action="store_true", help="print where each read is made")
    args = parser.parse_args()

    from click.testing import CliRunner

    from tribopipe.cli import main as cli
    from tribopipe.frictionmap import store

    calls: list[int] = []
    real: Callable[..., Any] = store._from_arrow

    def counting(*a: Any, **k: Any) -> Any:
        calls.append(1)
        if args.trace:
            import traceback

            frames = [f"{Path(f.filename).name}:{f.lineno}:{f.name}"
                      for f in traceback.extract_stack()[:-1] if "/tribopipe/" in f.filename]
            print("   read:", " <- ".join(reversed(frames[-5:])), file=sys.__stderr__)
        return real(*a, **k)

    work = Path(tempfile.mkdtemp(prefix="map_reads_"))
    raw = work / "raw"
    shutil.copytree(ROOT / "raw" / "example", raw)
    late = raw / "DS30_steel_9N_20C_r2.csv"
    held = work / late.name
    late.replace(held)                      # the new export of `batch` and `reduce`
    later = raw / "DS30_steel_9N_20C_r1.csv"
    held_later = work / later.name
    later.replace(held_later)               # a second batch's new export
    mp = work / "map.parquet"
    out = work / "out"
    runner = CliRunner()

    def run(*argv: str) -> Any:
        result = runner.invoke(cli, list(argv), catch_exceptions=False)
        if result.exit_code not in (0, 1):
            raise SystemExit(f"{' '.join(argv)}: exit {result.exit_code}\n{result.output}")
        return result

    run("batch", str(raw), "--manifest", str(raw / "manifest.csv"), "--map", str(mp),
        "--out", str(out), "--no-plots", "-j", "1")
    run("map", "import", "--published", "--map", str(mp))
    if args.single_file:
        runs = store.read_map(mp)
        shutil.rmtree(mp) if mp.is_dir() else mp.unlink()
        store.write_map_copy(mp, runs)
    shutil.copy(held, work / "new.csv")

    commands: list[tuple[str, list[str]]] = [
        ("reduce (one export into the map)",
         ["reduce", str(work / "new.csv"), "--pin", "DS30", "--disc", "steel", "--force", "9",
          "--temperature", "20", "--repeat", "2", "--map", str(mp), "--out", str(work / "r")]),
        ("batch (one new export, after `reduce` changed the map)",
         ["batch", str(raw), "--manifest", str(raw / "manifest.csv"), "--map", str(mp),
          "--out", str(out), "--no-plots", "-j", "1"]),
        ("batch (one new export, the map as the last batch left it)",
         ["batch", str(raw), "--manifest", str(raw / "manifest.csv"), "--map", str(mp),
          "--out", str(out), "--no-plots", "-j", "1"]),
        ("batch (unchanged re-run)",
         ["batch", str(raw), "--manifest", str(raw / "manifest.csv"), "--map", str(mp),
          "--out", str(out), "--no-plots", "-j", "1"]),
        ("map show", ["map", "show", "--map", str(mp)]),
        ("map show --groups", ["map", "show", "--groups", "--map", str(mp)]),
        ("map table --layout paper", ["map", "table", "--layout", "paper", "--map", str(mp)]),
        ("map validate", ["map", "validate", str(mp)]),
        ("map fit", ["map", "fit", "--map", str(mp)]),
        ("query", ["query", "--pin", "DS30", "--disc", "steel", "--pressure", "50",
                   "--temperature", "20", "--map", str(mp)]),
        ("export abaqus (one pair)", ["export", "abaqus", "--pin", "Dragonskin 30",
                                      "--disc", "steel",
                                      "--map", str(mp), "-o", str(work / "f.inp")]),
        ("export abaqus (every pair)", ["export", "abaqus", "--map", str(mp),
                                        "-o", str(work / "all.inp")]),
        ("explore", ["explore", "--map", str(mp), "-o", str(work / "explorer.html")]),
        ("report", ["report", "--map", str(mp), "--processed", str(out),
                    "-o", str(work / "report.html")]),
        ("map publish", ["map", "publish", str(work / "pkg"), "--lab", "Bench Lab",
                         "--allow-synthetic", "--map", str(mp)]),
    ]
    store._from_arrow = counting  # type: ignore[assignment]
    print("| command | map reads |")
    print("|---|---|")
    for name, argv in commands:
        if name.startswith("batch (one new export, after"):
            held.replace(late)
        if name.startswith("batch (one new export, the map"):
            held_later.replace(later)
        calls.clear()
        result = run(*argv)
        print(f"| `{name}` | {len(calls)} |" + ("" if result.exit_code == 0 else " (exit 1)"))
        if result.exit_code and args.trace:
            print(result.output[-600:], file=sys.__stderr__)
    store._from_arrow = real  # type: ignore[assignment]
    shutil.rmtree(work)


if __name__ == "__main__":
    sys.exit(main())
