"""Maps written before this version still read, and keep what they say.

``tests/data/frictionmap_v1.parquet`` was written by tribopipe with schema version 1 and
reduction method ``tribopipe-v1`` (see ``tests/data/README.md``); its reduced run is
regenerated here byte for byte from its seed. Issue 14: the uncertainty columns are new
(schema version 3; ``lab`` came in version 2), a v1 run keeps its method in the map until
it is re-reduced with ``--replace``.
"""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner

from tribopipe import frictionmap as fm
from tribopipe.cli import main
from tribopipe.pipeline import file_sha256
from tribopipe.synthetic import SyntheticRun, write_rheocompass_export

V1_MAP = Path(__file__).parent / "data" / "frictionmap_v1.parquet"
V1_RUN = SyntheticRun(mu_s=0.8, mu_k=0.55, noise=0.005, duration_s=120.0, seed=14)
LABELS = ["--pin", "Dragonskin 30", "--disc", "steel", "--force", "3", "--temperature", "20",
          "--repeat", "1"]


@pytest.fixture
def v1_map(tmp_path: Path) -> Path:
    target = tmp_path / "friction_map.parquet"
    shutil.copyfile(V1_MAP, target)
    return target


@pytest.fixture
def v1_export(tmp_path: Path) -> Path:
    return write_rheocompass_export(tmp_path / "v1_run.csv", V1_RUN, project="v1",
                                    test="Friction", sample="pin")


def reduced_row(runs):
    return runs[runs["source"] == fm.SOURCE_REDUCED].iloc[0]


def test_a_version_1_map_reads_with_the_new_columns_missing() -> None:
    info = json.loads(pq.read_schema(V1_MAP).metadata[fm.META_KEY])
    assert info["schema_version"] == 1
    assert "u_mu_k" not in pq.read_schema(V1_MAP).names
    assert "lab" not in pq.read_schema(V1_MAP).names
    runs = fm.read_map(V1_MAP)
    assert len(runs) == 4
    assert runs["u_mu_k"].isna().all() and runs["u_mu_s"].isna().all()
    assert runs["lab"].isna().all()
    row = reduced_row(runs)
    assert row["method"].startswith("tribopipe-v1")
    assert row["mu_k"] == pytest.approx(0.55, abs=0.01)


def test_the_regenerated_export_is_the_run_in_the_v1_map(v1_export: Path) -> None:
    assert file_sha256(v1_export) == reduced_row(fm.read_map(V1_MAP))["file_hash"]


def test_writing_to_an_old_map_keeps_its_rows_and_stores_the_current_schema(
    v1_map: Path, tmp_path: Path
) -> None:
    other = tmp_path / "other.csv"
    write_rheocompass_export(other, SyntheticRun(seed=15, duration_s=180.0), project="v2",
                             test="Friction", sample="pin")
    result = CliRunner().invoke(main, ["reduce", str(other), *LABELS, "--repeat", "2",
                                       "--map", str(v1_map), "--out", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    info = json.loads(pq.read_schema(v1_map).metadata[fm.META_KEY])
    assert info["schema_version"] == fm.SCHEMA_VERSION == 3
    runs = fm.read_map(v1_map)
    assert len(runs) == 5
    old = runs[runs["method"].str.startswith("tribopipe-v1")]
    assert len(old) == 1 and math.isnan(old["u_mu_k"].iloc[0])
    new = runs[runs["method"].str.startswith("tribopipe-v2")]
    assert len(new) == 1 and 0 < new["u_mu_k"].iloc[0] < 0.1


def test_a_v1_run_keeps_its_method_until_replaced(v1_map: Path, v1_export: Path,
                                                   tmp_path: Path) -> None:
    args = ["reduce", str(v1_export), *LABELS, "--map", str(v1_map),
            "--out", str(tmp_path / "out")]
    kept = CliRunner().invoke(main, args)
    assert kept.exit_code == 0, kept.output
    assert "1 kept conflicting" in kept.output
    row = reduced_row(fm.read_map(v1_map))
    assert row["method"].startswith("tribopipe-v1") and math.isnan(row["u_mu_k"])

    replaced = CliRunner().invoke(main, [*args, "--replace"])
    assert replaced.exit_code == 0, replaced.output
    assert "1 replaced" in replaced.output
    runs = fm.read_map(v1_map)
    assert len(runs) == 4  # the same run, updated in place; the imported rows untouched
    row = reduced_row(runs)
    assert row["method"].startswith("tribopipe-v2")
    assert row["u_mu_k"] > 0 and row["u_mu_s"] >= row["u_mu_k"]
    assert (runs["method"] == "published").sum() == 3
