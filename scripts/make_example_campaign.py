"""Write the shipped example campaign ``raw/example/`` (synthetic, seeded, deterministic).

2 pins × 2 discs × 3 normal forces × 2 temperatures × 2 repeats = 48 RheoCompass exports
(UTF-16 LE + BOM, TAB, CRLF; a set-up interval then the friction interval, 180 s at
10 Hz), a manifest, and a README that says the data are synthetic and lists the COF values
they were generated from.

The kinetic COF μ_K of each run is the founding paper's published value for that pin,
disc, force, temperature and repeat (Berthold et al., RebeccaBerthold/FrictionMap) where
the published map has it; the conditions it lacks get a stated, assumed value (marked so in
the README). μ_S = MU_S_FACTOR · μ_K. One run is written in French (decimal comma) and one
with a measured normal force 15 % above its nominal value, to show the reader and the
campaign's QC flag at work.

    python scripts/make_example_campaign.py [--out raw/example]
"""

from __future__ import annotations

import argparse
import csv
import io
import itertools
import sys
from dataclasses import dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the generators

from generators.synthetic import SyntheticRun, write_rheocompass_export

REPO = Path(__file__).resolve().parents[1]
MU_S_FACTOR = 1.3
DURATION_S = 180.0
NOISE = 0.006
BASE_SEED = 20240501

PINS = {"DS30": "Dragonskin 30", "EF50": "Ecoflex 00-50"}
DISCS = {"steel": "steel", "acrylic": "acrylic glass"}
FORCES_N = (1.0, 5.0, 9.0)
TEMPERATURES_C = (10.0, 20.0)
REPEATS = (1, 2)
FRENCH_RUN = "EF50_acrylic_9N_20C_r2"
OFF_NOMINAL_RUN = ("EF50_steel_1N_20C_r2", 1.15)  # (run, measured total normal force [N])

PUBLISHED = "published"
ASSUMED = "assumed"

#: μ_K per (pin, disc, force [N], temperature [°C]) for repeats 1 and 2, and where it comes
#: from. "published": the published map's per-repeat values; "assumed": not in the
#: published map, set by us following its trends (lower at 10 °C, falling with pressure).
MU_K: dict[tuple[str, str, float, float], tuple[tuple[float, float], str]] = {
    ("DS30", "acrylic", 1.0, 10.0): ((0.57, 0.57), PUBLISHED),
    ("DS30", "acrylic", 5.0, 10.0): ((0.32, 0.34), PUBLISHED),
    ("DS30", "acrylic", 9.0, 10.0): ((0.25, 0.26), PUBLISHED),
    ("DS30", "acrylic", 1.0, 20.0): ((1.07, 1.08), PUBLISHED),
    ("DS30", "acrylic", 5.0, 20.0): ((0.45, 0.53), PUBLISHED),
    ("DS30", "acrylic", 9.0, 20.0): ((0.40, 0.33), PUBLISHED),
    ("DS30", "steel", 1.0, 10.0): ((0.55, 0.57), ASSUMED),
    ("DS30", "steel", 5.0, 10.0): ((0.31, 0.31), PUBLISHED),
    ("DS30", "steel", 9.0, 10.0): ((0.26, 0.25), PUBLISHED),
    ("DS30", "steel", 1.0, 20.0): ((0.63, 0.63), PUBLISHED),
    ("DS30", "steel", 5.0, 20.0): ((0.36, 0.36), PUBLISHED),
    ("DS30", "steel", 9.0, 20.0): ((0.26, 0.26), PUBLISHED),
    ("EF50", "acrylic", 1.0, 10.0): ((0.95, 0.97), ASSUMED),
    ("EF50", "acrylic", 5.0, 10.0): ((0.42, 0.44), ASSUMED),
    ("EF50", "acrylic", 9.0, 10.0): ((0.31, 0.30), ASSUMED),
    ("EF50", "acrylic", 1.0, 20.0): ((1.15, 1.12), ASSUMED),
    ("EF50", "acrylic", 5.0, 20.0): ((0.55, 0.52), ASSUMED),
    ("EF50", "acrylic", 9.0, 20.0): ((0.41, 0.43), ASSUMED),
    ("EF50", "steel", 1.0, 10.0): ((0.93, 0.89), PUBLISHED),
    ("EF50", "steel", 5.0, 10.0): ((0.36, 0.36), PUBLISHED),
    ("EF50", "steel", 9.0, 10.0): ((0.28, 0.28), PUBLISHED),
    ("EF50", "steel", 1.0, 20.0): ((1.00, 1.02), ASSUMED),
    ("EF50", "steel", 5.0, 20.0): ((0.42, 0.40), ASSUMED),
    ("EF50", "steel", 9.0, 20.0): ((0.31, 0.32), ASSUMED),
}


@dataclass(frozen=True)
class ExampleRun:
    """One file of the example: its name, labels, truth and how it is written."""

    stem: str
    pin: str
    disc: str
    force_N: float
    temperature_C: float
    repeat: int
    mu_k: float
    mu_s: float
    source: str
    measured_force_N: float
    language: str
    seed: int


def example_runs() -> list[ExampleRun]:
    """The 48 runs of the example, in file-name order."""
    runs = []
    grid = itertools.product(PINS, DISCS, FORCES_N, TEMPERATURES_C, REPEATS)
    for index, (pin, disc, force, temperature, repeat) in enumerate(grid):
        values, source = MU_K[(pin, disc, force, temperature)]
        stem = f"{pin}_{disc}_{force:g}N_{temperature:g}C_r{repeat}"
        mu_k = values[repeat - 1]
        measured = OFF_NOMINAL_RUN[1] if stem == OFF_NOMINAL_RUN[0] else force
        runs.append(ExampleRun(
            stem=stem, pin=pin, disc=disc, force_N=force, temperature_C=temperature,
            repeat=repeat, mu_k=mu_k, mu_s=round(MU_S_FACTOR * mu_k, 4), source=source,
            measured_force_N=measured, language="fr" if stem == FRENCH_RUN else "en",
            seed=BASE_SEED + index,
        ))
    return sorted(runs, key=lambda r: r.stem)


def write_run(folder: Path, run: ExampleRun) -> Path:
    """Write one run as a RheoCompass export ``<folder>/<stem>.csv``."""
    synthetic = SyntheticRun(
        mu_s=run.mu_s, mu_k=run.mu_k, shape="overshoot", noise=NOISE,
        setup_interval=True, normal_force_N=run.measured_force_N,
        temperature_C=run.temperature_C, duration_s=DURATION_S, seed=run.seed,
    )
    return write_rheocompass_export(
        folder / f"{run.stem}.csv", synthetic, project="tribopipe example campaign",
        test=f"{PINS[run.pin]} on {DISCS[run.disc]} {run.force_N:g} N "
             f"{run.temperature_C:g} C r{run.repeat}",
        sample=PINS[run.pin], language=run.language,
    )


def manifest_text(runs: list[ExampleRun]) -> str:
    """The manifest CSV (full material names; ``language`` and ``mu_k_true`` are extra)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(["file", "pin", "disc", "normal_force_N", "temperature_C", "repeat",
                     "language", "mu_k_true", "mu_s_true"])
    for r in runs:
        writer.writerow([f"{r.stem}.csv", PINS[r.pin], DISCS[r.disc], f"{r.force_N:g}",
                         f"{r.temperature_C:g}", r.repeat, r.language, f"{r.mu_k:g}",
                         f"{r.mu_s:g}"])
    return buf.getvalue()


def readme_text(runs: list[ExampleRun]) -> str:
    """``raw/example/README.md``: what the files are, and the values behind them."""
    lines = [
        "# Example campaign — SYNTHETIC data",
        "",
        "**These files are synthetic.** They were written by "
        "`scripts/make_example_campaign.py` (seeded, deterministic) with "
        "the test generators (`tests/generators/synthetic.py`), not measured on a rheometer. "
        "They imitate the layout of a",
        "real Anton Paar RheoCompass export (UTF-16 LE with BOM, TAB-separated, CRLF; a "
        "normal-force set-up interval followed by the friction interval, "
        f"{DURATION_S:g} s at 10 Hz, torque in mN·m) and a realistic friction trace "
        f"(static overshoot, kinetic plateau, torque noise of σ = {NOISE:g} in COF units; "
        f"seeds {BASE_SEED}…{BASE_SEED + len(runs) - 1}).",
        "",
        "- 2 pins × 2 discs × 3 normal forces × 2 temperatures × 2 repeats = "
        f"{len(runs)} runs; file names follow `{{pin}}_{{disc}}_{{force}}N_{{temperature}}C_"
        "r{repeat}` with short material names (DS30 = Dragonskin 30, EF50 = Ecoflex 00-50, "
        "acrylic = acrylic glass; see `[names]` in `configs/example.toml`).",
        "- `manifest.csv` gives the same metadata with full names, plus the true values.",
        f"- μ_S = {MU_S_FACTOR} × μ_K for every run (a stated factor, not a measurement).",
        f"- `{FRENCH_RUN}.csv` is written in French (labels, decimal comma).",
        f"- `{OFF_NOMINAL_RUN[0]}.csv` was written with a measured normal force of "
        f"{OFF_NOMINAL_RUN[1]:g} N although its nominal force is 1 N: the campaign flags it "
        "`normal_force_off_nominal`.",
        "",
        "μ_K values: **published** = the per-repeat values of the founding paper's published "
        "friction map (Berthold et al., *Investigating frictional contact behavior for soft "
        "material robot simulations*; github.com/RebeccaBerthold/FrictionMap); "
        "**assumed** = a condition the published map does not contain, set by us following "
        "its trends. Do not cite the assumed values.",
        "",
        "| file | pin | disc | F_N [N] | T [°C] | repeat | μ_K | μ_S | μ_K source |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in runs:
        lines.append(
            f"| {r.stem}.csv | {PINS[r.pin]} | {DISCS[r.disc]} | {r.force_N:g} | "
            f"{r.temperature_C:g} | {r.repeat} | {r.mu_k:.2f} | {r.mu_s:.3f} | {r.source} |"
        )
    lines += ["", "Regenerate with `make example` (or `python scripts/make_example_campaign.py`).",
              ""]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    """Write the example campaign into ``--out`` (default ``raw/example``)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=REPO / "raw" / "example")
    args = parser.parse_args(argv)
    folder: Path = args.out
    folder.mkdir(parents=True, exist_ok=True)
    runs = example_runs()
    total = 0
    for run in runs:
        total += write_run(folder, run).stat().st_size
    (folder / "manifest.csv").write_text(manifest_text(runs), encoding="utf-8")
    (folder / "README.md").write_text(readme_text(runs), encoding="utf-8")
    print(f"wrote {len(runs)} exports ({total / 1e6:.1f} MB), manifest.csv and README.md "
          f"to {folder}")


if __name__ == "__main__":
    main()
