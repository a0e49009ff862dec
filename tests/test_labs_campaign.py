"""One vocabulary of materials and the metadata that makes runs comparable, end to end
through a real batch: names resolved at the edge and stored canonically (the raw name
kept), unknown names refused before any work with a did-you-mean, a lab's materials file,
`tribopipe materials add`, and the reporting items through manifest, campaign file, map,
runs.csv and a published package.
"""

from __future__ import annotations

import csv
import json
import shutil
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner

from generators.synthetic import SyntheticRun, write_rheocompass_export
from tribopipe import frictionmap as fm
from tribopipe.cli import main
from tribopipe.errors import ConfigError
from tribopipe.materials import load_vocabulary, name_key, shipped_vocabulary
from tribopipe.reporting import NAMES, from_export

PATTERN = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"
STEMS = ("DS30_steel_3N_20C_r1", "DS30_steel_3N_20C_r2")


@pytest.fixture(scope="module")
def exports(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("labs_exports")
    for seed, stem in enumerate(STEMS):
        run = SyntheticRun(mu_s=0.6, mu_k=0.45, normal_force_N=3.0, temperature_C=20.0,
                           duration_s=150.0, noise=0.004, seed=seed)
        write_rheocompass_export(folder / f"{stem}.csv", run, project="labs", test="t",
                                 sample="DS30")
    return folder


def campaign(tmp_path: Path, exports: Path, *, stems: dict[str, str] | None = None,
             extra: str = "", manifest: str | None = None) -> Path:
    raw = tmp_path / "raw"
    raw.mkdir()
    for stem in STEMS:
        shutil.copy(exports / f"{stem}.csv", raw / f"{(stems or {}).get(stem, stem)}.csv")
    cfg = tmp_path / "campaign.toml"
    text = (f'[campaign]\nname = "labs"\nraw_dir = "raw"\noutput_dir = "out"\n'
            f'filename_pattern = "{PATTERN}"\nplots = false\n')
    if manifest is not None:
        (raw / "manifest.csv").write_text(manifest, encoding="utf-8")
        text += 'manifest = "raw/manifest.csv"\n'
    cfg.write_text(text + extra, encoding="utf-8")
    return cfg


def batch(cfg: Path):
    return CliRunner().invoke(main, ["batch", str(cfg), "--jobs", "1"])


# ------------------------------------------------------------------ the vocabulary


def test_every_material_of_the_founding_map_is_in_the_vocabulary():
    published = pd.read_csv(Path(fm.published.__file__).parents[1] / "data"
                            / "frictionmap_published.csv")
    vocabulary = shipped_vocabulary()
    for name in set(published["pin"]) | set(published["disc"]):
        assert vocabulary.candidates(name) == (name,), name
        material = vocabulary.get(name)
        assert material is not None and material.material_class
    assert vocabulary.get("Dragonskin 30").shore == "30A"
    assert vocabulary.get("Dragonskin 30").supplier == "Smooth-On"
    assert vocabulary.get("lathed aluminium disk").finish


@pytest.mark.parametrize(("given", "canonical"), [
    ("Dragon Skin 30", "Dragonskin 30"),  # how Smooth-On writes it
    ("DS30", "Dragonskin 30"), ("dragonskin-30", "Dragonskin 30"),
    ("EF50", "Ecoflex 00-50"), ("PMMA", "acrylic glass"), ("Plexiglas", "acrylic glass"),
    ("aluminum sheet", "aluminium sheet"), ("Stahl", "steel"), ("Karton", "cardboard"),
])
def test_spellings_vendor_codes_and_translations_resolve(given, canonical):
    resolved = shipped_vocabulary().resolve(given)
    assert resolved.name == canonical and resolved.given == given


def test_typos_get_a_did_you_mean_and_ambiguous_names_both_choices():
    v = shipped_vocabulary()
    assert "did you mean 'Dragonskin 30'" in v.problem("DS03")
    assert v.problem("Aul").startswith("unknown material 'Aul'; did you mean 'aluminium")
    assert v.problem("aluminium") == ("material 'aluminium' is ambiguous: 'aluminium sheet' "
                                      "or 'lathed aluminium disk'")
    assert name_key("Dragon Skin™ 30") == name_key("dragonskin30")


def test_a_labs_file_extends_the_vocabulary_and_is_checked(tmp_path: Path):
    lab = tmp_path / "materials.toml"
    lab.write_text('[materials]\n"Elastosil M 4601" = { class = "silicone elastomer", '
                   'supplier = "Wacker", aliases = ["M4601"] }\n', encoding="utf-8")
    v = load_vocabulary([lab])
    assert v.resolve("m4601").name == "Elastosil M 4601"
    assert v.resolve("DS30").name == "Dragonskin 30"  # the shipped ones are still there
    lab.write_text('[materials]\n"X" = { class = "plastic" }\n', encoding="utf-8")
    with pytest.raises(ConfigError, match="class must be one of"):
        load_vocabulary([lab])


def test_materials_add_is_one_command_and_one_line(tmp_path: Path):
    path = tmp_path / "materials.toml"
    result = CliRunner().invoke(main, ["materials", "add", "Elastosil M 4601", "--class",
                                       "silicone elastomer", "--alias", "M4601",
                                       "--file", str(path)])
    assert result.exit_code == 0, result.output
    lines = path.read_text(encoding="utf-8").splitlines()
    assert lines == ["[materials]", '"Elastosil M 4601" = { class = "silicone elastomer", '
                     'aliases = ["M4601"] }']
    again = CliRunner().invoke(main, ["materials", "add", "Stahl", "--class", "metal",
                                      "--file", str(path)])
    assert again.exit_code == 1 and "'Stahl' already names 'steel'" in again.output
    check = CliRunner().invoke(main, ["materials", "check", "M4601", "--materials",
                                      str(path)])
    assert check.exit_code == 0 and "M4601 -> Elastosil M 4601" in check.output


# ------------------------------------------------------------------ a campaign


def test_short_codes_resolve_without_names_and_the_raw_name_is_kept(tmp_path, exports):
    cfg = campaign(tmp_path, exports)
    result = batch(cfg)
    assert result.exit_code == 0, result.output
    runs = fm.read_map(tmp_path / "out" / "friction_map.parquet")
    assert set(runs["pin"]) == {"Dragonskin 30"} and set(runs["pin_as_given"]) == {"DS30"}
    assert set(runs["disc"]) == {"steel"} and set(runs["disc_as_given"]) == {"steel"}


def test_unknown_names_refuse_the_whole_campaign_before_any_work(tmp_path, exports):
    cfg = campaign(tmp_path, exports, stems={STEMS[0]: "DS03_steel_3N_20C_r1",
                                             STEMS[1]: "DS30_stel_3N_20C_r2"})
    result = batch(cfg)
    assert result.exit_code == 1
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, result.stderr  # one line, every unknown name in it
    assert "2 material name(s) not in the vocabulary, nothing reduced" in lines[0]
    assert "unknown pin 'DS03'; did you mean 'Dragonskin 30'" in lines[0]
    assert "unknown disc 'stel'; did you mean 'steel'" in lines[0]
    assert "DS03_steel_3N_20C_r1.csv" in lines[0] and "materials add" in lines[0]
    out = tmp_path / "out"
    assert not (out / "friction_map.parquet").exists()
    assert not list(out.glob("traces/*.parquet"))


def test_a_materials_file_beside_the_config_adds_a_material(tmp_path, exports):
    cfg = campaign(tmp_path, exports, stems={STEMS[0]: "M4601_steel_3N_20C_r1",
                                             STEMS[1]: "M4601_steel_3N_20C_r2"})
    assert batch(cfg).exit_code == 1
    add = CliRunner().invoke(main, ["materials", "add", "Elastosil M 4601", "--class",
                                    "silicone elastomer", "--alias", "M4601", "--file",
                                    str(tmp_path / "materials.toml")])
    assert add.exit_code == 0, add.output
    result = batch(cfg)
    assert result.exit_code == 0, result.output
    runs = fm.read_map(tmp_path / "out" / "friction_map.parquet")
    assert set(runs["pin"]) == {"Elastosil M 4601"}


def test_an_ambiguous_name_is_settled_by_names(tmp_path, exports):
    stems = {STEMS[0]: "DS30_Alu_3N_20C_r1", STEMS[1]: "DS30_Alu_3N_20C_r2"}
    cfg = campaign(tmp_path, exports, stems=stems)
    result = batch(cfg)
    assert result.exit_code == 1
    assert "disc 'Alu' is ambiguous: 'aluminium sheet' or 'lathed aluminium disk'" \
        in result.stderr
    cfg.write_text(cfg.read_text(encoding="utf-8") + '[names]\nAlu = "aluminium sheet"\n',
                   encoding="utf-8")
    result = batch(cfg)
    assert result.exit_code == 0, result.output
    runs = fm.read_map(tmp_path / "out" / "friction_map.parquet")
    assert set(runs["disc"]) == {"aluminium sheet"} and set(runs["disc_as_given"]) == {"Alu"}


# ------------------------------------------------------------------ reporting items


MANIFEST = ("file,pin,disc,normal_force_N,temperature_C,repeat,humidity_pct,disc_Ra_um,"
            "operator,lot\n"
            f"{STEMS[0]}.csv,Dragon Skin 30,steel,3,20,1,45,0.8,RB,L7\n"
            f"{STEMS[1]}.csv,Dragon Skin 30,steel,3,20,2,\"47,5\",0.8,RB,L8\n")
METADATA = ('[metadata]\ninstrument = "Anton Paar MCR 302e"\ninstrument_serial = "81338249"\n'
            'software_version = "RheoCompass 1.30"\nconditioning_h = 24\n'
            'operator = "nobody"\n[metadata.extra]\nchamber = "T-PID/44"\n')


def test_reporting_items_travel_to_the_map_runs_csv_and_a_package(tmp_path, exports):
    cfg = campaign(tmp_path, exports, manifest=MANIFEST, extra=METADATA)
    result = batch(cfg)
    assert result.exit_code == 0, result.output
    runs = fm.read_map(tmp_path / "out" / "friction_map.parquet").sort_values("repeat")
    assert runs["humidity_pct"].tolist() == [45.0, 47.5]  # a decimal comma too
    assert runs["disc_Ra_um"].tolist() == [0.8, 0.8]
    assert runs["operator"].tolist() == ["RB", "RB"]  # the manifest over [metadata]
    assert set(runs["instrument_serial"]) == {"81338249"}
    assert set(runs["conditioning_h"]) == {24.0}
    extra = [json.loads(t) for t in runs["extra_metadata"]]
    assert extra == [{"chamber": "T-PID/44", "lot": "L7"}, {"chamber": "T-PID/44", "lot": "L8"}]
    assert set(runs["pin_as_given"]) == {"Dragon Skin 30"}
    with (tmp_path / "out" / "runs.csv").open(encoding="utf-8") as fh:
        table = list(csv.DictReader(fh))
    assert [r["humidity_pct"] for r in table] == ["45.0", "47.5"]
    assert {r["software_version"] for r in table} == {"RheoCompass 1.30"}
    assert {json.loads(r["extra_metadata"])["chamber"] for r in table} == {"T-PID/44"}

    out = tmp_path / "package"
    published = CliRunner().invoke(main, ["map", "publish", str(out), "--map",
                                          str(tmp_path / "out" / "friction_map.parquet"),
                                          "--lab", "Second Lab", "--contact", "A. Person",
                                          "--allow-synthetic"])
    assert published.exit_code == 0, published.output
    descriptor = json.loads((out / "datapackage.json").read_text(encoding="utf-8"))
    fields = {f["name"]: f for f in descriptor["resources"][0]["schema"]["fields"]}
    assert fields["humidity_pct"]["unit"] == "%" and fields["humidity_pct"]["type"] == "number"
    assert fields["humidity_pct"]["constraints"]["maximum"] == 100
    with (out / "data" / "runs.csv").open(encoding="utf-8") as fh:
        package_rows = list(csv.DictReader(fh))
    assert sorted(r["humidity_pct"] for r in package_rows) == ["45.0", "47.5"]
    merged = tmp_path / "merged.parquet"
    assert CliRunner().invoke(main, ["map", "merge", str(out), "--map",
                                     str(merged)]).exit_code == 0
    assert sorted(fm.read_map(merged)["humidity_pct"]) == [45.0, 47.5]


def test_an_unknown_metadata_key_is_refused_by_name(tmp_path, exports):
    cfg = campaign(tmp_path, exports, extra='[metadata]\nhumidity = 45\n')
    result = batch(cfg)
    assert result.exit_code == 1
    assert "[metadata] unknown key 'humidity'" in result.stderr
    assert "did you mean 'humidity_pct'?" in result.stderr
    (tmp_path / "b").mkdir()
    result = batch(campaign(tmp_path / "b", exports, extra='[metadata]\nhumidity_pct = 140\n'))
    assert result.exit_code == 1 and "humidity_pct" in result.stderr and "100" in result.stderr


def test_an_export_header_gives_instrument_serial_software_and_date():
    header = {"device": "MCR302 SN81338249; FW3.71; Slot(8,-1); Adj(7,0)",
              "application": "RHEOPLUS/32 V3.62 21006865-33024",
              "measuring_date_time": "21/03/2022; 15:04 PM"}
    assert from_export(header) == {"instrument": "MCR302", "instrument_serial": "81338249",
                                   "software_version": "RHEOPLUS/32 V3.62 21006865-33024",
                                   "measured_on": "21/03/2022; 15:04 PM"}


def test_every_reporting_item_is_a_map_column_with_its_unit():
    columns = {c.name: c for c in fm.schema.COLUMNS}
    for name in NAMES:
        assert name in columns and fm.schema.ADDED_IN_VERSION[name] == 6
    assert columns["disc_Ra_um"].unit == "µm" and columns["conditioning_h"].unit == "h"


def test_a_version_5_map_still_reads_with_the_new_columns_missing():
    runs = fm.read_map(Path(__file__).parent / "data" / "friction_map_v5.parquet")
    assert len(runs) == 169
    assert runs["humidity_pct"].isna().all() and runs["pin_as_given"].isna().all()


def test_the_materials_command_runs_as_a_subprocess(tmp_path):
    result = subprocess.run([sys.executable, "-m", "tribopipe", "materials", "check", "Aul"],
                            capture_output=True, text=True, cwd=tmp_path)
    assert result.returncode == 1 and "Traceback" not in result.stderr
    assert result.stderr.strip() == ("unknown material 'Aul'; did you mean 'aluminium sheet' "
                                     "or 'lathed aluminium disk'?")


# ------------------------------------------------------------------ labels against the export


def test_a_force_label_the_export_contradicts_is_refused_with_both_values(tmp_path):
    raw = tmp_path / "raw"
    raw.mkdir()
    for seed, (stem, force) in enumerate((("DS30_steel_9N_20C_r1", 5.0),
                                          ("DS30_steel_5N_20C_r1", 5.0),
                                          ("DS30_steel_1N_20C_r1", 1.13))):
        run = SyntheticRun(mu_s=0.6, mu_k=0.45, normal_force_N=force, temperature_C=20.0,
                           duration_s=150.0, noise=0.004, seed=7 + seed)
        write_rheocompass_export(raw / f"{stem}.csv", run, project="labs", test="t",
                                 sample="pin")
    args = ["batch", str(raw), "--pattern", PATTERN, "-o", str(tmp_path / "out"),
            "--no-plots", "--jobs", "1"]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 1
    (line,) = [ln for ln in result.stderr.splitlines() if "labels contradict" in ln]
    assert "DS30_steel_9N_20C_r1.csv" in line
    assert "measured mean normal force 5 N is 44% off the label 9 N (stated tolerance 25%)" \
        in line and "--keep-labels" in line
    runs = fm.read_map(tmp_path / "out" / "friction_map.parquet")
    # the 5 N run lands; 1.13 N labelled 1 N (13 %) is within 25 %: flagged, not refused
    assert sorted(runs["normal_force_N"]) == [1.0, 5.0]
    flagged = runs[runs["normal_force_N"] == 1.0]["flags"].iloc[0]
    assert "normal_force_off_nominal" in flagged

    kept = CliRunner().invoke(main, [*args, "--keep-labels"])
    assert kept.exit_code == 0, kept.output
    runs = fm.read_map(tmp_path / "out" / "friction_map.parquet")
    nine = runs[runs["normal_force_N"] == 9.0]
    assert len(nine) == 1 and "normal_force_off_nominal" in nine["flags"].iloc[0]


def test_a_test_name_naming_other_materials_than_the_labels_is_refused(tmp_path):
    raw = tmp_path / "raw"
    raw.mkdir()
    run = SyntheticRun(mu_s=0.6, mu_k=0.45, normal_force_N=3.0, temperature_C=20.0,
                       duration_s=150.0, noise=0.004, seed=3)
    write_rheocompass_export(raw / "DS30_Alu_3N_20C_r1.csv", run, project="labs",
                             test="Dragonskin 30 on steel", sample="Dragon Skin 30 pin")
    write_rheocompass_export(raw / "DS30_steel_3N_20C_r1.csv", replace(run, seed=4),
                             project="labs", test="Dragonskin 30 on steel",
                             sample="Dragon Skin 30 pin")
    cfg = tmp_path / "c.toml"
    cfg.write_text(f'[campaign]\nraw_dir = "raw"\noutput_dir = "out"\nplots = false\n'
                   f'filename_pattern = "{PATTERN}"\n[names]\nAlu = "aluminium sheet"\n',
                   encoding="utf-8")
    result = batch(cfg)
    assert result.exit_code == 1
    (line,) = [ln for ln in result.stderr.splitlines() if "labels contradict" in ln]
    assert line.startswith("failed: DS30_Alu_3N_20C_r1.csv")
    assert ("Test name 'Dragonskin 30 on steel' names 'steel', the labels say pin "
            "'Dragonskin 30' on disc 'aluminium sheet'") in line
    runs = fm.read_map(tmp_path / "out" / "friction_map.parquet")
    assert list(runs["disc"]) == ["steel"]  # the file whose names agree landed
    cfg.write_text(cfg.read_text(encoding="utf-8").replace(
        "plots = false\n", "plots = false\nkeep_labels = true\n"), encoding="utf-8")
    assert batch(cfg).exit_code == 0
