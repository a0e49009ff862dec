"""The reporting items an export's header gives (instrument, serial, software version,
date): read from the labelled lines Anton Paar's software writes for them, in Rheoplus
and in RheoCompass exports alike, into the map; and nothing made up where an export
holds none (RheoCompass's table export, as every real one we have shows).
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from generators.synthetic import SyntheticRun, rheocompass_text
from tribopipe import frictionmap as fm
from tribopipe.cli import main
from tribopipe.readers import read_export
from tribopipe.reporting import from_export

REAL_RHEOCOMPASS = ["rheocompass_en_utf16_two_tests.csv", "rheocompass_en_two_tests.xlsx",
                    "rheocompass_en_utf16_amplitude_sweep.csv",
                    "rheocompass_en_utf16_small.txt", "rheocompass_resaved_cp1252.txt"]
SHARED_ONLY = ["rheocompass_fr_utf16_laos.csv", "rheocompass_en_utf8_comma.csv"]
#: the measurement fields as Rheoplus writes them (the real MCR302 file's lines)
FIELDS = ("Application:\t\t\tRHEOPLUS/32 V3.62 21006865-33024\r\n"
          "Device:\t\t\tMCR302 SN81338429; FW3.71; Slot(8,-1); Adj(7,0)d\r\n"
          "Measuring Date/Time:\t\t\t21/03/2022; 15:04 PM\r\n")
ITEMS = {"instrument": "MCR302", "instrument_serial": "81338429",
         "software_version": "RHEOPLUS/32 V3.62 21006865-33024",
         "measured_on": "21/03/2022; 15:04 PM"}


def test_the_rheoplus_header_gives_instrument_serial_software_and_date(data_dir: Path):
    (first, *_) = read_export(data_dir / "rheoplus_mcr302_stress_relaxation.txt")
    assert from_export(dict(first.meta.extra)) == ITEMS


@pytest.mark.parametrize("name", REAL_RHEOCOMPASS)
def test_a_real_rheocompass_export_names_no_item_and_none_is_made_up(data_dir: Path,
                                                                     name: str):
    """RheoCompass's table export holds Project, Test and Result only: its project text
    ('Relaxation Test | DESKTOP-4HEH0CM, 8/20/2019 | 3') is not taken apart into a
    computer and a date, which no documentation names."""
    for m in read_export(data_dir / name):
        assert from_export(dict(m.meta.extra)) == {}
        assert m.meta.project  # kept as it is


@pytest.mark.parametrize("name", SHARED_ONLY)
def test_the_unlicensed_real_rheocompass_exports_name_no_item(shared_dir: Path, name: str):
    for m in read_export(shared_dir / "real-exports" / name):
        assert from_export(dict(m.meta.extra)) == {}


def _export(run: SyntheticRun, where: str) -> str:
    """A RheoCompass export of ``run`` with the measurement fields above the first test
    (``where="project"``) or inside it (``"test"``), CRLF, as RheoCompass writes."""
    text = rheocompass_text(run, project="labs", test="DS30 on steel", sample="DS30")
    lines = text.replace("\r\n", "\n").split("\n")
    at = 1 if where == "project" else next(i for i, ln in enumerate(lines)
                                           if ln.startswith("Test:")) + 1
    lines[at:at] = FIELDS.replace("\r\n", "\n").rstrip("\n").split("\n")
    return "\r\n".join(lines)


@pytest.mark.parametrize("where", ["project", "test"])
def test_rheocompass_lines_with_the_vendors_labels_are_read(tmp_path: Path, where: str):
    run = SyntheticRun(mu_s=0.6, mu_k=0.45, normal_force_N=3.0, seed=3)
    path = tmp_path / "run.txt"
    path.write_bytes(_export(run, where).encode("utf-16"))
    measurements = read_export(path)
    assert measurements
    for m in measurements:
        assert from_export(dict(m.meta.extra)) == ITEMS


def test_a_second_test_does_not_inherit_the_first_tests_fields(tmp_path: Path):
    run = SyntheticRun(mu_s=0.6, mu_k=0.45, normal_force_N=3.0, seed=4)
    first = _export(run, "test")
    second = rheocompass_text(run, project="labs", test="second", sample="DS30")
    body = second.replace("\r\n", "\n").split("\n")
    start = next(i for i, ln in enumerate(body) if ln.startswith("Test:"))
    path = tmp_path / "session.txt"
    path.write_bytes((first + "\r\n" + "\r\n".join(body[start:])).encode("utf-16"))
    by_test = {m.meta.test: from_export(dict(m.meta.extra)) for m in read_export(path)}
    assert by_test == {"DS30 on steel": ITEMS, "second": {}}


def test_the_header_items_reach_the_map_and_a_stated_value_wins(tmp_path: Path):
    raw = tmp_path / "raw"
    raw.mkdir()
    for repeat in (1, 2):
        run = SyntheticRun(mu_s=0.6, mu_k=0.45, normal_force_N=3.0, seed=10 + repeat)
        (raw / f"DS30_steel_3N_20C_r{repeat}.txt").write_bytes(
            _export(run, "project").encode("utf-16"))
    cfg = tmp_path / "c.toml"
    cfg.write_text('[campaign]\nname = "h"\nraw_dir = "raw"\noutput_dir = "out"\nplots = false\n'
                   'filename_pattern = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"\n'
                   '[metadata]\noperator = "RB"\nsoftware_version = "stated 1.0"\n',
                   encoding="utf-8")
    result = CliRunner().invoke(main, ["batch", str(cfg), "--jobs", "1"])
    assert result.exit_code == 0, result.output
    runs = fm.read_map(tmp_path / "out" / "friction_map.parquet")
    assert len(runs) == 2
    for row in runs.to_dict(orient="records"):
        assert (row["instrument"], row["instrument_serial"], row["measured_on"]) == (
            "MCR302", "81338429", "21/03/2022; 15:04 PM")
        # what the lab states in [metadata] wins over the header; the rest is the header's
        assert row["software_version"] == "stated 1.0" and row["operator"] == "RB"
    shutil.rmtree(tmp_path / "out")
