"""Scale benchmark: what grows with the number of runs, measured where it can be.

For ``bench/README.md``'s "Scale on paper". Measures, in one process (CPU time,
``time.process_time``, medians):

* **per file** — the steps a batch worker runs for one export (``read_export``, interval
  choice + reduction, SHA-256 + record, the trace's Parquet, the trace plot), on exports
  of 5,000, 10,000 and 15,000 rows in the three layouts of the campaign benchmark; the
  reduction both with the stick-slip test's thresholds cached (a length the process has
  met) and cold (cache cleared first);
* **per map size** N = 10³, 10⁴, 10⁵ rows (a synthetic map: one real record copied with
  new ids and conditions over the founding grid) — ``read_map``; ``update_map`` with 1,000
  new runs (the batch's one locked read-modify-write and atomic rewrite of the whole
  Parquet file); ``group_statistics``; the map's size on disk; the campaign state file
  (``save_state``/``load_state``) with N entries; the HTML report without traces (N ≤ 10⁴);
  and ``stat`` of N files (what an unchanged re-run does per file).

    nice .venv/bin/python bench/bench_scale.py [--sizes 1000,10000,100000]

Prints tables and writes ``bench/scale.json``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import shutil
import statistics
import sys
import tempfile
import time
import uuid
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the generators

HERE = Path(__file__).resolve().parent


def cpu(fn, repeat: int = 3) -> float:
    """Median CPU seconds of ``fn()`` over ``repeat`` calls."""
    times = []
    for _ in range(repeat):
        t0 = time.process_time()
        fn()
        times.append(time.process_time() - t0)
    return statistics.median(times)


def wall(fn, repeat: int = 3) -> float:
    """Median wall seconds of ``fn()`` (for steps that wait on the disk: fsync)."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


# --------------------------------------------------------------------------- per file


def per_file(folder: Path, repeat: int) -> dict:
    """CPU [ms] of each step a batch worker runs per export, median over the files."""
    import gc

    from threadpoolctl import threadpool_limits

    from generators.synthetic import SyntheticRun, write_rheocompass_export
    from tribopipe.campaign.worker import GC_THRESHOLDS
    from tribopipe.config import load_settings
    from tribopipe.files import file_sha256
    from tribopipe.frictionmap import make_record
    from tribopipe.labels import RunLabels, decide_run
    from tribopipe.pipeline import RunOutcome, plot_run, write_trace
    from tribopipe.readers import read_export
    from tribopipe.reduction.intervals import select_friction_interval
    from tribopipe.reduction.reduce import reduce_measurement

    gc.set_threshold(*GC_THRESHOLDS)  # as in the batch's workers: their GC setting,
    threadpool_limits(limits=1, user_api="blas")  # and one BLAS thread
    settings = load_settings()
    labels = RunLabels("Dragonskin 30", "steel", 3.0, 20.0, 1)
    layouts = {"utf16-tab-en": {}, "utf8-comma": {"encoding": "utf-8", "delimiter": ","},
               "utf16-tab-fr": {"language": "fr"}}
    from tribopipe.reduction import signals

    steps: dict[str, list[float]] = {k: [] for k in
                                      ("read", "reduce", "reduce_cold", "hash_record", "trace",
                                       "plot")}
    out = folder / "out"
    for rows in (5_000, 10_000, 15_000):
        for name, kw in layouts.items():
            path = write_rheocompass_export(
                folder / f"{name}_{rows}.csv", SyntheticRun(duration_s=rows / 10.0, seed=rows),
                project="scale", test="t", sample="DS30", **kw)
            measurements = read_export(path)
            m = select_friction_interval(measurements)
            result = reduce_measurement(m, settings.instrument, settings.reduction)
            file_hash = file_sha256(path)
            verdict = decide_run(labels, result.flags, result.normal_force_mean_N,
                                 result.temperature_C)
            record = make_record(result=result, verdict=verdict, meta=m.meta,
                                 file_hash=file_hash, settings=settings)
            outcome = RunOutcome(path=str(path), measurement=m, result=result,
                                 file_hash=file_hash, config_hash=settings.config_hash,
                                 measurement_id=record.measurement_id, verdict=verdict,
                                 record=record)
            plot_run(out, outcome)  # the figure is built once per process
            steps["read"].append(cpu(lambda p=path: read_export(p), repeat))
            steps["reduce"].append(cpu(lambda ms=measurements: reduce_measurement(
                select_friction_interval(ms), settings.instrument, settings.reduction), repeat))
            # the stick-slip test's false-alarm thresholds are cached per process (keyed by
            # the number of candidate frequencies, rounded): a run of a length this process
            # has not met yet pays for them
            def cold(ms=measurements) -> None:
                signals._threshold.cache_clear()
                reduce_measurement(select_friction_interval(ms), settings.instrument,
                                   settings.reduction)

            steps["reduce_cold"].append(cpu(cold, repeat))
            steps["hash_record"].append(cpu(lambda p=path, r=result, mm=m: make_record(
                result=r, labels=labels, meta=mm.meta, file_hash=file_sha256(p), settings=settings),
                repeat))
            steps["trace"].append(cpu(lambda o=outcome: write_trace(out, o), repeat))
            steps["plot"].append(cpu(lambda o=outcome: plot_run(out, o), repeat))
    return {k: statistics.median(v) * 1e3 for k, v in steps.items()}


# --------------------------------------------------------------------------- per map size


def records(template: dict, n: int, start: int = 0) -> list[dict]:
    """``n`` copies of a real map record with new ids, files and grid conditions."""
    pins = ("Dragonskin 30", "Ecoflex 00-50")
    discs = ("steel", "acrylic", "aluminium sheet", "aluminium lathed", "cardboard",
             "wood smooth", "wood structured", "DS30", "EF50")
    out = []
    for i in range(start, start + n):
        r = dict(template)
        r["measurement_id"] = uuid.UUID(int=i + 1).hex[-16:]
        r["file_hash"] = uuid.UUID(int=(i + 1) << 64).hex * 2
        r["source_file"] = f"lab{i // 10_000}/run_{i:06d}.csv"
        r["pin"], r["disc"] = pins[i % 2], discs[(i // 2) % 9]
        force = (1.0, 3.0, 5.0, 7.0, 9.0)[(i // 18) % 5]
        r["normal_force_N"], r["pressure_kPa"] = force, 11.789 * force
        r["temperature_C"] = (10.0, 20.0)[(i // 90) % 2]
        r["repeat"] = i // 180 + 1
        r["mu_k"] = 0.3 + 0.5 / force**0.5 + 0.01 * ((i * 7919) % 13 - 6) / 6
        out.append(r)
    return out


def template_record(folder: Path) -> dict:
    from generators.synthetic import SyntheticRun, write_rheocompass_export
    from tribopipe.config import load_settings
    from tribopipe.labels import RunLabels
    from tribopipe.pipeline import reduce_file

    path = write_rheocompass_export(folder / "t.csv", SyntheticRun(seed=1), project="p",
                                    test="t", sample="s")
    record = reduce_file(path, load_settings(), RunLabels("x", "y", 3.0, 20.0, 1)).record
    assert record is not None
    return record.as_dict()


def per_size(folder: Path, n: int, template: dict) -> dict:
    """Costs that grow with the number of runs N, at one N."""
    from tribopipe.campaign import folder_campaign
    from tribopipe.campaign.state import CampaignState, load_state, save_state
    from tribopipe.fit import fit_power_law
    from tribopipe.frictionmap import read_map, update_map
    from tribopipe.report import ReportInputs, report_files
    from tribopipe.stats import group_statistics

    base = folder / f"map_{n}.parquet"
    for k in range(0, n, 20_000):
        update_map(base, records(template, min(20_000, n - k), k))
    runs = read_map(base)
    assert len(runs) == n
    row: dict = {"map_MB": base.stat().st_size / 1e6}
    row["read_map_s"] = cpu(lambda: read_map(base))
    work = folder / "work.parquet"
    new = records(template, 1000, n)

    def append() -> None:
        shutil.copyfile(base, work)
        update_map(work, new)

    copy_wall = wall(lambda: shutil.copyfile(base, work))
    copy_cpu = cpu(lambda: shutil.copyfile(base, work))
    row["update_map_1000_s"] = wall(append) - copy_wall  # wall: it fsyncs
    row["update_map_1000_cpu_s"] = cpu(append) - copy_cpu
    row["group_statistics_s"] = cpu(lambda: group_statistics(runs), 1)
    campaign = folder_campaign(folder, filename_pattern="{pin}", output_dir=folder / "p")
    entries = {f"lab{i // 10_000}/run_{i:06d}.csv": {
        "size": 1_200_000, "mtime_ns": 1_700_000_000_000_000_000 + i,
        "config_hash": "2fc9df08b211fe45", "recipe": "0123456789abcdef",
        "sha256": uuid.UUID(int=i).hex * 2, "status": "reduced", "tests": [None],
        "runs": [{
            "status": "reduced",
            "labels": {"pin": "Dragonskin 30", "disc": "steel", "normal_force_N": 3.0,
                       "temperature_C": 20.0, "repeat": 1},
            "measurement_id": uuid.UUID(int=i + 1).hex[-16:],
            "trace": f"traces/run_{i:06d}_{uuid.UUID(int=i + 1).hex[-8:]}.parquet",
            "mu_s": 0.9, "mu_k": 0.6, "pressure_kPa": 35.4, "pressure_measured_kPa": 35.3,
            "normal_force_measured_N": 2.99, "temperature_measured_C": 20.1, "flags": ""}]}
        for i in range(n)}
    state = CampaignState.from_json({"version": 2, "campaign": "scale", "entries": entries})
    assert len(state.entries) == n
    row["state_save_s"] = wall(lambda: save_state(campaign, state))
    row["state_load_s"] = cpu(lambda: load_state(campaign))
    row["state_MB"] = campaign.state_path.stat().st_size / 1e6
    stat_dir = folder / f"stat_{n}"
    stat_dir.mkdir()
    names = [stat_dir / f"{i}.csv" for i in range(n)]
    for name in names:
        name.touch()
    row["stat_files_s"] = cpu(lambda: [os.stat(p) for p in names])
    shutil.rmtree(stat_dir)
    if n <= 10_000:
        inputs = ReportInputs(runs=runs, groups=group_statistics(runs),
                              fits=fit_power_law(runs))
        row["report_s"] = cpu(lambda: report_files(inputs), 1)
        files = report_files(inputs)  # the page last, what lies beside it before
        row["report_MB"] = len(files.popitem()[1].encode()) / 1e6
        row["report_beside_MB"] = sum(len(t.encode()) for t in files.values()) / 1e6
    return row


# --------------------------------------------------------------------------- commands


#: seconds after which a timed command is stopped and reported as not finished
TIMEOUT_S = 1200.0


def _env(cwd: Path) -> dict[str, str]:
    """The environment of a timed command: the package's source first, and compiled
    bytecode kept (in ``cwd``/pycache, as an installed package keeps it), so that every
    command is timed as a user runs it, not compiling its imports again."""
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    env["PYTHONPYCACHEPREFIX"] = str(cwd / "pycache")
    src = str(Path(__file__).resolve().parents[1] / "src")
    env["PYTHONPATH"] = src + os.pathsep + env.get("PYTHONPATH", "")
    return env


def _timed(argv: list[str], cwd: Path) -> dict[str, float]:
    """Wall and CPU seconds (user + system, the command and its children) and peak
    memory [MB] of ``tribopipe ARGV`` run as a process; ``wall_s`` is ``inf`` when it did
    not finish within :data:`TIMEOUT_S`."""
    import subprocess

    code = ("import resource, subprocess, sys, time\n"
            "t = time.perf_counter()\n"
            "try:\n"
            "    r = subprocess.run(sys.argv[2:], stdout=subprocess.DEVNULL, "
            "stderr=subprocess.PIPE, text=True, timeout=float(sys.argv[1]))\n"
            "    rc, err = r.returncode, r.stderr\n"
            "except subprocess.TimeoutExpired:\n"
            "    rc, err = -1, ''\n"
            "dt = time.perf_counter() - t\n"
            "u = resource.getrusage(resource.RUSAGE_CHILDREN)\n"
            "print(dt, u.ru_utime + u.ru_stime, u.ru_maxrss / 1024, rc)\n"
            "sys.stderr.write(err[-400:] if rc != 0 else '')\n")
    out = subprocess.run([sys.executable, "-c", code, str(TIMEOUT_S), sys.executable, "-m",
                          "tribopipe", *argv], capture_output=True, text=True, cwd=cwd,
                         check=True, env=_env(cwd))
    dt, cpu_s, mb, rc = out.stdout.split()
    if int(rc) > 1:
        raise SystemExit(f"tribopipe {' '.join(argv)}: exit {rc}: {out.stderr}")
    if int(rc) == -1:
        return {"wall_s": math.inf, "cpu_s": float(cpu_s), "peak_MB": float(mb),
                "exit_code": -1}
    return {"wall_s": float(dt), "cpu_s": float(cpu_s), "peak_MB": float(mb),
            "exit_code": int(rc), **({"stderr": out.stderr} if int(rc) else {})}


def canonical_names() -> dict[str, str]:
    """The shipped vocabulary's canonical name of each pin and disc name of
    :func:`records` (the names a reduction resolves on the way in; ``map validate`` and
    ``map publish`` call others problems)."""
    from tribopipe.materials import shipped_vocabulary

    vocabulary = shipped_vocabulary()
    out = {}
    for name in ("Dragonskin 30", "Ecoflex 00-50", "steel", "acrylic", "aluminium sheet",
                 "aluminium lathed", "cardboard", "wood smooth", "wood structured", "DS30",
                 "EF50"):
        found = vocabulary.candidates({"aluminium lathed": "lathed aluminium disk"}.get(
            name, name))
        out[name] = found[0] if len(found) == 1 else name
    return out


def build_map(path: Path, template: dict, n: int, *, pairs: bool = False,
              canonical: bool = False) -> None:
    """A map of ``n`` rows at ``path`` through the package's own API, landed in chunks of
    20,000 (as a batch lands them): relabelled copies of one real reduced run
    (:func:`records`); ``pairs``: every 180 runs (one of each condition of the grid) get
    their own pin, so that every run is a condition group of its own and the pairs grow
    with the runs, as when labs add their own materials and lots; ``canonical``: the pin
    and disc names the vocabulary's canonical ones (:func:`canonical_names`)."""
    from tribopipe.frictionmap import update_map

    names = canonical_names() if canonical else {}
    for k in range(0, n, 20_000):
        chunk = records(template, min(20_000, n - k), k)
        for r in chunk:
            r["pin"], r["disc"] = names.get(r["pin"], r["pin"]), names.get(r["disc"], r["disc"])
        if pairs:
            for i, r in enumerate(chunk, start=k):
                r["pin"] = f"{r['pin']} lot {i // 180}"
        update_map(path, chunk)


def _median(runs: list[dict[str, float]]) -> dict[str, float]:
    return {"wall_s": statistics.median(r["wall_s"] for r in runs),
            "cpu_s": statistics.median(r["cpu_s"] for r in runs),
            "peak_MB": max(r["peak_MB"] for r in runs)}


def _commands_at(folder: Path, n: int, template: dict, export: Path, raw: Path,
                 repeat: int) -> dict:
    """:func:`commands` on a map of ``n`` rows (``0``: an empty map)."""
    base = folder / f"cmd_{n}.parquet"
    if n:
        build_map(base, template, n, canonical=True)
    row: dict = {}
    work = folder / "work.parquet"

    def fresh() -> Path:
        if work.exists():
            shutil.rmtree(work) if work.is_dir() else work.unlink()
        if base.exists():
            shutil.copytree(base, work)
        return work

    def median(argv_of, prepare=None) -> dict[str, float]:
        runs = []
        for _ in range(repeat):
            if prepare is not None:
                prepare()
            runs.append(_timed(argv_of(), folder))
            # a refused command (exit 1: a name the vocabulary does not know, say) would
            # time its refusal, not its work
            if runs[-1]["exit_code"] != 0:
                raise SystemExit(f"tribopipe {' '.join(argv_of())}: exit "
                                 f"{runs[-1]['exit_code']}: {runs[-1].get('stderr', '')}")
        return _median(runs)

    def reduce_argv() -> list[str]:
        # a known pin (a name the vocabulary does not know is refused before any work),
        # a new repeat of a condition the map holds, as the batch's export
        return ["reduce", str(export), "--pin", "DS30", "--disc", "steel", "--force",
                "3", "--temperature", "20", "--repeat", "999", "--map", str(work),
                "--output", str(folder / "reduced"), "--no-plots"]

    def batch_prepare() -> None:
        fresh()
        shutil.rmtree(folder / "batch_out", ignore_errors=True)
        shutil.rmtree(raw)
        raw.mkdir()
        # a known pin (the campaign refuses a name not in the vocabulary), a new repeat
        # of a condition the map holds
        shutil.copy(export, raw / "DS30_steel_3N_20C_r999.csv")

    def batch_argv() -> list[str]:
        return ["batch", str(raw), "--pattern", "{pin}_{disc}_{force}N_{temperature}C_r{repeat}",
                "--map", str(work), "--out", str(folder / "batch_out"), "--no-plots",
                "-j", "1"]

    row["reduce"] = median(reduce_argv, fresh)
    row["batch_one_new"] = median(batch_argv, batch_prepare)
    if n:
        m = ["--map", str(base)]
        row["query"] = median(lambda: ["query", "--pin", "Dragonskin 30", "--disc",
                                       "steel", "--pressure", "40", "--temperature",
                                       "20", *m])
        row["map_show"] = median(lambda: ["map", "show", *m])
        row["map_table_paper"] = median(lambda: ["map", "table", "--layout", "paper", *m])
        row["export_abaqus_one_pair"] = median(lambda: [
            "export", "abaqus", "--pin", "Dragonskin 30", "--disc", "steel", *m,
            "-o", str(folder / "f.inp")])
        row["map_validate"] = median(lambda: ["map", "validate", str(base)], None)
        pkg = folder / "pkg"
        row["map_publish"] = median(
            lambda: ["map", "publish", str(pkg), "--lab", "Bench Lab", "--overwrite",
                     "--allow-synthetic", *m])
        row["map_MB_on_disk"] = sum(f.stat().st_size for f in base.rglob("*")
                                    if f.is_file()) / 1e6
    return row


def commands(folder: Path, sizes: list[int], template: dict, repeat: int) -> dict:
    """Wall and CPU time [s] and peak memory [MB] of each command of the map's targets on
    maps of each size (median of ``repeat`` runs; the appending commands on a fresh copy
    of the map each time), and on an empty map for ``reduce`` and ``batch``."""
    from generators.synthetic import SyntheticRun, write_rheocompass_export

    export = write_rheocompass_export(folder / "new_export.csv", SyntheticRun(seed=7),
                                      project="p", test="t", sample="s")
    raw = folder / "raw"
    raw.mkdir()
    results: dict = {}
    # every command once on a small map, untimed: the imports compiled into the cache
    # (:func:`_env`), as an installed package has them
    _commands_at(folder, 100, template, export, raw, 1) if sizes else None
    for n in [0, *sizes] if sizes else []:
        row = _commands_at(folder, n, template, export, raw, repeat)
        results[str(n)] = row
        print(f"  {n} rows (load {os.getloadavg()[0]:.1f}): " + ", ".join(
            f"{k} {v['wall_s']:.2f} s wall/{v['cpu_s']:.2f} s CPU/{v['peak_MB']:.0f} MB"
            if isinstance(v, dict) else f"{k} {v:.1f}" for k, v in row.items()), flush=True)
    return results


#: the commands over every pair :func:`per_group` times (``--per-group`` chooses)
PER_GROUP_COMMANDS = ("export_abaqus_every_pair", "explore", "report")


def _size_MB(page: Path) -> dict[str, float]:
    """The size of a page [MB] and of what was written beside it (``<stem>_*``) [MB]."""
    beside = [f for d in page.parent.glob(page.stem + "_*") for f in
              ([d] if d.is_file() else d.rglob("*")) if f.is_file()]
    return {"page_MB": page.stat().st_size / 1e6,
            "beside_MB": sum(f.stat().st_size for f in beside) / 1e6}


def per_group(folder: Path, groups: list[int], template: dict,
              commands: tuple[str, ...] = PER_GROUP_COMMANDS) -> dict:
    """Wall and CPU seconds in all and per condition group of the commands over every
    pair (``export abaqus`` of every pair, ``explore``, ``report``; ``commands`` of
    :data:`PER_GROUP_COMMANDS`) on maps where every run is a group of its own and the
    pairs grow with the runs (:func:`build_map`); the pages' sizes beside."""
    out: dict = {}
    for n in [100, *groups] if groups else []:  # 100: untimed, the imports compiled
        base = folder / f"groups_{n}.parquet"
        build_map(base, template, n, pairs=True)
        m = ["--map", str(base)]
        argv = {
            "export_abaqus_every_pair": ["export", "abaqus", *m, "-o", str(folder / "all.inp")],
            "explore": ["explore", *m, "-o", str(folder / f"e{n}.html")],
            "report": ["report", *m, "--processed", str(folder / "none"),
                       "-o", str(folder / f"r{n}.html")],
        }
        row = {name: _timed(argv[name], folder) for name in commands}
        if n == 100:
            continue
        for name, page in (("explore", folder / f"e{n}.html"), ("report", folder / f"r{n}.html")):
            if name in row and page.exists():
                row[name].update(_size_MB(page))
        out[str(n)] = {k: {**v, "wall_ms_per_group": v["wall_s"] / n * 1e3,
                           "cpu_ms_per_group": v["cpu_s"] / n * 1e3}
                       for k, v in row.items()}
        print(f"  {n} groups (load {os.getloadavg()[0]:.1f}): " + ", ".join(
            f"{k} {v['wall_s']:.1f} s wall, {v['cpu_s']:.1f} s CPU "
            f"({v['cpu_ms_per_group']:.2f} ms CPU/group, {v['peak_MB']:.0f} MB)"
            for k, v in out[str(n)].items()), flush=True)
    return out


def map_costs(folder: Path, sizes: list[int], template: dict) -> dict:
    """CPU seconds (``time.process_time``: what the load of other processes does not
    change) of the map's own operations at each size, the map folder of parts against
    the same rows in one file (the format before parts): open all columns, open the ids
    only, append one run, the full check of ``map validate``."""
    from tribopipe.frictionmap import records_frame, update_map
    from tribopipe.frictionmap.snapshot import open_map
    from tribopipe.frictionmap.store import verify_map, write_map_copy

    out: dict = {}
    for n in sizes:
        base = folder / f"costs_{n}.parquet"
        build_map(base, template, n)
        single = folder / f"costs_{n}_single.parquet"
        runs = open_map(base).runs
        write_map_copy(single, runs)
        one = records(template, 1, 10_000_000)
        counter = iter(range(10**6))

        def append(path: Path, one: list = one, counter: Any = counter) -> None:
            rec = dict(one[0])
            rec["measurement_id"] = uuid.UUID(int=(1 << 100) + next(counter)).hex[-16:]
            update_map(path, records_frame([rec]).to_dict("records"))

        row = {
            "open_all_parts": cpu(lambda b=base: open_map(b)),
            "open_ids_parts": cpu(lambda b=base: open_map(b, ["measurement_id"])),
            "open_all_single_file": cpu(lambda s=single: open_map(s)),
            "append_one_parts": cpu(lambda b=base: append(b)),
            "append_one_single_file": cpu(lambda s=single: append(s)),
            "validate_parts": cpu(lambda b=base: verify_map(b), 1),
            "parts": int(open_map(base, ["measurement_id"]).info["parts"]),
        }
        out[str(n)] = row
        print(f"  {n} rows: " + ", ".join(f"{k} {v:.3g}" for k, v in row.items()), flush=True)
    return out


#: the issue's targets: (command, what it is compared with, the ratio or seconds allowed)
TARGETS: tuple[tuple[str, str, float], ...] = (
    ("reduce", "empty", 1.5), ("batch_one_new", "empty", 1.5), ("query", "1000", 1.5),
    ("map_show", "1000", 1.5), ("map_table_paper", "1000", 1.5),
    ("export_abaqus_one_pair", "1000", 1.5), ("map_validate", "seconds", 10.0),
    ("map_publish", "seconds", 30.0))


def table(results: dict) -> str:
    """The Markdown table of ``--commands`` results (``bench/README.md``): per command, CPU
    and wall seconds at each size, the ratio of CPU seconds at 10⁵ rows to the command
    on an empty map (``reduce``, ``batch``) or on the 10³-row map, and whether the
    target holds (in CPU time, and in wall time)."""
    timed = results.get("commands_wall_s_peak_MB") or {}
    sizes = [k for k in timed if k != "0"]
    if not sizes:
        return per_group_table(results)
    largest = sizes[-1]
    head = ("| command | " + " | ".join(f"{int(n):,} rows: CPU / wall [s]" for n in
                                      ["0", *sizes])
            + f" | {int(largest):,} rows / base: CPU (wall) | target |")
    lines = [head, "|---" * (len(sizes) + 4) + "|"]
    for name, base, limit in TARGETS:
        cells = []
        for n in ["0", *sizes]:
            v = timed[n].get(name)
            cells.append("" if v is None else f"{v['cpu_s']:.2f} / {v['wall_s']:.2f}")
        top = timed[largest].get(name)
        if base == "seconds":
            ratio = "—"
            met = (f"< {limit:g} s: {'met' if top['cpu_s'] < limit else 'not met'} in CPU, "
                   f"{'met' if top['wall_s'] < limit else 'not met'} in wall")
        else:
            ref = timed["0" if base == "empty" else base][name]
            r_cpu, r_wall = top["cpu_s"] / ref["cpu_s"], top["wall_s"] / ref["wall_s"]
            ratio = f"{r_cpu:.2f} ({r_wall:.2f})"
            met = (f"≤ {limit:g}× {'empty map' if base == 'empty' else '10³ rows'}: "
                   f"{'met' if r_cpu <= limit else 'not met'} in CPU, "
                   f"{'met' if r_wall <= limit else 'not met'} in wall")
        lines.append(f"| `{name}` | " + " | ".join(cells) + f" | {ratio} | {met} |")
    grouped = per_group_table(results)
    return "\n".join(lines) + (f"\n\n{grouped}" if grouped else "")


def per_group_table(results: dict) -> str:
    """The Markdown table of ``--groups`` results: per command and number of groups, CPU
    and wall seconds, milliseconds of CPU per group and peak memory; empty where the
    results hold none."""
    grouped = results.get("per_group") or {}
    if not grouped:
        return ""
    lines = ["| command | groups | CPU / wall [s] | CPU per group [ms] | peak [MB] |",
             "|---|---:|---:|---:|---:|"]
    for n, row in grouped.items():
        for name, v in row.items():
            lines.append(f"| `{name}` | {int(n):,} | {v['cpu_s']:.2f} / {v['wall_s']:.2f} | "
                         f"{v['cpu_ms_per_group']:.2f} | {v['peak_MB']:.0f} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="1000,10000,100000")
    parser.add_argument("--repeat", type=int, default=5, help="per-file repeats (5)")
    parser.add_argument("--out", type=Path, default=HERE / "scale.json")
    parser.add_argument("--commands", action="store_true",
                        help="time the commands of the map's targets as processes instead "
                             "(writes bench/scale_commands.json)")
    parser.add_argument("--map-costs", action="store_true",
                        help="CPU time of the map's own operations, parts against one file "
                             "(writes bench/scale_map.json)")
    parser.add_argument("--groups", default="",
                        help="with --commands: also the per-group costs on maps of these "
                             "numbers of groups, e.g. 1000,10000")
    parser.add_argument("--per-group", default=",".join(PER_GROUP_COMMANDS),
                        help="with --groups: the commands to time, of "
                             f"{', '.join(PER_GROUP_COMMANDS)} (default: all)")
    parser.add_argument("--timeout", type=float, default=TIMEOUT_S,
                        help="with --commands: seconds after which a command is stopped "
                             f"and reported as not finished ({TIMEOUT_S:g})")
    parser.add_argument("--table", type=Path, default=None,
                        help="print the Markdown table of a --commands results file and stop")
    args = parser.parse_args(argv)
    if args.table is not None:
        results = json.loads(args.table.read_text(encoding="utf-8"))
        print(table(results))
        return results
    sizes = [int(s) for s in args.sizes.split(",") if s]
    globals()["TIMEOUT_S"] = args.timeout
    load_start = os.getloadavg()
    if args.map_costs:
        with tempfile.TemporaryDirectory(prefix="tribopipe-scale-") as tmp:
            folder = Path(tmp)
            costs = map_costs(folder, sizes, template_record(folder))
        results = {"when_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                   "load_average_at_start": load_start, "load_average_at_end": os.getloadavg(),
                   "python": platform.python_version(), "cpus": os.cpu_count(),
                   "map_cpu_s": costs}
        target = HERE / "scale_map.json"
        target.write_text(json.dumps(results, indent=1) + "\n", encoding="utf-8")
        print(f"wrote {target}")
        return results
    if args.commands:
        with tempfile.TemporaryDirectory(prefix="tribopipe-scale-") as tmp:
            folder = Path(tmp)
            template = template_record(folder)
            print("commands ...", flush=True)
            timed = commands(folder, sizes, template, max(1, min(args.repeat, 3)))
            grouped = per_group(folder, [int(g) for g in args.groups.split(",") if g],
                                template, tuple(c for c in args.per_group.split(",") if c))
        results = {"when_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                   "load_average_at_start": load_start, "load_average_at_end": os.getloadavg(),
                   "python": platform.python_version(), "cpus": os.cpu_count(),
                   "commands_wall_s_peak_MB": timed, "per_group": grouped}
        target = HERE / "scale_commands.json" if args.out == HERE / "scale.json" else args.out
        target.write_text(json.dumps(results, indent=1) + "\n", encoding="utf-8")
        print(f"wrote {target}")
        return results
    with tempfile.TemporaryDirectory(prefix="tribopipe-scale-") as tmp:
        folder = Path(tmp)
        print("per-file steps ...", flush=True)
        steps = per_file(folder, args.repeat)
        print("   " + ", ".join(f"{k} {v:.1f} ms" for k, v in steps.items()), flush=True)
        print("per map size ...", flush=True)
        template = template_record(folder)
        sized = {}
        for n in sizes:
            print(f"  map of {n} rows ...", flush=True)
            sized[str(n)] = per_size(folder, n, template)
            print("   " + ", ".join(f"{k} {v:.3g}" for k, v in sized[str(n)].items()),
                  flush=True)
    results = {"when_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
               "load_average_at_start": load_start, "load_average_at_end": os.getloadavg(),
               "python": platform.python_version(), "cpus": os.cpu_count(),
               "per_file_cpu_ms": steps, "per_map_size": sized}
    args.out.write_text(json.dumps(results, indent=1) + "\n", encoding="utf-8")
    print(f"wrote {args.out}")
    return results


if __name__ == "__main__":
    main()
