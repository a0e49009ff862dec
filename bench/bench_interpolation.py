"""Leave-one-out of the interpolation rule on the founding paper's published map.

Every interior pressure group of every pair and temperature (42 cases) is held out and
predicted from its two neighbours at the same temperature, by linear interpolation in p
(tribopipe's rule before) and in log p – log μ (:mod:`tribopipe.interpolation`, the rule
now); mean and max |error| per method, and how the interpolation's own uncertainty
u_interp compares with the errors it is meant to describe. Targets: mean |error| ≤ 0.015,
max ≤ 0.05 (``tests/test_interpolation.py`` asserts them from the same function).

    PYTHONPATH=src .venv/bin/python bench/bench_interpolation.py   # table; bench/interpolation.json
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

from tribopipe.frictionmap.published import import_records, published_csv_path
from tribopipe.frictionmap.schema import records_frame
from tribopipe.interpolation import LOO_METHODS, HeldOut, leave_one_out
from tribopipe.query import map_curvature
from tribopipe.stats import group_statistics

OUT = Path(__file__).with_name("interpolation.json")


def published_series() -> tuple[list[tuple[str, list[float], list[float]]], float]:
    """The published map's μ_K group means per pair and temperature (pressure order), and
    the map's κ as :func:`tribopipe.query.query` uses it."""
    groups = group_statistics(records_frame(import_records(published_csv_path())))
    series = []
    for (pin, disc, t), g in groups.groupby(["pin", "disc", "temperature_C"], sort=True):
        g = g.sort_values("pressure_kPa")
        series.append((f"{pin} on {disc}, {t:g} °C", g["pressure_kPa"].tolist(),
                       g["mu_k_mean"].tolist()))
    return series, map_curvature(groups, "mu_k")


def summary(cases: list[HeldOut]) -> dict[str, Any]:
    """Mean, max and RMS |error| per method, and the calibration of u_interp."""
    out: dict[str, Any] = {"cases": len(cases), "methods": {}}
    for method in LOO_METHODS:
        errors = [abs(c.predicted[method] - c.measured) for c in cases]
        out["methods"][method] = {
            "mean_abs_error": sum(errors) / len(errors),
            "max_abs_error": max(errors),
            "rms_error": math.sqrt(sum(e * e for e in errors) / len(errors)),
        }
    rule = LOO_METHODS[1]
    z = [(c.predicted[rule] - c.measured) / c.u_interpolation for c in cases
         if c.u_interpolation > 0]
    out["u_interpolation"] = {
        "rms_of_error_over_u": math.sqrt(sum(v * v for v in z) / len(z)),
        "share_within_2u": sum(abs(v) <= 2 for v in z) / len(z),
        "mean_u": sum(c.u_interpolation for c in cases) / len(cases),
    }
    return out


def main() -> int:
    series, kappa = published_series()
    cases = leave_one_out(series, kappa)
    result = summary(cases)
    result["kappa"] = kappa
    print(f"leave-one-out on the published map: {result['cases']} cases, κ = {kappa:.4f}")
    print(f"{'method':<18}{'mean |error|':>14}{'max |error|':>13}{'RMS':>8}")
    for method, m in result["methods"].items():
        print(f"{method:<18}{m['mean_abs_error']:>14.4f}{m['max_abs_error']:>13.4f}"
              f"{m['rms_error']:>8.4f}")
    u = result["u_interpolation"]
    print(f"u_interp: RMS(error/u) = {u['rms_of_error_over_u']:.2f}, "
          f"{100 * u['share_within_2u']:.0f} % of errors within 2·u_interp")
    OUT.write_text(json.dumps(result, indent=2) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
