"""A reduced run's parameters are typed per method (``tribopipe.reduction.parameters``):
the summary's JSON names every setting and every diagnostic, and a reciprocating run,
which has no window terms, goes through the real ``reduce`` command."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import fields
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from generators.forcerigs import ReciprocatingRun, write_reciprocating_export
from generators.synthetic import SyntheticRun, make_intervals
from tribopipe.config import InstrumentConfig, ReductionParams
from tribopipe.measurement import Measurement, MeasurementMeta
from tribopipe.reduction.intervals import select_friction_interval
from tribopipe.reduction.manual import TRACE_META_KEY, TraceTerms
from tribopipe.reduction.parameters import (
    InstrumentSide,
    ReciprocatingParameters,
    RotaryParameters,
    RunParameters,
)
from tribopipe.reduction.reduce import reduce_measurement

CONFIGS = Path(__file__).resolve().parents[1] / "configs" / "instruments"


def _rotary() -> RotaryParameters:
    run = SyntheticRun(seed=3)
    ms = [Measurement(f, MeasurementMeta("run.csv", "synthetic", test="Friction",
                                         result="Friction 1", interval=i))
          for i, f in enumerate(make_intervals(run), start=1)]
    got = reduce_measurement(select_friction_interval(ms), InstrumentConfig(),
                             ReductionParams())
    assert isinstance(got.parameters, RotaryParameters)
    return got.parameters


def _own_fields(cls: type[RunParameters]) -> set[str]:
    return {f.name for f in fields(cls)} - {"settings", "instrument", "uncertainty"}


def test_the_summary_names_every_setting_and_diagnostic() -> None:
    p = _rotary()
    out = p.to_json()
    json.dumps(out, allow_nan=False)
    settings = {f.name for f in fields(ReductionParams)}
    side = {f.name for f in fields(InstrumentSide)}
    # every field of the typed record is a key, and no key is anything else
    assert set(out) == settings | side | _own_fields(RotaryParameters) | {"uncertainty"}
    assert out["run_in_mm"] == ReductionParams().run_in_mm
    assert out["torque_offset_source"] == p.torque_offset_source
    budget = out["uncertainty"]
    assert budget["mu_k"]["combined"] == p.uncertainty.mu_k["combined"]
    assert budget["k"] == 1 and budget["coverage_factor_expanded"] == 2.0
    assert set(budget["terms"]) == {"relative", "absolute"}
    terms = p.trace_terms()
    assert isinstance(terms, TraceTerms)
    assert terms.min_plateau_samples == ReductionParams().min_plateau_samples
    assert (terms.u_relative, terms.u_absolute) == p.uncertainty.terms


def test_parameters_are_frozen() -> None:
    p = _rotary()
    with pytest.raises(AttributeError):
        p.torque_offset_Nm = 1.0  # type: ignore[misc]


def test_a_reciprocating_run_through_the_real_reduce(tmp_path: Path) -> None:
    """Its μ_K is read over cycles, so it has no window terms: the trace is written
    without them (a review refuses a window over it) rather than the command failing."""
    export = write_reciprocating_export(tmp_path / "recip.csv",
                                        ReciprocatingRun(cycles=40, run_in_cycles=3))
    out = tmp_path / "out"
    done = subprocess.run(
        [sys.executable, "-m", "tribopipe", "reduce", str(export), "--instrument",
         str(CONFIGS / "linear-reciprocating.toml"), "--pin", "PTFE", "--disc", "steel",
         "--no-map", "-o", str(out), "--json"],
        capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr
    (summary_path,) = (out / "summaries").glob("*.json")
    params = json.loads(summary_path.read_text())["parameters"]
    settings = {f.name for f in fields(ReductionParams)}
    side = {f.name for f in fields(InstrumentSide)}
    assert set(params) == (settings | side | _own_fields(ReciprocatingParameters)
                           | {"uncertainty"})
    assert len(params["cycles"]) == params["n_cycles"] >= 30
    assert set(params["cycles"][0]) == {"cycle", "mu", "mu_forward", "mu_backward",
                                        "distance_mm", "time_s", "normal_force_N"}
    assert "terms" not in params["uncertainty"]
    (trace,) = (out / "traces").glob("*.parquet")
    assert TRACE_META_KEY not in (pq.read_schema(trace).metadata or {})
