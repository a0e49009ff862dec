"""Campaign benchmark (issue 10): 1,000 realistic exports, measured in one run.

The files: 1,000 synthetic runs on the founding grid (2 pins × 9 discs × 5 forces ×
2 temperatures, repeats numbered on), each 5,000–15,000 rows of the friction interval at
10 Hz (500–1,500 s, 3.5–11 mm of sliding at the founding 0.007 mm/s) after a 200-row
set-up interval, written by the project's synthetic export writer
(:func:`generators.synthetic.write_rheocompass_export`) in three layouts: 70 % UTF-16 TAB
English (RheoCompass' own save), 15 % UTF-8 comma, 15 % UTF-16 French with decimal commas.
The same runs are also bundled ten to a file as multi-test exports (one Project, ten Tests,
as RheoCompass writes several tests into one file).

Measured in one run, on the same files, ``--repeat`` times (5) in alternation, medians
reported (the machine is shared: alternating exposes every measurement to the same load):

* **reader** — per file, CPU time of ``tribopipe.readers.read_export`` against the bare
  decode + ``pyarrow.csv`` parse of the same file's data lines (``bench_reader.bare_parse``,
  the reader benchmark's own definition), back-to-back pairs, median ratio per layout;
* **parse-only pool** — ``read_export`` over all files in a fresh process pool of the
  batch's size, chunking and garbage-collector setting (pool start-up included);
* **batch without plots** and **batch with plots** — ``tribopipe batch <config> --jobs N
  --no-plots`` / ``--plots`` end to end in a fresh process from an empty output folder;
  with each, the peak PSS summed over the process tree (proportional set size: pages shared
  after ``fork`` count once; sampled every 50 ms from ``/proc/<pid>/smaps_rollup``) and the
  largest single process's max RSS;
* **incremental re-run** (nothing changed) and **one file changed**;
* ``tribopipe --help`` (median of 7);
* **start-up** — ``python -X importtime`` of what a batch imports before its workers fork
  (``tribopipe.campaign``), whether ``scipy``/``scipy.signal`` are among it, and the import
  of matplotlib a plotting worker adds;
* **bundled exports** — the batch over the 100 multi-test files, when the code reads every
  test of a file as a run (detected from the map's rows; else reported as not supported).

Targets (issue 10): reader ≤ 2 × bare parse; batch with plots ≤ 1.5 × batch without;
batch ≤ 1.5 × parse-only pool; re-run ≤ 1 s; peak memory ≤ 500 MB. Prints a table and
writes ``bench/results.json``.

    nice .venv/bin/python bench/bench_campaign.py [--n 1000] [--repeat 5] [--jobs 2]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the generators

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))  # bench_reader, the reader benchmark's bare parse

PATTERN = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"
PINS = ("DS30", "EF50")
DISCS = ("steel", "acrylic", "alusheet", "alulathed", "cardboard", "woodsmooth",
         "woodstruct", "ds30disc", "ef50disc")
FORCES_N = (1, 3, 5, 7, 9)
TEMPERATURES_C = (10, 20)
ROWS = (5_000, 15_000)
SAMPLE_RATE_HZ = 10.0
#: layouts: name → writer keyword arguments; which layout a run gets: see _layout
LAYOUTS = {
    "utf16-tab-en": {},
    "utf8-comma-quoted": {"encoding": "utf-8", "delimiter": ","},
    "utf16-tab-fr": {"language": "fr"},
}
PER_BUNDLE = 10
FILES_VERSION = 2


# --------------------------------------------------------------------------- the files


def _layout(i: int) -> str:
    """Run ``i``'s layout: 14 of 20 UTF-16 English, 3 UTF-8 comma, 3 French."""
    k = i % 20
    return "utf8-comma-quoted" if k < 3 else "utf16-tab-fr" if k < 6 else "utf16-tab-en"


def plan(n: int) -> list[tuple[str, str, dict]]:
    """``n`` runs over the founding grid, repeats numbered on: (file stem, layout,
    SyntheticRun keyword arguments). Lengths are seeded draws in :data:`ROWS`."""
    import numpy as np

    rng = np.random.default_rng(2026)
    grid = [(p, d, f, t) for p in PINS for d in DISCS for f in FORCES_N for t in TEMPERATURES_C]
    runs = []
    for i in range(n):
        pin, disc, force, temperature = grid[i % len(grid)]
        repeat = i // len(grid) + 1
        mu_k = 0.25 + 0.8 / force**0.5 * (0.8 if temperature == 10 else 1.0)
        rows = int(rng.integers(ROWS[0], ROWS[1] + 1))
        runs.append((
            f"{pin}_{disc}_{force}N_{temperature}C_r{repeat}", _layout(i),
            {"mu_s": round(1.3 * mu_k, 4), "mu_k": round(mu_k, 4), "normal_force_N": float(force),
             "temperature_C": float(temperature), "duration_s": rows / SAMPLE_RATE_HZ,
             "noise": 0.006, "seed": 1000 + i},
        ))
    return runs


def _write_chunk(folder: str, chunk: list[tuple[str, str, dict]]) -> int:
    from generators.synthetic import SyntheticRun, write_rheocompass_export

    total = 0
    for stem, layout, kwargs in chunk:
        path = write_rheocompass_export(Path(folder) / f"{stem}.csv", SyntheticRun(**kwargs),
                                        project="bench", test=stem, sample=stem.split("_")[0],
                                        **LAYOUTS[layout])
        total += path.stat().st_size
    return total


def generate(raw: Path, n: int, jobs: int) -> int:
    """Write the ``n`` exports into ``raw`` (kept between runs when already complete);
    returns their total size [bytes]."""
    info = raw / ".bench-info.json"
    want = {"n": n, "rows": list(ROWS), "version": FILES_VERSION}
    if info.exists() and json.loads(info.read_text()) == want:
        return sum(p.stat().st_size for p in raw.glob("*.csv"))
    shutil.rmtree(raw, ignore_errors=True)
    raw.mkdir(parents=True)
    runs = plan(n)
    chunks = [runs[i : i + 25] for i in range(0, len(runs), 25)]
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        total = sum(pool.map(_write_chunk, [str(raw)] * len(chunks), chunks))
    info.write_text(json.dumps(want))
    return total


def _write_bundles(folder: str, groups: list[tuple[str, str, list[tuple[str, dict]]]]) -> int:
    from generators.synthetic import SyntheticRun, SyntheticTest, write_rheocompass_session

    total = 0
    for name, layout, runs in groups:
        tests = [SyntheticTest(stem, stem.split("_")[0], (SyntheticRun(**kw),))
                 for stem, kw in runs]
        path = write_rheocompass_session(Path(folder) / name, tests, project="bench",
                                         **LAYOUTS[layout])
        total += path.stat().st_size
    return total


def bundle(out: Path, n: int, jobs: int) -> list[Path]:
    """The same ``n`` runs bundled :data:`PER_BUNDLE` to a file as multi-test exports
    (:func:`generators.synthetic.write_rheocompass_session`: one Project, a Test per run,
    as RheoCompass writes a session), runs of one layout in plan order."""
    info = out / ".bench-info.json"
    want = {"n": n, "per_bundle": PER_BUNDLE, "rows": list(ROWS), "version": FILES_VERSION}
    if info.exists() and json.loads(info.read_text()) == want:
        return sorted(out.glob("*.csv"))
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    by_layout: dict[str, list[tuple[str, dict]]] = {}
    for stem, layout, kwargs in plan(n):
        by_layout.setdefault(layout, []).append((stem, kwargs))
    groups = [(f"bundle_{layout}_{k // PER_BUNDLE:03d}.csv", layout, runs[k : k + PER_BUNDLE])
              for layout, runs in by_layout.items() for k in range(0, len(runs), PER_BUNDLE)]
    chunks = [groups[i : i + 3] for i in range(0, len(groups), 3)]
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        sum(pool.map(_write_bundles, [str(out)] * len(chunks), chunks))
    info.write_text(json.dumps(want))
    return sorted(out.glob("*.csv"))


def write_configs(out: Path) -> tuple[Path, Path]:
    """The campaign configs: one file per run (labels from the file name), and the
    bundles (labels from each test's name, ``test_pattern``). No glob: the batch's default
    discovery (every export suffix the readers know). Plots are chosen on the command
    line."""
    names = ('[names]\nDS30 = "Dragonskin 30"\nEF50 = "Ecoflex 00-50"\n'
             # the discs' short names the vocabulary does not know
             'woodstruct = "wood (structured)"\nds30disc = "Dragonskin 30"\n'
             'ef50disc = "Ecoflex 00-50"\n')
    single = out / "campaign.toml"
    single.write_text(
        '[campaign]\nname = "bench"\nraw_dir = "raw"\noutput_dir = "processed"\n'
        f'filename_pattern = "{PATTERN}"\n' + names, encoding="utf-8")
    bundled = out / "bundles.toml"
    bundled.write_text(
        '[campaign]\nname = "bench-bundles"\nraw_dir = "bundles"\n'
        f'output_dir = "processed-bundles"\ntest_pattern = "{PATTERN}"\n' + names,
        encoding="utf-8")
    return single, bundled


# --------------------------------------------------------------------------- reader


def reader_ratios(files: list[Path], bundles: list[Path], per_layout: int,
                  repeat: int) -> dict:
    """Per layout, single-test exports and bundles: median CPU [ms] of ``read_export`` and
    of the bare parse over ``per_layout`` files (bundles: a third as many), and the median
    of the back-to-back pairs' ratios (with the worst file's median ratio)."""
    try:
        from bench_reader import LAYOUTS as BARE_LAYOUTS
        from bench_reader import bare_parse
    except ImportError:
        return {"skipped": "bench/bench_reader.py (the reader benchmark) is not here"}
    from tribopipe.readers import read_export

    def cpu_ms(fn) -> float:
        t0 = time.process_time()
        fn()
        return (time.process_time() - t0) * 1e3

    out: dict = {}
    stems = {stem: layout for stem, layout, _ in plan(len(files))}
    for layout in LAYOUTS:
        groups = {layout: [f for f in files if stems.get(f.stem) == layout][:per_layout],
                  f"{layout}, bundled": [b for b in bundles if b.stem.startswith(
                      f"bundle_{layout}_")][: max(1, per_layout // 3)]}
        spec = BARE_LAYOUTS[layout]
        for name, chosen in groups.items():
            reader, bare, ratios = [], [], []
            for path in chosen:
                rows = sum(len(m.data) for m in read_export(path))  # warm-up, sanity check
                if rows != bare_parse(path, spec):
                    raise SystemExit(f"{path}: read_export and the bare parse disagree")
                for k in range(repeat):
                    pair = [lambda p=path: read_export(p),
                            lambda p=path, s=spec: bare_parse(p, s)]
                    times = [cpu_ms(f) for f in (pair if k % 2 == 0 else pair[::-1])]
                    r, b = times if k % 2 == 0 else times[::-1]
                    reader.append(r)
                    bare.append(b)
                    ratios.append(r / b)
            out[name] = {"files": len(chosen), "read_export_ms": statistics.median(reader),
                         "bare_ms": statistics.median(bare),
                         "ratio": statistics.median(ratios),
                         "worst_file_ratio": max(
                             statistics.median(ratios[i : i + repeat])
                             for i in range(0, len(ratios), repeat))}
    return out


# --------------------------------------------------------------------------- parse-only


def _parse_chunk(paths: list[str]) -> int:
    from tribopipe.readers import read_export

    return sum(sum(len(m.data) for m in read_export(p)) for p in paths)


def parse_only_pool(files: list[Path], jobs: int) -> tuple[float, float]:
    """Wall time and CPU time [s] of ``read_export`` over all files in a fresh pool of
    ``jobs`` workers with the batch's chunking and garbage-collector setting (start-up
    included). CPU is user + system of this process and of the workers (reaped when the
    pool shuts down), as the batch's is counted; the readers are imported beforehand."""
    import resource

    import tribopipe.readers  # noqa: F401 - imported before the fork, as the batch does
    from tribopipe.campaign.batch import chunk_jobs
    from tribopipe.campaign.worker import worker_init

    def children_cpu() -> float:
        usage = resource.getrusage(resource.RUSAGE_CHILDREN)
        return usage.ru_utime + usage.ru_stime

    chunks = chunk_jobs([str(p) for p in files], jobs)
    c0, p0 = children_cpu(), time.process_time()
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=jobs, initializer=worker_init) as pool:
        sum(pool.map(_parse_chunk, chunks))
    wall = time.perf_counter() - t0
    return wall, (children_cpu() - c0) + (time.process_time() - p0)


# --------------------------------------------------------------------------- processes


def _children(pid: int) -> list[int]:
    out = []
    try:
        for task in os.listdir(f"/proc/{pid}/task"):
            with open(f"/proc/{pid}/task/{task}/children") as fh:
                out += [int(c) for c in fh.read().split()]
    except OSError:
        pass
    return out


def _pss_kB(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/smaps_rollup") as fh:
            for line in fh:
                if line.startswith("Pss:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return 0


#: A small launcher: runs the command, then reports its wall time, the CPU time (user +
#: system) of it and its workers, and the largest max RSS among them. Linux carries a
#: process's RSS high-water mark over fork and exec, so launching from this (large)
#: benchmark process would inflate the figure by the benchmark's own size; from this
#: launcher, by ~10 MB at most.
_LAUNCHER = """
import json, resource, subprocess, sys, time
t0 = time.perf_counter()
code = subprocess.call(sys.argv[2:])
wall = time.perf_counter() - t0
usage = resource.getrusage(resource.RUSAGE_CHILDREN)
with open(sys.argv[1], "w") as fh:
    json.dump({"wall_s": wall, "exit_code": code, "max_rss_kB": usage.ru_maxrss,
               "cpu_s": usage.ru_utime + usage.ru_stime}, fh)
"""


def run_measured(cmd: list[str], cwd: Path) -> dict:
    """Run ``cmd``; wall time [s], exit code, largest single-process max RSS [MB], the peak
    PSS summed over the process tree [MB] (sampled every 50 ms), the first output line."""
    import tempfile

    peak = parent_peak = 0
    stop = threading.Event()
    out_fh, err_fh = tempfile.TemporaryFile(), tempfile.TemporaryFile()
    report = Path(tempfile.mkstemp(suffix=".json")[1])
    launcher = subprocess.Popen([sys.executable, "-c", _LAUNCHER, str(report), *cmd],
                                cwd=cwd, stdout=out_fh, stderr=err_fh)

    def sample() -> None:
        nonlocal peak, parent_peak
        while not stop.is_set():
            pids, todo = [], _children(launcher.pid)  # the launcher itself is not counted
            if todo:  # the command's own process (a batch's parent), without its workers
                parent_peak = max(parent_peak, _pss_kB(todo[0]))
            while todo:
                pid = todo.pop()
                pids.append(pid)
                todo += _children(pid)
            peak = max(peak, sum(_pss_kB(p) for p in pids))
            stop.wait(0.05)

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    launcher.wait()
    stop.set()
    sampler.join()
    measured = json.loads(report.read_text())
    report.unlink()
    out_fh.seek(0)
    err_fh.seek(0)
    stdout, stderr = out_fh.read().decode(errors="replace"), err_fh.read().decode(errors="replace")
    if measured["exit_code"] not in (0, 1):
        raise SystemExit(f"{' '.join(cmd)} exited {measured['exit_code']}: {stderr[-2000:]}")
    return {"wall_s": measured["wall_s"], "cpu_s": measured["cpu_s"],
            "exit_code": measured["exit_code"],
            "max_rss_MB": measured["max_rss_kB"] / 1024,  # Linux reports kB
            "peak_pss_tree_MB": peak / 1024,
            "peak_pss_parent_MB": parent_peak / 1024,
            "said": _ledger_line(stdout),
            "stderr_tail": stderr.strip()[-300:]}


def _ledger_line(stdout: str) -> str:
    """The batch's account line (files, tests, runs) from its output (else its first)."""
    lines = [ln for ln in stdout.splitlines() if " file(s), " in ln] or stdout.splitlines()
    return lines[0].strip() if lines else ""


def help_times(exe: list[str], n: int = 7) -> list[float]:
    """Wall times [s] of ``tribopipe --help``."""
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        subprocess.run([*exe, "--help"], check=True, capture_output=True)
        times.append(time.perf_counter() - t0)
    return times


def startup() -> dict:
    """What a batch imports before its workers fork (``import tribopipe.campaign``): wall
    time over a bare interpreter [ms, median of 7], whether scipy / scipy.signal are among
    the modules (``python -X importtime``) and scipy.signal's cumulative import [ms]; and
    what matplotlib's Agg canvas and Pillow add in a plotting worker [ms]."""

    def wall(code: str) -> float:
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", code], check=True)
        return (time.perf_counter() - t0) * 1e3

    base = median([wall("pass") for _ in range(7)])
    batch = median([wall("import tribopipe.campaign") for _ in range(7)]) - base
    plots = median([wall("import tribopipe.campaign, matplotlib.backends.backend_agg, "
                         "PIL.Image") for _ in range(7)]) - base - batch
    proc = subprocess.run([sys.executable, "-X", "importtime", "-c", "import tribopipe.campaign"],
                          capture_output=True, text=True, check=True)
    cumulative = {}
    for line in proc.stderr.splitlines():
        parts = [p.strip() for p in line.removeprefix("import time:").split("|")]
        if len(parts) == 3 and parts[1].isdigit():
            cumulative[parts[2]] = int(parts[1]) / 1e3
    return {"batch_imports_ms": batch, "plot_worker_adds_ms": plots,
            "scipy_imported": any(m == "scipy" or m.startswith("scipy.") for m in cumulative),
            "scipy_signal_imported": "scipy.signal" in cumulative,
            "scipy_signal_ms": cumulative.get("scipy.signal")}


def touch_content(path: Path, k: int) -> None:
    """Give ``path`` new content that still reads (the Project name's case changed)."""
    raw = path.read_bytes()
    utf16 = raw[:2] == b"\xff\xfe"
    names = ["bench", "BENCH", "Bench"]
    old, new = names[k % 3], names[(k + 1) % 3]
    enc = (lambda s: s.encode("utf-16-le")) if utf16 else (lambda s: s.encode())
    path.write_bytes(raw.replace(enc(old), enc(new), 1))


def map_rows(path: Path) -> int:
    import pyarrow.parquet as pq

    return pq.ParquetFile(path).metadata.num_rows if path.exists() else 0


# --------------------------------------------------------------------------- main


def median(values: list[float]) -> float:
    return statistics.median(values)


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1000, help="number of exports (1000)")
    parser.add_argument("--jobs", type=int, default=None, help="workers (default: all CPUs)")
    parser.add_argument("--repeat", type=int, default=5,
                        help="rounds of parse-only / batch / batch with plots (5)")
    parser.add_argument("--out", type=Path, default=HERE / "out")
    parser.add_argument("--results", type=Path, default=HERE / "results.json")
    parser.add_argument("--incremental-only", action="store_true",
                        help="only one batch from scratch, then the unchanged re-run "
                             "(--repeat times); prints the figures, writes no results file")
    args = parser.parse_args(argv)

    from tribopipe.campaign.batch import default_jobs

    jobs = args.jobs or default_jobs()
    out: Path = args.out.resolve()
    raw, bundles_dir = out / "raw", out / "bundles"
    load_start = os.getloadavg()
    print(f"generating {args.n} exports in {raw} ...", flush=True)
    t0 = time.perf_counter()
    size = generate(raw, args.n, jobs)
    bundles = bundle(bundles_dir, args.n, jobs)
    print(f"  {size / 1e6:.0f} MB, {len(bundles)} bundles, {time.perf_counter() - t0:.0f} s",
          flush=True)
    single_cfg, bundles_cfg = write_configs(out)
    files = sorted(raw.glob("*.csv"))

    exe_path = Path(sys.executable).with_name("tribopipe")
    exe = [str(exe_path)] if exe_path.exists() else [sys.executable, "-m", "tribopipe"]

    def batch(cfg: Path, plots: bool, *, scratch: bool = True) -> dict:
        if scratch:
            shutil.rmtree(out / ("processed" if cfg == single_cfg else "processed-bundles"),
                          ignore_errors=True)
        return run_measured([*exe, "batch", str(cfg), "--jobs", str(jobs),
                             "--plots" if plots else "--no-plots"], out)

    if args.incremental_only:
        print("batch from scratch, then unchanged re-runs ...", flush=True)
        first = batch(single_cfg, plots=False)
        reruns = [batch(single_cfg, plots=False, scratch=False) for _ in range(args.repeat)]
        walls = [r["wall_s"] for r in reruns]
        print(f"batch from scratch {first['wall_s']:.2f} s ({first['said']}); unchanged "
              f"re-run median {median(walls):.2f} s ({', '.join(f'{w:.2f}' for w in walls)})")
        return {"batch": first, "rerun_s": walls}
    print("reader against the bare parse ...", flush=True)
    reader = reader_ratios(files, bundles, per_layout=9, repeat=7)
    rounds: list[dict] = []
    loads: list[tuple[float, float, float]] = []
    for i in range(args.repeat):
        print(f"round {i + 1}/{args.repeat}: parse-only pool, batch, batch with plots ...",
              flush=True)
        parse_wall, parse_cpu = parse_only_pool(files, jobs)
        rounds.append({"parse_pool_s": parse_wall, "parse_pool_cpu_s": parse_cpu,
                       "batch": batch(single_cfg, plots=False),
                       "batch_plots": batch(single_cfg, plots=True)})
        print("  " + "  ".join(
            f"{k} {v if isinstance(v, float) else v['wall_s']:.1f} s"
            + ("" if isinstance(v, float) else f" (CPU {v['cpu_s']:.1f} s)")
            for k, v in rounds[-1].items()) + f"  load {os.getloadavg()[0]:.1f}", flush=True)
        loads.append(os.getloadavg())
    print("incremental re-runs and one changed file ...", flush=True)
    reruns = [batch(single_cfg, plots=True, scratch=False) for _ in range(args.repeat)]
    victim = files[len(files) // 2]
    original = victim.read_bytes()
    changed = []
    for k in range(args.repeat):
        touch_content(victim, k)
        changed.append(batch(single_cfg, plots=True, scratch=False))
    victim.write_bytes(original)
    print("bundled exports ...", flush=True)
    bundled = batch(bundles_cfg, plots=False)
    bundled_rows = map_rows(out / "processed-bundles" / "friction_map.parquet")
    bundles_supported = bundled_rows == args.n
    if bundles_supported:
        bundled_runs = [bundled] + [batch(bundles_cfg, plots=False)
                                    for _ in range(args.repeat - 1)]
    print("tribopipe --help, start-up ...", flush=True)
    helps = help_times(exe)
    start = startup()

    walls = {k: [r[k]["wall_s"] for r in rounds] for k in ("batch", "batch_plots")}
    cpus = {k: [r[k]["cpu_s"] for r in rounds] for k in ("batch", "batch_plots")}
    parse = [r["parse_pool_s"] for r in rounds]
    parse_cpu = [r["parse_pool_cpu_s"] for r in rounds]
    results = {
        "when_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "load_average_at_start": load_start, "load_average_at_end": os.getloadavg(),
        "load_average_after_each_round": loads,
        "cpus": os.cpu_count(), "jobs": jobs, "python": platform.python_version(),
        "machine": platform.platform(), "repeat": args.repeat,
        "files": len(files), "bytes": size,
        "layouts": {name: sum(1 for _, lay, _ in plan(args.n) if lay == name)
                    for name in LAYOUTS},
        "rows": {"min": ROWS[0], "max": ROWS[1]},
        "reader": reader,
        "parse_pool_s": parse,
        "parse_pool_cpu_s": parse_cpu,
        "batch_s": walls["batch"],
        "batch_plots_s": walls["batch_plots"],
        "batch_cpu_s": cpus["batch"],
        "batch_plots_cpu_s": cpus["batch_plots"],
        "ratio_plots": median([p / b for p, b in zip(walls["batch_plots"], walls["batch"],
                                                     strict=True)]),
        "ratio_plots_cpu": median([p / b for p, b in zip(cpus["batch_plots"], cpus["batch"],
                                                         strict=True)]),
        "ratio_batch_parse": median([b / p for b, p in zip(walls["batch"], parse,
                                                           strict=True)]),
        "ratio_batch_parse_cpu": median([b / p for b, p in zip(cpus["batch"], parse_cpu,
                                                               strict=True)]),
        "peak_pss_MB": {"batch": max(r["batch"]["peak_pss_tree_MB"] for r in rounds),
                        "batch_plots": max(r["batch_plots"]["peak_pss_tree_MB"]
                                           for r in rounds)},
        "max_rss_MB": {"batch": max(r["batch"]["max_rss_MB"] for r in rounds),
                       "batch_plots": max(r["batch_plots"]["max_rss_MB"] for r in rounds)},
        "rerun_s": [r["wall_s"] for r in reruns],
        "one_changed_s": [r["wall_s"] for r in changed],
        "help_s": helps,
        "startup": start,
        "bundles": {"files": len(bundles), "tests": args.n, "map_rows": bundled_rows,
                    "supported": bundles_supported, "said": bundled["said"]},
        "said": {"batch": rounds[-1]["batch"]["said"],
                 "batch_plots": rounds[-1]["batch_plots"]["said"],
                 "rerun": reruns[-1]["said"]},
    }
    if bundles_supported:
        results["bundles"]["batch_s"] = [r["wall_s"] for r in bundled_runs]
        results["bundles"]["batch_cpu_s"] = [r["cpu_s"] for r in bundled_runs]
        results["bundles"]["ratio_to_single_files"] = (
            median(results["bundles"]["batch_s"]) / median(walls["batch"]))
    results["targets"] = {
        "reader_le_2x": (all(v["ratio"] <= 2.0 for v in reader.values())
                         if "skipped" not in reader else None),
        "plots_le_1.5x": results["ratio_plots"] <= 1.5,
        "batch_le_1.5x_parse": results["ratio_batch_parse"] <= 1.5,
        "batch_le_1.5x_parse_cpu": results["ratio_batch_parse_cpu"] <= 1.5,
        "plots_le_1.5x_cpu": results["ratio_plots_cpu"] <= 1.5,
        "rerun_le_1s": median(results["rerun_s"]) <= 1.0,
        "memory_le_500MB": max(results["peak_pss_MB"].values()) <= 500,
    }
    args.results.write_text(json.dumps(results, indent=1) + "\n", encoding="utf-8")
    report(results)
    print(f"wrote {args.results}")
    return results


def report(r: dict) -> None:
    """The results as the table of bench/README.md."""
    def spread(values: list[float], unit: str = "s", fmt: str = ".1f") -> str:
        return (f"{median(values):{fmt}} {unit} ({min(values):{fmt}}–{max(values):{fmt}})")

    rows = [("files", f"{r['files']} ({r['bytes'] / 1e6:.0f} MB), {r['layouts']}", "")]
    if "skipped" in r["reader"]:
        rows.append(("reader vs bare parse", r["reader"]["skipped"], "≤ 2×"))
    else:
        for layout, v in r["reader"].items():
            rows.append((f"reader, {layout}",
                         f"{v['read_export_ms']:.1f} vs {v['bare_ms']:.1f} ms: "
                         f"{v['ratio']:.2f}× (worst file {v['worst_file_ratio']:.2f}×)", "≤ 2×"))
    rows += [
        (f"parse-only pool of {r['jobs']}", spread(r["parse_pool_s"]),
         f"CPU {spread(r['parse_pool_cpu_s'])}"),
        ("batch, no plots", spread(r["batch_s"]),
         f"{r['ratio_batch_parse']:.2f}× parse-only (≤ 1.5×); in CPU time "
         f"{r['ratio_batch_parse_cpu']:.2f}×"),
        ("batch with plots", spread(r["batch_plots_s"]),
         f"{r['ratio_plots']:.2f}× without (≤ 1.5×)"),
        ("CPU, no plots / with plots", f"{median(r['batch_cpu_s']):.1f} s / "
         f"{median(r['batch_plots_cpu_s']):.1f} s", f"{r['ratio_plots_cpu']:.2f}× in CPU time"),
        ("incremental re-run", spread(r["rerun_s"], fmt=".2f"), "≤ 1 s"),
        ("one file changed", spread(r["one_changed_s"], fmt=".2f"), ""),
        ("peak PSS, process tree", f"{r['peak_pss_MB']['batch']:.0f} MB / "
         f"{r['peak_pss_MB']['batch_plots']:.0f} MB with plots", "≤ 500 MB"),
        ("max RSS, largest process", f"{r['max_rss_MB']['batch']:.0f} MB / "
         f"{r['max_rss_MB']['batch_plots']:.0f} MB with plots", ""),
        ("tribopipe --help", spread(r["help_s"], fmt=".3f"), ""),
        ("imports before the fork", f"{r['startup']['batch_imports_ms']:.0f} ms; scipy: "
         f"{r['startup']['scipy_imported']}, scipy.signal: "
         f"{r['startup']['scipy_signal_imported']}", ""),
        ("a plotting worker adds", f"{r['startup']['plot_worker_adds_ms']:.0f} ms", ""),
    ]
    b = r["bundles"]
    if b["supported"]:
        rows.append((f"bundled: {b['files']} files × {PER_BUNDLE} tests",
                     spread(b["batch_s"]), f"{b['ratio_to_single_files']:.2f}× single files"))
    else:
        rows.append(("bundled exports", f"not read as {b['tests']} runs on this code "
                     f"({b['map_rows']} map rows): skipped", ""))
    width = max(len(name) for name, _, _ in rows)
    print()
    for name, value, target in rows:
        print(f"{name:<{width}}  {value}  {target}")
    print(f"\nload average {r['load_average_at_start']} at start, {r['load_average_at_end']} "
          f"at end; targets: {r['targets']}")


if __name__ == "__main__":
    main()
