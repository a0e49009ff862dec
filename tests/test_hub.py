"""A hub grown by three labs, as they would grow it: real reduced runs published with their
evidence, checked, refused or filed through the real CLI, the site built and driven in a
real headless Chromium at three widths, and the pull-request workflow's own command run.

Lab A's package is clean. Lab B's has one μ_K raised and every checksum re-hashed (and the
tables that would betray it removed): the recompute refuses it; its honest package goes in.
Lab C's holds two of Lab A's raw exports as its own: refused as a duplicate.
"""

from __future__ import annotations

import csv
import functools
import http.server
import io
import json
import math
import os
import re
import shlex
import shutil
import subprocess
import sys
import threading
import zipfile
from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner

from conftest import CHROMIUM_ARGS, browser_unavailable, chromium_executable
from generators.synthetic import SyntheticRun
from reduced_runs import RUNS, make_processed
from tribopipe.cli import main
from tribopipe.escape import html_text
from tribopipe.evidence import recompute_package
from tribopipe.frictionmap.datapackage import sha256_hash
from tribopipe.hub.folder import CHECK_COMMAND, WORKFLOW, workflow_command
from tribopipe.hub.site import comparisons_page
from tribopipe.stats import group_statistics, lab_comparison, reproducibility

REPO = Path(__file__).resolve().parents[1]
#: Lab B: its own exports (other seeds), two conditions shared with Lab A
RUNS_B = [
    ("b_ds_steel_3N_r1", "Dragonskin 30", "steel", 3.0, 20.0, 1,
     SyntheticRun(mu_s=0.81, mu_k=0.56, normal_force_N=3.0, seed=31)),
    ("b_ds_steel_3N_r2", "Dragonskin 30", "steel", 3.0, 20.0, 2,
     SyntheticRun(mu_s=0.80, mu_k=0.55, normal_force_N=3.0, seed=32)),
    ("b_ds_steel_9N_r1", "Dragonskin 30", "steel", 9.0, 20.0, 1,
     SyntheticRun(mu_s=0.61, mu_k=0.40, normal_force_N=9.0, seed=33)),
]


def invoke(*args):
    result = CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)
    return result


def publish(root: Path, runs, lab: str, name: str) -> Path:
    map_path, _ = make_processed(root / name, runs)
    out = root / f"package-{name}"
    result = invoke("map", "publish", "-o", out, "--lab", lab, "--contact", f"{lab} contact",
                    "--email", "data@lab.example", "--map", map_path, "--with-raw",
                    "--raw-dir", root / name / "raw")
    assert result.exit_code == 0, result.output
    return out


def tamper_mu_k(package: Path, target: Path, delta: float) -> str:
    """Raise the first run's μ_K in data/runs.csv by ``delta``, drop the tables that would
    still hold the old value, re-hash the descriptor; returns the run's id."""
    shutil.copytree(package, target)
    text = (target / "data/runs.csv").read_text(encoding="utf-8")
    rows = list(csv.DictReader(io.StringIO(text)))
    rows[0]["mu_k"] = repr(float(rows[0]["mu_k"]) + delta)
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    (target / "data/runs.csv").write_text(buf.getvalue(), encoding="utf-8")
    desc = json.loads((target / "datapackage.json").read_text(encoding="utf-8"))
    keep = []
    for res in desc["resources"]:
        if res["name"] in ("runs-parquet", "groups", "groups-parquet", "frictionmap-app"):
            (target / res["path"]).unlink()
            continue
        data = (target / res["path"]).read_bytes()
        res["bytes"], res["hash"] = len(data), sha256_hash(data)
        keep.append(res)
    desc["resources"] = keep
    (target / "datapackage.json").write_text(json.dumps(desc, indent=1), encoding="utf-8")
    return rows[0]["measurement_id"]


@pytest.fixture(scope="module")
def grown(tmp_path_factory):
    """The hub after the three labs tried: A and B filed, B's tampered copy and C refused;
    returns the folders and each command's result."""
    root = tmp_path_factory.mktemp("hub")
    pkg_a = publish(root, RUNS, "Lab A", "a")
    pkg_b = publish(root, RUNS_B, "Lab B", "b")
    pkg_c = publish(root, RUNS[:2], "Lab C", "c")  # Lab A's raw exports, again
    tampered = root / "package-b-tampered"
    edited = tamper_mu_k(pkg_b, tampered, 0.05)
    hub = root / "hub"
    out = {"init": invoke("hub", "init", hub, "--title", "Soft friction hub")}
    out["add_a"] = invoke("hub", "add", pkg_a, "--hub", hub)
    out["check_tampered"] = invoke("hub", "check", tampered, "--hub", hub)
    out["add_tampered"] = invoke("hub", "add", tampered, "--hub", hub)
    out["add_b"] = invoke("hub", "add", pkg_b, "--hub", hub)
    out["check_c"] = invoke("hub", "check", pkg_c, "--hub", hub)
    out["add_c"] = invoke("hub", "add", pkg_c, "--hub", hub)
    out["build"] = invoke("hub", "build", hub, "-o", root / "site")
    return {"root": root, "hub": hub, "site": root / "site", "a": pkg_a, "b": pkg_b,
            "c": pkg_c, "tampered": tampered, "edited": edited, "out": out}


def test_package_carries_its_evidence(grown):
    pkg = grown["a"]
    desc = json.loads((pkg / "datapackage.json").read_text(encoding="utf-8"))
    names = {r["name"] for r in desc["resources"]}
    assert {"evidence", "evidence-settings"} <= names
    index = list(csv.DictReader(io.StringIO((pkg / "evidence/index.csv").read_text())))
    assert len(index) == len(RUNS)
    for row in index:
        trace = (pkg / row["trace_path"]).read_bytes()
        raw = (pkg / row["raw_path"]).read_bytes()
        assert sha256_hash(trace)[7:] == row["trace_sha256"]
        assert sha256_hash(raw)[7:] == row["raw_sha256"]
        assert row["method"].startswith("tribopipe-v")
    settings = json.loads((pkg / "evidence/settings.json").read_text())
    assert set(settings) == {row["config_hash"] for row in index}
    again = recompute_package(pkg)
    assert again.ok, again.lines()
    assert all(r.basis == "raw export" for r in again.rows)
    assert all(r.recomputed[1] is not None for r in again.rows)


def test_recompute_names_the_edited_row_and_both_values(grown):
    result = invoke("map", "validate", "--recompute", grown["tampered"])
    assert result.exit_code == 1
    # the package alone no longer betrays the edit ...
    assert invoke("map", "validate", grown["tampered"]).exit_code == 0
    bad = [line for line in result.output.splitlines() if grown["edited"] in line]
    assert len(bad) == 1, result.output
    assert "mu_k stored" in bad[0] and "re-derived from the raw export" in bad[0]
    assert "beyond its stated U" in bad[0]


def test_recompute_from_the_trace_only_says_so(grown, tmp_path):
    target = tmp_path / "no-raw"
    publish_root = grown["root"]
    result = invoke("map", "publish", "-o", target, "--lab", "Lab A",
                    "--map", publish_root / "a/processed/friction_map.parquet")
    assert result.exit_code == 0, result.output
    again = invoke("map", "validate", "--recompute", target)
    assert again.exit_code == 0, again.output
    assert f"{len(RUNS)} runs could only be checked from their trace" in again.output
    bare = tmp_path / "bare"
    result = invoke("map", "publish", "-o", bare, "--lab", "Lab A", "--no-evidence",
                    "--map", publish_root / "a/processed/friction_map.parquet")
    again = invoke("map", "validate", "--recompute", bare)
    assert again.exit_code == 0, again.output
    assert f"{len(RUNS)} runs carry no evidence" in again.output


def test_hub_refuses_the_tampered_and_the_duplicate(grown):
    out = grown["out"]
    assert out["init"].exit_code == 0
    assert out["add_a"].exit_code == 0 and "labs/lab-a/" in out["add_a"].output
    assert out["check_tampered"].exit_code == 1
    assert grown["edited"] in out["check_tampered"].output
    assert out["add_tampered"].exit_code == 1 and "not added" in out["add_tampered"].output
    assert out["add_b"].exit_code == 0, out["add_b"].output
    assert out["check_c"].exit_code == 1
    lines = [x for x in out["check_c"].output.splitlines() if "raw content" in x]
    assert len(lines) == 2 and all("'Lab A'" in x for x in lines)
    assert out["add_c"].exit_code == 1
    labs = sorted(p.name for p in (grown["hub"] / "labs").iterdir() if p.is_dir())
    assert labs == ["lab-a", "lab-b"]


def test_workflow_runs_the_check_it_names(grown):
    text = (grown["hub"] / WORKFLOW).read_text(encoding="utf-8")
    assert "pull_request" in text
    command = workflow_command(text)
    assert command == CHECK_COMMAND
    argv = shlex.split(command)
    assert argv[0] == "tribopipe"
    env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
    done = subprocess.run([sys.executable, "-m", "tribopipe", *argv[1:]], cwd=grown["hub"],
                          capture_output=True, text=True, env=env, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "2 packages checked, 0 refused" in done.stdout
    # the refused package, put in by hand as a pull request would, fails the same command
    shutil.copytree(grown["c"], grown["root"] / "hub-pr" / "x", dirs_exist_ok=True)
    pr = grown["root"] / "hub-pr"
    shutil.rmtree(pr)
    shutil.copytree(grown["hub"], pr)
    shutil.copytree(grown["c"], pr / "labs/lab-c/2099-01-01")
    done = subprocess.run([sys.executable, "-m", "tribopipe", *argv[1:]], cwd=pr,
                          capture_output=True, text=True, env=env, timeout=600)
    assert done.returncode == 1
    assert "raw content" in done.stdout and "1 refused" in done.stdout


def test_merged_map_and_downloads(grown):
    assert grown["out"]["build"].exit_code == 0, grown["out"]["build"].output
    site = grown["site"]
    merged = pd.read_parquet(site / "downloads/friction_map.parquet")
    assert len(merged) == len(RUNS) + len(RUNS_B)
    assert sorted(set(merged["lab"])) == ["Lab A", "Lab B"]
    csv_rows = list(csv.DictReader(io.StringIO(
        (site / "downloads/friction_map.csv").read_text(encoding="utf-8"))))
    assert len(csv_rows) == len(merged)
    for name in ("lab-a", "lab-b"):
        [zipped] = site.glob(f"downloads/{name}-*.zip")
        with zipfile.ZipFile(zipped) as zf:
            assert any(n.endswith("/datapackage.json") for n in zf.namelist())
    comparisons = (site / "comparisons.html").read_text(encoding="utf-8")
    assert comparisons.count("<tr><td>Dragonskin 30</td>") == 2  # 3 N and 9 N shared
    # the page shows the map's own between-lab statistics, not a copy of them
    pooled = group_statistics(merged)
    shared = pooled[pooled["mu_k_labs"] >= 2]
    assert len(shared) == 2
    rows = comparison_rows(comparisons)
    assert len(rows) == 2
    assert [r[13] for r in rows] == ["yes" if d else "no" for d in shared["labs_disagree"]]
    s_R = reproducibility(pooled, "mu_k").s_R
    assert math.isfinite(s_R) and f"s_R = {s_R:.3g} (ISO 5725-2)" in comparisons
    for r in rows:
        en = float(r[9])
        assert r[10] == ("agree" if abs(en) <= 1 else "disagree")


def comparison_rows(page: str) -> list[list[str]]:
    """The cells of each row of the comparisons table, as text (tags removed)."""
    body = page.split('<table id="comparisons">', 1)[1].split("<tbody>", 1)[1]
    return [[re.sub(r"<[^>]+>", "", cell) for cell in re.findall(r"<td>(.*?)</td>", row)]
            for row in re.findall(r"<tr>(.*?)</tr>", body.split("</tbody>", 1)[0])]


def test_comparisons_page_reads_map_compare(grown):
    """The site's comparisons are ``map compare``'s (:func:`lab_comparison`) for the same
    merged map, number for number, so the two can never disagree."""
    assert grown["out"]["build"].exit_code == 0, grown["out"]["build"].output
    site = grown["site"]
    merged = pd.read_parquet(site / "downloads/friction_map.parquet")
    table = lab_comparison(merged, "mu_k")
    rows = comparison_rows((site / "comparisons.html").read_text(encoding="utf-8"))
    assert len(rows) == len(table) == 2
    for row, expected in zip(rows, table.to_dict(orient="records"), strict=True):
        assert row[:2] == [expected["pin"], expected["disc"]]
        assert float(row[2]) == pytest.approx(expected["normal_force_N"], rel=1e-3)
        assert float(row[3]) == pytest.approx(expected["pressure_kPa"], rel=1e-3)
        assert float(row[4]) == pytest.approx(expected["temperature_C"], rel=1e-3)
        for cell, side in ((row[6], "a"), (row[7], "b")):
            lab, rest = cell.split(" (n = ", 1)
            n, mean_pm = rest.split("): ", 1)
            assert lab == expected["lab_" + side] and int(n) == expected["n_" + side]
            mean, u = (float(x) for x in mean_pm.split(" ± "))
            assert mean == pytest.approx(expected["mean_" + side], abs=u / 10)
            assert u == pytest.approx(expected["U_" + side], rel=0.05)
        diff, u_diff = (float(x) for x in row[8].split(" ± "))
        assert u_diff == pytest.approx(expected["U_difference"], rel=0.05)
        assert diff == pytest.approx(expected["difference"], abs=u_diff / 10)
        assert float(row[9]) == pytest.approx(expected["En"], abs=0.005)
        assert float(row[11]) == pytest.approx(expected["z_a"], abs=0.005)
        assert float(row[12]) == pytest.approx(expected["z_b"], abs=0.005)
        assert row[13] == ("yes" if expected["labs_disagree"] else "no")
    # a hostile lab or material name in a comparison row stays text
    hostile = table.assign(lab_a=HOSTILE_LAB, pin=HOSTILE_LAB)
    page = comparisons_page("hub", hostile, {}, 0.1)
    assert "<script>alert(1)" not in page
    assert page.count(html_text(HOSTILE_LAB)) == 2 * len(table)


# --------------------------------------------------------------------------- browser


def with_browser(body) -> None:
    """Run ``body(browser)`` with a headless Chromium (the system's, under Playwright) in a
    thread of its own: Playwright's sync API allows one instance per thread, and other
    test modules keep theirs open for the session."""
    executable = chromium_executable()
    from playwright.sync_api import sync_playwright

    outcome: dict[str, BaseException] = {}

    def run() -> None:
        try:
            with sync_playwright() as manager:
                try:
                    instance = manager.chromium.launch(executable_path=executable,
                                                       args=CHROMIUM_ARGS)
                except Exception as exc:  # the browser exists but cannot start here
                    browser_unavailable(f"chromium at {executable} did not start: "
                                        f"{str(exc).splitlines()[0]}")
                try:
                    body(instance)
                finally:
                    instance.close()
        except BaseException as exc:  # re-raised in the test's own thread
            outcome["exc"] = exc

    thread = threading.Thread(target=run)
    thread.start()
    thread.join()
    if "exc" in outcome:
        raise outcome["exc"]


@pytest.mark.parametrize("width", [800, 1024, 1400])
def test_site_in_a_browser(grown, served, width):
    with_browser(lambda browser: site_steps(browser, grown, served, width))


def site_steps(browser, grown, served, width):
    site = grown["site"]
    context = browser.new_context(viewport={"width": width, "height": 900},
                                  accept_downloads=True)
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.goto((site / "index.html").as_uri())
    rows = page.locator("#groups tbody tr")
    total = rows.count()
    assert total > 0
    # the lab filter: untick Lab B, only Lab A's rows stay
    page.locator('input.lab-filter[value="Lab B"]').uncheck()
    visible = page.locator("#groups tbody tr:not([hidden])")
    assert 0 < visible.count() < total
    assert set(visible.evaluate_all("rs => rs.map(r => r.dataset.lab)")) == {"Lab A"}
    assert f"of {total} lab groups shown" in page.locator("#shown-count").inner_text()
    # nothing wider than the window
    assert page.evaluate("document.documentElement.scrollWidth") <= width
    # a lab page, with its citation
    page.locator('#lab-filter a:has-text("Lab B")').click()
    page.wait_for_url("**/labs/lab-b.html")
    bib = page.locator("#bibtex").inner_text()
    assert bib.startswith("@misc{labb") and "author = {{Lab B}}" in bib
    assert "cff-version" in page.locator("#cff").inner_text()
    assert page.locator("#lab-email").inner_text() == "data@lab.example"
    assert page.locator("#conditions tbody tr").count() == 2
    href = page.locator('#releases a:has-text("CITATION.cff")').get_attribute("href")
    assert (site / "labs" / href).resolve().read_bytes().count(b"Lab B") >= 1
    # the explorer over all labs opens from the lab page's navigation
    page.locator('nav a:has-text("explorer")').click()
    page.wait_for_load_state()
    assert page.locator("#pin").count() == 1
    assert not errors, errors
    # a download link, with the site served as GitHub Pages serves it
    page.goto(f"{served}/index.html")
    with page.expect_download() as info:
        page.locator("#download-csv").click()
    saved = Path(info.value.path())
    assert saved.read_bytes() == (site / "downloads/friction_map.csv").read_bytes()
    assert info.value.suggested_filename == "friction_map.csv"
    context.close()


class _Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args) -> None:
        pass


@pytest.fixture(scope="module")
def served(grown):
    """The built site over HTTP on localhost (as GitHub Pages would serve it)."""
    handler = functools.partial(_Quiet, directory=str(grown["site"]))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_address[1]}"
    server.shutdown()
    server.server_close()


def test_materials_outside_the_vocabulary_are_refused_until_the_hub_adds_them(grown,
                                                                               tmp_path):
    hub = tmp_path / "hub"
    shutil.copytree(grown["hub"], hub)
    runs = [("s_new_3N_r1", "Mold Star 15", "steel", 3.0, 20.0, 1,
             SyntheticRun(mu_s=0.9, mu_k=0.6, normal_force_N=3.0, seed=41)),
            ("s_typo_3N_r1", "Dragonskn 30", "steel", 3.0, 20.0, 1,
             SyntheticRun(mu_s=0.9, mu_k=0.6, normal_force_N=3.0, seed=42))]
    pkg = publish(tmp_path, runs, "Lab D", "d")
    result = invoke("hub", "check", pkg, "--hub", hub)
    assert result.exit_code == 1
    lines = [x for x in result.output.splitlines() if x.startswith("data/runs.csv: ")]
    assert len(lines) == 2, result.output
    assert "unknown pin 'Dragonskn 30'; did you mean 'Dragonskin 30'" in lines[0]
    assert "unknown pin 'Mold Star 15'" in lines[1]
    assert 'e.g. "Mold Star 15" = { class = "CLASS" }' in lines[1]  # the line to add
    # one line in the hub's materials file (a pull request) adds the genuinely new one
    (hub / "materials.toml").write_text(
        '[materials]\n"Mold Star 15" = { class = "silicone elastomer", supplier = "Smooth-On" }\n',
        encoding="utf-8")
    again = invoke("hub", "check", pkg, "--hub", hub)
    assert again.exit_code == 1
    assert [x for x in again.output.splitlines() if x.startswith("data/runs.csv: ")] \
        == [lines[0]]


HOSTILE_LAB = '<script>alert(1)</script> & "Lab" {\\x}'


def test_hostile_names_stay_text_on_every_page(tmp_path):
    pkg = publish(tmp_path, RUNS[:1], HOSTILE_LAB, "h")
    hub = tmp_path / "hub"
    assert invoke("hub", "init", hub).exit_code == 0
    added = invoke("hub", "add", pkg, "--hub", hub)
    assert added.exit_code == 0, added.output
    [folder] = [p for p in (hub / "labs").iterdir() if p.is_dir()]
    assert folder.name == "script-alert-1-script-lab-x"
    assert invoke("hub", "build", hub, "-o", tmp_path / "site").exit_code == 0
    pages = list((tmp_path / "site").rglob("*.html"))
    for page in pages:
        text = page.read_text(encoding="utf-8")
        assert "<script>alert(1)" not in text, page
    lab_page = tmp_path / "site/labs" / f"{folder.name}.html"
    with_browser(lambda browser: hostile_steps(browser, lab_page, tmp_path))


def hostile_steps(browser, lab_page, tmp_path):
    context = browser.new_context()
    tab = context.new_page()
    dialogs: list[str] = []
    tab.on("dialog", lambda d: (dialogs.append(d.message), d.dismiss()))
    tab.goto(lab_page.as_uri())
    assert tab.locator("h1").inner_text() == HOSTILE_LAB
    assert "\\{\\textbackslash{}x\\}" in tab.locator("#bibtex").inner_text()
    tab.goto((tmp_path / "site/index.html").as_uri())
    assert tab.locator("input.lab-filter").get_attribute("value") == HOSTILE_LAB
    assert not dialogs
    context.close()


def test_hub_init_writes_its_files_with_the_title_inert(tmp_path):
    import tomllib

    import yaml

    title = 'Hub <script>x</script> "q" *b* \\ é'
    result = invoke("hub", "init", tmp_path / "h", "--title", title)
    assert result.exit_code == 0, result.output
    h = tmp_path / "h"
    assert tomllib.loads((h / "hub.toml").read_text(encoding="utf-8"))["hub"]["title"] == title
    assert yaml.safe_load((h / "CITATION.cff").read_text(encoding="utf-8"))["title"] == title
    assert json.loads((h / ".zenodo.json").read_text(encoding="utf-8"))["title"] == title
    heading = (h / "README.md").read_text(encoding="utf-8").splitlines()[0]
    assert heading.startswith("# Hub \\<script>")  # a backslash-escaped "<": text
    workflow = yaml.safe_load((h / WORKFLOW).read_text(encoding="utf-8"))
    steps = workflow["jobs"]["check"]["steps"]
    assert steps[-1]["run"] == CHECK_COMMAND
    assert "pull_request" in workflow[True]  # YAML 1.1 reads the key `on` as true
    again = invoke("hub", "init", h)
    assert again.exit_code == 1 and "a hub starts empty" in again.output
