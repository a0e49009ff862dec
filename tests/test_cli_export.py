"""`tribopipe query`, `tribopipe export ...` and the `map fit` command, end to end on a real
Parquet map imported from the published friction map."""

from __future__ import annotations

import dataclasses
import json
import math
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner

from published_map import PUBLISHED_CSV, write_published_map
from sim_files import (
    lsdyna_contact,
    mujoco_pair,
    parse_abaqus,
    parse_ansys,
    pyelastica_values,
    sdf_friction,
    urdf_friction,
    usd_values,
)
from tribopipe.cli import main
from tribopipe.cli.fit import fit_cmd
from tribopipe.query import query

PIN, DISC = "Dragonskin 30", "steel"


@pytest.fixture(scope="module")
def map_path(tmp_path_factory) -> Path:
    return write_published_map(PUBLISHED_CSV,
                               tmp_path_factory.mktemp("map") / "friction_map.parquet")


def _run(*args: str):
    return CliRunner().invoke(main, list(args), catch_exceptions=False)


def test_query_json_matches_the_library(map_path, groups):
    result = _run("query", "--map", str(map_path), "--pin", PIN, "--disc", DISC,
                  "--pressure", "47.16", "--temperature", "12.5", "--json")
    assert result.exit_code == 0, result.output
    data = json.loads(result.output)
    expected = query(groups, PIN, DISC, 47.16, 12.5)
    assert data["mu_k"]["value"] == pytest.approx(expected.mu_k.value)
    assert data["mu_k"]["uncertainty"] == pytest.approx(expected.mu_k.uncertainty)
    assert data["clamped"] is False
    assert data["mu_s"] is None
    assert len(data["mu_k"]["used"]) == 4


def test_query_text_says_what_it_used_and_that_it_clamped(map_path):
    result = _run("query", "--map", str(map_path), "--pin", PIN, "--disc", DISC,
                  "--pressure", "200", "--temperature", "20")
    assert result.exit_code == 0
    assert "mu_k = 0.260" in result.output
    assert "clamped: yes" in result.output
    assert "106.1 kPa, 20 °C, 0.260, n=2, w=1.000" in result.output


def test_query_force_converts_through_the_instrument_config(map_path, groups, tmp_path):
    from tribopipe.physics import contact_pressure_kPa

    result = _run("query", "--map", str(map_path), "--pin", PIN, "--disc", DISC,
                  "--force", "4", "--temperature", "20", "--json")
    assert result.exit_code == 0, result.output
    data = json.loads(result.output)
    p = float(contact_pressure_kPa(4.0, 3, 3.0))  # the default T-PID/44: 3 pins of r = 3 mm
    assert data["pressure_kPa"] == pytest.approx(p) and data["normal_force_N"] == 4.0
    assert data["mu_k"]["value"] == pytest.approx(query(groups, PIN, DISC, p, 20.0).mu_k.value)
    # another cell: one pin of radius 2 mm
    config = tmp_path / "one_pin.toml"
    config.write_text("[instrument]\nn_pins = 1\npin_radius_mm = 2.0\n", encoding="utf-8")
    text = _run("query", "--map", str(map_path), "--pin", PIN, "--disc", DISC, "--force",
                "0.5", "--temperature", "20", "--instrument", str(config)).output
    p1 = float(contact_pressure_kPa(0.5, 1, 2.0))
    assert f"at {p1:.4g} kPa (0.5 N on 1 pin(s) of radius 2 mm)" in text
    both = CliRunner().invoke(main, ["query", "--map", str(map_path), "--pin", PIN, "--disc",
                                     DISC, "--force", "1", "--pressure", "10"])
    assert both.exit_code == 2 and "exactly one of --pressure and --force" in both.output
    for bad in ("0", "-3", "nan", "inf"):
        refused = CliRunner().invoke(main, ["query", "--map", str(map_path), "--pin", PIN,
                                            "--disc", DISC, "--force", bad])
        assert refused.exit_code == 2 and "Traceback" not in refused.output, refused.output
        assert "--force" in refused.output and "finite number > 0 N" in refused.output


def test_query_unknown_pair_is_one_friendly_line(map_path):
    result = CliRunner().invoke(main, ["query", "--map", str(map_path), "--pin", PIN,
                                       "--disc", "glass", "--pressure", "20",
                                       "--temperature", "20"])
    assert result.exit_code == 1
    assert "Traceback" not in result.output
    lines = [ln for ln in result.output.splitlines() if ln.strip()]
    assert len(lines) == 1
    assert "the map holds" in lines[0] and "Dragonskin 30 on acrylic glass" in lines[0]


def test_query_without_map_says_so(tmp_path):
    result = CliRunner().invoke(main, ["query", "--map", str(tmp_path / "none.parquet"),
                                       "--pin", PIN, "--disc", DISC, "--pressure", "20"])
    assert result.exit_code == 1
    assert "empty or absent" in result.output


@pytest.mark.parametrize("units,factor", [("mm-N-s", 1e-3), ("m-N-s", 1e3)])
def test_export_abaqus_to_file(map_path, groups, tmp_path, units, factor):
    out = tmp_path / "friction.inp"
    result = _run("export", "abaqus", "--map", str(map_path), "--pin", PIN, "--disc", DISC,
                  "--units", units, "-o", str(out))
    assert result.exit_code == 0
    rows = [
        [float(v) for v in line.split(",")]
        for line in out.read_text().splitlines()
        if line and not line.startswith("*")
    ]
    assert len(rows) > 10  # 5 x 2 measured cells and the rows added between them
    for mu, _, p, t in rows:
        assert mu == pytest.approx(query(groups, PIN, DISC, p / factor, t).mu_k.value, rel=1e-5)
    assert str(map_path) in out.read_text()


def test_export_and_fit_write_into_a_new_folder(map_path, tmp_path):
    # -o goes through the shared atomic writer, like `map table -o`: the folder is made
    out = tmp_path / "new" / "friction.inp"
    result = _run("export", "abaqus", "--map", str(map_path), "-o", str(out))
    assert result.exit_code == 0
    assert out.read_text() == _run("export", "abaqus", "--map", str(map_path)).stdout
    fits = tmp_path / "new" / "fits" / "fits.csv"
    assert _run("map", "fit", "--map", str(map_path), "-o", str(fits)).exit_code == 0
    assert len(pd.read_csv(fits)) > 0
    assert not list(tmp_path.rglob("*.tmp"))


def test_export_ansys_stdout(map_path):
    result = _run("export", "ansys", "--map", str(map_path), "--pin", "Ecoflex 00-50",
                  "--material-id", "7")
    assert result.exit_code == 0
    assert sorted(parse_ansys(result.output)) == [7, 8]


def test_export_single_values(map_path):
    common = ["--map", str(map_path), "--pin", PIN, "--disc", DISC, "--pressure", "106.1",
              "--temperature", "20"]
    mujoco = _run("export", "mujoco", *common, "--geom1", "finger").output
    assert 'geom1="finger"' in mujoco and 'friction="0.26 0.26 0.005 0.0001 0.0001"' in mujoco
    assert 'responseParams="mu=0.26"' in _run("export", "sofa", *common).output
    assert pyelastica_values(_run("export", "pyelastica", *common).output)[
        "kinetic_mu_array"] == [0.26, 0.26, 0.26]
    card = lsdyna_contact(_run("export", "lsdyna", *common, "--pin-part", "4",
                               "--disc-part", "9").output)
    assert (card["fs"], card["fd"], card["dc"]) == (0.26, 0.26, 0.0)
    assert (card["surfa"], card["surfb"]) == (4, 9)


def test_export_usd_pybullet_drake(map_path):
    common = ["--map", str(map_path), "--pin", PIN, "--disc", DISC, "--pressure", "106.1",
              "--temperature", "20"]
    # the published map holds mu_k only: the static coefficients are mu_k, and say so
    usd = _run("export", "usd", *common).output
    assert usd_values(usd) == {"dynamic": 0.26, "static": 0.26, "mode": "average"}
    assert "# static = mu_k: the map holds no mu_s for this pair" in usd
    assert urdf_friction(_run("export", "pybullet", *common).output) == ("pin", 0.26)
    assert urdf_friction(_run("export", "pybullet", *common, "--body", "disc").output) == (
        "disc", 1.0)
    assert sdf_friction(_run("export", "drake", *common).output) == {
        "pin": (0.26, 0.26), "disc": (0.26, 0.26)}
    refused = CliRunner().invoke(main, ["export", "pybullet", *common, "--coefficient", "mu_s"])
    assert refused.exit_code == 1 and "no mu_s in the map" in refused.output


def test_every_format_is_a_command_with_the_options_it_declares():
    import click

    from tribopipe.cli.export import export_group
    from tribopipe.export.formats import ENTRIES as WRITERS
    from tribopipe.export.registry import WRITERS as REGISTERED

    ctx = click.Context(export_group)
    assert export_group.list_commands(ctx) == [w.name for w in WRITERS]
    assert [w.name for w in REGISTERED] == [w.name for w in WRITERS]
    shared = {"pin", "disc", "temperature_C", "pressure_kPa", "speed_mm_s", "method", "map_path",
              "output"}
    for writer in WRITERS:
        command = export_group.get_command(ctx, writer.name)
        params = {p.name: p for p in command.params}
        assert set(params) == shared | {o.name for o in writer.options}, writer.name
        for option in writer.options:
            assert option.flag in params[option.name].opts, (writer.name, option.name)
            if option.choices:
                assert tuple(params[option.name].type.choices) == option.choices


@pytest.mark.parametrize("fmt", ["mujoco", "sofa", "pyelastica", "lsdyna"])
def test_export_mu_s_from_a_map_without_it_is_one_line(map_path, fmt):
    result = CliRunner().invoke(main, ["export", fmt, "--map", str(map_path), "--pin", PIN,
                                       "--disc", DISC, "--pressure", "35.37", "--temperature",
                                       "20", "--coefficient", "mu_s"])
    assert result.exit_code == 1
    lines = [ln for ln in result.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in result.output
    assert "no mu_s in the map" in lines[0] and "leave out --coefficient mu_s" in lines[0]


def test_export_single_value_without_pressure_lists_the_pressures(map_path):
    result = CliRunner().invoke(main, ["export", "mujoco", "--map", str(map_path),
                                       "--pin", PIN, "--disc", DISC])
    assert result.exit_code == 1
    assert "11.79, 35.37, 58.95, 82.52, 106.1 kPa" in result.output
    assert "--pressure" in result.output


def test_export_exponential_decay_without_mu_s_is_refused(map_path):
    result = CliRunner().invoke(main, ["export", "abaqus", "--exponential-decay", "--map",
                                       str(map_path), "--pin", PIN, "--disc", DISC,
                                       "--pressure", "20", "--temperature", "20"])
    assert result.exit_code == 1
    assert "no mu_s" in result.output and "Traceback" not in result.output


def test_fit_command_json_and_csv(map_path, tmp_path):
    out = tmp_path / "fits.csv"
    result = CliRunner().invoke(fit_cmd, ["--map", str(map_path), "--pin", PIN, "--json",
                                          "-o", str(out)], catch_exceptions=False)
    assert result.exit_code == 0
    records = json.loads(result.stdout)
    assert {r["disc"] for r in records} >= {"steel", "acrylic glass"}
    assert all(r["pin"] == PIN for r in records)
    assert all(r["exponent"] < 0 for r in records)
    written = pd.read_csv(out)
    assert len(written) == len(records)
    table = CliRunner().invoke(fit_cmd, ["--map", str(map_path), "--disc", "steel"])
    assert table.exit_code == 0
    assert "Ecoflex 00-50" in table.output and "n-1" in table.output


@pytest.mark.slow
def test_query_and_export_in_a_real_process(map_path, tmp_path):
    out = tmp_path / "contact.xml"
    proc = subprocess.run(
        [sys.executable, "-m", "tribopipe", "export", "mujoco", "--map", str(map_path),
         "--pin", PIN, "--disc", DISC, "--pressure", "35.37", "--temperature", "20",
         "-o", str(out)],
        capture_output=True, text=True, timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    assert 'friction="0.45 0.45' in out.read_text()
    proc = subprocess.run(
        [sys.executable, "-m", "tribopipe", "export", "lsdyna", "--map", str(map_path),
         "--pin", PIN, "--disc", DISC, "--pressure", "35.37", "--temperature", "20"],
        capture_output=True, text=True, timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    assert lsdyna_contact(proc.stdout)["fd"] == 0.45
    proc = subprocess.run(
        [sys.executable, "-m", "tribopipe", "query", "--map", str(map_path), "--pin", PIN,
         "--disc", "steal", "--pressure", "35.37", "--temperature", "20"],
        capture_output=True, text=True, timeout=120,
    )
    assert proc.returncode == 1
    assert proc.stderr.count("\n") == 1  # one line, no traceback
    assert "unknown disc 'steal'; did you mean 'steel'?" in proc.stderr
    assert "Traceback" not in proc.stderr


@pytest.fixture(scope="module")
def reduced_map(tmp_path_factory) -> Path:
    from reduced_runs import make_processed

    return make_processed(tmp_path_factory.mktemp("reduced"))[0]


def test_query_on_reduced_runs_reports_mu_s(reduced_map):
    from tribopipe.frictionmap import read_map
    from tribopipe.stats import group_statistics

    groups = group_statistics(read_map(reduced_map))
    steel = groups[groups.disc == "steel"].sort_values("pressure_kPa")
    p_lo, p_hi = steel["pressure_kPa"].tolist()
    mid = math.sqrt(p_lo * p_hi)
    result = _run("query", "--map", str(reduced_map), "--pin", PIN, "--disc", DISC,
                  "--pressure", repr(mid), "--json")
    assert result.exit_code == 0, result.output
    data = json.loads(result.output)
    # one temperature measured: no --temperature needed; halfway in ln p between the two
    # groups, so the geometric mean of their means (log p - log mu)
    assert data["mu_s"]["value"] == pytest.approx(math.sqrt(steel["mu_s_mean"].prod()))
    assert data["mu_k"]["value"] == pytest.approx(math.sqrt(steel["mu_k_mean"].prod()))
    # U (k = 2) travels with the value
    assert data["mu_k"]["expanded"] > 0
    assert data["temperatures_C"] == [20.0]


def test_export_exponential_decay_from_reduced_runs(reduced_map, tmp_path):
    from tribopipe.frictionmap import read_map
    from tribopipe.stats import group_statistics

    groups = group_statistics(read_map(reduced_map))
    g = groups[(groups.disc == "steel")].sort_values("pressure_kPa").iloc[0]
    out = tmp_path / "decay.inp"
    result = _run("export", "abaqus", "--exponential-decay", "--map", str(reduced_map),
                  "--pin", PIN, "--disc", DISC, "--pressure", repr(float(g.pressure_kPa)),
                  "--units", "m-N-s", "--decay", "500", "-o", str(out))
    assert result.exit_code == 0, result.output
    lines = [ln for ln in out.read_text().splitlines() if not ln.startswith("**")]
    assert lines[1] == "*FRICTION, EXPONENTIAL DECAY"
    mu_s, mu_k, d_c = (float(v) for v in lines[2].split(","))
    assert mu_s == pytest.approx(g.mu_s_mean, rel=1e-5)
    assert mu_k == pytest.approx(g.mu_k_mean, rel=1e-5)
    assert d_c == pytest.approx(500e3)  # 500 s/mm = 5e5 s/m
    assert mu_s > mu_k


def test_export_mu_s_from_reduced_runs(reduced_map, tmp_path):
    from tribopipe.frictionmap import read_map
    from tribopipe.stats import group_statistics

    groups = group_statistics(read_map(reduced_map))
    g = groups[(groups.disc == "steel")].sort_values("pressure_kPa").iloc[0]
    common = ["--map", str(reduced_map), "--pin", PIN, "--disc", DISC, "--pressure",
              repr(float(g.pressure_kPa)), "--coefficient", "mu_s"]
    pair = mujoco_pair(_run("export", "mujoco", *common).stdout)
    assert float(pair.get("friction").split()[0]) == pytest.approx(g.mu_s_mean, rel=1e-8)
    out = tmp_path / "contact.k"
    result = _run("export", "lsdyna", *common, "--units", "m-N-s", "-o", str(out))
    assert result.exit_code == 0, result.output
    card = lsdyna_contact(out.read_text())
    assert card["fs"] == pytest.approx(g.mu_s_mean, rel=1e-6)
    assert card["fd"] == pytest.approx(g.mu_k_mean, rel=1e-6)
    # DC [s/m]: 99 % decayed at the pair's measured speed (mm/s in the map, m/s in the file)
    speed_m_s = read_map(reduced_map).query("disc == @DISC")["sliding_speed_mm_s"].median() * 1e-3
    assert card["dc"] == pytest.approx(math.log(100) / speed_m_s, rel=1e-6)


def test_abaqus_slip_rate_is_the_runs_measured_speed(reduced_map):
    from tribopipe.frictionmap import read_map

    runs = read_map(reduced_map)
    result = _run("export", "abaqus", "--map", str(reduced_map), "--pin", PIN, "--disc", DISC,
                  "--units", "m-N-s")
    assert result.exit_code == 0
    rows = [ln.split(",") for ln in result.output.splitlines() if ln and not ln.startswith("*")]
    speeds = {float(r[1]) for r in rows}
    assert len(speeds) == 1
    # mm/s in the map, m/s in the file
    steel = runs[runs["disc"] == DISC]
    assert speeds.pop() == pytest.approx(steel["sliding_speed_mm_s"].median() * 1e-3, rel=1e-8)


def test_abaqus_slip_rate_per_pair_from_a_real_map(tmp_path):
    """Steel runs recorded at three times the speed: only the steel table says so."""
    from tribopipe.frictionmap import append_records, import_records

    records = [dataclasses.replace(r, sliding_speed_mm_s=0.021) if r.disc == DISC else r
               for r in import_records(PUBLISHED_CSV)]
    map_path = tmp_path / "friction_map.parquet"
    append_records(map_path, records)
    result = _run("export", "abaqus", "--map", str(map_path), "--pin", PIN)
    assert result.exit_code == 0, result.output
    blocks = parse_abaqus(result.output)
    assert len(blocks) == 9
    for name, block in blocks.items():
        expected = 0.021 if name.endswith("_ON_STEEL") else 0.007
        assert {row[1] for row in block["rows"]} == {expected}, name


def test_the_simulator_page_holds_the_registry_table():
    from tribopipe.export.simulators import formats_table

    doc = (Path(__file__).resolve().parents[1] / "docs" / "simulators.md").read_text(
        encoding="utf-8")
    start = doc.index("-->\n", doc.index("<!-- formats:")) + 4
    end = doc.index("<!-- end of formats -->")
    assert doc[start:end] == formats_table(), (
        "docs/simulators.md is stale: paste tribopipe.export.simulators.formats_table()")
