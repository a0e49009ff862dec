"""Accuracy of the force-based reductions on the force-rig families (unseen).

Writes every run of :func:`generators.forcerigs.forcerig_grid` as its instrument's
software would (sled: Bluehill and testXpert layouts; reciprocating: TAB with a header
block; rotary: CSV in ms, rev and gf), reads it back with ``read_export``, reduces it with
the instrument file beside ``t-pid44.toml`` (the rotary runs with their own track radius
and speed, as a lab sets them) and compares with the run's truth. Table on stdout, every
run in ``bench/forcerigs.json``.

    nice .venv/bin/python bench/bench_forcerigs.py
"""

from __future__ import annotations

import json
import statistics
import sys
import tempfile
from dataclasses import replace
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the generators

from generators.forcerigs import ForceGridPoint, forcerig_grid  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
CONFIG = {"sled": "sled-d1894.toml", "reciprocating": "linear-reciprocating.toml",
          "rotary": "rotary-pin-on-disc.toml"}


def reduce_point(point: ForceGridPoint, folder: Path) -> dict[str, Any]:
    """Write, read and reduce one run; its errors against the truth."""
    from tribopipe.config import load_settings
    from tribopipe.errors import TribopipeError
    from tribopipe.readers import read_export
    from tribopipe.reduction.intervals import select_friction_interval
    from tribopipe.reduction.reduce import reduce_measurement

    settings = load_settings(ROOT / "configs" / "instruments" / CONFIG[point.family])
    instrument = settings.instrument
    if point.family == "rotary":
        instrument = replace(instrument, friction_radius_mm=point.run.radius_mm,
                             nominal_speed_rpm=point.run.rpm)
    truth = point.truth()
    path = point.write(folder / f"run{point.index}.csv")
    row: dict[str, Any] = {"index": point.index, "family": point.family, "set": point.set,
                           "true_mu_k": truth.mu_k, "true_mu_s": truth.mu_s,
                           "stick_slip": truth.stick_slip, "run_out": truth.run_out,
                           "preloaded": truth.preloaded}
    try:
        got = reduce_measurement(select_friction_interval(read_export(path)), instrument,
                                 settings.reduction)
    except TribopipeError as exc:
        row.update(error=str(exc))
        return row
    flags = set(got.flags)
    row.update(
        error=None, mu_k=got.mu_k, mu_s=got.mu_s, flags=sorted(flags),
        mu_k_error=got.mu_k - truth.mu_k, u_mu_k=got.u_mu_k,
        mu_s_error=(got.mu_s - truth.mu_s) if truth.mu_s is not None
        and "static_not_distinct" not in flags else None,
        stick_slip_ok=("stick_slip" in flags) == truth.stick_slip,
        # where a saw-tooth rides on the run-out the flag names the stick-slip only
        run_out_ok=(("run_out" in flags) == truth.run_out) if not truth.stick_slip
        else "run_out" not in flags,
        zero_ok=("zero_under_load" in flags) == truth.preloaded,
    )
    return row


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    ok = [r for r in rows if r["error"] is None]
    k = [abs(r["mu_k_error"]) for r in ok]
    s = [abs(r["mu_s_error"]) for r in ok if r["mu_s_error"] is not None]
    within = [abs(r["mu_k_error"]) <= max(0.01, 2 * r["u_mu_k"]) for r in ok]
    return {
        "runs": len(rows), "errors": len(rows) - len(ok),
        "mu_k_median_abs": statistics.median(k) if k else None,
        "mu_k_worst_abs": max(k) if k else None,
        "mu_k_within_0.01_or_U": sum(within),
        "mu_s_runs": len(s), "mu_s_worst_abs": max(s) if s else None,
        "stick_slip_ok": sum(r["stick_slip_ok"] for r in ok),
        "run_out_ok": sum(r["run_out_ok"] for r in ok),
        "zero_ok": sum(r["zero_ok"] for r in ok),
    }


def main() -> int:
    grid = forcerig_grid()
    with tempfile.TemporaryDirectory() as tmp:
        rows = [reduce_point(p, Path(tmp)) for p in grid]
    sets = sorted({r["set"] for r in rows}, key=[p.set for p in grid].index)
    summary = {name: summarise([r for r in rows if r["set"] == name]) for name in sets}
    summary["all"] = summarise(rows)
    head = (f"{'set':<30}{'runs':>5}{'err':>5}{'med|Δμ_K|':>11}{'max|Δμ_K|':>11}"
            f"{'≤max(.01,U)':>12}{'max|Δμ_S|':>11}{'s-s ok':>8}{'r-o ok':>8}{'zero ok':>8}")
    print(head)
    for name, s in summary.items():
        def f(v: float | None) -> str:
            return "–" if v is None else f"{v:.4f}"
        print(f"{name:<30}{s['runs']:>5}{s['errors']:>5}{f(s['mu_k_median_abs']):>11}"
              f"{f(s['mu_k_worst_abs']):>11}{s['mu_k_within_0.01_or_U']:>12}"
              f"{f(s['mu_s_worst_abs']):>11}{s['stick_slip_ok']:>8}{s['run_out_ok']:>8}"
              f"{s['zero_ok']:>8}")
    for r in rows:
        if r["error"]:
            print(f"run {r['index']} ({r['set']}): {r['error']}")
    out = Path(__file__).with_name("forcerigs.json")
    out.write_text(json.dumps({"summary": summary, "runs": rows}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
