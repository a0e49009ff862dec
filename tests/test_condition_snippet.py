"""ABAQUS and Ansys input for one condition (what the explorer copies): the constant μ_K
is query's, the comments are the other single-condition writers', and a name cannot break
out of a comment line."""

from __future__ import annotations

import math

import pytest

from tribopipe.errors import ExportError
from tribopipe.export.fe_decks import (
    abaqus_name,
    condition_header,
    condition_snippet,
    deck_safe,
)
from tribopipe.export.headers import comment_block, condition_lines
from tribopipe.query import query


def test_abaqus_constant_friction_at_an_interpolated_condition(groups):
    res = query(groups, "Dragonskin 30", "steel", 50.0, 15.0)
    text = condition_snippet(res, "abaqus", source="map.parquet")
    lines = text.splitlines()
    assert lines[-3:] == [
        f"*SURFACE INTERACTION, NAME={abaqus_name('Dragonskin 30', 'steel')}",
        "*FRICTION",
        f"{res.mu_k.value:.10g}",
    ]
    assert float(lines[-1]) == pytest.approx(res.mu_k.value, rel=1e-9)
    # every line before the keywords is a comment of at most 100 characters: the header,
    # then the condition as the other single-condition writers say it
    assert all(line.startswith("**") and len(line) <= 100 for line in lines[:-3])
    header = condition_header("abaqus", "map.parquet")
    assert lines[:len(header)] == header
    assert comment_block("**", condition_lines(res, deck_safe)) == lines[
        len(header):len(header) + len(comment_block("**", condition_lines(res, deck_safe)))]
    assert "map.parquet" in text and "not for CalculiX" in text
    # the measured groups used, with their weights (log p - log mu: 0.5 * 0.322 here)
    w = 0.5 * (1 - math.log(50 / 35.37) / math.log(58.95 / 35.37))
    assert f"35.37 kPa/10 C (w={w:.3g})" in text
    assert "outside the measured range" not in text


def test_ansys_constant_friction_says_when_it_held_the_edge(groups):
    res = query(groups, "Dragonskin 30", "steel", 500.0, 40.0)
    assert res.clamped
    text = condition_snippet(res, "ansys", material_id=7)
    lines = text.splitlines()
    assert lines[-2:] == ["TB,FRIC,7,,,ISO", f"TBDATA,1,{res.mu_k.value:.10g}"]
    assert all(line.startswith("!") for line in lines[:-2])
    assert "! outside the measured range: edge value held constant" in lines
    assert "! material 7: pin Dragonskin 30 on disc steel" in lines
    assert res.mu_k.value == pytest.approx(0.26)  # 106.1 kPa at 20 °C, the published edge


def test_a_name_with_line_breaks_stays_inside_its_comment(groups):
    res = query(groups, "Dragonskin 30", "steel", 35.37, 20.0)
    hostile = res.__class__(**{**res.__dict__, "pin": "x\n*INCLUDE, INPUT=evil.inp\r$y"})
    for fmt, comment, n_data in (("abaqus", "**", 3), ("ansys", "!", 2)):
        lines = condition_snippet(hostile, fmt).splitlines()
        # only the writer's own keyword and data lines are not comments
        assert [line for line in lines if not line.startswith(comment)] == lines[-n_data:]
        assert not any(line.startswith("*INCLUDE") for line in lines), fmt
    assert "x\\n*INCLUDE, INPUT=evil.inp\\r\\x24y" in condition_snippet(hostile, "ansys")


def test_unknown_format_or_material_is_refused(groups):
    res = query(groups, "Dragonskin 30", "steel", 35.37, 20.0)
    with pytest.raises(ExportError, match="expected one of abaqus, ansys"):
        condition_snippet(res, "mujoco")
    with pytest.raises(ExportError, match="expected one of abaqus, ansys"):
        condition_snippet(res, "lsdyna")
    with pytest.raises(ExportError, match="material number must be >= 1"):
        condition_snippet(res, "ansys", material_id=0)
