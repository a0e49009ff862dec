"""The ids of runs already in people's maps never change.

A map row's ``measurement_id`` is the key every later batch, merge and exclusion finds it
by: if reducing the same single-test export gave another id, a lab's map would grow a
second row for the same run. The shipped example exports (one test each, a set-up
interval then the friction interval) are pinned here to the ids tribopipe gave them
before exports with several tests were reduced run by run.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tribopipe.config import load_settings
from tribopipe.files import file_sha256
from tribopipe.labels import RunLabels
from tribopipe.pipeline import reduce_file

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "raw" / "example"

#: file -> (SHA-256 of its bytes, measurement id, the friction interval's number)
PINNED = {
    "DS30_acrylic_1N_10C_r1.csv": (
        "c186aaf1f2c7f28d71bde0674066d8af0385005acd71481a2284847cf0cb7448",
        "c5fe21dcc5e014de", 2,
    ),
    # the French export (labels, decimal comma)
    "EF50_acrylic_9N_20C_r2.csv": (
        "dfa1daf97d3341004a300050622e1186f0eea0def3e01fddc256424a9b0cdb26",
        "0bdeec7f6269ecd5", 2,
    ),
}


#: what each pinned file is (the reduction refuses labels its export contradicts; the id
#: depends on the content alone, not on these)
LABELS = {
    "DS30_acrylic_1N_10C_r1.csv": RunLabels(pin="Dragonskin 30", disc="acrylic glass",
                                            normal_force_N=1.0, temperature_C=10.0, repeat=1),
    "EF50_acrylic_9N_20C_r2.csv": RunLabels(pin="Ecoflex 00-50", disc="acrylic glass",
                                            normal_force_N=9.0, temperature_C=20.0, repeat=2),
}


@pytest.mark.parametrize("name", sorted(PINNED))
def test_a_shipped_single_test_export_keeps_its_measurement_id(name: str) -> None:
    path = EXAMPLE / name
    sha, pinned_id, interval = PINNED[name]
    assert file_sha256(path) == sha, f"{name} itself changed: its pinned id no longer applies"
    labels = LABELS[name]
    outcome = reduce_file(path, load_settings(), labels)
    assert outcome.measurement_id == pinned_id
    assert outcome.record is not None and outcome.record.measurement_id == pinned_id
    assert outcome.record.interval == interval
