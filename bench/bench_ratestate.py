"""μ_S / μ_K on the third family — rate-and-state friction on the pins' spring, recorded by
an imperfect instrument — end to end.

The family (:mod:`generators.ratestate`: Dieterich–Ruina friction with the ageing
law on a spring of the pins' shear stiffness, driven at 0.007 mm/s; peaks 0.02–5 mm after
a hold, stable velocity-strengthening and -weakening sliding, creep without a peak,
weak stick-slip of 0.01–0.05; quantised torque, jitter, pink noise, spikes, a normal
force wandering by up to ±3 %, runs of 120–1,100 s with and without a set-up interval)
was written and its grid and seeds committed before it was first reduced and before any
detection change that followed (``bench/README.md``). Every run is written as a
RheoCompass export through the project's writer (every other one in French), read back
with ``read_export`` and reduced with the default T-PID/44 settings, as
``tribopipe reduce`` does.

Targets (issue 14, the same as the validation family's): μ_K within ±0.01 on all runs
with a plateau in the trace; a distinct μ_S within ±0.02 on ≥ 98 %;
``static_not_distinct`` on ≥ 95 % of the runs without a peak; stick-slip flagged on
≥ 90 % of the runs whose plateau oscillates. Runs with less than 0.5 mm of settled
plateau (truncated) must be flagged or refused; runs without a torque zero must be
flagged ``torque_offset_unknown``.

    nice .venv/bin/python bench/bench_ratestate.py            # 896 runs
    nice .venv/bin/python bench/bench_ratestate.py --quick    # 2 draws per cell
    nice .venv/bin/python bench/bench_ratestate.py --cache bench/out/ratestate

``--cache DIR`` keeps every written export and its truth in DIR and reuses them on the
next run while the generator's sources are unchanged (their SHA-256 is stamped in DIR):
solving the rate-and-state ODEs for the grid costs ~30 min of CPU, reducing it ~1 min.

Prints tables per shape, peak distance, noise colour, duration and set-up; writes
bench/ratestate.json (or bench/ratestate_quick.json). Exit code 1 when a target is missed.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the generators

from bench_validation import (
    _print_table,
    json_rows,
    offset_scores,
    summarise,
    targets_met,
    truncated_scores,
)

from generators.ratestate import (
    DURATIONS_S,
    NOISE_COLOURS,
    PEAK_DISTANCES_MM,
    SHAPES,
    GridPoint,
    RateStateRun,
    ratestate_grid,
    truth,
)


def _truth_row(i: int, point: GridPoint) -> tuple[RateStateRun, dict[str, Any]]:
    """Build run ``i``: the run, and its parameters and truth (a row without any
    reduction)."""
    run = point.build()
    want = truth(run)
    return run, {
        "index": i, "set": point.set, "shape": run.shape, "label": run.label,
        "noise": run.noise, "noise_colour": run.noise_colour,
        "normal_force_N": run.normal_force_N, "distance_mm": run.distance_mm,
        "duration_s": run.duration_s, "setup_interval": run.setup_interval,
        "rest_s": run.rest_s, "torque_digits": run.torque_digits,
        "nominal_peak_mm": run.nominal_peak_mm, "a": run.a, "b": run.b, "dc_mm": run.dc_mm,
        "k_per_mm": run.k_per_mm, "true_mu_s": want.mu_s, "true_mu_k": want.mu_k,
        "true_peak_mm": want.mu_s_distance_mm, "static": want.static,
        "oscillating": want.oscillating, "oscillation_pp": want.oscillation_pp,
        "settle_mm": want.settle_mm, "truncated": want.truncated,
        "offset_estimable": want.offset_estimable,
    }


def generator_stamp() -> str:
    """SHA-256 of the sources the family is built from (a cache is valid while equal)."""
    root = Path(__file__).resolve().parents[1] / "tests" / "generators"
    digest = hashlib.sha256()
    for name in ("ratestate.py", "instrument.py", "synthetic.py", "truth.py"):
        digest.update((root / name).read_bytes())
    return digest.hexdigest()


def _one(job: tuple[int, GridPoint, str, bool]) -> dict[str, Any]:
    """Build (or, from a cache, reuse), write, read back and reduce one run; compare
    with its truth."""
    from generators.ratestate import write_export
    from tribopipe.config import load_settings
    from tribopipe.errors import TribopipeError
    from tribopipe.readers import read_export
    from tribopipe.reduction.intervals import select_friction_interval
    from tribopipe.reduction.reduce import reduce_measurement

    i, point, folder, keep = job
    started = time.process_time()
    path = Path(folder) / f"run{i}.csv"
    cached = Path(folder) / f"run{i}.json"
    if keep and path.exists() and cached.exists():
        row = json.loads(cached.read_text())
    else:
        run, row = _truth_row(i, point)
        write_export(path, run, language="fr" if i % 2 else "en")
        if keep:
            cached.write_text(json.dumps(row))
    row["build_s"] = time.process_time() - started
    settings = load_settings()
    try:
        got = reduce_measurement(select_friction_interval(read_export(path)),
                                 settings.instrument, settings.reduction)
    except TribopipeError as exc:
        if not keep:
            path.unlink()
        row.update(error=str(exc), flags=[])
        return row
    if not keep:
        path.unlink()
    want_k, want_s = row["true_mu_k"], row["true_mu_s"]
    row.update(
        error=None, mu_s=got.mu_s, mu_k=got.mu_k, flags=list(got.flags),
        mu_s_distance_mm=got.mu_s_distance_mm, mu_k_window_mm=list(got.mu_k_window_mm),
        mu_k_error=got.mu_k - want_k, mu_s_error=got.mu_s - want_s,
        u_mu_k=got.u_mu_k, u_mu_s=got.u_mu_s,
        u_mu_k_plateau=got.parameters.uncertainty.mu_k["reading"],
    )
    return row


def special_sets(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Truncated runs (of the shapes): flagged or refused, else silently right or wrong.
    Runs without a torque zero: flagged, and μ_K within its expanded uncertainty."""
    trunc = [r for r in rows if r["set"] in SHAPES and r["truncated"]]
    unknown = [r for r in rows if r["set"] == "offset_unknown"]
    refused = sum(r["error"] is not None for r in unknown)
    offsets = offset_scores(unknown)
    return {"truncated": truncated_scores(trunc),
            "offset_unknown": {"runs": offsets.pop("runs"), "refused": refused, **offsets}}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="2 draws per grid cell")
    parser.add_argument("--jobs", type=int, default=min(2, os.cpu_count() or 1))
    parser.add_argument("--cache", type=Path, default=None,
                        help="keep the written exports and truths here and reuse them")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    grid = ratestate_grid(limit_per_cell=2 if args.quick else None)
    with tempfile.TemporaryDirectory() as tmp:
        folder = tmp
        if args.cache is not None:
            args.cache.mkdir(parents=True, exist_ok=True)
            stamp = args.cache / "stamp.txt"
            if not stamp.exists() or stamp.read_text().strip() != generator_stamp():
                for old in (*args.cache.glob("run*.csv"), *args.cache.glob("run*.json")):
                    old.unlink()
                stamp.write_text(generator_stamp() + "\n")
            folder = str(args.cache)
        jobs = [(i, point, folder, args.cache is not None) for i, point in enumerate(grid)]
        if args.jobs > 1:
            with ProcessPoolExecutor(args.jobs) as pool:
                rows = list(pool.map(_one, jobs, chunksize=2))
        else:
            rows = [_one(j) for j in jobs]
    elapsed = time.perf_counter() - started
    main_rows = [r for r in rows if r["set"] in SHAPES and not r["truncated"]]
    by_shape = {"all": summarise(main_rows)}
    for shape in SHAPES:
        by_shape[shape] = summarise([r for r in main_rows if r["shape"] == shape])
    by_peak = {f"{p:g} mm": summarise([r for r in main_rows if r["nominal_peak_mm"] == p])
               for p in PEAK_DISTANCES_MM}
    by_noise = {c: summarise([r for r in main_rows if r["noise_colour"] == c])
                for c in NOISE_COLOURS}
    by_duration = {f"{d:g} s": summarise([r for r in main_rows if r["duration_s"] == d])
                   for d in DURATIONS_S}
    by_setup = {
        "set-up interval": summarise([r for r in main_rows if r["setup_interval"]]),
        "rest only": summarise([r for r in main_rows if not r["setup_interval"]]),
    }
    special = special_sets(rows)
    print(f"{len(rows)} runs built, written, read and reduced in {elapsed:.0f} s "
          f"({len(main_rows)} with a plateau in the trace)")
    for title, table in (("by shape", by_shape), ("by peak (creep: 95 % rise)", by_peak),
                         ("by noise colour", by_noise), ("by duration", by_duration),
                         ("by set-up", by_setup)):
        _print_table(title, table)
    print("\nspecial sets:", json.dumps(special, indent=1))
    targets = targets_met(by_shape["all"])
    print("\ntargets:", ", ".join(f"{k} {'met' if v else 'MISSED'}" for k, v in targets.items()))
    out = Path(__file__).with_name("ratestate_quick.json" if args.quick else "ratestate.json")
    out.write_text(json.dumps({
        "elapsed_s": elapsed, "targets": targets, "by_shape": by_shape, "by_peak": by_peak,
        "by_noise": by_noise, "by_duration": by_duration, "by_setup": by_setup,
        "special": special,
        "runs": json_rows(rows),
    }, indent=1) + "\n")
    return 0 if all(targets.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
