"""Every material name that comes in is resolved through the one vocabulary at the edge
(tribopipe.materials): a campaign's patterns and manifest, the options of `reduce`,
`query`, `export`, `map table`, a merged package, an imported table. A known name or
alias is stored (or looked up) under its canonical name, the given one kept; an unknown
name is refused in one line with a did-you-mean and the fix, before any work.
"""

from __future__ import annotations

import csv
import io
import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from helpers import reduce_cli
from hostile import good_export
from tribopipe import frictionmap as fm
from tribopipe.cli import main
from tribopipe.export.citation import Publisher
from tribopipe.export.publish import publish_map
from tribopipe.frictionmap.records import imported_id

EXAMPLE = Path(__file__).resolve().parents[1] / "raw" / "example"
PATTERN = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"
NAMES = '[names]\nDS30 = "Dragonskin 30"\nEF50 = "Ecoflex 00-50"\nacrylic = "acrylic glass"\n'
#: the two files of the 48 whose names carry a typo, and what they become
TYPOS = {"DS30_acrylic_5N_10C_r1.csv": "DS03_acrylic_5N_10C_r1.csv",
         "EF50_steel_9N_20C_r2.csv": "EF50_stel_9N_20C_r2.csv"}


def invoke(*args: str | Path):
    return CliRunner().invoke(main, [str(a) for a in args])


def one_line(result) -> str:
    lines = [ln for ln in result.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, result.stderr
    return lines[0]


def example_campaign(root: Path, *, manifest: str | None = None) -> Path:
    """The 48 example exports in ``root/raw``, two of them renamed with a typo when no
    ``manifest`` is given (then labelled by the file-name pattern), else labelled by the
    manifest text only; returns the campaign file."""
    raw = root / "raw"
    raw.mkdir(parents=True)
    exports = sorted(EXAMPLE.glob("*.csv"))
    exports = [p for p in exports if p.name != "manifest.csv"]
    assert len(exports) == 48
    for p in exports:
        name = TYPOS.get(p.name, p.name) if manifest is None else p.name
        shutil.copy(p, raw / name)
    text = ('[campaign]\nname = "typos"\nraw_dir = "raw"\noutput_dir = "out"\n'
            "plots = false\nsynthetic = true\n")
    if manifest is None:
        text += f'filename_pattern = "{PATTERN}"\n' + NAMES
    else:
        (root / "manifest.csv").write_text(manifest, encoding="utf-8")
        text += 'manifest = "manifest.csv"\n'
    cfg = root / "campaign.toml"
    cfg.write_text(text, encoding="utf-8")
    return cfg


def assert_nothing_reduced(root: Path) -> None:
    out = root / "out"
    assert not (out / "friction_map.parquet").exists()
    assert not list(out.glob("traces/*"))
    assert not list(out.glob("summaries/*"))


# ------------------------------------------------------------------ a whole campaign


def test_two_typos_in_48_file_names_are_both_refused_before_any_work(tmp_path: Path):
    cfg = example_campaign(tmp_path)
    result = invoke("batch", cfg, "--jobs", "1")
    assert result.exit_code == 1
    line = one_line(result)
    assert "2 material name(s) not in the vocabulary, nothing reduced" in line
    assert "unknown pin 'DS03'; did you mean 'Dragonskin 30'" in line
    assert "unknown disc 'stel'; did you mean 'steel'" in line
    assert "DS03_acrylic_5N_10C_r1.csv" in line and "EF50_stel_9N_20C_r2.csv" in line
    assert "materials add" in line
    assert_nothing_reduced(tmp_path)


def test_two_typos_in_a_48_row_manifest_are_both_refused_before_any_work(tmp_path: Path):
    rows = list(csv.DictReader(io.StringIO((EXAMPLE / "manifest.csv").read_text("utf-8"))))
    assert len(rows) == 48
    rows[7]["pin"] = "Dragonskni 30"
    rows[40]["disc"] = "acryl glass"
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=["file", "pin", "disc", "normal_force_N",
                                              "temperature_C", "repeat"],
                            extrasaction="ignore", lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    cfg = example_campaign(tmp_path, manifest=text.getvalue())
    result = invoke("batch", cfg, "--jobs", "1")
    assert result.exit_code == 1
    line = one_line(result)
    assert "2 material name(s) not in the vocabulary, nothing reduced" in line
    assert "unknown pin 'Dragonskni 30'; did you mean 'Dragonskin 30'" in line
    assert "unknown disc 'acryl glass'; did you mean 'acrylic glass'" in line
    assert rows[7]["file"] in line and rows[40]["file"] in line
    assert_nothing_reduced(tmp_path)


# ------------------------------------------------------------------ reduce's options


def test_reduce_stores_the_canonical_name_and_keeps_the_given_one(tmp_path: Path):
    export = good_export(tmp_path / "run.csv")
    map_path = tmp_path / "m.parquet"
    result = reduce_cli(export, "--pin", "Dragon Skin 30", "--disc", "Stahl", "--force", "3",
                        "--temperature", "20", "--map", map_path, "-o", tmp_path / "out")
    assert result.exit_code == 0, result.output
    (row,) = fm.read_map(map_path).to_dict(orient="records")
    assert (row["pin"], row["disc"]) == ("Dragonskin 30", "steel")
    assert (row["pin_as_given"], row["disc_as_given"]) == ("Dragon Skin 30", "Stahl")


def test_reduce_refuses_unknown_names_in_one_line_before_any_work(tmp_path: Path):
    export = good_export(tmp_path / "run.csv")
    map_path, out = tmp_path / "m.parquet", tmp_path / "out"
    result = reduce_cli(export, "--pin", "Dragonskn 30", "--disc", "steal", "--force", "3",
                        "--temperature", "20", "--map", map_path, "-o", out)
    assert result.exit_code == 1
    line = one_line(result)
    assert "unknown pin 'Dragonskn 30'; did you mean 'Dragonskin 30'" in line
    assert "unknown disc 'steal'; did you mean 'steel'" in line
    assert "tribopipe materials add" in line
    assert not map_path.exists() and not out.exists()


# ------------------------------------------------------------------ options that read the map


@pytest.fixture(scope="module")
def founding(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("founding") / "map.parquet"
    fm.import_table(path)
    return path


def test_query_resolves_an_alias_and_refuses_a_typo(founding: Path):
    ok = invoke("query", "--pin", "DS30", "--disc", "Stahl", "--pressure", "35.37",
                "--temperature", "20", "--map", founding)
    assert ok.exit_code == 0, ok.output
    assert "Dragonskin 30" in ok.stdout and "steel" in ok.stdout
    bad = invoke("query", "--pin", "Dragonskni 30", "--disc", "steel", "--pressure", "35.37",
                 "--temperature", "20", "--map", founding)
    assert bad.exit_code == 1
    line = one_line(bad)
    assert "unknown pin 'Dragonskni 30'; did you mean 'Dragonskin 30'" in line
    assert "the map holds" in line


def test_a_single_pair_export_resolves_an_alias_and_refuses_a_typo(founding: Path):
    ok = invoke("export", "mujoco", "--pin", "Dragon Skin 30", "--disc", "steel",
                "--pressure", "35.37", "--temperature", "20", "--map", founding)
    assert ok.exit_code == 0, ok.output
    assert "Dragonskin 30" in ok.stdout
    bad = invoke("export", "mujoco", "--pin", "Dragonskin 30", "--disc", "stell",
                 "--pressure", "35.37", "--temperature", "20", "--map", founding)
    assert bad.exit_code == 1
    assert "unknown disc 'stell'; did you mean 'steel'" in one_line(bad)


def test_map_table_filters_by_an_alias(founding: Path):
    result = invoke("map", "table", "--format", "csv", "--pin", "DS30", "--disc", "PMMA",
                    "--map", founding)
    assert result.exit_code == 0, result.output
    rows = list(csv.DictReader(io.StringIO(result.stdout)))
    assert rows and {(r["pin"], r["disc"]) for r in rows} == {("Dragonskin 30",
                                                               "acrylic glass")}


def test_a_name_an_older_map_holds_outside_the_vocabulary_still_filters(tmp_path: Path):
    from test_labs import lab_row

    path = tmp_path / "old.parquet"
    fm.store.append_records(path, [lab_row(1, "Lab B", 0.5, pin="Mold Star 15",
                                           disc="steel")])  # stored below the edges
    result = invoke("map", "table", "--format", "csv", "--pin", "mold star 15",
                    "--map", path)
    assert result.exit_code == 0, result.output
    assert "Mold Star 15" in result.stdout


# ------------------------------------------------------------------ rows from elsewhere


def test_an_imported_table_is_stored_under_canonical_names_or_refused(tmp_path: Path):
    header = "pin,disc,contactForce,contactPressure,temperature,measurementNo,cof\n"
    table = tmp_path / "theirs.csv"
    table.write_text(header + "DS30,Stahl,3,35.37,20,1,0.5\n", encoding="utf-8")
    map_path = tmp_path / "m.parquet"
    assert invoke("map", "import", table, "--map", map_path).exit_code == 0
    (row,) = fm.read_map(map_path).to_dict(orient="records")
    assert (row["pin"], row["disc"], row["pin_as_given"], row["disc_as_given"]) == (
        "Dragonskin 30", "steel", "DS30", "Stahl")
    # the row's id is made from the names as the table writes them, as before names were
    # resolved: a map that imported this table earlier finds the same rows again
    assert row["measurement_id"] == imported_id("import:theirs.csv", "DS30", "Stahl", 3.0,
                                                20.0, 1)
    again = invoke("map", "import", table, "--map", map_path)
    assert again.exit_code == 0 and len(fm.read_map(map_path)) == 1
    bad = tmp_path / "bad.csv"
    bad.write_text(header + "Mold Star 15,steel,3,35.37,20,1,0.5\n", encoding="utf-8")
    other = tmp_path / "other.parquet"
    result = invoke("map", "import", bad, "--map", other)
    assert result.exit_code == 1
    assert "unknown pin 'Mold Star 15'" in one_line(result)
    assert not other.exists()


def test_a_package_with_a_material_the_vocabulary_lacks_is_refused_with_the_fix(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    from test_labs import lab_row

    theirs = tmp_path / "theirs.parquet"
    fm.store.append_records(theirs, [lab_row(i, None, 0.5 + i / 100, pin="Mold Star 15",
                                             disc="steel") for i in (1, 2)])
    package = tmp_path / "package"
    publish_map(theirs, package, Publisher("Lab B", "B. Person"), date="2026-01-01")
    monkeypatch.chdir(tmp_path)
    ours = tmp_path / "ours.parquet"
    result = invoke("map", "merge", package, "--map", ours)
    assert result.exit_code == 1
    line = one_line(result)
    assert "unknown pin 'Mold Star 15'" in line
    assert "`tribopipe materials add 'Mold Star 15' --class CLASS`" in line
    assert '"Mold Star 15" = { class = "CLASS" }' in line
    assert not ours.exists()
    # the one line in the lab's materials.toml, and the same package merges
    Path("materials.toml").write_text(
        '[materials]\n"Mold Star 15" = { class = "silicone elastomer" }\n', encoding="utf-8")
    again = invoke("map", "merge", package, "--map", ours)
    assert again.exit_code == 0, again.output
    assert set(fm.read_map(ours)["pin"]) == {"Mold Star 15"}


def test_a_refusal_of_many_names_stays_a_readable_line():
    """A package of a thousand lots' own pin names is refused in one line that names the
    first ten, each with its fix, and counts the rest (not a line of some 100 kB)."""
    from tribopipe.materials import NAMES_SHOWN, MaterialError, load_vocabulary

    names = [("pin", f"Sample lot {k}") for k in range(1000)] + [("disc", "steel")]
    with pytest.raises(MaterialError) as caught:
        load_vocabulary().resolve_all(names, where="pkg")
    text = str(caught.value)
    assert text.count("unknown pin 'Sample lot ") == NAMES_SHOWN
    assert "1000 material names not in the vocabulary" in text
    assert f"; and {1000 - NAMES_SHOWN} more" in text
    assert f"and {1000 - NAMES_SHOWN} more)" in caught.value.hint
    assert "'Sample lot 0'" in caught.value.hint and "'Sample lot 999'" not in text
    assert len(text) + len(caught.value.hint) < 3000
