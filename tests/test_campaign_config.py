"""Campaign description: config validation, file-name patterns, manifests, metadata rules.

These checks need no raw export: they are what a lab checks before anything runs.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from generators.synthetic import SyntheticRun, write_rheocompass_export
from tribopipe.campaign import campaign_table, load_campaign, read_manifest
from tribopipe.campaign.metadata import labels_from, merge_metadata
from tribopipe.campaign.patterns import match_pattern
from tribopipe.errors import CampaignError, ConfigError
from tribopipe.labels import RunLabels, Tolerances, qc_flags

REPO = Path(__file__).resolve().parents[1]
PATTERN = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"
HEADER = "file,pin,disc,normal_force_N,temperature_C,repeat\n"


def write_config(folder: Path, body: str, name: str = "c.toml") -> Path:
    (folder / "raw").mkdir(exist_ok=True)
    path = folder / name
    path.write_text(body, encoding="utf-8")
    return path


def make_campaign(tmp_path: Path, *, manifest: str | None = None, pattern: bool = True,
                  extra: str = "", files: tuple[str, ...] = ()) -> object:
    raw = tmp_path / "raw"
    raw.mkdir(exist_ok=True)
    for i, f in enumerate(files):
        # a real export: a campaign looks at the content before it judges the labels
        write_rheocompass_export(raw / f, SyntheticRun(duration_s=40.0, seed=i),
                                 project="p", test="t", sample="s")
    lines = ['[campaign]', 'raw_dir = "raw"', 'output_dir = "out"']
    if pattern:
        lines.append(f'filename_pattern = "{PATTERN}"')
    if manifest is not None:
        (raw / "manifest.csv").write_text(manifest, encoding="utf-8")
        lines.append('manifest = "raw/manifest.csv"')
    cfg = tmp_path / "c.toml"
    cfg.write_text("\n".join(lines) + "\n" + extra, encoding="utf-8")
    return load_campaign(cfg)


# --------------------------------------------------------------------------- config


def test_paths_are_relative_to_the_config_folder(tmp_path: Path) -> None:
    cfg = write_config(tmp_path, f"""
[campaign]
name = "lab A"
raw_dir = "raw"
filename_pattern = "{PATTERN}"
""")
    campaign = load_campaign(cfg)
    assert campaign.name == "lab A"
    assert campaign.raw_dir == (tmp_path / "raw").resolve()
    # default output beside the config's folder, map inside it
    assert campaign.output_dir == (tmp_path.parent / "processed").resolve()
    assert campaign.map_path == campaign.output_dir / "friction_map.parquet"
    assert campaign.glob is None  # every export the readers know


def test_reduction_table_overrides_the_instrument_config(tmp_path: Path) -> None:
    (tmp_path / "inst.toml").write_text(
        "[instrument]\npin_radius_mm = 4.0\n[reduction]\nmedian_window = 9\n", encoding="utf-8"
    )
    base = (f'[campaign]\nraw_dir = "raw"\ninstrument = "inst.toml"\n'
            f'filename_pattern = "{PATTERN}"\n')
    plain = load_campaign(write_config(tmp_path, base))
    assert plain.settings.instrument.pin_radius_mm == 4.0
    assert plain.settings.reduction.median_window == 9
    over = load_campaign(write_config(tmp_path, base + "[reduction]\nmedian_window = 3\n",
                                      name="d.toml"))
    assert over.settings.reduction.median_window == 3
    assert over.settings.instrument.pin_radius_mm == 4.0
    # the override changes what a run depends on
    assert over.settings.config_hash != plain.settings.config_hash


@pytest.mark.parametrize("section", ["reduction", "instrument"])
def test_an_instrument_file_whose_section_is_not_a_table_is_a_config_error(
    tmp_path: Path, section: str
) -> None:
    (tmp_path / "inst.toml").write_text(f"{section} = 3\n", encoding="utf-8")
    cfg = write_config(tmp_path, f'[campaign]\nraw_dir = "raw"\ninstrument = "inst.toml"\n'
                                 f'filename_pattern = "{PATTERN}"\n')
    with pytest.raises(ConfigError, match=rf"inst\.toml: \[{section}\] must be a table"):
        load_campaign(cfg)


@pytest.mark.parametrize(
    ("body", "expected"),
    [
        ('[campaign]\nraw_dir = "raw"\nfilename_patern = "{pin}"\n', "filename_patern"),
        ('[campaign]\nfilename_pattern = "{pin}"\n', "raw_dir"),
        ('[campaign]\nraw_dir = "nowhere"\nfilename_pattern = "{pin}"\n', "raw_dir"),
        ('[campaign]\nraw_dir = "raw"\n', "no metadata source"),
        ('[campaign]\nraw_dir = "raw"\nfilename_pattern = "{pin}"\nforce_tolerance_N = -1\n',
         "force_tolerance_N"),
        ('[campaign]\nraw_dir = "raw"\nfilename_pattern = "{pin}"\nuse_export_names = "yes"\n',
         "use_export_names"),
        ('[campaign]\nraw_dir = "raw"\nfilename_pattern = "{pin}"\nmanifest = "m.csv"\n',
         "manifest"),
        ('[campaign]\nraw_dir = "raw"\nfilename_pattern = "plain"\n', "filename_pattern"),
        ('[campaign]\nraw_dir = "raw"\nfilename_pattern = "{pin}"\n[reduction]\nwindow = 3\n',
         "window"),
        ('[campaign]\nraw_dir = "raw"\nfilename_pattern = "{pin}"\n[extras]\na = 1\n',
         "extras"),
        ('raw_dir = "raw"\n', "[campaign]"),
    ],
)
def test_bad_config_names_file_and_key(tmp_path: Path, body: str, expected: str) -> None:
    cfg = write_config(tmp_path, body)
    with pytest.raises(ConfigError) as info:
        load_campaign(cfg)
    message = str(info.value)
    assert str(cfg) in message
    assert expected in message
    assert "\n" not in message


def test_shipped_example_config_loads() -> None:
    cfg = REPO / "configs" / "example.toml"
    if not cfg.exists():
        pytest.skip("configs/example.toml not written yet")
    campaign = load_campaign(cfg)
    assert campaign.raw_dir == (REPO / "raw" / "example").resolve()
    # the demo has its own folder and map, and its runs are flagged synthetic
    assert campaign.output_dir == (REPO / "processed" / "demo").resolve()
    assert campaign.map_path == (REPO / "processed" / "demo" / "friction_map.parquet").resolve()
    assert campaign.synthetic


# --------------------------------------------------------------------------- patterns


def test_pattern_reads_the_founding_naming() -> None:
    found = match_pattern(PATTERN, "DS30_steel_5N_20C_r2")
    assert found == {"pin": "DS30", "disc": "steel", "normal_force_N": 5.0,
                     "temperature_C": 20.0, "repeat": 2}
    # decimal written with p or comma, negative temperature
    assert match_pattern(PATTERN, "EF50_acrylic glass_0p5N_-5C_r1")["normal_force_N"] == 0.5
    assert match_pattern(PATTERN, "EF50_acrylic glass_0p5N_-5C_r1")["temperature_C"] == -5.0
    assert match_pattern(PATTERN, "EF50_steel_1,5N_20C_r1")["normal_force_N"] == 1.5
    assert match_pattern(PATTERN, "notes") is None
    assert match_pattern(PATTERN, "DS30_steel_fiveN_20C_r2") is None


def test_unknown_placeholders_match_and_are_ignored() -> None:
    found = match_pattern("{date}_{pin}_{disc}_{force}N", "2024-05-01_DS30_steel_3N")
    assert found == {"pin": "DS30", "disc": "steel", "normal_force_N": 3.0}


names = st.text(alphabet="abcdefghijklmnopqrstuvwxyz ()-0123456789", min_size=1,
                max_size=12).filter(lambda s: s.strip() == s)


@given(pin=names, disc=names, force=st.integers(1, 200), tenths=st.integers(0, 9),
       temperature=st.integers(-40, 150), repeat=st.integers(1, 99))
def test_pattern_round_trip(pin: str, disc: str, force: int, tenths: int, temperature: int,
                            repeat: int) -> None:
    """Whatever a lab writes into a name through the pattern, the pattern reads back."""
    force_text = f"{force}p{tenths}" if tenths else str(force)
    stem = f"{pin}_{disc}_{force_text}N_{temperature}C_r{repeat}"
    found = match_pattern(PATTERN, stem)
    assert found is not None
    assert found["pin"] == pin and found["disc"] == disc
    assert found["normal_force_N"] == pytest.approx(force + tenths / 10)
    assert found["temperature_C"] == temperature
    assert found["repeat"] == repeat


# --------------------------------------------------------------------------- manifest


def test_manifest_rows_and_extra_columns(tmp_path: Path) -> None:
    path = tmp_path / "m.csv"
    path.write_text("file,pin,disc,normal_force_N,temperature_C,repeat,operator,lot\n"
                    "a.csv,Dragonskin 30,steel,3,20,1,RB,L7\n"
                    "b.csv,Ecoflex 00-50,steel,,10,\n", encoding="utf-8")
    rows = read_manifest(path)
    # a reporting item is kept as its column, an unknown column as extra metadata
    assert rows.get("a.csv").fields == {"pin": "Dragonskin 30", "disc": "steel",
                                    "normal_force_N": 3.0, "temperature_C": 20.0, "repeat": 1,
                                    "operator": "RB", "extra:lot": "L7"}
    assert rows.get("a.csv").line == 2
    assert rows.get("b.csv").fields == {"pin": "Ecoflex 00-50", "disc": "steel",
                                    "temperature_C": 10.0}


def test_semicolon_manifest_with_decimal_comma(tmp_path: Path) -> None:
    path = tmp_path / "m.csv"
    path.write_text("file;pin;disc;normal_force_N;temperature_C;repeat\n"
                    "a.csv;DS30;steel;2,5;20;1\n", encoding="utf-8")
    assert read_manifest(path).get("a.csv").fields["normal_force_N"] == 2.5


@pytest.mark.parametrize(
    ("encoding", "sep", "newline"),
    [("utf-8", ",", "\n"), ("utf-8-sig", ";", "\r\n"), ("utf-16", "\t", "\r\n"),
     ("cp1252", ";", "\n")],
)
def test_manifests_as_spreadsheets_save_them_are_read_like_exports(
    tmp_path: Path, encoding: str, sep: str, newline: str
) -> None:
    """Excel and LibreOffice save CSV as UTF-8 (with BOM), cp1252 or 'Unicode text'
    (UTF-16, TAB): the manifest goes through the readers' own detection."""
    rows = [["file", "pin", "disc", "normal_force_N", "temperature_C", "repeat"],
            ["a.csv", "Ecoflex 00-50 (µ-batch)", "steel", "2,5" if sep == ";" else "2.5",
             "20", "1"]]
    path = tmp_path / "m.csv"
    path.write_bytes(newline.join(sep.join(r) for r in rows).encode(encoding) + b"")
    row = read_manifest(path).get("a.csv")
    assert row.fields == {"pin": "Ecoflex 00-50 (µ-batch)", "disc": "steel",
                          "normal_force_N": 2.5, "temperature_C": 20.0, "repeat": 1}


def test_an_empty_or_binary_manifest_is_one_config_error(tmp_path: Path) -> None:
    empty = tmp_path / "empty.csv"
    empty.write_bytes(b"")
    with pytest.raises(ConfigError, match=r"empty\.csv:1: manifest is empty"):
        read_manifest(empty)
    binary = tmp_path / "photo.csv"
    binary.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" * 20)
    with pytest.raises(ConfigError, match=r"photo\.csv: cannot read manifest: binary file"):
        read_manifest(binary)


def test_manifest_missing_column_is_a_config_error(tmp_path: Path) -> None:
    path = tmp_path / "m.csv"
    path.write_text("file,pin,disc,force,temperature_C,repeat\n", encoding="utf-8")
    with pytest.raises(ConfigError, match=r"m\.csv:1: .*normal_force_N"):
        read_manifest(path)


def test_manifest_duplicate_file_names_both_lines(tmp_path: Path) -> None:
    path = tmp_path / "m.csv"
    path.write_text(HEADER + "a.csv,DS30,steel,3,20,1\na.csv,DS30,steel,5,20,1\n",
                    encoding="utf-8")
    with pytest.raises(ConfigError, match=r"m\.csv:3: .*line 2"):
        read_manifest(path)


def test_manifest_bad_number_fails_only_that_file(tmp_path: Path) -> None:
    campaign = make_campaign(
        tmp_path,
        manifest=HEADER + "DS30_steel_3N_20C_r1.csv,DS30,steel,three,20,1\n"
                          "DS30_steel_5N_20C_r1.csv,DS30,steel,5,20,1\n",
        files=("DS30_steel_3N_20C_r1.csv", "DS30_steel_5N_20C_r1.csv"),
    )
    rows = {r.file: r for r in campaign_table(campaign)}
    bad = rows["DS30_steel_3N_20C_r1.csv"]
    assert bad.status == "failed"
    assert "manifest.csv:2" in bad.reason and "'three'" in bad.reason
    assert "normal_force_N" in bad.reason
    assert rows["DS30_steel_5N_20C_r1.csv"].status == "new"


# --------------------------------------------------------------------------- resolution


def test_manifest_and_name_agree_through_aliases(tmp_path: Path) -> None:
    campaign = make_campaign(
        tmp_path,
        manifest=HEADER + "DS30_steel_3N_20C_r1.csv,Dragonskin 30,Steel,3.0,20,1\n",
        extra='[names]\nDS30 = "Dragonskin 30"\n',
        files=("DS30_steel_3N_20C_r1.csv",),
    )
    (row,) = campaign_table(campaign)
    assert row.problem is None, row.problem
    assert row.status == "new"
    # the vocabulary's canonical name is stored; the manifest, first, gave the spelling
    assert row.labels == RunLabels(pin="Dragonskin 30", disc="steel", normal_force_N=3.0,
                                   temperature_C=20.0, repeat=1, pin_as_given="Dragonskin 30",
                                   disc_as_given="Steel")
    # the manifest itself is not a run
    assert [r.file for r in campaign_table(campaign)] == ["DS30_steel_3N_20C_r1.csv"]


def test_contradiction_names_file_field_and_both_sources(tmp_path: Path) -> None:
    campaign = make_campaign(
        tmp_path,
        manifest=HEADER + "DS30_steel_5N_20C_r1.csv,DS30,steel,3,20,1\n"
                          "DS30_steel_3N_20C_r1.csv,DS30,steel,3,20,1\n",
        files=("DS30_steel_5N_20C_r1.csv", "DS30_steel_3N_20C_r1.csv"),
    )
    rows = {r.file: r for r in campaign_table(campaign)}
    bad = rows["DS30_steel_5N_20C_r1.csv"]
    assert bad.status == "failed"
    assert bad.reason.startswith("DS30_steel_5N_20C_r1.csv: contradictory normal_force_N")
    assert "manifest line 2 says 3.0" in bad.reason and "file name says 5.0" in bad.reason
    assert rows["DS30_steel_3N_20C_r1.csv"].status == "new"


def test_missing_metadata_says_what_and_why(tmp_path: Path) -> None:
    campaign = make_campaign(
        tmp_path,
        manifest=HEADER + "run7.csv,DS30,steel,,20,1\n",
        files=("run7.csv", "stray.csv"),
    )
    rows = {r.file: r for r in campaign_table(campaign)}
    assert "metadata missing: normal_force_N" in rows["run7.csv"].reason
    assert "does not match pattern" in rows["run7.csv"].reason
    stray = rows["stray.csv"].reason
    assert "metadata missing: pin, disc, normal_force_N, temperature_C" in stray
    assert "no row for it in manifest manifest.csv" in stray


def test_merge_is_order_sensitive_only_for_spelling(tmp_path: Path) -> None:
    campaign = make_campaign(tmp_path)
    a = ("manifest", {"pin": "ecoflex 00-50", "normal_force_N": 3.0})
    b = ("file name", {"pin": "Ecoflex 00-50", "temperature_C": 20.0})
    ab = merge_metadata("x.csv", [a, b], campaign)
    ba = merge_metadata("x.csv", [b, a], campaign)
    # both store the vocabulary's canonical name; the first source's spelling is kept
    assert ab["pin"] == ba["pin"] == "Ecoflex 00-50"
    assert ab["pin_as_given"] == "ecoflex 00-50" and ba["pin_as_given"] == "Ecoflex 00-50"
    assert {k: v for k, v in ab.items() if k != "pin_as_given"} == \
        {k: v for k, v in ba.items() if k != "pin_as_given"}
    with pytest.raises(CampaignError, match="contradictory temperature_C"):
        merge_metadata("x.csv", [b, ("export", {"temperature_C": 10.0})], campaign)
    with pytest.raises(CampaignError, match="metadata missing: disc"):
        labels_from("x.csv", ab | ba)


# --------------------------------------------------------------------------- QC


def test_qc_flags_follow_the_tolerances() -> None:
    labels = RunLabels(pin="p", disc="d", normal_force_N=5.0, temperature_C=20.0)
    tol = Tolerances(force_N=0.2, force_rel=0.05, temperature_C=1.0)
    # at 5 N the relative limit (0.25 N) is the larger one
    assert tol.force_limit_N(5.0) == pytest.approx(0.25)
    assert tol.force_limit_N(1.0) == pytest.approx(0.2)
    assert qc_flags(labels, 5.2, 20.5, tol) == []
    assert qc_flags(labels, 5.3, 20.5, tol) == ["normal_force_off_nominal"]
    assert qc_flags(labels, 4.6, 21.6, tol) == ["normal_force_off_nominal",
                                                "temperature_off_nominal"]
    # an unknown measured temperature is not a QC failure
    assert qc_flags(labels, 5.0, None, tol) == []


@given(nominal=st.floats(0.1, 50), measured=st.floats(0.0, 60))
def test_force_flag_iff_outside_the_limit(nominal: float, measured: float) -> None:
    labels = RunLabels(pin="p", disc="d", normal_force_N=nominal, temperature_C=20.0)
    tol = Tolerances()
    flagged = "normal_force_off_nominal" in qc_flags(labels, measured, 20.0, tol)
    assert flagged == (abs(measured - nominal) > tol.force_limit_N(nominal))


manifest_rows = st.lists(
    st.tuples(
        st.text(alphabet="abcdefghij_-0123456789", min_size=1, max_size=10),
        names,
        names,
        st.one_of(st.none(), st.floats(0.01, 100, allow_nan=False).map(lambda v: round(v, 3))),
        st.one_of(st.none(), st.integers(-20, 80).map(float)),
        st.one_of(st.none(), st.integers(1, 9)),
    ),
    min_size=1, max_size=8, unique_by=lambda r: r[0],
)


@given(rows=manifest_rows, semicolon=st.booleans())
def test_manifest_round_trip(tmp_path_factory: pytest.TempPathFactory, rows: list,
                             semicolon: bool) -> None:
    """What a lab writes into a manifest (comma, or semicolon with decimal comma) reads back;
    empty cells stay unknown."""
    import csv

    sep = ";" if semicolon else ","
    path = tmp_path_factory.mktemp("m") / "manifest.csv"
    with path.open("w", encoding="utf-8", newline="") as fh:
        writer = csv.writer(fh, delimiter=sep)
        writer.writerow(["file", "pin", "disc", "normal_force_N", "temperature_C", "repeat"])
        for file, pin, disc, force, temperature, repeat in rows:
            cells = ["" if v is None else (str(v).replace(".", ",") if semicolon else str(v))
                     for v in (force, temperature)]
            writer.writerow([f"{file}.csv", pin, disc, *cells,
                             "" if repeat is None else repeat])
    read = read_manifest(path)
    assert len(read) == len(rows)
    for file, pin, disc, force, temperature, repeat in rows:
        fields = read.get(f"{file}.csv").fields
        expected = {"pin": pin, "disc": disc, "normal_force_N": force,
                    "temperature_C": temperature, "repeat": repeat}
        assert fields == {k: v for k, v in expected.items() if v is not None}


def test_reader_overrides(tmp_path: Path) -> None:
    campaign = make_campaign(tmp_path, extra='encoding = "utf-16"\ndelimiter = "tab"\n'
                                             'decimal = ","\n')
    assert (campaign.read_options.encoding, campaign.read_options.delimiter,
            campaign.read_options.decimal) == ("utf-16", "\t", ",")
    with pytest.raises(ConfigError, match="decimal"):
        make_campaign(tmp_path, extra='decimal = ";"\n')


# --------------------------------------------------------------------------- sessions


def test_a_manifest_names_tests_of_one_file_and_refuses_a_test_twice(tmp_path: Path) -> None:
    path = tmp_path / "m.csv"
    path.write_text("file;test;pin;disc;normal_force_N;temperature_C;repeat\n"
                    "s.txt;;DS30;steel;;20;\n"
                    "s.txt;DS30 1 N #1 ;;;1;;1\n"
                    "s.txt;DS30 3 N #1;;;3,5;;1\n", encoding="utf-8")
    manifest = read_manifest(path)
    assert manifest.get("s.txt").fields == {"pin": "DS30", "disc": "steel",
                                            "temperature_C": 20.0}
    # the Test name as the export writes it, surrounding blanks aside
    assert manifest.get("s.txt", "DS30 1 N #1").fields == {"normal_force_N": 1.0, "repeat": 1}
    assert manifest.get("s.txt", "DS30 3 N #1").line == 4
    whole, tests = manifest.for_file("raw/s.txt", "s.txt")
    assert whole.line == 2 and sorted(r.test for r in tests) == ["DS30 1 N #1", "DS30 3 N #1"]
    path.write_text(path.read_text(encoding="utf-8") + "s.txt;DS30 1 N #1;;;2;;1\n",
                    encoding="utf-8")
    with pytest.raises(ConfigError, match=r"m\.csv:5: file 's\.txt' with test 'DS30 1 N #1' "
                                          r"listed twice \(first on line 3\)"):
        read_manifest(path)


def test_the_test_pattern_key_and_its_older_spelling(tmp_path: Path) -> None:
    pattern = "{pin} on {disc}, {force} N, {temperature} °C, #{repeat}"
    assert match_pattern(pattern, "DS30 on steel, 2,5 N, 20 °C, #3") == {
        "pin": "DS30", "disc": "steel", "normal_force_N": 2.5, "temperature_C": 20.0,
        "repeat": 3}
    new = make_campaign(tmp_path, pattern=False, extra=f'test_pattern = "{pattern}"\n')
    assert new.test_pattern == pattern and new.use_export_names
    old = make_campaign(tmp_path, extra="use_export_names = true\n")
    assert old.test_pattern == PATTERN  # export_pattern defaults to the file-name pattern
    with pytest.raises(ConfigError, match="test_pattern and export_pattern"):
        make_campaign(tmp_path, extra=f'test_pattern = "{pattern}"\nuse_export_names = true\n'
                                      f'export_pattern = "{PATTERN}"\n')
    with pytest.raises(ConfigError, match="test_pattern.*no usable placeholder"):
        make_campaign(tmp_path, extra='test_pattern = "plain"\n')
