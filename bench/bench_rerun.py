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

A batch that found nothing to do keeps its ledger in the state, and a batch that did its
work cleanly keeps its next re-run's ledger as pending (:mod:`tribopipe.campaign.stamp`),
so the rounds report a ledger without building the campaign's table; round 1, the first
re-run after a batch that did work (with code that keeps no pending ledger, the full
one), is said apart. ``--redo K`` makes every round's re-run such a first one: each
round, per size and source tree, first deletes ``K`` traces and runs the batch, which
reduces those ``K`` files again (the working batch, measured too). ``--rehearse`` then
times, per size, the rehearsal a working batch adds at its end
(:func:`tribopipe.campaign.batch._rehearse`, CPU of its own process, on the unchanged
campaign: the same state and table), and again as a working batch runs it (one trace
deleted, the batch run in one process with one worker: the rehearsal's own CPU, from
what the batch holds where the code does so, beside the batch's). The batch from
scratch also gives its parent's own peak PSS (without its workers).

Target (issue "10⁵ runs"): an unchanged re-run of 10⁴ files under 1 s; the batch's memory
flat in the number of exports.

    nice /work/main/.venv/bin/python bench/bench_rerun.py [--n 1000 10000] [--repeat 5]
        [--keep] [--src TREE/src ...] [--redo K] [--rehearse]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
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


#: times the rehearsal of a campaign's next re-run in this process (CPU: user + system)
_REHEARSE = """import json, resource, sys, time
from tribopipe.campaign import load_campaign
from tribopipe.campaign.batch import _rehearse
campaign = load_campaign(sys.argv[1])
def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime
c0, t0 = cpu(), time.perf_counter()
rerun = _rehearse(campaign)
print(json.dumps({"cpu_s": cpu() - c0, "wall_s": time.perf_counter() - t0,
                  "found_nothing_to_do": rerun is not None}))
"""

#: times the rehearsal as a working batch runs it at its end (from what the batch holds,
#: where the code does so): one trace deleted, the batch run in this process (one
#: worker), the rehearsal's own CPU (user + system)
_REHEARSE_IN_BATCH = """import json, resource, sys, time
from pathlib import Path
import tribopipe.campaign.batch as batch
from tribopipe.campaign import load_campaign
cfg = Path(sys.argv[1])
for trace in sorted((cfg.parent / "processed" / "traces").glob("*.parquet"))[:1]:
    trace.unlink()
def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime
timed, rehearse = {}, batch._rehearse
def watched(*args):
    c0, t0 = cpu(), time.perf_counter()
    out = rehearse(*args)
    timed.update(cpu_s=cpu() - c0, wall_s=time.perf_counter() - t0,
                 found_nothing_to_do=out is not None)
    return out
batch._rehearse = watched
c0 = cpu()
batch.run_campaign(load_campaign(cfg), jobs=1, plots=False)
timed["batch_cpu_s"] = cpu() - c0
print(json.dumps(timed))
"""


def redo(cfg: Path, k: int) -> None:
    """Delete the first ``k`` traces of the campaign's output folder: the next batch
    reduces their files again."""
    for trace in sorted((cfg.parent / "processed" / "traces").glob("*.parquet"))[:k]:
        trace.unlink()


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
    parser.add_argument("--redo", type=int, default=0, metavar="K",
                        help="before each re-run, delete K traces and run the batch (it "
                             "reduces K files again): every re-run is the first after a "
                             "batch that did work")
    parser.add_argument("--rehearse", action="store_true",
                        help="time the rehearsal a working batch adds at its end, per size")
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
                work = None
                if args.redo:
                    redo(cfg, args.redo)
                    work = bc.run_measured([*exe, "batch", str(cfg), "--jobs",
                                            str(args.jobs), "--no-plots"], cfg.parent)
                    print(f"  round {i + 1}: {n}, batch reducing {args.redo} file(s) "
                          f"({tree or 'this tribopipe'}): {work['wall_s']:.2f} s wall, "
                          f"{work['cpu_s']:.2f} s CPU", flush=True)
                r = bc.run_measured([*exe, "batch", str(cfg), "--jobs", str(args.jobs),
                                     "--no-plots"], cfg.parent)
                r["load_1min"] = os.getloadavg()[0]
                r["src"] = tree
                r["after_work"] = work
                result["sizes"][n]["rerun"].append(r)
                print(f"  round {i + 1}: {n} unchanged ({tree or 'this tribopipe'}): "
                      f"{r['wall_s']:.2f} s wall, {r['cpu_s']:.2f} s CPU, peak PSS "
                      f"{r['peak_pss_tree_MB']:.0f} MB; load {r['load_1min']:.1f}", flush=True)
    for n, entry in result["sizes"].items():
        for tree in trees:
            mine = [r for r in entry["rerun"] if r["src"] == tree]
            if not mine:
                continue
            # the first re-run after a batch that did work is said apart when there are
            # more rounds (with --redo, every round is one)
            first, rest = (mine[0], mine[1:]) if len(mine) > 1 and not args.redo \
                else (None, mine)
            walls = [r["wall_s"] for r in rest]
            cpus = [r["cpu_s"] for r in rest]
            name = tree or "this tribopipe"
            if first is not None:
                print(f"{n} files unchanged ({name}), round 1: {first['wall_s']:.2f} s wall,"
                      f" {first['cpu_s']:.2f} s CPU")
            print(f"{n} files unchanged ({name}), rounds {2 if first else 1}-{len(mine)}"
                  f"{' (each after a working batch)' if args.redo else ''}: "
                  f"wall median {statistics.median(walls):.2f} s "
                  f"({min(walls):.2f}–{max(walls):.2f}), CPU median "
                  f"{statistics.median(cpus):.2f} s ({min(cpus):.2f}–{max(cpus):.2f}), "
                  f"peak PSS {max(r['peak_pss_tree_MB'] for r in rest):.0f} MB")
            works = [r["after_work"]["cpu_s"] for r in mine if r.get("after_work")]
            if works:
                print(f"{n} files, the working batches ({name}): CPU median "
                      f"{statistics.median(works):.2f} s ({min(works):.2f}–{max(works):.2f})")
    if args.rehearse:
        for n, cfg in configs.items():
            for tree in trees:
                env = {**os.environ, **({"PYTHONPATH": tree} if tree else {})}
                done = subprocess.run([sys.executable, "-c", _REHEARSE, str(cfg)], env=env,
                                      capture_output=True, text=True, check=False)
                if done.returncode != 0:  # a tree without the rehearsal
                    print(f"{n} files, rehearsal ({tree or 'this tribopipe'}): not there")
                    continue
                timed = json.loads(done.stdout.strip().splitlines()[-1])
                result["sizes"][n].setdefault("rehearsal", []).append({**timed, "src": tree})
                name = tree or "this tribopipe"
                print(f"{n} files, rehearsal at a working batch's end ({name}): "
                      f"{timed['cpu_s']:.2f} s CPU, {timed['wall_s']:.2f} s wall "
                      f"(found nothing to do: {timed['found_nothing_to_do']})")
                done = subprocess.run([sys.executable, "-c", _REHEARSE_IN_BATCH, str(cfg)],
                                      env=env, capture_output=True, text=True, check=False)
                if done.returncode != 0:
                    print(f"{n} files, rehearsal in a working batch ({name}): failed")
                    continue
                timed = json.loads(done.stdout.strip().splitlines()[-1])
                result["sizes"][n].setdefault("rehearsal_in_batch", []).append(
                    {**timed, "src": tree})
                print(f"{n} files, rehearsal in a working batch ({name}): "
                      f"{timed['cpu_s']:.2f} s CPU, {timed['wall_s']:.2f} s wall, of the "
                      f"batch's {timed['batch_cpu_s']:.2f} s CPU in its process "
                      f"(found nothing to do: {timed['found_nothing_to_do']})")
    args.results.write_text(json.dumps(result, indent=1, default=str))
    return result


if __name__ == "__main__":
    main()
