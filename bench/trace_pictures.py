"""Sample trace plots: seeded synthetic runs drawn by ``pipeline.plot_run`` as the batch
draws them, to look at before and after a change to the per-run plot.

    .venv/bin/python bench/trace_pictures.py --prefix after   # docs/img/trace_after_*.png

The runs (seeded, 10 Hz RheoCompass exports written by the project's synthetic writer): a
10,000-row run with a static overshoot; a 12,000-row stick-slip run whose normal force
wobbles by ±15 % (flagged); a 6,000-row run without a distinct static peak (flagged); a
2,380-row run whose plateau the trace cuts short (flagged, and marked on the plot where
the reduction raises the boundary flags). Labels name the conditions the header shows
(pin, disc, nominal force, temperature, repeat).
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the generators

HERE = Path(__file__).resolve().parent
IMG = HERE.parent / "docs" / "img"

RUNS = {
    "overshoot": dict(mu_s=0.92, mu_k=0.61, shape="overshoot", duration_s=1000.0,
                      noise=0.006, normal_force_N=3.0, seed=21),
    "stick_slip": dict(mu_s=0.70, mu_k=0.48, shape="stick_slip", duration_s=1200.0,
                       noise=0.008, normal_force_N=5.0, normal_force_wobble=0.15, seed=22),
    "no_overshoot": dict(mu_k=0.41, shape="no_overshoot", duration_s=600.0, noise=0.004,
                         normal_force_N=1.0, seed=23),
    # a peak at 1 mm and the trace ending 0.65 mm after it: the plateau is cut short
    "short_plateau": dict(mu_s=0.8, mu_k=0.55, peak_distance_mm=1.0, duration_s=238.0,
                          normal_force_N=3.0, seed=6),
}


def main(argv: list[str] | None = None) -> list[Path]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--prefix", default="after", help="file name prefix (after)")
    parser.add_argument("--out", type=Path, default=IMG)
    args = parser.parse_args(argv)

    from generators.synthetic import SyntheticRun, write_rheocompass_export
    from tribopipe.config import load_settings
    from tribopipe.labels import RunLabels
    from tribopipe.pipeline import plot_run, reduce_file

    settings = load_settings()
    args.out.mkdir(parents=True, exist_ok=True)
    written = []
    with tempfile.TemporaryDirectory() as tmp:
        for i, (name, kwargs) in enumerate(RUNS.items(), start=1):
            raw = write_rheocompass_export(Path(tmp) / f"DS30_steel_{name}_r{i}.csv",
                                           SyntheticRun(**kwargs), project="pictures",
                                           test=name, sample="DS30")
            labels = RunLabels("Dragonskin 30", "steel", kwargs["normal_force_N"], 20.0, i)
            outcome = reduce_file(raw, settings, labels)
            png = plot_run(Path(tmp) / "out", outcome)
            target = args.out / f"trace_{args.prefix}_{name}.png"
            shutil.copyfile(png, target)
            written.append(target)
            print(f"{target}  flags: {';'.join(outcome.result.flags) or '-'}")
    return written


if __name__ == "__main__":
    main()
