"""Write ``tests/data/friction_map_v3.parquet`` and ``tests/data/package_v3/``: a friction map
and a data package of schema version 3 (before the ``test`` and ``result`` columns of
version 4), written by the tribopipe of commit d0b8513, so the tests can check that a map
and a package written by the old code still read, validate and merge.

Run it against that commit's source, not the current one::

    git archive d0b8513 src | tar -x -C /tmp/v3src
    PYTHONPATH=/tmp/v3src/src python scripts/make_v3_fixtures.py tests/data /tmp/v3raw

It reduces a seeded synthetic session export of two tests (Dragonskin 30 on steel, 1 N and
3 N, 20 °C, each test its own run), adds the first three published rows and excludes the
second run, so the map holds reduced, published and excluded rows of a session export;
the package is ``map publish`` of that map by the lab "Fixture Lab" on 2026-11-24.
"""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the generators

from generators.synthetic import SyntheticRun, SyntheticTest, write_rheocompass_session
from tribopipe import frictionmap as fm
from tribopipe.config import load_settings
from tribopipe.export.citation import Publisher
from tribopipe.export.publish import publish_map
from tribopipe.labels import RunLabels
from tribopipe.pipeline import reduce_export

#: Test name -> (mu_s, mu_k, force [N], seed)
TESTS = {
    "DS30 on steel, 1 N, 20 °C, #1": (0.80, 0.62, 1.0, 31),
    "DS30 on steel, 3 N, 20 °C, #1": (0.60, 0.47, 3.0, 32),
}


def session_tests() -> list[SyntheticTest]:
    """The two tests of the fixture's session export."""
    return [SyntheticTest(name, "DS30", (SyntheticRun(
        mu_s=mu_s, mu_k=mu_k, normal_force_N=force, temperature_C=20.0, duration_s=120.0,
        noise=0.004, seed=seed),)) for name, (mu_s, mu_k, force, seed) in TESTS.items()]


def main(out_dir: Path, raw_dir: Path) -> None:
    """Write the version-3 map and package to ``out_dir``, the raw export to ``raw_dir``."""
    if fm.schema.SCHEMA_VERSION != 3:
        raise SystemExit("run this with the source of commit d0b8513 (schema version 3)")
    settings = load_settings()
    raw_dir.mkdir(parents=True, exist_ok=True)
    raw = write_rheocompass_session(raw_dir / "v3_session.txt", session_tests(),
                                    project="v3")
    records = []
    for run in reduce_export(raw, settings).runs:
        force = TESTS[run.place.test][2]
        labels = RunLabels("Dragonskin 30", "steel", force, 20.0, 1)
        records.append(fm.make_record(result=run.outcome.result, labels=labels,
                                      meta=run.outcome.measurement.meta,
                                      file_hash=run.outcome.file_hash, settings=settings))
    target = out_dir / "friction_map_v3.parquet"
    target.unlink(missing_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        published = Path(tmp) / "published.parquet"
        fm.import_table(published)
        first_three = fm.schema.frame_records(fm.read_map(published).iloc[:3])
    fm.append_records(target, records + first_three)
    fm.exclude_runs(target, [records[1]["measurement_id"]], "v3 fixture: excluded")
    Path(str(target) + ".lock").unlink(missing_ok=True)
    package = out_dir / "package_v3"
    shutil.rmtree(package, ignore_errors=True)
    publish_map(target, package, Publisher("Fixture Lab", contact="A. Person"),
                date="2026-11-24")
    Path(str(target) + ".lock").unlink(missing_ok=True)
    print(len(fm.read_map(target)), "runs, schema version",
          fm.store.map_metadata(target)["schema_version"], "; package in", package)


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]))
