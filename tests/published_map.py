"""Test inputs from the founding paper's published friction map (../shared/reference).

The published CSV holds one μ_K per run (no μ_S). These helpers turn it into run rows with
the friction-map column names, and into a group table with the columns of
``stats.group_statistics`` (the real function is used when it exists).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats as sps


def published_runs(csv_path: Path) -> pd.DataFrame:
    """The 169 published runs as friction-map rows (subset of the run columns)."""
    raw = pd.read_csv(csv_path)
    runs = pd.DataFrame(
        {
            "measurement_id": [f"pub{i:04d}" for i in range(len(raw))],
            "source": "published",
            "pin": raw["pin"].astype(str),
            "disc": raw["disc"].astype(str),
            "normal_force_N": raw["contactForce"].astype(float),
            "pressure_kPa": raw["contactPressure"].astype(float),
            "temperature_C": raw["temperature"].astype(float),
            "repeat": raw["measurementNo"].astype(int),
            "mu_s": math.nan,
            "mu_k": raw["cof"].astype(float),
            "flags": "",
            "excluded": False,
            "exclusion_reason": "",
        }
    )
    return runs


def _own_group_statistics(runs: pd.DataFrame) -> pd.DataFrame:
    keys = ["pin", "disc", "normal_force_N", "pressure_kPa", "temperature_C"]
    rows = []
    for key, grp in runs.groupby(keys, sort=True):
        row = dict(zip(keys, key, strict=True))
        for q in ("mu_k", "mu_s"):
            v = grp[q].to_numpy(dtype=float)
            v = v[np.isfinite(v)]
            n = len(v)
            mean = float(v.mean()) if n else math.nan
            std = float(v.std(ddof=1)) if n > 1 else math.nan
            sem = std / math.sqrt(n) if n > 1 else math.nan
            half = float(sps.t.ppf(0.975, n - 1)) * sem if n > 1 else math.nan
            row.update(
                {
                    f"{q}_n": n,
                    f"{q}_mean": mean,
                    f"{q}_std": std,
                    f"{q}_sem": sem,
                    f"{q}_ci95_low": mean - half,
                    f"{q}_ci95_high": mean + half,
                    f"{q}_cv": std / mean if n > 1 else math.nan,
                    f"{q}_min": float(v.min()) if n else math.nan,
                    f"{q}_max": float(v.max()) if n else math.nan,
                    f"{q}_values": ";".join(f"{x:g}" for x in v),
                }
            )
        row["range_exceeds_r"] = False
        row["qc_flagged"] = False
        row["run_ids"] = ";".join(grp["measurement_id"])
        rows.append(row)
    return pd.DataFrame(rows)


def group_table(runs: pd.DataFrame) -> pd.DataFrame:
    """Group statistics of ``runs``: ``stats.group_statistics`` once it exists."""
    try:
        from tribopipe.stats import group_statistics
    except ImportError:
        return _own_group_statistics(runs)
    return group_statistics(runs)
