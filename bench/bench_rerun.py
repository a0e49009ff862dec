"""Re-run benchmark: a batch at 10³ and 10⁴ exports, its peak memory and the unchanged re-run.

The files: ``--n`` short synthetic runs on the founding grid (the campaign benchmark's own
plan and export writer, :mod:`bench_campaign`, in its three layouts), each ``--rows``
rows of friction interval (default 300–1,000 at 10 Hz) after the 200-row set-up interval,
so 10⁴ files fit on disk and in time. Per size, once: ``tribopipe batch <config> --jobs N
--no-plots`` from an empty output folder, with the peak PSS summed over its process tree
(sampled every 50 ms from ``/proc/<pid>/smaps_rollup``). Then ``--repeat`` rounds, each
the unchanged re-run of every size in turn (alternating, so each size meets the same
load): wall time, and CPU time (user + system) from the launcher's ``RUSAGE_CHILDREN``,
Python start-up included, with the 1-min load average after each round.

The first re-run after a batch that did work is the full one: it finds nothing to do and
keeps its ledger in the state (:mod:`tribopipe.campaign.stamp`), so the rounds after it
report that ledger without building the campaign's table; the summary says round 1 apart.
The batch from scratch also gives its parent's own peak PSS (without its workers).

Target (issue "10⁵ runs"): an unchanged re-run of 10⁴ files under 1 s; the batch's memory
flat in the number of exports.

    nice /work/main/.venv/bin/python bench/bench_rerun.py [--n 1000 10000] [--repeat 5]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import bench_campaign as bc  # noqa: E402  (the campaign benchmark's files and launcher)


def prepare(out: Path, n: int, rows: tuple[int, int], jobs: int) -> tuple[Path, int]:
    """``n`` exports of ``rows`` rows under ``out`` and the campaign config; returns the
    config and the exports' total size [bytes]."""
    bc.ROWS = rows  # the plan's run lengths (and the cache key of generate)
    out.mkdir(parents=True, exist_ok=True)
    size = bc.generate(out / "raw", n, jobs)
    single, _ = bc.write_configs(out)
    return single, size


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, nargs="+", default=[1000, 10000])
    parser.add_argument("--rows", type=int, nargs=2, default=[300, 1000])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", type=Path, default=HERE / "out" / "rerun")
    parser.add_argument("--keep", action="store_true",
                        help="keep the batch's outputs (re-run only, no batch from scratch)")
    parser.add_argument("--results", type=Path, default=HERE / "rerun.json")
    parser.add_argument("--src", type=Path, nargs="+", default=None,
                        help="source trees (their src/ folders) to alternate the re-runs "
                             "between, e.g. a copy of the code before a change and after; "
                             "default: the tribopipe this interpreter imports")
    args = parser.parse_args(argv)

    exe_path = Path(sys.executable).with_name("tribopipe")
    exe = [str(exe_path)] if exe_path.exists() else [sys.executable, "-m", "tribopipe"]
    result: dict = {"rows": args.rows, "jobs": args.jobs, "sizes": {}}
    configs: dict[int, Path] = {}
    for n in args.n:
        out = args.out.resolve() / f"n{n}"
        t0 = time.perf_counter()
        cfg, size = prepare(out, n, tuple(args.rows), args.jobs)
        configs[n] = cfg
        print(f"{n} exports: {size / 1e6:.0f} MB ({time.perf_counter() - t0:.0f} s)",
              flush=True)
        entry: dict = {"files": n, "bytes": size}
        if not args.keep or not (out / "processed").exists():
            shutil.rmtree(out / "processed", ignore_errors=True)
            first = bc.run_measured([*exe, "batch", str(cfg), "--jobs", str(args.jobs),
                                     "--no-plots"], out)
            first["load_1min"] = os.getloadavg()[0]
            entry["batch"] = first
            print(f"  batch from scratch: {first['wall_s']:.1f} s wall, "
                  f"{first['cpu_s']:.1f} s CPU, peak PSS {first['peak_pss_tree_MB']:.0f} MB"
                  f" (its parent {first['peak_pss_parent_MB']:.0f} MB)"
                  f" ({first['said']}); load {first['load_1min']:.1f}", flush=True)
        entry["rerun"] = []
        result["sizes"][n] = entry
    trees = [str(p.resolve()) for p in args.src] if args.src else [None]
    for i in range(args.repeat):
        for n, cfg in configs.items():
            for tree in trees:
                if tree is not None:
                    os.environ["PYTHONPATH"] = tree
                r = bc.run_measured([*exe, "batch", str(cfg), "--jobs", str(args.jobs),
                                     "--no-plots"], cfg.parent)
                r["load_1min"] = os.getloadavg()[0]
                r["src"] = tree
                result["sizes"][n]["rerun"].append(r)
                print(f"  round {i + 1}: {n} unchanged ({tree or 'this tribopipe'}): "
                      f"{r['wall_s']:.2f} s wall, {r['cpu_s']:.2f} s CPU, peak PSS "
                      f"{r['peak_pss_tree_MB']:.0f} MB; load {r['load_1min']:.1f}", flush=True)
    for n, entry in result["sizes"].items():
        for tree in trees:
            mine = [r for r in entry["rerun"] if r["src"] == tree]
            if not mine:
                continue
            # the first re-run after a batch that did work is the full one (it keeps its
            # ledger for the next): said apart when there are more rounds
            first, rest = (mine[0], mine[1:]) if len(mine) > 1 else (None, mine)
            walls = [r["wall_s"] for r in rest]
            cpus = [r["cpu_s"] for r in rest]
            name = tree or "this tribopipe"
            if first is not None:
                print(f"{n} files unchanged ({name}), round 1: {first['wall_s']:.2f} s wall,"
                      f" {first['cpu_s']:.2f} s CPU")
            print(f"{n} files unchanged ({name}), rounds {2 if first else 1}-{len(mine)}: "
                  f"wall median {statistics.median(walls):.2f} s "
                  f"({min(walls):.2f}–{max(walls):.2f}), CPU median "
                  f"{statistics.median(cpus):.2f} s ({min(cpus):.2f}–{max(cpus):.2f}), "
                  f"peak PSS {max(r['peak_pss_tree_MB'] for r in rest):.0f} MB")
    args.results.write_text(json.dumps(result, indent=1, default=str))
    return result


if __name__ == "__main__":
    main()
