"""Write ``tests/data/friction_map_v1.parquet``: a friction map of schema version 1, written by
the tribopipe of commit 064bf4b (before the ``lab`` column), so the tests can check that a map
written by the old code still reads.

Run it against that commit's source, not the current one::

    git archive 064bf4b src | tar -x -C /tmp/v1src
    PYTHONPATH=/tmp/v1src/src python scripts/make_v1_map.py \
        tests/data/friction_map_v1.parquet /tmp/v1raw

It reduces two seeded synthetic runs (Dragonskin 30 on steel, 3 N and 9 N, 20 °C), imports
the published map (169 rows) and excludes the first run, so the file holds reduced,
published and excluded rows.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the generators

from generators.synthetic import SyntheticRun, write_rheocompass_export
from tribopipe import frictionmap as fm
from tribopipe.config import load_settings
from tribopipe.labels import RunLabels
from tribopipe.pipeline import reduce_file


def main(out: Path, raw_dir: Path) -> None:
    """Write the version-1 map to ``out``, the raw exports it reduces to ``raw_dir``."""
    if fm.schema.SCHEMA_VERSION != 1:
        raise SystemExit("run this with the source of commit 064bf4b (schema version 1)")
    settings = load_settings()
    raw_dir.mkdir(parents=True, exist_ok=True)
    records = []
    for i, (force, mu_k) in enumerate([(3.0, 0.55), (9.0, 0.41)], 1):
        raw = raw_dir / f"v1_run_{i}.csv"
        run = SyntheticRun(mu_s=mu_k + 0.2, mu_k=mu_k, normal_force_N=force, seed=40 + i)
        write_rheocompass_export(raw, run, project="v1", test=f"run {i}", sample="Dragonskin 30")
        labels = RunLabels("Dragonskin 30", "steel", force, 20.0, 1)
        records.append(reduce_file(raw, settings, labels).record)
    fm.append_records(out, records)
    fm.import_table(out)
    fm.exclude_runs(out, [records[0]["measurement_id"]], "v1 fixture: excluded to keep the flag")
    Path(str(out) + ".lock").unlink(missing_ok=True)
    version = fm.store.map_metadata(out)["schema_version"]
    print(len(fm.read_map(out)), "runs, schema version", version)


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]))
