"""The rheometer's results before and after a change of the reduction: identical values.

Writes the exports of three rheometer families once into a cache folder (the example
campaign ``raw/example``, the development family of ``bench_accuracy.py`` at one seed,
the validation family of ``bench_validation.py`` at 2 draws per cell), reduces every
friction interval of every export with the default T-PID/44 settings and writes every
number the reduction reports (μ_S, μ_K, their uncertainties, windows, flags, the torque
offset) to a JSON file. Two such files, one from the code before a change and one from
after, are compared with ``--compare BEFORE AFTER``: the exit code is 1 when any value
differs.

    nice .venv/bin/python bench/rheometer_unchanged.py --cache /tmp/rheo --out before.json
    nice .venv/bin/python bench/rheometer_unchanged.py --cache /tmp/rheo --out after.json
    .venv/bin/python bench/rheometer_unchanged.py --compare before.json after.json
"""

from __future__ import annotations

import argparse
import itertools
import json
import shutil
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the generators

ROOT = Path(__file__).resolve().parents[1]


def write_families(cache: Path) -> list[Path]:
    """The exports of the three families in ``cache`` (written once; sorted paths)."""
    done = cache / ".complete"
    if not done.exists():
        from generators.contact import validation_grid, write_export
        from generators.synthetic import SyntheticRun, write_rheocompass_export

        cache.mkdir(parents=True, exist_ok=True)
        for src in sorted((ROOT / "raw" / "example").glob("*.csv")):
            shutil.copy(src, cache / f"example_{src.name}")
        shapes = ("overshoot", "no_overshoot", "stick_slip", "drift", "cliff")
        grid = itertools.product(shapes, (0.003, 0.008, 0.015),
                                 ((0.33, 0.25), (0.80, 0.55), (1.40, 1.08)),
                                 (0.0, 5e-4), (True, False), (1.0, 9.0))
        for i, (shape, noise, (mu_s, mu_k), offset, setup, force) in enumerate(grid):
            run = SyntheticRun(mu_s=mu_s, mu_k=mu_k, shape=shape, noise=noise,
                               torque_offset_Nm=offset, setup_interval=setup,
                               normal_force_N=force, seed=i)
            write_rheocompass_export(cache / f"accuracy_{i:04d}.csv", run, project="a",
                                     test=shape, sample="pin",
                                     language="fr" if i % 2 else "en")
        for i, point in enumerate(validation_grid(limit_per_cell=2)):
            write_export(cache / f"validation_{i:04d}.csv", point.build(),
                         language="fr" if i % 2 else "en")
        done.write_text("ok\n")
    return sorted(p for p in cache.glob("*.csv"))


def reduce_all(paths: list[Path]) -> dict[str, Any]:
    """Every number of every run's reduction, by file name and interval."""
    from tribopipe.config import load_settings
    from tribopipe.errors import TribopipeError
    from tribopipe.readers import read_export
    from tribopipe.reduction.intervals import all_friction_intervals
    from tribopipe.reduction.reduce import reduce_measurement

    settings = load_settings()
    out: dict[str, Any] = {}
    for path in paths:
        try:
            intervals = all_friction_intervals(read_export(path))
        except TribopipeError as exc:
            out[path.name] = {"error": str(exc)}
            continue
        for k, m in enumerate(intervals):
            key = f"{path.name}#{k}"
            try:
                r = reduce_measurement(m, settings.instrument, settings.reduction)
            except TribopipeError as exc:
                out[key] = {"error": str(exc)}
                continue
            out[key] = {
                "mu_s": r.mu_s, "mu_k": r.mu_k, "u_mu_s": r.u_mu_s, "u_mu_k": r.u_mu_k,
                "mu_s_distance_mm": r.mu_s_distance_mm,
                "mu_k_window_mm": list(r.mu_k_window_mm), "plateau_std": r.plateau_std,
                "flags": list(r.flags), "normal_force_mean_N": r.normal_force_mean_N,
                "sliding_distance_mm": r.sliding_distance_mm,
                # a typed record since the typed parameters, a dict before
                "offset": (r.parameters.get("torque_offset_Nm")
                           if isinstance(r.parameters, dict)
                           else r.parameters.torque_offset_Nm),
            }
    return out


def compare(before: dict[str, Any], after: dict[str, Any]) -> list[str]:
    """One line per run whose values differ (or that is in one file only)."""
    lines = []
    for key in sorted(set(before) | set(after)):
        a, b = before.get(key), after.get(key)
        if a != b:
            lines.append(f"{key}: {a} -> {b}")
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cache", type=Path, default=Path("bench/out/rheometer"))
    parser.add_argument("--out", type=Path)
    parser.add_argument("--compare", nargs=2, type=Path)
    args = parser.parse_args(argv)
    if args.compare:
        before, after = (json.loads(p.read_text()) for p in args.compare)
        lines = compare(before, after)
        print("\n".join(lines) if lines else f"identical: {len(before)} runs")
        return 1 if lines else 0
    results = reduce_all(write_families(args.cache))
    args.out.write_text(json.dumps(results, indent=1, sort_keys=True) + "\n")
    print(f"{len(results)} runs -> {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
