"""Two labs meet at one condition: the figures of docs/map.md ("Two labs, one map").

    python scripts/two_labs.py [FOLDER]

Reduces three seeded synthetic exports of a second lab (Dragonskin 30 on steel, 3 N
= 35.37 kPa, 20 °C; μ_K 0.440, 0.451, 0.462 as generated) with `tribopipe batch`,
publishes them as the package of "Second Lab", publishes the founding paper's map as a
package, merges both packages into a new map, and prints μ_K ± U at that condition for
each lab alone and for the merged map, then `tribopipe map compare`. Every step is the
real command line; FOLDER (default: a temporary folder) keeps what it wrote.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the generators

from click.testing import CliRunner

from generators.synthetic import SyntheticRun, write_rheocompass_export
from tribopipe import frictionmap as fm
from tribopipe.cli import main
from tribopipe.rounding import plus_minus
from tribopipe.stats import group_statistics

PATTERN = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"
SECOND_LAB_MU_K = (0.440, 0.451, 0.462)


def run(*args: str) -> str:
    """One tribopipe command; its output, or exit with it when it fails."""
    result = CliRunner().invoke(main, list(args))
    if result.exit_code != 0:
        sys.exit(f"tribopipe {' '.join(args)} failed:\n{result.output}")
    return result.output


def condition(map_path: Path) -> str:
    """μ_K ± U (k = 2) of Dragonskin 30 on steel at 35.37 kPa, 20 °C, with n and labs."""
    groups = group_statistics(fm.read_map(map_path))
    g = groups[(groups.pin == "Dragonskin 30") & (groups.disc == "steel")
               & (groups.pressure_kPa.round(2) == 35.37)
               & (groups.temperature_C == 20.0)].iloc[0]
    estimated = "; runs without a budget carry the stated u" if g["mu_k_u_estimated"] else ""
    return (f"{plus_minus(g['mu_k_mean'], 2 * g['mu_k_u'])} (n = {g['mu_k_n']}, "
            f"labs: {g['labs'].replace(';', ', ')}{estimated})")


def main_(folder: Path) -> None:
    raw = folder / "second-lab" / "raw"
    raw.mkdir(parents=True, exist_ok=True)
    for repeat, mu_k in enumerate(SECOND_LAB_MU_K, start=1):
        generated = SyntheticRun(mu_s=1.3 * mu_k, mu_k=mu_k, normal_force_N=3.0,
                                 temperature_C=20.0, duration_s=150.0, noise=0.004,
                                 seed=40 + repeat)
        write_rheocompass_export(raw / f"DS30_steel_3N_20C_r{repeat}.csv", generated,
                                 project="second lab", test="friction", sample="DS30")
    second_map = folder / "second-lab" / "friction_map.parquet"
    run("batch", str(raw), "--pattern", PATTERN, "-o", str(second_map.parent),
        "--no-plots", "--jobs", "1")
    run("map", "publish", str(folder / "second-lab-package"), "--map", str(second_map),
        "--lab", "Second Lab", "--contact", "A. Person", "--overwrite")

    founding_map = folder / "founding" / "friction_map.parquet"
    founding_map.parent.mkdir(parents=True, exist_ok=True)
    run("map", "import", "--published", "--map", str(founding_map))
    run("map", "publish", str(folder / "founding-package"), "--map", str(founding_map),
        "--lab", "Berthold et al.", "--contact", "R. Berthold", "--overwrite")

    merged = folder / "merged" / "friction_map.parquet"
    merged.parent.mkdir(parents=True, exist_ok=True)
    merged.unlink(missing_ok=True)
    run("map", "merge", str(folder / "founding-package"), "--map", str(merged))
    run("map", "merge", str(folder / "second-lab-package"), "--map", str(merged))

    print("Dragonskin 30 on steel, 35.37 kPa, 20 °C: mu_K ± U (k = 2)")
    print(f"  the second lab's map        {condition(second_map)}")
    print(f"  the founding paper's map    {condition(founding_map)}")
    print(f"  both, after map merge       {condition(merged)}")
    print()
    print(f"$ tribopipe map compare --map {merged}")
    print(run("map", "compare", "--map", str(merged)), end="")


if __name__ == "__main__":
    if len(sys.argv) > 1:
        main_(Path(sys.argv[1]))
    else:
        with tempfile.TemporaryDirectory() as tmp:
            main_(Path(tmp))
