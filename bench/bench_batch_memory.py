"""The batch's parent memory per file, by ``tracemalloc``: what it keeps of a campaign
before any work, and what it keeps at the end of a real batch from scratch, by owner.

Planning (a config given): over a campaign a batch already ran (e.g. ``bench_rerun.py``'s
``n10000`` folder), the state is read (row by row, its names kept), the table built and
the plan made as ``tribopipe batch`` does, and the bytes each keeps after a garbage
collection are divided by the number of files. Read-only (the state is opened
read-only, no export is read: their size and ``mtime_ns`` match).

    nice python bench/bench_batch_memory.py bench/out/rerun/n10000/campaign.toml

A batch from scratch (``--batch N1 N2``): per size, a fresh process generates ``N``
short exports (``bench_rerun.py``'s, 300–1,000 rows of friction interval), then runs
``run_campaign(…, jobs=2, plots=False)`` from an empty output folder with ``tracemalloc``
on in the parent only (one frame; its forked workers stop it). When the batch writes
``runs.csv`` (everything it keeps is alive then) the bytes each local of the batch's
frame reaches are summed (``sys.getsizeof`` over ``gc.get_referents``, each object
counted once, for the first local that reaches it; the campaign and constant locals for
none). Printed per owner: the bytes kept at each size and the growth per file between
the sizes; and the parent's traced memory, its RSS (``VmRSS``) and peak (``VmHWM``), then
and after the batch (``end_``: its rehearsal of the next re-run included).

    nice python bench/bench_batch_memory.py --batch 2000 6000

Where the parent's peak is reached (``--phases CONFIG``): a batch of a campaign as
``tribopipe batch --no-plots`` runs it (in this process, no ``tracemalloc``), while a
thread samples the parent's RSS and peak (``VmRSS``, ``VmHWM``) every 10 ms with the
stack of tribopipe functions the batch is in. Printed: the peak and the stack where it
was reached, how much the peak rose while in each phase (the stack cut at ``--depth``
functions), the RSS over the batch (with Arrow's allocated bytes), and after the batch
what its allocators keep of what was freed: the RSS after a garbage collection, after
glibc's ``malloc_trim`` and after Arrow's pool released its unused memory, and the bytes
of Python's small-object arenas against those in use. Run it from an empty output
folder (a batch from scratch).

    nice python bench/bench_batch_memory.py --phases /tmp/c/n10000/campaign.toml
"""

from __future__ import annotations

import argparse
import gc
import json
import shutil
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path
from types import CodeType, FrameType, FunctionType, ModuleType

HERE = Path(__file__).resolve().parent


def planning(config: Path) -> dict[str, float]:
    """What the parent keeps of a campaign before any work, per file."""
    from tribopipe.campaign import batch, state, table
    from tribopipe.campaign.spec import load_campaign

    campaign = load_campaign(config)
    gc.collect()
    tracemalloc.start()
    cpu = time.process_time()
    try:  # as the batch reads it: each row checked, the names kept
        kept = state.load_state(campaign, lazy=True)
    except TypeError:  # a tree from before the lazy read (``--src``-style comparisons)
        kept = state.load_state(campaign)
    gc.collect()
    after_state = tracemalloc.get_traced_memory()[0]
    rows = table.campaign_table(campaign, state=kept)
    gc.collect()
    after_table = tracemalloc.get_traced_memory()[0]
    plan = batch._plan(rows, set())
    gc.collect()
    after_plan, peak = tracemalloc.get_traced_memory()
    n = max(1, len(rows))
    result = {"files": len(rows), "state_B_per_file": after_state / n,
              "table_B_per_file": (after_table - after_state) / n,
              "plan_B_per_file": (after_plan - after_table) / n,
              "total_B_per_file": after_plan / n, "peak_B_per_file": peak / n,
              "cpu_s": time.process_time() - cpu}
    del plan
    print(json.dumps({k: round(v) if k != "cpu_s" else round(v, 2)
                      for k, v in result.items()}))
    return result


#: kept by the batch whatever the number of files (not owners to size)
_CONSTANT = ("campaign", "progress", "stop", "review", "manifest", "jobs", "plots")


#: the batch's locals in the order they are given what they share
_FIRST = ("state", "entries", "rows", "by_file", "plan", "todo", "order", "redone", "account",
          "failures", "this_batch", "outcomes", "duplicates", "notes", "vanished")


def deep_size(obj: object, seen: set[int]) -> int:
    """The bytes of ``obj`` and of every object it reaches that ``seen`` does not hold
    yet (added to it): types, modules and functions are not followed."""
    size, stack = 0, [obj]
    while stack:
        o = stack.pop()
        if id(o) in seen or isinstance(o, (type, ModuleType, FunctionType, CodeType)):
            continue
        seen.add(id(o))
        size += sys.getsizeof(o)
        stack.extend(gc.get_referents(o))
    return size


def owners_of(frame: FrameType) -> dict[str, int]:
    """The bytes each local of the batch's frame keeps, each object counted once (for
    the first local that reaches it, in the frame's order of locals; what the campaign
    and the constant locals reach is counted for none)."""
    seen: set[int] = set()
    local = dict(frame.f_locals)
    for name in _CONSTANT:
        if name in local:
            deep_size(local.pop(name), seen)
    first = [n for n in _FIRST if n in local]
    return {name: deep_size(local[name], seen)
            for name in [*first, *(n for n in local if n not in first)]
            if not callable(local[name])}


def _rss_kB() -> dict[str, int]:
    out = {}
    for line in Path("/proc/self/status").read_text().splitlines():
        key, _, value = line.partition(":")
        if key in ("VmRSS", "VmHWM"):
            out[key] = int(value.split()[0])
    return out


def one_batch(out: Path, n: int, jobs: int) -> dict:
    """Generate ``n`` exports under ``out`` and run a batch from scratch over them,
    measuring the parent when it writes ``runs.csv``; returns the figures."""
    sys.path.insert(0, str(HERE))
    import bench_campaign as bc
    import bench_rerun

    from tribopipe.campaign import batch
    from tribopipe.campaign.spec import load_campaign

    config, _ = bench_rerun.prepare(out, n, (300, 1000), jobs)
    shutil.rmtree(out / "processed", ignore_errors=True)
    del bc
    campaign = load_campaign(config)
    found: dict = {}
    start_worker = batch.worker_init

    def worker_init() -> None:  # the workers are forked: they stop tracing
        tracemalloc.stop()
        start_worker()

    write = batch.write_runs_csv

    def write_runs_csv(*args: object, **kwargs: object) -> None:
        gc.collect()
        current, peak = tracemalloc.get_traced_memory()
        frame = sys._getframe(1)
        while not {"rows", "entries"} <= frame.f_locals.keys():  # the batch's own frame
            frame = frame.f_back  # type: ignore[assignment]
        sites = {f"{st.traceback[0].filename.rsplit('/', 2)[-1]}:{st.traceback[0].lineno}":
                 st.size for st in tracemalloc.take_snapshot().statistics("lineno")[:400]}
        found.update(traced_B=current, traced_peak_B=peak, owners=owners_of(frame),
                     sites=sites, **_rss_kB())
        del frame
        write(*args, **kwargs)  # type: ignore[arg-type]

    batch.worker_init = worker_init  # type: ignore[assignment]
    batch.write_runs_csv = write_runs_csv  # type: ignore[assignment]
    gc.collect()
    tracemalloc.start(1)
    cpu, wall = time.process_time(), time.perf_counter()
    report = batch.run_campaign(campaign, jobs=jobs, plots=False)
    # after the batch and what follows its outputs (the rehearsal of its next re-run)
    found.update(end_traced_peak_B=tracemalloc.get_traced_memory()[1],
                 end_VmHWM=_rss_kB()["VmHWM"])
    found.update(files=report.files, reduced=len(report.reduced), failures=len(report.failures),
                 parent_cpu_s=round(time.process_time() - cpu, 1),
                 wall_s=round(time.perf_counter() - wall, 1))
    tracemalloc.stop()
    return found


def _stack(frame: FrameType | None) -> tuple[str, ...]:
    """The tribopipe functions of ``frame``'s stack, outermost first (``module.function``)."""
    names: list[str] = []
    while frame is not None:
        code = frame.f_code
        if "/tribopipe/" in code.co_filename:
            names.append(f"{Path(code.co_filename).stem}.{code.co_name}")
        frame = frame.f_back
    return tuple(reversed(names))


def _pymalloc() -> dict[str, int]:
    """Python's small-object allocator: the bytes its arenas hold and those in use
    (``sys._debugmallocstats``, read from the C stderr it prints to)."""
    import os
    import re
    import tempfile

    with tempfile.TemporaryFile() as tmp:
        saved = os.dup(2)
        try:
            sys.stderr.flush()
            os.dup2(tmp.fileno(), 2)
            sys._debugmallocstats()
        finally:
            os.dup2(saved, 2)
            os.close(saved)
        tmp.seek(0)
        text = tmp.read().decode(errors="replace")
    out = {}
    for key, pattern in (("pymalloc_arenas_kB", r"arenas \* \d+ bytes/arena\s*=\s*([\d,]+)"),
                         ("pymalloc_in_use_kB", r"bytes in allocated blocks\s*=\s*([\d,]+)")):
        found = re.search(pattern, text)
        if found:
            out[key] = int(found.group(1).replace(",", "")) // 1000
    return out


def phases(config: Path, jobs: int, depth: int) -> dict:
    """A batch of ``config`` in this process with the parent's RSS sampled by phase."""
    import threading

    from tribopipe.campaign import batch
    from tribopipe.campaign.spec import load_campaign

    campaign = load_campaign(config)
    main_id = threading.main_thread().ident
    assert main_id is not None
    by_stack: dict[tuple[str, ...], int] = {}  # the largest RSS [kB] seen in each stack
    rises: list[tuple[int, tuple[str, ...]]] = []  # each new peak [kB] and its stack
    done = threading.Event()

    # every 0.5 s: time [s], RSS [kB], Arrow's allocated bytes [kB], phase
    timeline: list[tuple[float, int, int, str]] = []
    t0 = time.perf_counter()

    def sample() -> None:
        last, when = 0, 0.0
        while not done.wait(0.01):
            status = _rss_kB()
            stack = _stack(sys._current_frames().get(main_id))
            if time.perf_counter() - t0 >= when:
                arrow = sys.modules.get("pyarrow")  # not loaded here before the batch does
                timeline.append((round(time.perf_counter() - t0, 1), status["VmRSS"],
                                 arrow.total_allocated_bytes() // 1000 if arrow else 0,
                                 " > ".join(stack[2:5])))
                when += 0.5
            if status["VmRSS"] > by_stack.get(stack, 0):
                by_stack[stack] = status["VmRSS"]
            if status["VmHWM"] > last:
                last = status["VmHWM"]
                rises.append((last, stack))

    start = _rss_kB()
    sampler = threading.Thread(target=sample, daemon=True)
    cpu, wall = time.process_time(), time.perf_counter()
    sampler.start()
    try:
        report = batch.run_campaign(campaign, jobs=jobs, plots=False)
    finally:
        done.set()
        sampler.join()
    end = _rss_kB()
    import pyarrow as pa

    gc.collect()
    after: dict[str, int] = {"RSS_kB": _rss_kB()["VmRSS"],
                             "arrow_kB": pa.total_allocated_bytes() // 1000}
    try:  # what the C heap keeps of what was freed
        import ctypes

        ctypes.CDLL("libc.so.6").malloc_trim(0)
        after["RSS_after_malloc_trim_kB"] = _rss_kB()["VmRSS"]
        pa.default_memory_pool().release_unused()
        after["RSS_after_arrow_release_kB"] = _rss_kB()["VmRSS"]
    except (OSError, AttributeError):
        pass
    after.update(_pymalloc())
    print(f"after the batch: {after}")
    cut: dict[str, int] = {}
    for stack, rss in by_stack.items():
        key = " > ".join(stack[:depth]) or "(outside tribopipe)"
        cut[key] = max(cut.get(key, 0), rss)
    rose: dict[str, int] = {}  # how much the peak rose [kB] while in each phase
    below = start["VmHWM"]
    for kb, stack in rises:
        key = " > ".join(stack[:depth]) or "(outside tribopipe)"
        rose[key] = rose.get(key, 0) + kb - below
        below = kb
    peak_stack = rises[-1][1] if rises else ()
    result = {"files": report.files, "reduced": len(report.reduced),
              "failures": len(report.failures), "start_kB": start["VmRSS"],
              "peak_kB": end["VmHWM"], "end_kB": end["VmRSS"],
              "parent_cpu_s": round(time.process_time() - cpu, 1),
              "wall_s": round(time.perf_counter() - wall, 1),
              "peak_stack": " > ".join(peak_stack),
              "phases_kB": dict(sorted(cut.items(), key=lambda kv: -kv[1])),
              "rose_kB": dict(sorted(rose.items(), key=lambda kv: -kv[1])),
              "timeline": timeline, "after": after,
              "rises": [(kb, " > ".join(st)) for kb, st in rises[-8:]]}
    print(f"{result['files']} files, {result['reduced']} runs reduced; parent "
          f"{result['parent_cpu_s']} s CPU, {result['wall_s']} s wall; RSS "
          f"{start['VmRSS'] / 1e3:.0f} MB at start, peak {end['VmHWM'] / 1e3:.0f} MB, "
          f"{end['VmRSS'] / 1e3:.0f} MB at end")
    print(f"peak reached in: {result['peak_stack']}")
    print("how much the peak rose while in each phase [MB] (sampled every 10 ms):")
    for key, kb in list(result["rose_kB"].items())[:25]:
        print(f"  {kb / 1e3:7.1f}  {key}")
    print("RSS over the batch [MB] (time [s], RSS, of it Arrow's, phase):")
    for k in range(0, len(timeline), max(1, len(timeline) // 24)):
        at, kb, arrow, where = timeline[k]
        print(f"  {at:7.1f} s  {kb / 1e3:6.1f}  {arrow / 1e3:6.1f}  {where}")
    print(json.dumps(result))
    return result


def batches(sizes: list[int], out: Path, jobs: int) -> dict:
    """A batch from scratch per size, each in a fresh process; prints what the parent
    keeps per owner and its growth per file between the first and last size."""
    results = {}
    for n in sizes:
        done = subprocess.run([sys.executable, __file__, "--one", str(n), "--out", str(out),
                               "--jobs", str(jobs)], check=True, capture_output=True,
                              text=True)
        results[n] = json.loads(done.stdout.strip().splitlines()[-1])
        r = results[n]
        print(f"{n} exports: {r['files']} files, {r['reduced']} runs reduced, "
              f"{r['failures']} failures; {r['wall_s']} s wall, parent {r['parent_cpu_s']} s "
              f"CPU; traced {r['traced_B'] / 1e6:.1f} MB (peak {r['traced_peak_B'] / 1e6:.1f}"
              f" MB), RSS {r['VmRSS'] / 1e3:.0f} MB (peak {r['VmHWM'] / 1e3:.0f} MB)",
              flush=True)
    small, large = min(sizes), max(sizes)
    a, b = results[small], results[large]
    per = large - small
    owners = set(a["owners"]) | set(b["owners"])
    growth = {k: (b["owners"].get(k, 0) - a["owners"].get(k, 0)) / per for k in owners}
    print(f"kept by the parent when it writes runs.csv, growth per file from {small} to "
          f"{large} exports (B/file; owners of more than 10 B/file):")
    for key in sorted(growth, key=lambda k: -abs(growth[k])):
        if abs(growth[key]) > 10:
            print(f"  {growth[key]:8.0f}  {key}  ({a['owners'].get(key, 0) / 1e3:.0f} → "
                  f"{b['owners'].get(key, 0) / 1e3:.0f} kB)")
    sites = set(a["sites"]) | set(b["sites"])
    by_site = {k: (b["sites"].get(k, 0) - a["sites"].get(k, 0)) / per for k in sites}
    print("traced, by the line that allocated it (B/file; lines of more than 20 B/file):")
    for key in sorted(by_site, key=lambda k: -abs(by_site[k])):
        if abs(by_site[key]) > 20:
            print(f"  {by_site[key]:8.0f}  {key}")
    summary = {"traced_B_per_file": (b["traced_B"] - a["traced_B"]) / per,
               "traced_peak_B_per_file": (b["traced_peak_B"] - a["traced_peak_B"]) / per,
               "rss_B_per_file": (b["VmRSS"] - a["VmRSS"]) * 1e3 / per,
               "rss_peak_B_per_file": (b["VmHWM"] - a["VmHWM"]) * 1e3 / per,
               "end_traced_peak_B_per_file":
                   (b["end_traced_peak_B"] - a["end_traced_peak_B"]) / per,
               "end_rss_peak_B_per_file": (b["end_VmHWM"] - a["end_VmHWM"]) * 1e3 / per}
    print(json.dumps({k: round(v) for k, v in summary.items()}))
    return {"sizes": results, "growth_B_per_file": growth, **summary}


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", type=Path, nargs="?",
                        help="a campaign a batch already ran: what planning keeps")
    parser.add_argument("--batch", type=int, nargs="+", metavar="N",
                        help="batches from scratch of these numbers of exports")
    parser.add_argument("--one", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", type=Path, default=HERE / "out" / "batch_memory")
    parser.add_argument("--phases", type=Path, metavar="CONFIG",
                        help="a campaign to batch with the parent's RSS sampled by phase")
    parser.add_argument("--depth", type=int, default=9,
                        help="with --phases: functions of the stack a phase is cut at")
    args = parser.parse_args(argv)
    if args.one is not None:
        found = one_batch(args.out.resolve() / f"n{args.one}", args.one, args.jobs)
        print(json.dumps(found))
        return found
    if args.phases is not None:
        return phases(args.phases, args.jobs, args.depth)
    if args.batch:
        return batches(sorted(args.batch), args.out, args.jobs)
    if args.config is None:
        parser.error("give a campaign config or --batch N1 N2")
    return planning(args.config)


if __name__ == "__main__":
    main()
