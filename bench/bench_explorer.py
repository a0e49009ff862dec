"""The explorer page at 10³–10⁵ runs: the page's size, the runs beside it, the CPU of
``write_explorer``.

Two shapes of map, built from ``bench_scale``'s copies of a real reduced run: ``few
pairs`` (the 18 pin–disc pairs of the founding grid, runs added as repeats) and ``own
pins`` (each 1,000 runs under a pin name of their own, as when labs add their own lots:
pairs and groups grow with the runs). Run from the repository::

    PYTHONPATH=src:tests:bench python bench/bench_explorer.py [--sizes 1000 10000 100000]

Prints one line per map and writes ``bench/explorer.json``.
"""

from __future__ import annotations

import argparse
import json
import shutil
import tempfile
import time
from pathlib import Path

import bench_scale

HERE = Path(__file__).parent


def build(folder: Path, n: int, own_pins: bool, template: dict) -> Path:
    """A map of ``n`` rows (``own_pins``: a pin name per 1,000 rows)."""
    from tribopipe.frictionmap import update_map

    path = folder / f"{'pins' if own_pins else 'few'}_{n}.parquet"
    for k in range(0, n, 20_000):
        records = bench_scale.records(template, min(20_000, n - k), k)
        if own_pins:
            for j, r in enumerate(records):
                r["pin"] = f"{r['pin']} lot {(k + j) // 1000}"
        update_map(path, records)
    return path


def measure(path: Path, folder: Path) -> dict:
    """Size of the page and of the runs beside it [MB], CPU of writing both [s]."""
    from tribopipe.export.explorer import runs_folder, write_explorer
    from tribopipe.frictionmap import read_map

    runs = read_map(path)
    page = folder / (path.stem + ".html")
    start = time.process_time()
    write_explorer(path, page)
    cpu = time.process_time() - start
    beside = runs_folder(page)
    files = list(beside.iterdir()) if beside.exists() else []
    groups = len({(r.pin, r.disc, r.normal_force_N, r.temperature_C)
                  for r in runs.itertuples()})
    return {"runs": len(runs), "pairs": runs.groupby(["pin", "disc"]).ngroups,
            "groups": groups, "page_MB": round(page.stat().st_size / 1e6, 2),
            "beside_MB": round(sum(f.stat().st_size for f in files) / 1e6, 2),
            "largest_file_MB": round(max((f.stat().st_size for f in files), default=0) / 1e6, 2),
            "explore_cpu_s": round(cpu, 2)}


def main(argv: list[str] | None = None) -> list[dict]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 10_000, 100_000])
    args = parser.parse_args(argv)
    folder = Path(tempfile.mkdtemp(prefix="bench_explorer_"))
    rows = []
    try:
        template = bench_scale.template_record(folder)
        for own_pins in (False, True):
            for n in args.sizes:
                row = {"shape": "own pins" if own_pins else "few pairs",
                       **measure(build(folder, n, own_pins, template), folder)}
                print(json.dumps(row), flush=True)
                rows.append(row)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    (HERE / "explorer.json").write_text(json.dumps(rows, indent=1) + "\n", encoding="utf-8")
    return rows


if __name__ == "__main__":
    main()
