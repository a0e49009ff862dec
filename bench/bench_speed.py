"""Friction over sliding speed, end to end, on a stepped-speed campaign the code was not
tuned on.

The campaign (:mod:`generators.speed`, grid and seeds committed before the pipeline first
reduced it): 4 pairs × 2 forces × 3 temperatures × 2 repeats, each test a set-up then
friction intervals at 0.005, 0.015, 0.05 and 0.15 rpm, with a known Arrhenius shift
(Ea = 60 kJ/mol). Every test is written as a RheoCompass export, read and reduced as
``tribopipe reduce`` does (one run per friction interval), and the runs' map records
grouped as the map groups them. Reported:

* μ_K per step against the step's truth; nominal speeds decided; speed flags;
* the groups: n per group, the pooled repeatability s_r (truth: the repeat offsets'
  SD, 0.003) and the groups with range > r;
* ``query`` between measured speeds (geometric middles) against the condition's truth;
* the master curve per pair (Arrhenius and WLF): Ea recovered (target within 15 %);
* predictions at an unmeasured temperature (32.5 °C) by the master curve and, for
  comparison, by ``query``'s linear temperature interpolation.

    nice .venv/bin/python bench/bench_speed.py [--jobs 2]

Writes bench/speed.json. Exit code 1 when Ea misses its target for a pair.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the generators

from generators.speed import (  # noqa: E402
    EA_KJ_MOL,
    PAIRS,
    REPEAT_SD,
    SPEEDS_RPM,
    TEMPERATURES_C,
    UNMEASURED_TEMPERATURE_C,
    SpeedTest,
    mu_k_true,
    pressure_kPa,
    sliding_speed_mm_s,
    speed_grid,
    write_test,
)

EA_TARGET_REL = 0.15


def _reduce(job: tuple[int, SpeedTest, str]) -> dict[str, Any]:
    """Write one test, read and reduce its friction intervals; the records and truths."""
    from tribopipe.config import load_settings
    from tribopipe.labels import RunLabels
    from tribopipe.pipeline import read_runs, reduce_run

    index, test, folder = job
    path = write_test(Path(folder) / f"test{index:02d}.txt", test)
    settings = load_settings()
    export = read_runs(path)
    labels = RunLabels(pin=test.pair.pin, disc=test.pair.disc, normal_force_N=test.force_N,
                       temperature_C=test.temperature_C, repeat=test.repeat)
    steps = []
    for (place, measurement), truth in zip(export.runs, test.steps, strict=False):
        outcome = reduce_run(export, place, measurement, settings, labels)
        steps.append({
            "record": outcome.record,
            "speed_rpm": truth.speed_rpm,
            "true_mu_k": truth.mu_k,
            "mu_k": outcome.result.mu_k,
            "speed_set_point_rpm": outcome.result.speed_set_point_rpm,
            "sliding_speed_mm_s": outcome.result.sliding_speed_mm_s,
            "flags": list(outcome.verdict.flags),
        })
    path.unlink()
    return {"index": index, "n_runs": len(export.runs), "steps": steps}


def _stats(errors: list[float]) -> dict[str, float]:
    a = [abs(e) for e in errors]
    return {"n": len(a), "max_abs": max(a), "rms": math.sqrt(sum(e * e for e in errors) / len(a)),
            "mean": sum(errors) / len(a)}


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", default=str(Path(__file__).with_name("speed.json")))
    args = parser.parse_args()

    from tribopipe import frictionmap as fm
    from tribopipe.mastercurve import master_curve, predict
    from tribopipe.query import groups_of, query
    from tribopipe.stats import repeatability

    tests = speed_grid()
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        jobs = [(i, t, folder) for i, t in enumerate(tests)]
        if args.jobs > 1:
            with ProcessPoolExecutor(args.jobs) as pool:
                done = list(pool.map(_reduce, jobs))
        else:
            done = [_reduce(j) for j in jobs]
    elapsed = time.perf_counter() - started
    report: dict[str, Any] = {"campaign": {
        "tests": len(tests), "speeds_rpm": list(SPEEDS_RPM), "temperatures_C": list(TEMPERATURES_C),
        "Ea_true_kJ_mol": EA_KJ_MOL, "repeat_sd_true": REPEAT_SD,
        "runs_found": sum(d["n_runs"] for d in done), "reduce_seconds": round(elapsed, 1)}}

    # ---- per step
    by_speed: dict[float, list[float]] = {}
    records = []
    speed_err = []
    nominal: dict[float, set[float]] = {}
    flagged_speed = 0
    for d in done:
        for s in d["steps"]:
            by_speed.setdefault(s["speed_rpm"], []).append(s["mu_k"] - s["true_mu_k"])
            speed_err.append(s["sliding_speed_mm_s"] / sliding_speed_mm_s(s["speed_rpm"]) - 1)
            nominal.setdefault(s["speed_rpm"], set()).add(s["record"].nominal_speed_mm_s)
            flagged_speed += "sliding_speed_off_nominal" in s["flags"]
            records.append(s["record"])
    report["per_step"] = {
        "mu_k_minus_truth": {f"{k:g} rpm": _stats(v) for k, v in sorted(by_speed.items())},
        "all": _stats([e for v in by_speed.values() for e in v]),
        "measured_speed_rel_error": _stats(speed_err),
        "nominal_speeds_mm_s": {f"{k:g} rpm": sorted(v) for k, v in sorted(nominal.items())},
        "runs_flagged_speed_off_nominal": flagged_speed,
    }

    # ---- groups
    runs = fm.records_frame(records)
    groups = groups_of(runs, "bench")
    rep = repeatability(groups)
    report["groups"] = {
        "n_groups": len(groups),
        "n_per_group": sorted(set(int(n) for n in groups["mu_k_n"])),
        "s_r": rep.s_r, "r": rep.r,
        "groups_range_exceeds_r": int(groups["range_exceeds_r"].sum()),
        "s_r_true_repeat_offsets": REPEAT_SD,
    }

    # ---- query between speeds
    speeds = sorted({float(v) for v in groups["nominal_speed_mm_s"]})
    between = []
    at_measured = []
    for pair in PAIRS:
        sel = groups[(groups["pin"] == pair.pin) & (groups["disc"] == pair.disc)]
        for force in sorted({float(f) for f in sel["normal_force_N"]}):
            p = float(sel.loc[sel["normal_force_N"] == force, "pressure_kPa"].iloc[0])
            for t in TEMPERATURES_C:
                for v in speeds:
                    res = query(groups, pair.pin, pair.disc, p, t, v)
                    at_measured.append(res.mu_k.value - mu_k_true(pair, force, t, v))
                for lo, hi in zip(speeds, speeds[1:], strict=False):
                    v = math.sqrt(lo * hi)
                    res = query(groups, pair.pin, pair.disc, p, t, v)
                    truth = mu_k_true(pair, force, t, v)
                    between.append({"pair": f"{pair.pin} on {pair.disc}", "force_N": force,
                                    "temperature_C": t, "speed_mm_s": v,
                                    "query": res.mu_k.value, "U": res.mu_k.expanded,
                                    "truth": truth, "error": res.mu_k.value - truth,
                                    "within_U": res.mu_k.expanded is not None and
                                    abs(res.mu_k.value - truth) <= res.mu_k.expanded})
    report["query"] = {
        "at_measured_speeds_minus_truth": _stats(at_measured),
        "between_speeds_minus_truth": _stats([b["error"] for b in between]),
        "between_speeds_within_U": sum(b["within_U"] for b in between),
        "between_speeds_n": len(between),
        "between": between,
    }

    # ---- master curves
    curves = {}
    ea_ok = True
    for pair in PAIRS:
        label = f"{pair.pin} on {pair.disc}"
        arr = master_curve(groups, pair.pin, pair.disc, shift="arrhenius")
        wlf = master_curve(groups, pair.pin, pair.disc, shift="wlf")
        ea = arr.parameters["Ea_kJ_mol"]
        rel = ea / EA_KJ_MOL - 1
        ea_ok &= abs(rel) <= EA_TARGET_REL
        predictions = []
        forces = sorted({float(f) for f in runs.loc[runs["pin"] == pair.pin, "normal_force_N"]})
        for force in forces:
            p = pressure_kPa(force)
            p_group = float(groups.loc[(groups["pin"] == pair.pin) & (groups["disc"] == pair.disc)
                                       & (groups["normal_force_N"] == force),
                                       "pressure_kPa"].iloc[0])
            for v in speeds + [math.sqrt(a * b) for a, b in zip(speeds, speeds[1:], strict=False)]:
                truth = mu_k_true(pair, force, UNMEASURED_TEMPERATURE_C, v)
                try:
                    model = predict(arr, p_group, UNMEASURED_TEMPERATURE_C, v).mu_k
                except Exception as exc:  # noqa: BLE001 - a refusal is a result here
                    model = None
                    refused = str(exc)
                else:
                    refused = None
                linear = query(groups, pair.pin, pair.disc, p_group, UNMEASURED_TEMPERATURE_C,
                               v).mu_k.value
                predictions.append({
                    "force_N": force, "pressure_kPa": p, "speed_mm_s": v, "truth": truth,
                    "master_curve": model, "refused": refused,
                    "master_curve_error": None if model is None else model - truth,
                    "query_linear_T": linear, "query_linear_T_error": linear - truth})
        model_errors = [q["master_curve_error"] for q in predictions
                        if q["master_curve_error"] is not None]
        curves[label] = {
            "arrhenius": {"Ea_kJ_mol": ea, "u_Ea_kJ_mol": arr.uncertainties.get("Ea_kJ_mol"),
                          "Ea_rel_error": rel, "residual_sd": arr.residual_sd,
                          "log10_aT": {f"{t:g}": v for t, v in arr.log10_aT.items()}},
            "wlf": {"C1": wlf.parameters["C1"], "C2_K": wlf.parameters["C2_K"],
                    "residual_sd": wlf.residual_sd,
                    "log10_aT": {f"{t:g}": v for t, v in wlf.log10_aT.items()}},
            "true_log10_aT": {f"{t:g}": arr_true for t, arr_true in (
                (t, _true_shift(t, arr.reference_temperature_C)) for t in TEMPERATURES_C)},
            "unmeasured_temperature_C": UNMEASURED_TEMPERATURE_C,
            "master_curve_prediction_error": _stats(model_errors) if model_errors else None,
            "query_linear_T_error": _stats([q["query_linear_T_error"] for q in predictions]),
            "refused": sum(q["refused"] is not None for q in predictions),
            "predictions": predictions,
        }
    report["master_curve"] = curves
    report["Ea_target"] = {"rel": EA_TARGET_REL, "met": bool(ea_ok)}
    Path(args.out).write_text(json.dumps(report, indent=1, allow_nan=False) + "\n",
                              encoding="utf-8")
    print(json.dumps({k: report[k] for k in ("campaign", "groups")}, indent=1))
    print("per step:", json.dumps(report["per_step"], indent=1))
    print("query:", {k: v for k, v in report["query"].items() if k != "between"})
    for label, c in curves.items():
        print(label, "Ea", round(c["arrhenius"]["Ea_kJ_mol"], 2), "±",
              c["arrhenius"]["u_Ea_kJ_mol"], "rel", round(c["arrhenius"]["Ea_rel_error"], 3),
              "| mc err", c["master_curve_prediction_error"], "| linT err",
              c["query_linear_T_error"], "| refused", c["refused"])
    return 0 if ea_ok else 1


def _true_shift(temperature_C: float, reference_C: float) -> float:
    from generators.speed import log10_shift

    return log10_shift(temperature_C, reference_C=reference_C)


if __name__ == "__main__":
    sys.exit(main())
