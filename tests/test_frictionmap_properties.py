"""Invariants of the store, checked with hypothesis: write → read is lossless, appending the
same runs again changes nothing, and a failing append changes no byte of the map."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from map_files import map_bytes
from tribopipe import frictionmap as fm
from tribopipe.errors import MapError
from tribopipe.frictionmap.schema import (
    BOUNDS,
    CHOICES,
    KIND,
    REQUIRED,
    SOURCE_PUBLISHED,
    SOURCE_REDUCED,
)

# A map's text: one printable line (no control, format, surrogate, private-use, unassigned
# character, no line or paragraph separator: tribopipe.validate's rule for every map text).
TEXT = st.text(st.characters(blacklist_categories=("Cc", "Cf", "Cs", "Co", "Cn", "Zl", "Zp")),
               max_size=12)
NAME = TEXT.filter(lambda s: s.strip() != "")
FLOAT = st.floats(allow_nan=True, allow_infinity=False, width=64)
MAYBE_TEXT = st.none() | TEXT


def float_values(name: str):
    """Valid values of a float column: inside its physical range (NaN where it may be
    missing), else any finite number or NaN."""
    bounds = BOUNDS.get(name)
    if bounds is None:
        return FLOAT
    inside = st.floats(min_value=bounds.low, max_value=bounds.high,
                       exclude_min=bounds.low_open, width=64)
    return inside if name in REQUIRED else inside | st.just(math.nan)


def int_values(name: str):
    bounds = BOUNDS[name]
    return st.none() | st.integers(min_value=int(bounds.low), max_value=int(bounds.high))


@st.composite
def records(draw, min_size: int = 0, max_size: int = 6) -> list[dict]:
    """Arbitrary valid map records with unique ids."""
    ids = draw(st.lists(NAME, min_size=min_size, max_size=max_size, unique=True))
    out = []
    for mid in ids:
        rec: dict = {}
        for name in fm.RUN_COLUMNS:
            kind = KIND[name]
            if kind == "float":
                rec[name] = draw(float_values(name))
            elif kind == "int":
                rec[name] = draw(int_values(name))
            elif kind == "bool":
                rec[name] = draw(st.booleans())
            elif name in CHOICES:  # a closed vocabulary: one of its words, or missing
                rec[name] = draw(st.none() | st.sampled_from(CHOICES[name]))
            else:
                rec[name] = draw(MAYBE_TEXT)
        source = draw(st.sampled_from([SOURCE_REDUCED, SOURCE_PUBLISHED]) | NAME)
        rec.update(
            measurement_id=mid,
            source=source,
            pin=draw(NAME),
            disc=draw(NAME),
        )
        if source == fm.schema.SOURCE_REDUCED and math.isnan(rec["mu_s"]):
            rec["mu_s"] = draw(float_values("mu_k"))
        out.append(rec)
    return out


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(records(min_size=1))
def test_write_then_read_is_lossless(recs):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "map.parquet"
        report = fm.append_records(path, recs)
        assert report.added == len(recs)
        pd.testing.assert_frame_equal(fm.read_map(path), fm.records_frame(recs))


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(records(min_size=1), st.randoms(use_true_random=False))
def test_appending_the_same_runs_again_changes_nothing(recs, rnd):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "map.parquet"
        fm.append_records(path, recs)
        before = map_bytes(path)
        again = list(recs)
        rnd.shuffle(again)
        report = fm.append_records(path, again)
        assert report.added == report.replaced == report.kept_conflicting == 0
        assert report.unchanged == len(recs)
        assert map_bytes(path) == before


BREAKERS = {
    "mu_k is NaN": lambda r: r.update(mu_k=float("nan")),
    "no pin": lambda r: r.update(pin=" "),
    "reduced without mu_s": lambda r: r.update(source=fm.schema.SOURCE_REDUCED, mu_s=None),
    "text in a number column": lambda r: r.update(normal_force_N="3 N"),
    "half a repeat": lambda r: r.update(repeat=1.5),
    "an infinite repeat": lambda r: r.update(repeat=float("inf")),
    "a column missing": lambda r: r.pop("flags"),
}


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(records(min_size=1), records(min_size=1), st.sampled_from(sorted(BREAKERS)),
       st.data())
def test_a_failing_append_changes_no_byte_of_the_map(existing, new, breaker, data):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "map.parquet"
        fm.append_records(path, existing)
        before = map_bytes(path)
        bad = [dict(r) for r in new]
        BREAKERS[breaker](bad[data.draw(st.integers(0, len(bad) - 1))])
        with pytest.raises(MapError):
            fm.append_records(path, bad, replace=data.draw(st.booleans()))
        assert map_bytes(path) == before
        assert not [p.name for p in Path(tmp).iterdir() if p.name.endswith(".tmp")]


@pytest.fixture(scope="module")
def map_with_runs(tmp_path_factory) -> Path:
    """A map holding the published rows and one reduced run."""
    from test_frictionmap import run_record

    path = tmp_path_factory.mktemp("prop") / "friction_map.parquet"
    fm.import_table(path)
    fm.append_records(path, [run_record(1)])
    return path


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(st.binary(max_size=400) | st.text(max_size=400).map(str.encode))
def test_a_raw_file_that_fails_to_reduce_changes_no_byte_of_the_map(map_with_runs, content):
    from click.testing import CliRunner

    from tribopipe.cli import main

    before = map_bytes(map_with_runs)
    with tempfile.TemporaryDirectory() as tmp:
        raw = Path(tmp) / "broken_export.csv"
        raw.write_bytes(content)
        result = CliRunner().invoke(
            main,
            ["reduce", str(raw), "--pin", "Ecoflex 00-50", "--disc", "steel", "--force", "3",
             "--map", str(map_with_runs), "--output", str(Path(tmp) / "out")],
        )
    assert result.exit_code == 1, result.output
    assert "Traceback" not in result.output
    assert map_bytes(map_with_runs) == before


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(records(min_size=1, max_size=8), records(max_size=8), st.booleans(), st.data())
def test_folding_keeps_first_seen_order_and_the_latest_or_first_content(first, second,
                                                                         replace, data):
    # let part of the second batch re-use ids of the first, with another μ_K
    reused = data.draw(st.lists(st.sampled_from(first), unique_by=lambda r: r["measurement_id"]))
    taken = {r["measurement_id"] for r in first}
    second = [r for r in second if r["measurement_id"] not in taken]
    # a real change, far beyond the 1e-9 relative tolerance for re-reduction noise
    second += [{**r, "mu_k": r["mu_k"] + 1.0 if r["mu_k"] < 5 else r["mu_k"] / 2}
               for r in reused]
    runs = fm.records_frame(first)
    merged, report = fm.store.fold_records(runs, second, replace=replace)

    order = [r["measurement_id"] for r in first] + [
        r["measurement_id"] for r in second if r["measurement_id"] not in taken
    ]
    assert merged["measurement_id"].tolist() == order
    expected = {r["measurement_id"]: r["mu_k"] for r in first}
    for r in second:
        if r["measurement_id"] not in taken or replace:
            expected[r["measurement_id"]] = r["mu_k"]
    assert merged["mu_k"].tolist() == [expected[m] for m in order]
    assert set(report.replaced_ids if replace else report.conflicting_ids) <= {
        r["measurement_id"] for r in reused
    }
    assert report.added == len(order) - len(first)
    # exclusion state of a replaced row is the map's, not the newcomer's
    if replace:
        old = {r["measurement_id"]: r["excluded"] for r in first}
        got = dict(zip(merged["measurement_id"], merged["excluded"], strict=True))
        assert all(got[m] == old[m] for m in report.replaced_ids)
