"""Simulator input: parse what we write and check every number against the map."""

from __future__ import annotations

import ast
import math
import xml.etree.ElementTree as ET

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import shared_file
from published_map import group_table, published_runs
from tribopipe.errors import ExportError
from tribopipe.export.simulators import (
    UNIT_SYSTEMS,
    abaqus_name,
    convert_pressure_kPa,
    default_decay_s_per_mm,
    write_abaqus,
    write_abaqus_decay,
    write_ansys,
    write_mujoco,
    write_pyelastica,
    write_sofa,
)
from tribopipe.query import pairs, query

PIN, DISC = "Dragonskin 30", "steel"


@pytest.fixture(scope="module")
def groups() -> pd.DataFrame:
    return group_table(published_runs(shared_file("reference", "frictionmap_published.csv")))


@pytest.fixture(scope="module")
def groups_with_mu_s(groups) -> pd.DataFrame:
    """The published groups plus a μ_S column (the published map has none)."""
    g = groups.copy()
    g["mu_s_n"] = g["mu_k_n"]
    g["mu_s_mean"] = g["mu_k_mean"] * 1.4
    g["mu_s_ci95_low"] = g["mu_s_mean"] - 0.02
    g["mu_s_ci95_high"] = g["mu_s_mean"] + 0.02
    return g


# ---------------------------------------------------------------------------- parsers


def parse_abaqus(text: str) -> dict[str, dict]:
    """{interaction name: {"options": [...], "rows": [[floats], ...]}} from an .inp text."""
    blocks: dict[str, dict] = {}
    current = None
    for raw in text.splitlines():
        line = raw.strip()
        if not line or line.startswith("**"):
            continue
        if line.startswith("*"):
            keyword, *params = [p.strip() for p in line.split(",")]
            if keyword.upper() == "*SURFACE INTERACTION":
                name = dict(p.split("=") for p in params)["NAME"]
                current = blocks.setdefault(name, {"options": [], "rows": []})
            else:
                assert current is not None, f"{line} outside a *SURFACE INTERACTION"
                current["options"].append((keyword.upper(), [p.upper() for p in params]))
            continue
        current["rows"].append([float(v) for v in line.split(",")])
    return blocks


def parse_ansys(text: str) -> dict[int, list[tuple[float | None, float, float]]]:
    """{material: [(temperature, pressure, mu), ...]} from TB/TBFIELD/TBDATA commands."""
    tables: dict[int, list] = {}
    mat = temp = pres = None
    for raw in text.splitlines():
        line = raw.split("!")[0].strip()
        if not line:
            continue
        cmd, *args = line.split(",")
        if cmd == "TB":
            assert args[0] == "FRIC" and args[4] == "ISO"
            mat = int(args[1])
            tables[mat] = []
            temp = pres = None
        elif cmd == "TBFIELD":
            if args[0] == "TEMP":
                temp = float(args[1])
            else:
                assert args[0] == "NPRES"
                pres = float(args[1])
        elif cmd == "TBDATA":
            assert args[0] == "1"
            tables[mat].append((temp, pres, float(args[1])))
        else:
            raise AssertionError(f"unexpected command {cmd}")
    return tables


# ---------------------------------------------------------------------------- ABAQUS


@pytest.mark.parametrize("units,factor", [("mm-N-s", 1e-3), ("m-N-s", 1e3)])
def test_abaqus_table_matches_the_map_in_both_unit_systems(groups, units, factor):
    text = write_abaqus(groups, pin=PIN, disc=DISC, units=units, source="map.parquet")
    blocks = parse_abaqus(text)
    assert list(blocks) == [abaqus_name(PIN, DISC)]
    block = blocks[abaqus_name(PIN, DISC)]
    assert block["options"] == [("*FRICTION", [])]
    rows = np.array(block["rows"])
    # column order: mu, slip rate, contact pressure, temperature
    assert rows.shape == (10, 4)
    speed = 0.007 if units == "mm-N-s" else 0.007e-3
    assert rows[:, 1] == pytest.approx(np.full(10, speed))
    # a full rectangular grid: 5 pressures × 2 temperatures, temperature outer
    assert list(rows[:, 3]) == [10.0] * 5 + [20.0] * 5
    pressures_kPa = rows[:, 2] / factor
    assert sorted(set(np.round(pressures_kPa, 2))) == [11.79, 35.37, 58.95, 82.52, 106.1]
    for mu, _, p_kpa, t in np.column_stack([rows[:, 0], rows[:, 1], pressures_kPa, rows[:, 3]]):
        assert mu == pytest.approx(query(groups, PIN, DISC, p_kpa, t).mu_k.value, rel=1e-5)
    assert "map.parquet" in text
    assert "1 cell(s) not measured" in text  # 11.79 kPa at 10 °C


def test_abaqus_pressure_units_are_converted():
    assert convert_pressure_kPa(11.79, "mm-N-s") == pytest.approx(0.01179)
    assert convert_pressure_kPa(11.79, "m-N-s") == pytest.approx(11790.0)
    assert UNIT_SYSTEMS["m-N-s"].speed_per_mm_s == 1e-3
    with pytest.raises(ExportError, match="unit system"):
        convert_pressure_kPa(1.0, "in-lbf-s")


def test_abaqus_all_pairs_every_group_mean_is_in_the_file(groups):
    blocks = parse_abaqus(write_abaqus(groups))
    assert len(blocks) == len(pairs(groups)) == 11
    for row in groups.itertuples():
        rows = np.array(blocks[abaqus_name(row.pin, row.disc)]["rows"])
        at = np.isclose(rows[:, 2], row.pressure_kPa * 1e-3) & (rows[:, 3] == row.temperature_C)
        hit = rows[at]
        assert len(hit) == 1
        assert hit[0, 0] == pytest.approx(row.mu_k_mean, rel=1e-5)


def test_abaqus_single_temperature_slice(groups):
    rows = np.array(parse_abaqus(write_abaqus(groups, pin=PIN, disc=DISC, temperature_C=15.0))[
        abaqus_name(PIN, DISC)]["rows"])
    assert rows.shape == (5, 4)
    assert set(rows[:, 3]) == {15.0}
    for mu, _, p_mpa, t in rows:
        assert mu == pytest.approx(query(groups, PIN, DISC, p_mpa * 1e3, t).mu_k.value, rel=1e-5)


def test_abaqus_selection_by_pin_only(groups):
    blocks = parse_abaqus(write_abaqus(groups, pin="Ecoflex 00-50"))
    assert set(blocks) == {abaqus_name("Ecoflex 00-50", "steel"),
                           abaqus_name("Ecoflex 00-50", "wood (smooth)")}
    with pytest.raises(ExportError, match="the map holds"):
        write_abaqus(groups, pin="Sylgard 184")


@pytest.mark.parametrize("units,decay_factor", [("mm-N-s", 1.0), ("m-N-s", 1e3)])
def test_abaqus_exponential_decay(groups_with_mu_s, units, decay_factor):
    text = write_abaqus_decay(
        groups_with_mu_s, pin=PIN, disc=DISC, pressure_kPa=35.37, temperature_C=20.0, units=units
    )
    block = parse_abaqus(text)[abaqus_name(PIN, DISC)]
    assert block["options"] == [("*FRICTION", ["EXPONENTIAL DECAY"])]
    (mu_s, mu_k, d_c), = block["rows"]
    assert mu_k == pytest.approx(0.45)
    assert mu_s == pytest.approx(0.45 * 1.4)
    assert d_c == pytest.approx(default_decay_s_per_mm() * decay_factor, rel=1e-5)
    # the default d_c makes μ 99 % kinetic at the measured sliding speed
    assert math.exp(-default_decay_s_per_mm() * 0.007) == pytest.approx(0.01)


def test_abaqus_exponential_decay_needs_mu_s(groups):
    with pytest.raises(ExportError, match="no mu_s"):
        write_abaqus_decay(groups, pin=PIN, disc=DISC, pressure_kPa=35.37, temperature_C=20.0)


# ---------------------------------------------------------------------------- Ansys


@pytest.mark.parametrize("units,factor", [("mm-N-s", 1e-3), ("m-N-s", 1e3)])
def test_ansys_tables_match_the_map(groups, units, factor):
    text = write_ansys(groups, pin=PIN, units=units, material_id=5)
    tables = parse_ansys(text)
    held = [p for p in pairs(groups) if p[0] == PIN]
    assert sorted(tables) == list(range(5, 5 + len(held)))
    for mat, (pin, disc) in zip(sorted(tables), held, strict=True):
        assert f"material {mat}: pin {pin} on disc {disc}" in text
        entries = tables[mat]
        temps = [e[0] for e in entries]
        assert temps == sorted(temps)  # ascending field values, temperature outer
        for t, p, mu in entries:
            assert mu == pytest.approx(query(groups, pin, disc, p / factor, t).mu_k.value, rel=1e-5)


# ---------------------------------------------------------------------------- single values


def test_mujoco_pair_friction(groups):
    text = write_mujoco(groups, pin=PIN, disc=DISC, pressure_kPa=47.16, temperature_C=20.0,
                        geom1="finger", geom2="table")
    root = ET.fromstring(text[text.index("<mujoco>"):])
    pair = root.find("contact/pair")
    assert pair.get("geom1") == "finger" and pair.get("geom2") == "table"
    friction = [float(v) for v in pair.get("friction").split()]
    expected = query(groups, PIN, DISC, 47.16, 20.0).mu_k.value
    assert friction[:2] == pytest.approx([expected, expected], rel=1e-5)
    assert expected == pytest.approx((0.45 + 0.36) / 2)
    assert "maximum" in text and "product" in text


def test_sofa_response_mu(groups):
    text = write_sofa(groups, pin=PIN, disc=DISC, pressure_kPa=106.1, temperature_C=20.0)
    root = ET.fromstring(text[text.index("<Node"):])
    response = root.find("CollisionResponse")
    assert response.get("response") == "FrictionContactConstraint"
    key, value = response.get("responseParams").split("=")
    assert key == "mu" and float(value) == pytest.approx(0.26)


def _pyelastica_arrays(text: str) -> dict[str, list[float]]:
    found = {}
    for node in ast.parse(text).body:
        if isinstance(node, ast.Assign):
            call = node.value
            assert isinstance(call, ast.Call) and call.func.attr == "array"
            found[node.targets[0].id] = ast.literal_eval(call.args[0])
    return found


def test_pyelastica_static_and_kinetic_arrays(groups, groups_with_mu_s):
    arrays = _pyelastica_arrays(
        write_pyelastica(groups_with_mu_s, pin=PIN, disc=DISC, pressure_kPa=11.79,
                         temperature_C=20.0)
    )
    assert arrays["kinetic_mu_array"] == pytest.approx([0.63] * 3)
    assert arrays["static_mu_array"] == pytest.approx([0.63 * 1.4] * 3)
    # no μ_S in the published map: static = kinetic, and the file says so
    text = write_pyelastica(groups, pin=PIN, disc=DISC, pressure_kPa=11.79, temperature_C=20.0)
    assert _pyelastica_arrays(text)["static_mu_array"] == pytest.approx([0.63] * 3)
    assert "mu_s unknown" in text


def test_single_value_writers_reject_unknown_pairs(groups):
    for writer in (write_mujoco, write_sofa, write_pyelastica):
        with pytest.raises(ExportError, match="Dragonskin 30 on steel"):
            writer(groups, pin="Ecoflex 00-50", disc="acrylic", pressure_kPa=10.0,
                   temperature_C=20.0)


def test_writers_do_not_modify_groups(groups):
    before = groups.copy()
    write_abaqus(groups)
    write_ansys(groups)
    write_mujoco(groups, pin=PIN, disc=DISC, pressure_kPa=40.0, temperature_C=12.0)
    pd.testing.assert_frame_equal(groups, before)


def test_options_that_do_not_apply_are_refused(groups):
    from tribopipe.export.simulators import export_simulator_input

    with pytest.raises(ExportError, match="every measured pressure"):
        export_simulator_input(groups, "abaqus", pin=PIN, disc=DISC, pressure_kPa=20.0)
    with pytest.raises(ExportError, match="exponential-decay"):
        export_simulator_input(groups, "ansys", decay_s_per_mm=10.0)
    with pytest.raises(ExportError, match="unknown simulator"):
        export_simulator_input(groups, "comsol")


def test_mujoco_geom_names_are_escaped(groups):
    text = write_mujoco(groups, pin=PIN, disc=DISC, pressure_kPa=35.37, temperature_C=20.0,
                        geom1='pin"1', geom2="a<b")
    pair = ET.fromstring(text[text.index("<mujoco>"):]).find("contact/pair")
    assert pair.get("geom1") == 'pin"1' and pair.get("geom2") == "a<b"


@settings(max_examples=30, deadline=None)
@given(
    st.lists(st.floats(1, 300), min_size=1, max_size=5, unique=True),
    st.lists(st.floats(-20, 80), min_size=1, max_size=3, unique=True),
    st.data(),
)
def test_abaqus_grid_property(pressures, temps, data):
    """Any grid with holes: the table is full, ordered, and every value is query's."""
    cells = [(p, t) for t in temps for p in pressures]
    keep = data.draw(st.lists(st.booleans(), min_size=len(cells), max_size=len(cells)))
    kept = [c for c, k in zip(cells, keep, strict=True) if k] or cells[:1]
    groups = pd.DataFrame(
        [{"pin": "A", "disc": "B", "pressure_kPa": p, "temperature_C": t,
          "mu_k_mean": data.draw(st.floats(0.05, 3.0)), "mu_k_n": 2,
          "mu_k_ci95_low": math.nan, "mu_k_ci95_high": math.nan} for p, t in kept]
    )
    rows = np.array(parse_abaqus(write_abaqus(groups))[abaqus_name("A", "B")]["rows"])
    p_kept = sorted({p for p, _ in kept})
    t_kept = sorted({t for _, t in kept})
    assert len(rows) == len(p_kept) * len(t_kept)
    expected_t = [t for t in t_kept for _ in p_kept]
    expected_p = [p for _ in t_kept for p in p_kept]
    assert rows[:, 3] == pytest.approx(expected_t, rel=1e-5, abs=1e-5)
    assert rows[:, 2] * 1e3 == pytest.approx(expected_p, rel=1e-5)
    for mu, p, t in zip(rows[:, 0], expected_p, expected_t, strict=True):
        assert mu == pytest.approx(query(groups, "A", "B", p, t).mu_k.value, rel=1e-8)
