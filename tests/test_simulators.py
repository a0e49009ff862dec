"""Simulator input: read back every file we write and check every number against the map."""

from __future__ import annotations

import math
import os

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from helpers import with_mu_s
from sim_files import (
    lsdyna_contact,
    mujoco_pair,
    parse_abaqus,
    parse_ansys,
    parse_lsdyna,
    pyelastica_values,
    sdf_friction,
    sofa_response,
    urdf_friction,
    usd_values,
)
from tribopipe.errors import ExportError
from tribopipe.escape import SIM_COMMENTS, sim_comment
from tribopipe.export import drake, fe_decks, pybullet, scenes, usd
from tribopipe.export.fe_decks import abaqus_name, deck_names, field10, write_abaqus, write_ansys
from tribopipe.export.formats import FORMATS
from tribopipe.export.simulators import export_simulator_input
from tribopipe.export.slip_rates import (
    FOUNDING_SLIP_RATE,
    SlipRate,
    default_decay_s_per_mm,
    pair_slip_rates,
)
from tribopipe.export.unit_systems import UNIT_SYSTEMS, convert_pressure_kPa
from tribopipe.export.xml_text import xml_comment
from tribopipe.query import pairs, query


def _at_condition(writer):
    """``writer`` (which takes a query result) called as the tests call it: the group
    table and the condition, queried here as export_simulator_input does."""

    def call(groups, *, pin, disc, pressure_kPa, temperature_C=None, **options):
        return writer(query(groups, pin, disc, pressure_kPa, temperature_C), **options)

    return call


write_abaqus_decay = _at_condition(fe_decks.write_abaqus_decay)
write_lsdyna = _at_condition(fe_decks.write_lsdyna)
write_mujoco = _at_condition(scenes.write_mujoco)
write_sofa = _at_condition(scenes.write_sofa)
write_pyelastica = _at_condition(scenes.write_pyelastica)
write_usd = _at_condition(usd.write_usd)
write_pybullet = _at_condition(pybullet.write_pybullet)
write_drake = _at_condition(drake.write_drake)

PIN, DISC = "Dragonskin 30", "steel"


@pytest.fixture(scope="module")
def groups_with_mu_s(groups) -> pd.DataFrame:
    """The published groups plus a μ_S column (the published map has none)."""
    return with_mu_s(groups)


def _steel_rates() -> dict[tuple[str, str], SlipRate]:
    return {(PIN, DISC): SlipRate(0.021, 4, 0.02, 0.022)}


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
    n = len(rows) // 2
    assert rows.shape == (2 * n, 4) and n > 5  # pressure rows added between the measured
    speed = 0.007 if units == "mm-N-s" else 0.007e-3
    assert rows[:, 1] == pytest.approx(np.full(2 * n, speed))
    # a full rectangular grid: n pressures × 2 temperatures, temperature outer
    assert list(rows[:, 3]) == [10.0] * n + [20.0] * n
    pressures_kPa = rows[:, 2] / factor
    assert list(pressures_kPa[:n]) == pytest.approx(list(pressures_kPa[n:]))
    assert {11.79, 35.37, 58.95, 82.52, 106.1} <= set(np.round(pressures_kPa, 2))
    assert f"{n - 5} pressure row(s) added between the measured pressures" in text
    for mu, _, p_kpa, t in np.column_stack([rows[:, 0], rows[:, 1], pressures_kPa, rows[:, 3]]):
        assert mu == pytest.approx(query(groups, PIN, DISC, p_kpa, t).mu_k.value, rel=1e-5)
    assert "map.parquet" in text
    assert "1 cell(s) not measured" in text  # 11.79 kPa at 10 °C


def test_abaqus_slip_rate_is_each_pairs_own(groups, runs):
    """Steel ran three times faster: its table says so, the other pairs keep theirs."""
    faster = runs.copy()
    faster.loc[faster["disc"] == DISC, "sliding_speed_mm_s"] = 0.021
    rates = pair_slip_rates(faster)
    assert rates[(PIN, DISC)] == SlipRate(0.021, 18, 0.021, 0.021)
    blocks = parse_abaqus(write_abaqus(groups, pin=PIN, units="m-N-s", slip_rates=rates))
    assert len(blocks) == len(pairs(groups[groups.pin == PIN])) == 9
    for pin, disc in pairs(groups[groups.pin == PIN]):
        slips = [row[1] for row in blocks[abaqus_name(pin, disc)]["rows"]]
        assert slips == pytest.approx([(0.021 if disc == DISC else 0.007) * 1e-3] * len(slips))


def test_slip_rates_flag_a_pair_run_at_different_speeds(runs):
    mixed = runs.copy()
    steel = mixed.index[mixed["disc"] == DISC]
    mixed.loc[steel[:4], "sliding_speed_mm_s"] = 0.05
    rate = pair_slip_rates(mixed)[(PIN, DISC)]
    assert (rate.n_runs, rate.min_mm_s, rate.max_mm_s) == (18, 0.007, 0.05)
    assert "FLAG" in rate.describe() and "no slip-rate dependence" in rate.describe()
    # excluded runs and missing speeds do not count; no speed at all: the founding 0.007
    mixed["excluded"] = False
    mixed.loc[steel[:4], "excluded"] = True
    assert pair_slip_rates(mixed)[(PIN, DISC)].max_mm_s == 0.007
    mixed["sliding_speed_mm_s"] = np.nan
    assert pair_slip_rates(mixed) == {}
    assert "founding paper" in FOUNDING_SLIP_RATE.describe()


def test_abaqus_pressure_units_are_converted():
    assert convert_pressure_kPa(11.79, "mm-N-s") == pytest.approx(0.01179)
    assert convert_pressure_kPa(11.79, "m-N-s") == pytest.approx(11790.0)
    assert UNIT_SYSTEMS["m-N-s"].speed_per_mm_s == 1e-3
    assert UNIT_SYSTEMS["m-N-s"].decay_per_s_per_mm == 1e3  # 1 s/mm = 1000 s/m
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
    assert rows.shape[0] > 5 and rows.shape[1] == 4
    assert set(rows[:, 3]) == {15.0}
    for mu, _, p_mpa, t in rows:
        assert mu == pytest.approx(query(groups, PIN, DISC, p_mpa * 1e3, t).mu_k.value, rel=1e-5)


def test_abaqus_selection_by_pin_only(groups):
    blocks = parse_abaqus(write_abaqus(groups, pin="Ecoflex 00-50"))
    assert set(blocks) == {abaqus_name("Ecoflex 00-50", "steel"),
                           abaqus_name("Ecoflex 00-50", "wood (smooth)")}
    with pytest.raises(ExportError, match="the map holds"):
        write_abaqus(groups, pin="Sylgard 184")


def test_abaqus_says_it_is_not_calculix_input(groups, groups_with_mu_s):
    for text in (write_abaqus(groups, pin=PIN, disc=DISC),
                 write_abaqus_decay(groups_with_mu_s, pin=PIN, disc=DISC, pressure_kPa=35.37,
                                    temperature_C=20.0)):
        flat = " ".join(line.lstrip("* ") for line in text.splitlines())
        assert "Abaqus input only, not for CalculiX" in flat
        assert "stick slope" in flat and "keeps only the last data line" in flat


@pytest.mark.parametrize("units,decay_factor,unit", [("mm-N-s", 1.0, "s/mm"),
                                                     ("m-N-s", 1e3, "s/m")])
def test_abaqus_exponential_decay(groups_with_mu_s, units, decay_factor, unit):
    text = write_abaqus_decay(
        groups_with_mu_s, pin=PIN, disc=DISC, pressure_kPa=35.37, temperature_C=20.0, units=units
    )
    block = parse_abaqus(text)[abaqus_name(PIN, DISC)]
    assert block["options"] == [("*FRICTION", ["EXPONENTIAL DECAY"])]
    (mu_s, mu_k, d_c), = block["rows"]
    assert mu_k == pytest.approx(0.45)
    assert mu_s == pytest.approx(0.45 * 1.4)
    assert d_c == pytest.approx(default_decay_s_per_mm() * decay_factor, rel=1e-5)
    # the comment gives d_c in the file's own units, the number of the data line
    stated = next(ln for ln in text.splitlines() if ln.startswith("** d_c = "))
    value, stated_unit = stated.split()[3:5]
    assert float(value) == pytest.approx(d_c) and stated_unit == unit
    # the default d_c makes μ 99 % kinetic at the measured sliding speed
    assert math.exp(-default_decay_s_per_mm() * 0.007) == pytest.approx(0.01)


def test_abaqus_exponential_decay_at_the_pairs_own_speed(groups_with_mu_s):
    text = write_abaqus_decay(groups_with_mu_s, pin=PIN, disc=DISC, pressure_kPa=35.37,
                              temperature_C=20.0, slip_rate=_steel_rates()[(PIN, DISC)])
    (_, _, d_c), = parse_abaqus(text)[abaqus_name(PIN, DISC)]["rows"]
    assert math.exp(-d_c * 0.021) == pytest.approx(0.01)


def test_abaqus_exponential_decay_needs_mu_s(groups):
    with pytest.raises(ExportError, match="no mu_s"):
        write_abaqus_decay(groups, pin=PIN, disc=DISC, pressure_kPa=35.37, temperature_C=20.0)


def test_deck_names_stay_unique_when_sanitised_names_collide():
    names = deck_names([("a b", "steel"), ("a_b", "steel"), ("c", "steel")])
    assert len(set(names.values())) == 3
    assert names[("c", "steel")] == abaqus_name("c", "steel")
    assert all(len(n) <= 80 for n in names.values())
    long = deck_names([("x" * 100, "y"), ("x" * 100 + "!", "y")], limit=70)
    assert len(set(long.values())) == 2 and all(len(n) <= 70 for n in long.values())


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


@pytest.mark.parametrize("fmt", ["abaqus", "ansys"])
def test_the_engines_linear_reading_stays_within_tolerance_of_query(groups, fmt):
    """Read every pair's table as the engine does (linear between rows and temperatures)
    and compare with query on a fine grid over the measured range."""
    from sim_files import engine_reading
    from tribopipe.interpolation import ENGINE_TOLERANCE

    if fmt == "abaqus":
        names = {abaqus_name(p, d): (p, d) for p, d in pairs(groups)}
        tables = {names[name]: [(r[3], r[2] * 1e3, r[0]) for r in block["rows"]]
                  for name, block in parse_abaqus(write_abaqus(groups)).items()}
    else:
        tables = {pair: [(t, p * 1e3, mu) for t, p, mu in entries] for pair, (_, entries)
                  in zip(pairs(groups), sorted(parse_ansys(write_ansys(groups)).items()),
                         strict=True)}
    worst = 0.0
    for (pin, disc), entries in tables.items():
        pair = groups[(groups.pin == pin) & (groups.disc == disc)]
        ps = np.geomspace(pair.pressure_kPa.min(), pair.pressure_kPa.max(), 29)
        temps = sorted(set(pair.temperature_C))
        ts = sorted(set(temps) | {(temps[0] + temps[-1]) / 2 + 0.5})
        for p in ps:
            for t in ts:
                gap = abs(engine_reading(entries, p, t) - query(groups, pin, disc, p, t).mu_k.value)
                worst = max(worst, gap)
    assert worst <= ENGINE_TOLERANCE


# ---------------------------------------------------------------------------- LS-DYNA


def test_lsdyna_default_is_kinetic_coulomb_friction(groups):
    text = write_lsdyna(groups, pin=PIN, disc=DISC, pressure_kPa=47.16, temperature_C=20.0,
                        pin_part=11, disc_part=12, contact_id=7)
    card = lsdyna_contact(text)
    expected = query(groups, PIN, DISC, 47.16, 20.0).mu_k.value
    w = math.log(47.16 / 35.37) / math.log(58.95 / 35.37)  # log p - log mu between groups
    assert expected == pytest.approx(0.45 ** (1 - w) * 0.36 ** w)
    assert card["fs"] == pytest.approx(expected, rel=1e-6)
    assert card["fd"] == card["fs"] and card["dc"] == 0.0
    assert (card["cid"], card["surfa"], card["surfb"]) == (7, 11, 12)
    assert (card["surfatyp"], card["surfbtyp"]) == (3, 3)  # part IDs
    assert card["heading"] == abaqus_name(PIN, DISC)
    assert "holds: FS = FD = mu_k" in text


@pytest.mark.parametrize("units,factor,unit", [("mm-N-s", 1.0, "s/mm"), ("m-N-s", 1e3, "s/m")])
def test_lsdyna_static_dynamic_and_decay(groups_with_mu_s, units, factor, unit):
    text = write_lsdyna(groups_with_mu_s, pin=PIN, disc=DISC, pressure_kPa=35.37,
                        temperature_C=20.0, units=units, coefficient="mu_s",
                        slip_rate=_steel_rates()[(PIN, DISC)])
    card = lsdyna_contact(text)
    assert card["fs"] == pytest.approx(0.45 * 1.4) and card["fd"] == pytest.approx(0.45)
    # DC in 1/velocity of the unit system: 99 % decayed at the pair's 0.021 mm/s
    assert card["dc"] == pytest.approx(math.log(100) / 0.021 * factor, rel=1e-6)
    assert f"DC = {card['dc']:.6g}"[:8] in text.replace("\n$   ", " ")
    assert f" {unit} " in text
    given = lsdyna_contact(write_lsdyna(groups_with_mu_s, pin=PIN, disc=DISC, pressure_kPa=35.37,
                                        temperature_C=20.0, units=units, coefficient="mu_s",
                                        decay_s_per_mm=2.5))
    assert given["dc"] == pytest.approx(2.5 * factor)


def test_lsdyna_refusals_are_one_line(groups, groups_with_mu_s):
    cond = {"pin": PIN, "disc": DISC, "pressure_kPa": 35.37, "temperature_C": 20.0}
    with pytest.raises(ExportError, match="no mu_s in the map") as err:
        write_lsdyna(groups, coefficient="mu_s", **cond)
    assert "\n" not in str(err.value) and "--coefficient mu_s" in str(err.value)
    with pytest.raises(ExportError, match="needs FS = mu_s"):
        write_lsdyna(groups_with_mu_s, decay_s_per_mm=3.0, **cond)
    with pytest.raises(ExportError, match="from 1 to"):
        write_lsdyna(groups, pin_part=0, **cond)
    with pytest.raises(ExportError, match="positive"):
        write_lsdyna(groups_with_mu_s, coefficient="mu_s", decay_s_per_mm=-1.0, **cond)


@pytest.mark.parametrize("value", [0.45, 0.0, 1.0, 657.8814551, 657881.4551, 1.234567e-7,
                                   0.7033333333, 12345678901.0, -0.5])
def test_lsdyna_fields_are_ten_columns_with_a_blank(value):
    text = field10(value)
    assert len(text) == 10 and text[0] == " "
    assert float(text) == pytest.approx(value, rel=1e-3)
    assert "." in text or "e" in text  # a real, not an integer
    assert field10(3) == "         3"
    with pytest.raises(ExportError):
        field10(math.nan)


# ---------------------------------------------------------------------------- single values


def test_mujoco_pair_friction(groups):
    text = write_mujoco(groups, pin=PIN, disc=DISC, pressure_kPa=47.16, temperature_C=20.0,
                        geom1="finger", geom2="table")
    pair = mujoco_pair(text)
    assert pair.get("geom1") == "finger" and pair.get("geom2") == "table"
    friction = [float(v) for v in pair.get("friction").split()]
    expected = query(groups, PIN, DISC, 47.16, 20.0).mu_k.value
    assert friction == pytest.approx([expected, expected, 0.005, 0.0001, 0.0001], rel=1e-5)
    w = math.log(47.16 / 35.37) / math.log(58.95 / 35.37)  # log p - log mu between groups
    assert expected == pytest.approx(0.45 ** (1 - w) * 0.36 ** w)
    assert "element-wise maximum" in text and "overrides both" in text


def test_sofa_response_mu_and_the_solvers_that_use_it(groups):
    text = write_sofa(groups, pin=PIN, disc=DISC, pressure_kPa=106.1, temperature_C=20.0)
    response = sofa_response(text)
    assert response.get("response") == "FrictionContactConstraint"
    key, value = response.get("responseParams").split("=")
    assert key == "mu" and float(value) == pytest.approx(0.26)
    assert "LCPConstraintSolver applies its own mu (default 0.6)" in text
    assert "GenericConstraintSolver" in text and "BlockGaussSeidelConstraintSolver" in text


@pytest.mark.parametrize("writer", [write_mujoco, write_sofa])
def test_the_xml_header_names_the_mu_s_option_readably(groups, writer):
    # an XML comment cannot hold "--": the header must not print a mangled "- -coefficient"
    text = writer(groups, pin=PIN, disc=DISC, pressure_kPa=47.16, temperature_C=20.0)
    holds = next(line for line in text.splitlines() if "holds:" in line)
    assert "'coefficient mu_s' writes mu_s (breakaway) instead" in holds
    assert "- -" not in text


def test_pyelastica_arrays(groups, groups_with_mu_s):
    cond = {"pin": PIN, "disc": DISC, "pressure_kPa": 11.79, "temperature_C": 20.0}
    default = pyelastica_values(write_pyelastica(groups_with_mu_s, **cond))
    assert default["kinetic_mu_array"] == pytest.approx([0.63] * 3)
    assert default["static_mu_array"] == pytest.approx([0.63] * 3)  # mu_k unless asked
    assert default["PAIR"] == (PIN, DISC)
    breakaway = pyelastica_values(write_pyelastica(groups_with_mu_s, coefficient="mu_s", **cond))
    assert breakaway["static_mu_array"] == pytest.approx([0.63 * 1.4] * 3)
    assert breakaway["kinetic_mu_array"] == pytest.approx([0.63] * 3)
    text = write_pyelastica(groups, **cond)
    assert "RodPlaneContactWithAnisotropicFriction" in text
    assert "detect_contact_between(rod, plane)" in text
    # detect_contact_between is a method of the Contact mixin: the usage must say so
    assert "class Simulator(BaseSystemCollection, Contact)" in text
    assert "AnisotropicFrictionalPlane is gone" in text


def _onset_mu(text: str) -> float:
    """The coefficient for the onset of slip a MuJoCo, SOFA or PyElastica file holds."""
    if text.lstrip().startswith("#"):
        return pyelastica_values(text)["static_mu_array"][0]
    if "<mujoco>" in text:
        return float(mujoco_pair(text).get("friction").split()[0])
    return float(sofa_response(text).get("responseParams").split("=")[1])


@pytest.mark.parametrize("writer", [write_mujoco, write_sofa, write_pyelastica])
def test_coefficient_mu_s_writes_the_breakaway_value(groups_with_mu_s, writer):
    cond = {"pin": PIN, "disc": DISC, "pressure_kPa": 35.37, "temperature_C": 20.0}
    kinetic, static = (writer(groups_with_mu_s, coefficient=c, **cond) for c in ("mu_k", "mu_s"))
    assert _onset_mu(kinetic) == pytest.approx(0.45)
    assert _onset_mu(static) == pytest.approx(0.45 * 1.4)
    assert "= mu_k, the kinetic" in kinetic and "= mu_s, the static (breakaway)" in static


@pytest.mark.parametrize("fmt", ["mujoco", "sofa", "pyelastica", "lsdyna"])
def test_coefficient_mu_s_is_refused_where_the_map_has_none(groups, fmt):
    with pytest.raises(ExportError) as err:
        export_simulator_input(groups, fmt, pin=PIN, disc=DISC, pressure_kPa=35.37,
                               temperature_C=20.0, coefficient="mu_s")
    message = str(err.value)
    assert "\n" not in message and "no mu_s in the map" in message
    assert "'Dragonskin 30' on disc 'steel'" in message


def test_single_value_writers_reject_unknown_pairs(groups):
    for writer in (write_mujoco, write_sofa, write_pyelastica, write_lsdyna):
        with pytest.raises(ExportError, match="Dragonskin 30 on steel"):
            writer(groups, pin="Ecoflex 00-50", disc="acrylic", pressure_kPa=10.0,
                   temperature_C=20.0)


def test_writers_do_not_modify_groups(groups):
    before = groups.copy()
    write_abaqus(groups)
    write_ansys(groups)
    write_mujoco(groups, pin=PIN, disc=DISC, pressure_kPa=40.0, temperature_C=12.0)
    write_lsdyna(groups, pin=PIN, disc=DISC, pressure_kPa=40.0, temperature_C=12.0)
    pd.testing.assert_frame_equal(groups, before)


@pytest.mark.parametrize("fmt", ["abaqus", "ansys"])
def test_abaqus_and_ansys_take_a_single_condition(groups, fmt):
    """As the explorer offers: one pair at one pressure gives its constant mu_K, the text
    of the single-condition snippet (condition_snippet of the same query)."""
    from tribopipe.export.fe_decks import condition_snippet

    text = export_simulator_input(groups, fmt, pin=PIN, disc=DISC, pressure_kPa=35.0,
                                  temperature_C=12.0, source="m.parquet")
    res = query(groups, PIN, DISC, 35.0, 12.0)
    assert text == condition_snippet(res, fmt, source="m.parquet")
    assert f"{res.mu_k.value:.10g}" in text.splitlines()[-1]
    # at 10 °C the pair is measured from 35.37 kPa up: 35 kPa is held at that edge, and
    # the value carries no U
    assert res.mu_k.clamped_pressure and "(U, k = 2)" not in text
    assert "extrapolated: U not valid" in text
    inside = query(groups, PIN, DISC, 50.0, 12.0)
    assert not inside.clamped
    assert "(U, k = 2)" in condition_snippet(inside, fmt, source="m.parquet")
    with pytest.raises(ExportError, match="takes one condition; give --pin .*; --disc "):
        export_simulator_input(groups, fmt, pressure_kPa=35.0)


def test_options_that_do_not_apply_are_refused(groups):
    with pytest.raises(ExportError, match="exponential-decay"):
        export_simulator_input(groups, "ansys", decay_s_per_mm=10.0)
    with pytest.raises(ExportError, match="exponential-decay"):
        export_simulator_input(groups, "mujoco", pin=PIN, disc=DISC, pressure_kPa=20.0,
                               decay_s_per_mm=10.0)
    for fmt in ("abaqus", "ansys"):
        with pytest.raises(ExportError, match="--coefficient is for"):
            export_simulator_input(groups, fmt, coefficient="mu_s")
    with pytest.raises(ExportError, match="unknown coefficient"):
        export_simulator_input(groups, "mujoco", coefficient="mu")
    with pytest.raises(ExportError, match="unknown simulator"):
        export_simulator_input(groups, "comsol")


def test_mujoco_geom_names_are_escaped_or_refused(groups):
    cond = {"pin": PIN, "disc": DISC, "pressure_kPa": 35.37, "temperature_C": 20.0}
    pair = mujoco_pair(write_mujoco(groups, geom1='pin"1', geom2="a<b&'c", **cond))
    assert pair.get("geom1") == 'pin"1' and pair.get("geom2") == "a<b&'c"
    with pytest.raises(ExportError, match="control character"):
        write_mujoco(groups, geom1="pin\n<x/>", **cond)


# ---------------------------------------------------------------------------- headers


def _all_files(groups, groups_with_mu_s) -> dict[str, str]:
    """One file of every kind the exporters write."""
    cond = {"pin": PIN, "disc": DISC, "pressure_kPa": 35.37, "temperature_C": 20.0}
    return {
        "abaqus": write_abaqus(groups, pin=PIN, disc=DISC),
        "abaqus decay": write_abaqus_decay(groups_with_mu_s, **cond),
        "ansys": write_ansys(groups, pin=PIN, disc=DISC),
        "lsdyna": write_lsdyna(groups, **cond),
        "lsdyna mu_s": write_lsdyna(groups_with_mu_s, coefficient="mu_s", **cond),
        "mujoco": write_mujoco(groups, **cond),
        "sofa": write_sofa(groups, **cond),
        "pyelastica": write_pyelastica(groups, **cond),
        "usd": write_usd(groups, **cond),
        "usd mu_s": write_usd(groups_with_mu_s, **cond),
        "pybullet": write_pybullet(groups, **cond),
        "drake": write_drake(groups, **cond),
        "drake mu_s": write_drake(groups_with_mu_s, **cond),
    }


def test_every_header_names_engine_version_coefficient_and_combination(
    groups, groups_with_mu_s
):
    versions = {"abaqus": "2017-2024", "ansys": "2025 R1", "lsdyna": "R14",
                "mujoco": "mujoco 4.0.0", "sofa": "v24.12", "pyelastica": "pyelastica 1.0.0",
                "usd": "usd-core 26.11", "pybullet": "pybullet 3.2.7", "drake": "drake 1.51.1"}
    for kind, text in _all_files(groups, groups_with_mu_s).items():
        head = " ".join(text.splitlines()[:12])
        assert "checked against:" in head, kind
        assert versions[kind.split()[0]] in head, kind
        holds = head.split("holds:")[1][:120]
        assert "mu_k" in holds, kind
        assert ("mu_s" in holds) == (kind in ("abaqus decay", "lsdyna mu_s")
                                     or kind in ("mujoco", "sofa", "pyelastica", "pybullet")
                                     or kind.split()[0] in ("usd", "drake")), kind
        assert "two surfaces:" in head, kind
    assert set(FORMATS) == {k.split()[0] for k in versions}


# ---------------------------------------------------------------------------- hostile names

HOSTILE = "Evil\n*HEADING\r\n** x'\"</pair><!-- -->--$ import os\x00\x1b\u2028end"


@pytest.fixture(scope="module")
def hostile_groups(groups_with_mu_s) -> pd.DataFrame:
    g = groups_with_mu_s.copy()
    g.loc[(g.pin == PIN) & (g.disc == DISC), "pin"] = HOSTILE
    return g


def test_sim_comment_leaves_no_line_break_or_control_character():
    for syntax in SIM_COMMENTS:
        text = sim_comment(HOSTILE, syntax)
        assert all(ch.isprintable() for ch in text)
        assert "\n" not in text and "\r" not in text and "\u2028" not in text
    for syntax in ("**", "$", "!"):
        assert sim_comment(HOSTILE, syntax).isascii()
    assert "$" not in sim_comment(HOSTILE, "!")
    assert "--" not in xml_comment(HOSTILE)[4:-3]


def test_hostile_names_stay_data_in_every_file(hostile_groups):
    cond = {"pin": HOSTILE, "disc": DISC, "pressure_kPa": 35.37, "temperature_C": 20.0}
    source = "maps/" + HOSTILE + ".parquet"
    files = {
        "abaqus": write_abaqus(hostile_groups, pin=HOSTILE, disc=DISC, source=source),
        "abaqus decay": write_abaqus_decay(hostile_groups, source=source, **cond),
        "ansys": write_ansys(hostile_groups, pin=HOSTILE, disc=DISC, source=source),
        "lsdyna": write_lsdyna(hostile_groups, coefficient="mu_s", source=source, **cond),
        "mujoco": write_mujoco(hostile_groups, source=source, **cond),
        "sofa": write_sofa(hostile_groups, source=source, **cond),
        "pyelastica": write_pyelastica(hostile_groups, source=source, **cond),
        "usd": write_usd(hostile_groups, source=source, **cond),
        "pybullet": write_pybullet(hostile_groups, source=source, **cond),
        "drake": write_drake(hostile_groups, source=source, **cond),
    }
    expected_mu_k = query(hostile_groups, HOSTILE, DISC, 35.37, 20.0).mu_k.value
    for kind, text in files.items():
        assert "\r" not in text and "\x00" not in text and "\u2028" not in text, kind
        assert not any(line.startswith("*HEADING") for line in text.split("\n")), kind
    # each file reads back with its strict parser: only our keywords, commands, elements
    abaqus = parse_abaqus(files["abaqus"])
    assert list(abaqus) == [abaqus_name(HOSTILE, DISC)]
    assert abaqus_name(HOSTILE, DISC).replace("_", "").isalnum()
    assert list(parse_abaqus(files["abaqus decay"])) == [abaqus_name(HOSTILE, DISC)]
    assert list(parse_ansys(files["ansys"])) == [1]
    assert files["abaqus"].isascii() and files["ansys"].isascii()
    card = lsdyna_contact(files["lsdyna"])
    assert card["fd"] == pytest.approx(expected_mu_k)
    assert card["heading"].replace("_", "").isalnum()
    assert files["lsdyna"].isascii()
    assert all(ln.startswith("$") for ln in files["lsdyna"].split("*KEYWORD")[0].splitlines())
    assert float(mujoco_pair(files["mujoco"]).get("friction").split()[0]) == pytest.approx(
        expected_mu_k)
    assert sofa_response(files["sofa"]).get("responseParams") == f"mu={expected_mu_k:.10g}"
    values = pyelastica_values(files["pyelastica"])
    assert values["PAIR"] == (HOSTILE, DISC)  # the exact name, as a Python literal
    assert values["kinetic_mu_array"] == pytest.approx([expected_mu_k] * 3)
    for kind in ("usd", "pybullet", "drake"):  # names only in ASCII comments
        assert files[kind].isascii(), kind
        assert "Evil" not in "".join(line for line in files[kind].splitlines()
                                     if not line.startswith(("#", "<!--"))), kind
    assert usd_values(files["usd"])["dynamic"] == pytest.approx(expected_mu_k)
    assert urdf_friction(files["pybullet"]) == ("pin", pytest.approx(expected_mu_k))
    assert sdf_friction(files["drake"])["pin"][1] == pytest.approx(expected_mu_k)


@pytest.mark.parametrize("fmt", ["abaqus", "ansys"])
def test_hostile_names_in_tables_of_every_pair(hostile_groups, fmt):
    text = export_simulator_input(hostile_groups, fmt)
    parsed = parse_abaqus(text) if fmt == "abaqus" else parse_ansys(text)
    assert len(parsed) == len(pairs(hostile_groups))


# ---------------------------------------------------------------------------- properties


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
    n = len(rows) // len(t_kept)
    assert len(rows) == n * len(t_kept) and n >= len(p_kept)
    p_rows = list(rows[:n, 2] * 1e3)
    assert rows[:, 3] == pytest.approx([t for t in t_kept for _ in range(n)], rel=1e-5,
                                       abs=1e-5)
    assert all(min(abs(r - p) for r in p_rows) <= 1e-5 * p for p in p_kept)
    assert p_rows == sorted(p_rows) and min(p_rows) == pytest.approx(p_kept[0], rel=1e-5)
    for mu, p_mpa, t in zip(rows[:, 0], rows[:, 2], rows[:, 3], strict=True):
        # the file's pressures carry 10 digits; a steep drawn law magnifies that
        assert mu == pytest.approx(query(groups, "A", "B", p_mpa * 1e3, t).mu_k.value,
                                   rel=1e-6)


@settings(max_examples=60, deadline=None)
@given(st.text(min_size=1, max_size=40))
def test_any_name_stays_a_comment_or_a_literal(name):
    """Whatever a pin is called, the files parse back with only what we write."""
    groups = pd.DataFrame([{"pin": name, "disc": "B", "pressure_kPa": 10.0,
                            "temperature_C": 20.0, "mu_k_mean": 0.5, "mu_k_n": 2,
                            "mu_k_ci95_low": 0.4, "mu_k_ci95_high": 0.6}])
    cond = {"pin": name, "disc": "B", "pressure_kPa": 10.0, "temperature_C": 20.0}
    assert len(parse_abaqus(write_abaqus(groups))) == 1
    assert len(parse_ansys(write_ansys(groups))) == 1
    assert lsdyna_contact(write_lsdyna(groups, **cond))["fs"] == 0.5
    assert mujoco_pair(write_mujoco(groups, **cond)).get("friction").startswith("0.5 0.5")
    assert sofa_response(write_sofa(groups, **cond)).get("responseParams") == "mu=0.5"
    assert pyelastica_values(write_pyelastica(groups, **cond))["PAIR"] == (name, "B")
    assert parse_lsdyna(write_lsdyna(groups, **cond))[0][0] == "*KEYWORD"
    assert usd_values(write_usd(groups, **cond)) == {"dynamic": 0.5, "static": 0.5,
                                                     "mode": "average"}
    assert urdf_friction(write_pybullet(groups, **cond)) == ("pin", 0.5)
    assert sdf_friction(write_drake(groups, **cond)) == {"pin": (0.5, 0.5),
                                                         "disc": (0.5, 0.5)}


# ---------------------------------------------------------------------------- usd, pybullet, drake


def test_static_coefficient_where_mu_s_is_unknown_or_below_mu_k(groups, groups_with_mu_s):
    cond = {"pin": PIN, "disc": DISC, "pressure_kPa": 35.37, "temperature_C": 20.0}
    mu_k = query(groups, PIN, DISC, 35.37, 20.0).mu_k.value
    # unknown: mu_k written as the static coefficient, and said so
    for text in (write_usd(groups, **cond), write_drake(groups, **cond)):
        assert "static = mu_k: the map holds no mu_s for this pair" in text
    assert usd_values(write_usd(groups, **cond))["static"] == pytest.approx(mu_k)
    # measured and above mu_k: written as it is
    assert usd_values(write_usd(groups_with_mu_s, **cond))["static"] == pytest.approx(
        1.4 * mu_k)
    # below mu_k: raised to mu_k (Drake would refuse the file), and said so
    low = groups_with_mu_s.copy()
    low["mu_s_mean"] = low["mu_k_mean"] * 0.8
    text = write_drake(low, **cond)
    assert "is below mu_k at this condition" in text
    assert sdf_friction(text)["pin"] == (pytest.approx(mu_k), pytest.approx(mu_k))


def test_new_formats_refuse_what_they_do_not_take(groups):
    cond = {"pin": PIN, "disc": DISC, "pressure_kPa": 35.37, "temperature_C": 20.0}
    with pytest.raises(ExportError, match="--coefficient is for .*pybullet; not for usd"):
        export_simulator_input(groups, "usd", coefficient="mu_s", **cond)
    with pytest.raises(ExportError, match="--units is for abaqus, ansys, lsdyna; not for drake"):
        export_simulator_input(groups, "drake", units="m-N-s", **cond)
    # a table format at one pressure is that condition's constant: it needs the pair
    with pytest.raises(ExportError, match="ansys --pressure takes one condition; give --pin "):
        export_simulator_input(groups, "ansys", pressure_kPa=20.0)
    with pytest.raises(ExportError, match="usd takes one condition"):
        export_simulator_input(groups, "usd", pin=PIN, disc=DISC)
    high = groups.copy()
    high["mu_k_mean"] = 12.0
    with pytest.raises(ExportError, match="exceeds Bullet's clamp"):
        export_simulator_input(high, "pybullet", **cond)


def test_every_registry_entry_resolves_and_declares_what_its_writer_takes():
    """The registry holds the writer functions themselves, one entry per format in the
    formats' order, and a writer's keyword arguments are exactly the options its format
    declares (plus what export_simulator_input passes), so that no option is dropped or
    unknown."""
    import inspect

    from tribopipe.export.formats import ENTRIES, UNITS
    from tribopipe.export.headers import Engine
    from tribopipe.export.registry import WRITERS

    assert UNITS.choices == tuple(UNIT_SYSTEMS)
    assert [w.format for w in WRITERS] == list(ENTRIES)
    for w in WRITERS:
        spec = w.format
        assert isinstance(w.engine, Engine), w.name
        for target, options, passed in (
            (w.table, spec.table_options, {"pin", "disc", "temperature_C", "source"}
             | ({"slip_rates"} if spec.slip_rate else set())),
            (w.condition, spec.condition_options,
             {"source"} | ({"slip_rate"} if spec.slip_rate else set())
             | ({"speed_curve"} if spec.speed_curve else set())),
        ):
            if target is None:
                continue
            params = inspect.signature(target).parameters
            keywords = {n for n, p in params.items() if p.kind is p.KEYWORD_ONLY}
            assert keywords == passed | {o.name for o in options}, (w.name, target)
            for option in options:
                assert option.check is None or callable(option.check)
        assert (w.snippet is None) == (w.snippet_header is None) == (not spec.snippet), w.name
        if w.snippet is not None:
            assert callable(w.snippet) and callable(w.snippet_header), w.name


def test_a_writer_entry_must_have_the_writers_its_format_declares():
    """A registry entry whose functions are not those its format declares is refused
    when it is made (so the light list the command line reads cannot drift)."""
    from tribopipe.export.formats import format_named
    from tribopipe.export.registry import Writer
    from tribopipe.export.scenes import MUJOCO, write_mujoco

    with pytest.raises(TypeError, match="the writers of abaqus are not those"):
        Writer(format_named("abaqus"), MUJOCO, condition=write_mujoco)
    with pytest.raises(TypeError, match="the writers of mujoco are not those"):
        Writer(format_named("mujoco"), MUJOCO, table=write_abaqus, condition=write_mujoco)


# ---------------------------------------------------------------------------- every pair


@pytest.mark.parametrize("speeds,temperature", [
    ("one", None), ("one", 15.0), pytest.param("three", None, marks=pytest.mark.slow)])
def test_every_pair_tables_read_each_pair_once_and_equal_the_one_pair_tables(
        groups, monkeypatch, temperature, speeds):
    """A table over every pair selects each pair's groups once and computes the map's κ
    once (per speed): never a pass over the whole group table per pair, which made the
    export of every pair grow with the square of the pairs. Each pair's table is the one
    its own export writes (κ of the whole map in both)."""
    from test_speed_condition import _multi_speed_runs
    from tribopipe import query as query_module
    from tribopipe.export import engine_tables
    from tribopipe.query import groups_of

    table = groups if speeds == "one" else groups_of(_multi_speed_runs(), "map")
    held = pairs(table)
    one = {pair: write_abaqus(table, pin=pair[0], disc=pair[1], temperature_C=temperature)
           for pair in held}
    one_ansys = {pair: write_ansys(table, pin=pair[0], disc=pair[1], material_id=k,
                                   temperature_C=temperature)
                 for k, pair in enumerate(held, 1)}
    passes: list[str] = []
    curvature, select = query_module.map_curvature, query_module.select_pair

    def counted_curvature(frame, quantity="mu_k"):
        if len(frame) == len(table):
            passes.append(f"curvature {quantity}")
        return curvature(frame, quantity)

    def counted_select(frame, pin, disc):
        if len(frame) == len(table):
            passes.append("select")
        return select(frame, pin, disc)

    for module in (query_module, engine_tables):
        monkeypatch.setattr(module, "map_curvature", counted_curvature)
        monkeypatch.setattr(module, "select_pair", counted_select)
    every = write_abaqus(table, temperature_C=temperature)
    every_ansys = write_ansys(table, temperature_C=temperature)
    # no pair selected from the whole table; κ of μ_K and μ_S once per writer (μ_S's
    # falls back to μ_K's where it has no interior point: at most 3 passes a writer),
    # however many pairs
    assert "select" not in passes and len(passes) <= 6, passes
    assert len(held) > 10
    # the file of every pair is the files of each pair after their common header
    for whole, single in ((every, one), (every_ansys, one_ansys)):
        texts = [single[pair] for pair in held]
        head = os.path.commonprefix(texts)
        head = head[:head.rindex("\n") + 1]  # up to the blank comment line before a pair
        head = head[:head.rindex("\n", 0, len(head) - 1) + 1]
        assert whole == head + "".join(text[len(head):] for text in texts)
