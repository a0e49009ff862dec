"""A small processed folder of really reduced synthetic runs, for plot and report tests.

Synthetic RheoCompass exports with known μ_S/μ_K are written, reduced with the real
pipeline, their traces written under ``<processed>/traces`` and their records appended
to a real friction map — the same layout a campaign produces.
"""

from __future__ import annotations

from pathlib import Path

from generators.synthetic import SyntheticRun, write_rheocompass_export
from tribopipe.config import load_settings
from tribopipe.frictionmap import append_records
from tribopipe.labels import RunLabels
from tribopipe.pipeline import reduce_file, write_trace

#: (file stem, pin, disc, force N, temperature °C, repeat, synthetic run)
RUNS = [
    ("ds_steel_3N_r1", "Dragonskin 30", "steel", 3.0, 20.0, 1,
     SyntheticRun(mu_s=0.80, mu_k=0.55, normal_force_N=3.0, seed=1)),
    ("ds_steel_3N_r2", "Dragonskin 30", "steel", 3.0, 20.0, 2,
     SyntheticRun(mu_s=0.82, mu_k=0.57, normal_force_N=3.0, seed=2)),
    ("ds_steel_9N_r1", "Dragonskin 30", "steel", 9.0, 20.0, 1,
     SyntheticRun(mu_s=0.60, mu_k=0.40, normal_force_N=9.0, seed=3)),
    ("ds_steel_9N_r2", "Dragonskin 30", "steel", 9.0, 20.0, 2,
     SyntheticRun(mu_s=0.62, mu_k=0.41, normal_force_N=9.0, seed=4)),
    ("ds_steel_9N_r3", "Dragonskin 30", "steel", 9.0, 20.0, 3,
     SyntheticRun(mu_k=0.42, shape="stick_slip", normal_force_N=9.0, seed=5,
                  stick_slip_amplitude=0.08)),
    ("eco_wood_3N_r1", "Ecoflex 00-50", "wood (smooth)", 3.0, 20.0, 1,
     SyntheticRun(mu_s=1.3, mu_k=1.05, normal_force_N=3.0, seed=6)),
]


#: :data:`RUNS` plus two groups: one whose repeats agree (6 N) and one whose two repeats
#: disagree by 0.15 (12 N), so that its range exceeds the pooled r = 2.8·s_r (≈ 0.12)
SPREAD_RUNS = RUNS + [
    ("ds_steel_6N_r1", "Dragonskin 30", "steel", 6.0, 20.0, 1,
     SyntheticRun(mu_s=0.70, mu_k=0.470, normal_force_N=6.0, seed=7)),
    ("ds_steel_6N_r2", "Dragonskin 30", "steel", 6.0, 20.0, 2,
     SyntheticRun(mu_s=0.70, mu_k=0.480, normal_force_N=6.0, seed=8)),
    ("ds_steel_6N_r3", "Dragonskin 30", "steel", 6.0, 20.0, 3,
     SyntheticRun(mu_s=0.70, mu_k=0.475, normal_force_N=6.0, seed=9)),
    ("ds_steel_12N_r1", "Dragonskin 30", "steel", 12.0, 20.0, 1,
     SyntheticRun(mu_s=0.50, mu_k=0.30, normal_force_N=12.0, seed=10)),
    ("ds_steel_12N_r2", "Dragonskin 30", "steel", 12.0, 20.0, 2,
     SyntheticRun(mu_s=0.65, mu_k=0.45, normal_force_N=12.0, seed=11)),
]


def make_processed(root: Path, runs: list | None = None) -> tuple[Path, Path]:
    """Write, reduce and store ``runs`` (default :data:`RUNS`) under ``root``; returns
    ``(map, processed dir)``."""
    raw = root / "raw"
    processed = root / "processed"
    raw.mkdir(parents=True, exist_ok=True)
    settings = load_settings()
    records = []
    for stem, pin, disc, force, temp, repeat, run in (RUNS if runs is None else runs):
        path = raw / f"{stem}.csv"
        write_rheocompass_export(path, run, project="tests", test=stem, sample=pin)
        outcome = reduce_file(path, settings, RunLabels(pin, disc, force, temp, repeat))
        write_trace(processed, outcome)
        records.append(outcome.record)
    map_path = processed / "friction_map.parquet"
    append_records(map_path, records)
    return map_path, processed
