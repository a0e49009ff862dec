"""ABAQUS and Ansys input for one condition (what the explorer copies): the constant μ_K
is query's, the comments are the other single-condition writers', and a name cannot break
out of a comment line."""

from __future__ import annotations

import pytest

from published_map import group_table, published_runs
from tribopipe.errors import ExportError
from tribopipe.export.simulators import (
    _condition_comments,
    abaqus_name,
    condition_snippet,
    write_condition,
)
from tribopipe.frictionmap import published_csv_path
from tribopipe.query import query


@pytest.fixture(scope="module")
def groups():
    return group_table(published_runs(published_csv_path()))


def test_abaqus_constant_friction_at_an_interpolated_condition(groups):
    res = query(groups, "Dragonskin 30", "steel", 50.0, 15.0)
    text = write_condition(groups, "abaqus", pin="Dragonskin 30", disc="steel",
                           pressure_kPa=50.0, temperature_C=15.0, source="map.parquet")
    lines = text.splitlines()
    assert lines[-3:] == [
        f"*SURFACE INTERACTION, NAME={abaqus_name('Dragonskin 30', 'steel')}",
        "*FRICTION",
        f"{res.mu_k.value:.10g}",
    ]
    assert float(lines[-1]) == pytest.approx(res.mu_k.value, rel=1e-9)
    # every line before the keywords is a comment, and the condition's comments are those
    # of the other single-condition writers
    assert all(line.startswith("**") for line in lines[:-3])
    for comment in _condition_comments("**", res):
        assert comment in lines
    assert "** written by tribopipe" in text and "map.parquet" in text
    assert "35.37 kPa/10 C (w=0.19)" in text  # the measured groups used, with weights
    assert "outside the measured range" not in text


def test_ansys_constant_friction_says_when_it_held_the_edge(groups):
    res = query(groups, "Dragonskin 30", "steel", 500.0, 40.0)
    assert res.clamped
    text = condition_snippet(res, "ansys", material_id=7)
    lines = text.splitlines()
    assert lines[-2:] == ["TB,FRIC,7,,,ISO", f"TBDATA,1,{res.mu_k.value:.10g}"]
    assert all(line.startswith("!") for line in lines[:-2])
    assert "! outside the measured range: edge value held constant" in lines
    assert res.mu_k.value == pytest.approx(0.26)  # 106.1 kPa at 20 °C, the published edge


def test_a_name_with_line_breaks_stays_inside_its_comment(groups):
    res = query(groups, "Dragonskin 30", "steel", 35.37, 20.0)
    hostile = res.__class__(**{**res.__dict__, "pin": "x\n*INCLUDE, INPUT=evil.inp\r\u2028y"})
    for fmt, comment, n_data in (("abaqus", "**", 3), ("ansys", "!", 2)):
        lines = condition_snippet(hostile, fmt).splitlines()
        # only the writer's own keyword and data lines are not comments
        assert [line for line in lines if not line.startswith(comment)] == lines[-n_data:]
        assert not any(line.startswith("*INCLUDE") for line in lines), fmt
        assert any("pin x *INCLUDE, INPUT=evil.inp  y on disc steel" in line for line in lines)


def test_unknown_format_is_refused(groups):
    res = query(groups, "Dragonskin 30", "steel", 35.37, 20.0)
    with pytest.raises(ExportError, match="expected one of abaqus, ansys"):
        condition_snippet(res, "mujoco")
