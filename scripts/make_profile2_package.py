"""Write ``tests/data/package_profile2/``: a data package of package profile version 2 (map
schema 6, each group's runs and values joined into one cell of ``data/groups.csv``),
written by the tribopipe of commit 788c7f1, so the tests can check that a package written
before the group table linked its runs (profile version 3) still reads, validates, merges
and is said to be upgraded.

Run it against that commit's source, not the current one::

    git archive 788c7f1 src | tar -x -C /tmp/p2src
    PYTHONPATH=/tmp/p2src/src:tests python scripts/make_profile2_package.py tests/data

It reduces the six seeded synthetic runs of ``tests/reduced_runs.py`` (three condition
groups with repeats, one group of one run) and publishes them as the lab "Fixture Lab"
on 2026-11-27, without evidence (the traces would add 0.8 MB; the profile carries
evidence where there is some).
"""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the generators

from reduced_runs import make_processed
from tribopipe.export.citation import Publisher
from tribopipe.export.publish import publish_map


def main(out: Path) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        map_path, _ = make_processed(Path(tmp))
        target = out / "package_profile2"
        if target.exists():
            shutil.rmtree(target)
        publish_map(map_path, target, Publisher(lab="Fixture Lab"), date="2026-11-27",
                    evidence=False)


if __name__ == "__main__":
    main(Path(sys.argv[1]))
