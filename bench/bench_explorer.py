"""The explorer page at 10³–10⁵ runs and 10³–10⁵ condition groups: the pages' sizes, the
runs beside them, the CPU of writing them.

Shapes of map, built from ``bench_scale``'s copies of a real reduced run: ``few
pairs`` (the 18 pin–disc pairs of the founding grid, runs added as repeats), ``own pins``
(each 1,000 runs under a pin name of their own, as when labs add their own lots: pairs
and groups grow with the runs), with ``--shapes "own discs"`` each 1,000 runs under a
disc name of their own (two pins of many groups each), and with ``--groups``, ``every run a group``
(``bench_scale.build_map(pairs=True)``: every 180 runs under a pin of their own, so that
every run is a condition group of its own), where ``tribopipe explore`` is also timed as
a process (CPU per group, as ``bench_scale --commands --groups`` times the other
commands over every pair). Run from the repository::

    PYTHONPATH=src:tests:bench python bench/bench_explorer.py [--sizes 1000 10000 100000]
        [--shapes "few pairs" "own pins" "own discs"] [--groups 1000 10000 100000]
        [--out bench/explorer.json]

Prints one line per map and writes the figures as JSON (``--out``).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import tempfile
import time
from pathlib import Path

import bench_scale

HERE = Path(__file__).parent


#: the shapes of map: which name each 1,000 rows get a lot number in (None: neither)
SHAPES = {"few pairs": None, "own pins": "pin", "own discs": "disc"}


def build(folder: Path, n: int, shape: str, template: dict) -> Path:
    """A map of ``n`` rows of ``shape`` (:data:`SHAPES`): ``own pins``, a pin name per
    1,000 rows; ``own discs``, a disc name per 1,000 rows (the pairs grow under the two
    pins of the grid: a pin of many groups)."""
    from tribopipe.frictionmap import update_map

    column = SHAPES[shape]
    path = folder / f"{shape.replace(' ', '_')}_{n}.parquet"
    for k in range(0, n, 20_000):
        records = bench_scale.records(template, min(20_000, n - k), k)
        if column is not None:
            for j, r in enumerate(records):
                r[column] = f"{r[column]} lot {(k + j) // 1000}"
        update_map(path, records)
    return path


def _mb(size: int) -> float:
    return round(size / 1e6, 2)


def measure(path: Path, folder: Path) -> dict:
    """The explorer of ``path`` written in this process: the page a user opens (one page,
    or the index of pin pages), every page, the runs beside them [MB], and the CPU of
    opening the map and writing them all [s]."""
    from tribopipe.export.explorer import write_explorer
    from tribopipe.frictionmap.snapshot import open_map

    out = folder / path.stem / "explorer.html"
    out.parent.mkdir(parents=True, exist_ok=True)
    start = time.process_time()
    snap = open_map(path)
    write_explorer(snap, out)
    cpu = time.process_time() - start
    groups = snap.groups(show_method=True)
    runs = snap.runs
    pages = sorted(out.parent.rglob("*.html"))
    beside = sorted(out.parent.rglob("*.js"))
    return {"runs": len(runs), "pairs": groups.groupby(["pin", "disc"]).ngroups,
            "groups": len(groups), "page_MB": _mb(out.stat().st_size),
            "pages": len(pages), "largest_page_MB": _mb(max(p.stat().st_size for p in pages)),
            "beside_MB": _mb(sum(f.stat().st_size for f in beside)),
            "beside_files": len(beside),
            "largest_file_MB": _mb(max((f.stat().st_size for f in beside), default=0)),
            "explore_cpu_s": round(cpu, 2),
            "cpu_ms_per_group": round(cpu / len(groups) * 1e3, 2),
            "load_1min": round(os.getloadavg()[0], 1)}


def per_group(folder: Path, n: int, template: dict) -> dict:
    """``tribopipe explore`` as a process on a map of ``n`` runs, each a group of its own
    (``bench_scale.build_map(pairs=True)``): CPU, wall and peak memory, per group; and the
    pages it wrote."""
    path = folder / f"groups_{n}.parquet"
    bench_scale.build_map(path, template, n, pairs=True)
    out = folder / f"groups_{n}" / "explorer.html"
    out.parent.mkdir(parents=True, exist_ok=True)
    timed = bench_scale._timed(["explore", "--map", str(path), "-o", str(out)], folder)
    pages = sorted(out.parent.rglob("*.html"))
    return {"groups": n, **{k: round(v, 2) for k, v in timed.items()},
            "cpu_ms_per_group": round(timed["cpu_s"] / n * 1e3, 2),
            "page_MB": _mb(out.stat().st_size), "pages": len(pages),
            "largest_page_MB": _mb(max(p.stat().st_size for p in pages)),
            "load_1min": round(os.getloadavg()[0], 1)}


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="*", default=[1000, 10_000, 100_000])
    parser.add_argument("--shapes", nargs="*", default=["few pairs", "own pins"],
                        choices=list(SHAPES))
    parser.add_argument("--groups", type=int, nargs="*", default=[])
    parser.add_argument("--out", type=Path, default=HERE / "explorer.json")
    args = parser.parse_args(argv)
    folder = Path(tempfile.mkdtemp(prefix="bench_explorer_"))
    results: dict = {"when_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                     "load_average_at_start": os.getloadavg(), "pages": [], "per_group": []}
    try:
        template = bench_scale.template_record(folder)
        for shape in args.shapes:
            for n in args.sizes:
                row = {"shape": shape, **measure(build(folder, n, shape, template), folder)}
                print(json.dumps(row), flush=True)
                results["pages"].append(row)
        for n in args.groups:
            row = per_group(folder, n, template)
            print(json.dumps(row), flush=True)
            results["per_group"].append(row)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    results["load_average_at_end"] = os.getloadavg()
    args.out.write_text(json.dumps(results, indent=1) + "\n", encoding="utf-8")
    return results


if __name__ == "__main__":
    main()
