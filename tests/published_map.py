"""Test inputs from the founding paper's published friction map.

The published CSV holds one μ_K per run (no μ_S). tribopipe ships it
(``src/tribopipe/data/frictionmap_published.csv``, :data:`PUBLISHED_CSV`), so these tests
run on every clone; ``test_frictionmap`` checks that the shipped copy is byte for byte the
reference file in ``../shared/reference`` where that exists. These helpers import it with
the real friction-map code into a real Parquet map and compute the real group statistics.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from tribopipe.frictionmap import import_records, import_table, read_map, records_frame
from tribopipe.frictionmap.published import published_csv_path
from tribopipe.stats import group_statistics

#: the published map as tribopipe ships it
PUBLISHED_CSV: Path = published_csv_path()


def published_runs(csv_path: Path) -> pd.DataFrame:
    """The 169 published runs as a friction-map DataFrame (μ_S missing)."""
    return records_frame(import_records(csv_path))


def write_published_map(csv_path: Path, map_path: Path) -> Path:
    """Import the published CSV into a (new) Parquet friction map at ``map_path``."""
    import_table(map_path, csv_path)
    assert len(read_map(map_path)) == 169
    return map_path


def group_table(runs: pd.DataFrame) -> pd.DataFrame:
    """Group statistics of ``runs`` (``stats.group_statistics``)."""
    return group_statistics(runs)
