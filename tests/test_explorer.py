"""The explorer page without a browser: it is one self-contained file, its embedded data
read back exactly, carry query's own points, survive hostile names, and the command
writes it (in-process and as a subprocess). The page's behaviour in a real browser is
checked in test_explorer_browser.py."""

from __future__ import annotations

import base64
import hashlib
import json
import math
import re
import shutil
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner

from helpers import lab_vocabulary
from reduced_runs import make_processed
from tribopipe.cli import main
from tribopipe.escape import script_json
from tribopipe.export.explorer import (
    DATA_ELEMENT_ID,
    explorer_data,
    explorer_page,
    explorer_parts,
    read_embedded_data,
    write_explorer,
)
from tribopipe.fit import fit_power_law, power_law
from tribopipe.frictionmap import exclude_runs, import_table, read_map
from tribopipe.frictionmap.published import published_csv_path
from tribopipe.query import pair_points, select_pair
from tribopipe.stats import group_statistics

#: the only absolute URL the page may contain: the SVG namespace name (never fetched)
SVG_NAMESPACE = "http://www.w3.org/2000/svg"
HOSTILE_PIN = "</script><script>alert(1)</script>"
HOSTILE_DISC = "<img src=x onerror=alert(2)> & co"
#: a JavaScript line terminator: refused in names at every edge (tribopipe.validate), so
#: it can only reach the page from a DataFrame built in code; the page escapes it anyway
SEPARATOR_DISC = HOSTILE_DISC + "\u2028line"


class Page(HTMLParser):
    """What the checks look at: tags, attributes that load things, scripts and styles."""

    def __init__(self) -> None:
        super().__init__()
        self.tags: list[str] = []
        self.loads: list[str] = []
        self.scripts: list[tuple[dict[str, str | None], str]] = []
        self.styles: list[str] = []
        self.meta: list[dict[str, str | None]] = []
        self._open: tuple[str, dict[str, str | None]] | None = None
        self._text: list[str] = []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.tags.append(tag)
        for name in ("src", "href", "action", "poster", "srcset", "data"):
            if a.get(name):
                self.loads.append(a[name])
        if tag == "meta":
            self.meta.append(a)
        if tag in ("script", "style"):
            self._open = (tag, a)
            self._text = []

    def handle_data(self, data):
        if self._open is not None:
            self._text.append(data)

    def handle_endtag(self, tag):
        if self._open is not None and tag == self._open[0]:
            text = "".join(self._text)
            if tag == "script":
                self.scripts.append((self._open[1], text))
            else:
                self.styles.append(text)
            self._open = None


def parse(html: str) -> Page:
    page = Page()
    page.feed(html)
    page.close()
    return page


def csp_hash(text: str) -> str:
    return "'sha256-" + base64.b64encode(hashlib.sha256(text.encode()).digest()).decode() + "'"


@pytest.fixture(scope="module")
def published(tmp_path_factory) -> tuple[Path, pd.DataFrame]:
    """The shipped published map imported into a real Parquet map, and its runs."""
    map_path = tmp_path_factory.mktemp("published") / "friction_map.parquet"
    import_table(map_path, published_csv_path())
    return map_path, read_map(map_path)


@pytest.fixture(scope="module")
def published_html(published) -> tuple[dict, str]:
    _, runs = published
    data = explorer_data(runs, source="friction_map.parquet")
    return data, explorer_page(data)


def test_the_page_loads_nothing_from_anywhere(published_html):
    _, html = published_html
    page = parse(html)
    assert html.startswith("<!DOCTYPE html>")
    # the only attribute that names a resource is the empty data: icon (no favicon request)
    assert page.loads == ["data:,"]
    assert "link" in page.tags and "iframe" not in page.tags and "img" not in page.tags
    # the only URLs are XML namespace names, never fetched: SVG's, and the one the Drake
    # snippet declares for its drake: elements
    assert sorted(set(re.findall(r"https?://[^\s\"'<>]+", html))) == [
        "http://drake.mit.edu", SVG_NAMESPACE]
    assert "@import" not in html and "url(" not in html
    # no fetch, XHR, websocket, beacon or worker in the script
    script = page.scripts[-1][1]
    for call in ("fetch(", "XMLHttpRequest", "WebSocket", "sendBeacon", "Worker(", "import("):
        assert call not in script, call


def test_the_content_security_policy_admits_exactly_the_page_own_script_and_style(
    published_html,
):
    _, html = published_html
    page = parse(html)
    policy = next(m["content"] for m in page.meta
                  if (m.get("http-equiv") or "").lower() == "content-security-policy")
    rules = dict(r.strip().split(" ", 1) for r in policy.split(";"))
    assert rules["default-src"] == "'none'"
    assert rules["img-src"] == "data:"
    executable = [text for attrs, text in page.scripts if attrs.get("type") != "application/json"]
    assert len(executable) == 1 and len(page.styles) == 1
    assert rules["script-src"] == csp_hash(executable[0])
    assert rules["style-src"] == csp_hash(page.styles[0])


def test_embedded_json_round_trips(published_html):
    data, html = published_html
    page = parse(html)
    blocks = [(attrs["id"], text) for attrs, text in page.scripts
              if attrs.get("type") == "application/json"]
    # the document, then each pair's runs in an element of its own (read when shown)
    assert [i for i, _ in blocks] == [DATA_ELEMENT_ID] + [
        f"tpx-runs-{i}" for i in range(len(data["pairs"]))]
    head = json.loads(blocks[0][1])
    assert head["format"] == data["format"] and "runs" not in head
    # the groups packed as columns and rows, their names left to their pair's
    assert len(head["groups"]["rows"]) == len(data["groups"])
    assert "pin" not in head["groups"]["columns"] and "text/qc" in head["groups"]["columns"]
    # and each speed's interpolation points, each key once per list
    points = head["pairs"][0]["speeds"][0]["mu_k_points"]
    assert "text/mean" in points["columns"] and len(points["rows"]) == len(
        data["pairs"][0]["speeds"][0]["mu_k_points"])
    # packed: each key once per pair, each run a row
    packed = [json.loads(text) for _, text in blocks[1:]]
    assert [[dict(zip(c["columns"], row, strict=True)) for row in c["rows"]]
            for c in packed] == data["runs"]
    assert read_embedded_data(html) == data


def test_the_data_hold_query_points_runs_groups_and_fits(published, published_html):
    _, runs = published
    data, _ = published_html
    groups = group_statistics(runs)
    assert data["format"] == "tribopipe-explorer/2"
    assert len(data["pairs"]) == 11 == len(data["runs"])
    assert len(data["groups"]) == len(groups) == 76
    assert sum(len(r) for r in data["runs"]) == 169
    for pair, pair_runs in zip(data["pairs"], data["runs"], strict=True):
        points = pair_points(select_pair(groups, pair["pin"], pair["disc"]), "mu_k")
        (speed,) = pair["speeds"]  # the published map: one speed
        assert [(p["pressure_kPa"], p["temperature_C"], p["mean"], p["n"])
                for p in speed["mu_k_points"]] == list(
            zip(points["pressure_kPa"], points["temperature_C"], points["mean"], points["n"],
                strict=True))
        assert speed["mu_s_points"] == []  # the published map holds no μ_S
        for point in speed["mu_k_points"]:
            # the repeats behind a point are the pair's runs at its condition
            behind = [pair_runs[i] for i in point["runs"]]
            assert len(behind) == point["n"]
            assert all(r["pressure_kPa"] == pytest.approx(point["pressure_kPa"], rel=1e-3)
                       and r["temperature_C"] == point["temperature_C"] for r in behind)
            assert math.fsum(r["mu_k"] for r in behind) / len(behind) == pytest.approx(
                point["mean"], rel=1e-12)
            # its texts are the tables' (pressure to 4 significant digits, μ to 3 decimals)
            assert point["text"]["p"] == f"{point['pressure_kPa']:.4g}"
            assert point["text"]["mean"] == f"{point['mean']:.3f}"
        # the chips: each measured pressure once, as the tables print it
        assert [c["text"] for c in speed["pressures"]] == [
            f"{v:.4g}" for v in sorted(set(points["pressure_kPa"]))]


def test_fits_are_fit_py_fits_with_their_curves(published, published_html):
    _, runs = published
    data, _ = published_html
    fits = fit_power_law(runs)
    embedded = [(p["pin"], p["disc"], f) for p in data["pairs"] for f in p["fits"]]
    assert len(embedded) == len(fits) == 17
    for pin, disc, f in embedded:
        row = fits[(fits["pin"] == pin) & (fits["disc"] == disc)
                   & (fits["temperature_C"] == f["temperature_C"])].iloc[0]
        assert f["k"] == row["k"] and f["exponent"] == row["exponent"]
        # drawn, never computed with: 24 points to 4 significant digits
        assert len(f["curve"]) == 24
        (p0, _), (p1, _) = f["curve"][0], f["curve"][-1]
        assert (p0, p1) == pytest.approx((row["pressure_min_kPa"], row["pressure_max_kPa"]),
                                         rel=5e-4)
        for p, mu in f["curve"]:
            assert mu == pytest.approx(power_law(p, row["k"], row["exponent"]), rel=2e-3)
            assert (f"{p:.4g}", f"{mu:.4g}") == (repr(p).removesuffix(".0"),
                                                repr(mu).removesuffix(".0"))


def test_missing_numbers_are_null_never_nan(tmp_path):
    map_path, _ = make_processed(tmp_path)
    data = explorer_data(read_map(map_path))
    text = script_json(data)
    assert "NaN" not in text and "Infinity" not in text
    one_run = next(p for p in data["pairs"] if p["pin"] == "Ecoflex 00-50")
    assert one_run["speeds"][0]["mu_k_points"][0]["half"] is None  # one run: CI unknown
    assert one_run["fits"][0]["k"] is None and one_run["fits"][0]["curve"] == []
    ds = next(p for p in data["pairs"] if p["pin"] == "Dragonskin 30")
    assert len(ds["speeds"][0]["mu_s_points"]) == 2  # reduced runs hold μ_S


def test_each_point_carries_the_combined_uncertainty_query_interpolates(tmp_path):
    # the page shows query's u beside the repeats' CI: the points must hold pair_points' u
    from tribopipe.query import pair_points, pairs, select_pair
    from tribopipe.stats import group_statistics

    map_path, _ = make_processed(tmp_path)
    runs = read_map(map_path)
    data = explorer_data(runs)
    groups = group_statistics(runs)
    checked = 0
    for pair in data["pairs"]:
        want = pair_points(select_pair(groups, pair["pin"], pair["disc"]), "mu_k")
        for got, (_, row) in zip(pair["speeds"][0]["mu_k_points"], want.iterrows(),
                                 strict=True):
            if row["u"] == row["u"]:  # not NaN: reduced runs carry their budgets
                assert got["u"] == pytest.approx(float(row["u"]), rel=1e-12)
                assert got["u"] > 0
                checked += 1
            else:
                assert got["u"] is None
    assert checked > 0
    assert pairs(groups)  # the map has pairs to show


def test_excluded_runs_are_left_out(tmp_path):
    map_path, _ = make_processed(tmp_path)
    runs = read_map(map_path)
    victim = runs.loc[runs["pin"] == "Dragonskin 30", "measurement_id"].iloc[0]
    exclude_runs(map_path, [victim], "pin torn")
    data = explorer_data(read_map(map_path))
    ids = {r["id"] for chunk in data["runs"] for r in chunk}
    assert victim not in ids and len(ids) == len(runs) - 1
    behind = [chunk[i]["id"] for p, chunk in zip(data["pairs"], data["runs"], strict=True)
              for pt in p["speeds"][0]["mu_k_points"] for i in pt["runs"]]
    assert victim not in behind and len(behind) == len(runs) - 1


def test_script_json_escapes_what_could_close_the_element():
    value = {"a": "</script><!-- & \u2028\u2029 >", "b": [1.5, None, True]}
    text = script_json(value)
    for raw in ("<", ">", "&", "\u2028", "\u2029"):
        assert raw not in text
    assert json.loads(text) == value
    with pytest.raises(ValueError):
        script_json({"x": math.nan})


def hostile_map(root: Path) -> Path:
    """A published-schema table whose names are markup, imported into a real map."""
    csv = root / "hostile.csv"
    rows = ["pin,disc,contactForce,contactPressure,temperature,measurementNo,cof"]
    for force, pressure, mu in ((1.0, 11.79, 0.6), (3.0, 35.37, 0.4)):
        for repeat in (1, 2):
            rows.append(f'"{HOSTILE_PIN}","{HOSTILE_DISC}",{force},{pressure},20,{repeat},'
                        f"{mu + 0.01 * repeat}")
    csv.write_text("\n".join(rows) + "\n", encoding="utf-8")
    map_path = root / "friction_map.parquet"
    # a hostile lab's materials file names them: names are data, whatever they hold
    import_table(map_path, csv, vocabulary=lab_vocabulary(HOSTILE_PIN, HOSTILE_DISC))
    return map_path


def test_hostile_names_never_become_markup(tmp_path):
    map_path = hostile_map(tmp_path)
    html = write_explorer(map_path, tmp_path / "explorer.html").read_text(encoding="utf-8")
    page = parse(html)
    # the data, its pair's runs and the page's own script, nothing injected
    assert [a.get("type") for a, _ in page.scripts] == ["application/json"] * 2 + [None]
    assert "img" not in page.tags
    assert HOSTILE_PIN not in html and "<img" not in html and "\u2028" not in html
    data = read_embedded_data(html)
    assert data["pairs"][0]["pin"] == HOSTILE_PIN
    assert data["pairs"][0]["disc"] == HOSTILE_DISC
    runs = read_map(map_path)
    runs["disc"] = SEPARATOR_DISC
    page = explorer_page(explorer_data(runs, source="s"))
    assert "\u2028" not in page and "<img" not in page
    assert read_embedded_data(page)["pairs"][0]["disc"] == SEPARATOR_DISC


def test_the_command_writes_the_page(published, tmp_path):
    map_path, _ = published
    out = tmp_path / "site" / "index.html"
    result = CliRunner().invoke(main, ["explore", "--map", str(map_path), "-o", str(out),
                                       "--title", "Our <lab> map"])
    assert result.exit_code == 0, result.output
    assert result.output.strip() == str(out)
    html = out.read_text(encoding="utf-8")
    assert "<title>Our &lt;lab&gt; map</title>" in html
    assert len(read_embedded_data(html)["groups"]) == 76


def test_the_command_defaults_to_explorer_html_beside_the_map(published, tmp_path):
    map_path, _ = published
    copy = tmp_path / "friction_map.parquet"
    shutil.copytree(map_path, copy)
    proc = subprocess.run(
        [sys.executable, "-m", "tribopipe", "explore", "--map", str(copy)],
        capture_output=True, text=True, cwd=tmp_path,
    )
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "explorer.html").is_file()
    assert proc.stdout.strip() == str(tmp_path / "explorer.html")


def test_an_absent_map_is_one_line(tmp_path):
    result = CliRunner().invoke(main, ["explore", "--map", str(tmp_path / "none.parquet"),
                                       "-o", str(tmp_path / "x.html")])
    assert result.exit_code == 1
    assert "friction map is empty or absent" in result.output
    assert len(result.output.strip().splitlines()) == 1
    assert "Traceback" not in result.output
    assert not (tmp_path / "x.html").exists()


def test_a_foreign_file_at_the_map_path_is_refused(tmp_path):
    bogus = tmp_path / "friction_map.parquet"
    bogus.write_text("not parquet", encoding="utf-8")
    result = CliRunner().invoke(main, ["explore", "--map", str(bogus)])
    assert result.exit_code == 1
    assert len(result.output.strip().splitlines()) == 1
    assert "Traceback" not in result.output


def test_the_page_writes_note_cells_without_an_escape_of_its_own():
    """The page quotes its CSV cell of notes without escaping it (snippets.js csvQuoted):
    the notes are the library's words, with no quote to double and no formula start for
    :func:`tribopipe.escape.csv_cell` to neutralise, joined or alone."""
    from tribopipe.escape import csv_cell
    from tribopipe.query import NOTES

    texts = [t.replace("{n}", "3") for t in NOTES.values()]
    for text in [*texts, "; ".join(texts)]:
        assert '"' not in text and csv_cell(text) == text, text


def test_the_snippet_notes_and_name_rule_come_laid_out_from_python(published):
    """What the page does not compute is handed to it: the decks' note as their comment
    lines (wrapped by the writers' own rule), and the name rule as data."""
    from tribopipe.export.explorer import name_rule
    from tribopipe.export.fe_decks import CONSTANT_NOTE
    from tribopipe.export.headers import comment_block
    from tribopipe.query import name_key

    data = explorer_data(published[1])
    lines = data["texts"]["snippet"]["note_lines"]
    assert lines["abaqus"] == comment_block("**", [CONSTANT_NOTE.format(fmt="abaqus")])
    assert len(lines["ansys"]) > 1 and all(len(x) <= 100 for x in lines["ansys"])
    rule = name_rule()
    assert data["texts"]["names"] == rule
    assert all(name_key(c) == rule["fold"][c] for c in rule["fold"] if not c.isspace())
    assert "ß" in rule["fold"] and "\x1c" in rule["space"] and "A" not in rule["fold"]


def _awkward_groups() -> pd.DataFrame:
    """A group table with what the points' merge must handle: conditions shared by
    several groups (two speeds, two labs), temperatures unknown beside known ones, a
    pair of only unknown temperatures, missing means, pressures and counts, two
    spellings of one pair."""
    import numpy as np

    rng = np.random.default_rng(7)
    rows = []
    for i in range(400):
        pin = ("A", " a ", "B", "C")[i % 4]
        rows.append({
            "pin": pin, "disc": ("steel", "STEEL", "wood")[i % 3],
            "pressure_kPa": (10.0, 20.0, 40.0, math.nan)[i % 7 % 4],
            "temperature_C": math.nan if pin == "C" else (20.0, 40.0, math.nan)[i % 5 % 3],
            "nominal_speed_mm_s": (1.0, 10.0, math.nan)[i % 11 % 3],
            "mu_k_mean": math.nan if i % 13 == 0 else float(rng.uniform(0.2, 1.5)),
            "mu_k_ci95_high": math.nan if i % 9 == 0 else float(rng.uniform(1.5, 2)),
            "mu_k_n": (1.0, 3.0, math.nan, 5.0)[i % 4],
            "mu_k_u": math.nan if i % 6 == 0 else float(rng.uniform(0.01, 0.1)),
            "mu_k_sem": float(rng.uniform(0.01, 0.1)),
            "mu_k_u_estimated": ("True", "False")[i % 2],
            "mu_s_mean": math.nan if i % 3 else float(rng.uniform(0.2, 1.5)),
        })
    return pd.DataFrame(rows)


def test_every_pairs_points_in_one_pass_are_each_pairs_own(published_groups):
    """The explorer reads every pair's interpolation points in one pass
    (``query.points_by``): for each code they are exactly (to the bit) what
    ``query.pair_points`` gives that code's groups alone, on a table with merged
    conditions, unknown temperatures and missing values, and on the published map."""
    import numpy as np

    from tribopipe.query import name_key, points_by

    published = published_groups
    for groups in (_awkward_groups(), published):
        keys = list(zip(groups["pin"].map(name_key), groups["disc"].map(name_key),
                        strict=True))
        number = {k: i for i, k in enumerate(dict.fromkeys(keys))}
        codes = np.array([number[k] for k in keys])
        for q in ("mu_k", "mu_s"):
            every = points_by(groups, codes, q)
            for code in range(len(number)):
                own = pair_points(groups[codes == code], q).reset_index(drop=True)
                got = every[every["code"] == code].drop(columns="code").reset_index(drop=True)
                if own.empty:
                    assert got.empty
                    continue
                pd.testing.assert_frame_equal(got, own, check_dtype=False, check_exact=True)
    assert points_by(published.iloc[0:0], np.zeros(0, dtype=int)).empty


def test_each_pair_speed_and_point_on_the_page_is_selected_as_query_selects_it():
    """Selected once for all pairs, each pair's points at each speed, its runs and its
    points' runs are those of that pair's own groups (``select_pair``, the speeds of
    ``pair_speeds`` and ``groups_at_speed``): two spellings of a pair are one pair."""
    from tribopipe.query import groups_at_speed, name_key, pair_speeds, pairs

    groups = _awkward_groups().assign(mu_s_n=1.0, range_exceeds_r=False, qc_flagged=False)
    runs = pd.DataFrame({"pin": groups["pin"], "disc": groups["disc"],
                         "measurement_id": [f"r{i}" for i in range(len(groups))],
                         "pressure_kPa": groups["pressure_kPa"],
                         "temperature_C": groups["temperature_C"], "repeat": 1,
                         "mu_k": groups["mu_k_mean"], "mu_s": math.nan,
                         "nominal_speed_mm_s": groups["nominal_speed_mm_s"]})
    groups["run_ids"] = runs["measurement_id"]
    fits = pd.DataFrame({"pin": ["a", "B"], "disc": ["steel", "wood"], "nominal_speed_mm_s": 1.0,
                         **{f: math.nan for f in ("temperature_C", "k", "k_ci95_low",
                            "k_ci95_high", "exponent", "exponent_ci95_low",
                            "exponent_ci95_high", "r_squared", "n_points",
                            "pressure_min_kPa", "pressure_max_kPa")}, "note": ""})
    data = explorer_data(runs, groups=groups, fits=fits)
    # query's pairs, one per casefolded spelling (the first in query's order), each
    # named as its first group spells it
    first = {}
    for pin, disc in pairs(groups):
        first.setdefault((name_key(pin), name_key(disc)), (pin, disc))
    assert [tuple(p["keys"]) for p in data["pairs"]] == list(first)
    assert ("a", "steel") in first and len(first) < len(pairs(groups))
    for pair in data["pairs"]:
        own = select_pair(groups, pair["pin"], pair["disc"])
        assert (pair["pin"], pair["disc"]) == tuple(own.iloc[0][["pin", "disc"]])
    for pair, pair_runs in zip(data["pairs"], data["runs"], strict=True):
        own = select_pair(groups, pair["pin"], pair["disc"])
        assert [s["speed_mm_s"] for s in pair["speeds"]] == pair_speeds(own)
        assert [r["id"] for r in pair_runs] == runs.loc[own.index].sort_values(
            ["temperature_C", "pressure_kPa", "repeat", "measurement_id"],
            kind="mergesort")["measurement_id"].tolist()
        assert len(pair["fits"]) == ((pair["keys"] == ["a", "steel"])
                                     + (pair["keys"] == ["b", "wood"]))
        for speed in pair["speeds"]:
            at = groups_at_speed(own, speed["speed_mm_s"])
            for q in ("mu_k", "mu_s"):
                want = pair_points(at, q)
                got = speed[f"{q}_points"]
                assert [(p["pressure_kPa"], p["temperature_C"], p["mean"], p["n"])
                        for p in got] == [
                    (r.pressure_kPa, None if math.isnan(r.temperature_C) else r.temperature_C,
                     r.mean, r.n) for r in want.itertuples()]
                for p in got:  # the runs behind a point: its condition's groups' runs
                    t = p["temperature_C"]
                    behind = at[(at["pressure_kPa"] == p["pressure_kPa"])
                                & (at["temperature_C"].isna() if t is None
                                   else at["temperature_C"] == t)]
                    assert [pair_runs[i]["id"] for i in p["runs"]] == behind[
                        "run_ids"].tolist()


def test_a_pin_of_more_groups_than_a_page_is_split_by_whole_pairs(published, tmp_path):
    """No page grows with one pin either: a map split into pages of at most N groups
    keeps each pin's pairs together while they fit, spreads a larger pin's pairs over
    pages of its own (a pair whole), and the index lists each pin on every page it is on
    with the discs there; every pair and group is on exactly one page, with its runs."""
    from collections import Counter

    from tribopipe.export.explorer import pages_folder
    from tribopipe.query import name_key

    map_path, runs = published
    groups = group_statistics(runs)
    per_pin = groups["pin"].map(name_key).value_counts()
    per_pair = groups.groupby([groups["pin"].map(name_key), groups["disc"].map(name_key)]).size()
    limit = int(per_pair.max())  # a pair always fits; some pin does not
    assert per_pin.max() > limit
    index = write_explorer(map_path, tmp_path / "e.html", groups_page_limit=limit)
    pages = sorted(pages_folder(index).glob("part-*.html"), key=lambda p: int(p.stem[5:]))
    seen: Counter = Counter()
    pins_on: dict[str, list[set[str]]] = {}
    for page in pages:
        data = read_embedded_data(page.read_text(encoding="utf-8"))
        assert 0 < len(data["groups"]) <= limit
        for pair in data["pairs"]:
            seen[tuple(pair["keys"])] += 1
        by_pin: dict[str, set[str]] = {}
        for pair in data["pairs"]:
            by_pin.setdefault(pair["pin"], set()).add(pair["disc"])
        for pin, discs in by_pin.items():
            pins_on.setdefault(pin, []).append(discs)
        # a page holds whole pins, or part of one pin alone
        if len(by_pin) > 1:
            assert all(per_pin[name_key(p)] <= limit for p in by_pin)
    assert seen == Counter({tuple(k): 1 for k in per_pair.index})
    assert sum(len(read_embedded_data(p.read_text(encoding="utf-8"))["groups"])
               for p in pages) == len(groups)
    split = [pin for pin, parts in pins_on.items() if len(parts) > 1]
    assert split and all(per_pin[name_key(p)] > limit for p in split)
    # the index: one row per pin and page, its discs there, linking to that page
    html = index.read_text(encoding="utf-8")
    rows = re.findall(r'<tr><td><a href="[^"]*?(part-\d+\.html)\?pin=[^"]*">([^<]*)</a></td>'
                      r"<td>([^<]*)</td>", html)
    assert len(rows) == sum(len(parts) for parts in pins_on.values())
    for href, pin, discs in rows:
        data = read_embedded_data((pages_folder(index) / href).read_text(encoding="utf-8"))
        assert sorted(discs.split(", ")) == sorted(p["disc"] for p in data["pairs"]
                                                   if p["pin"] == pin)


def _undated(files: dict[str, str]) -> dict[str, str]:
    """The files with the minute each page was made left out (two calls may straddle
    one)."""
    return {name: re.sub(r"\d{4}-\d\d-\d\d \d\d:\d\d UTC", "<made>", text)
            for name, text in files.items()}


def test_a_bound_on_files_moves_a_pages_runs_into_it_only_when_needed(published):
    """A package lists each file of its explorer as a resource, and lists few: with
    ``max_files`` the explorer of one page keeps its runs beside it while the files fit,
    and carries them in the page, one file, when they would not: the same files the
    explorer writes without the bound, or with its runs inline."""
    _, runs = published
    beside = dict(explorer_parts(runs, "e.html", runs_inline_limit=0))
    assert len(beside) > 2
    assert _undated(dict(explorer_parts(runs, "e.html", runs_inline_limit=0,
                                   max_files=len(beside)))) == _undated(beside)
    inline = dict(explorer_parts(runs, "e.html", runs_inline_limit=0, max_files=len(beside) - 1))
    assert list(inline) == ["e.html"]
    assert _undated(inline) == _undated(dict(explorer_parts(runs, "e.html",
                                                       runs_inline_limit=sys.maxsize)))


def test_a_bound_on_files_makes_fewer_larger_pages_before_it_is_passed(published):
    """A split explorer within the bound is what it is without one; one whose runs
    would not fit beside its pages carries them in its pages; one whose pages alone
    would not fit gets fewer pages of more groups each, every group and included run on
    exactly one of them, and never more files than the bound."""
    from collections import Counter

    from tribopipe.export.explorer import pages_folder
    from tribopipe.query import name_key

    _, runs = published
    groups = group_statistics(runs)
    per_pair = groups.groupby([groups["pin"].map(name_key), groups["disc"].map(name_key)]).size()
    limit = int(per_pair.max())
    split = dict(explorer_parts(runs, "e.html", groups_page_limit=limit))
    pages = [n for n in split if n.endswith(".html") and n != "e.html"]
    assert len(split) > len(pages) + 1 > 2  # runs beside the pages
    assert _undated(dict(explorer_parts(runs, "e.html", groups_page_limit=limit,
                                   max_files=len(split)))) == _undated(split)
    assert _undated(dict(explorer_parts(runs, "e.html", groups_page_limit=limit,
                                   max_files=len(split) - 1))) == _undated(dict(explorer_parts(
        runs, "e.html", groups_page_limit=limit, runs_beside_pages=False,
        runs_inline_limit=sys.maxsize)))
    bound = len(pages)  # the pages and their index would be one file too many
    fewer = dict(explorer_parts(runs, "e.html", groups_page_limit=limit, max_files=bound))
    assert 1 < len(fewer) <= bound
    folder = pages_folder("e.html").as_posix()
    datas = [read_embedded_data(text) for name, text in fewer.items()
             if name.startswith(folder + "/")]
    assert len(datas) == len(fewer) - 1  # every file a page: the runs are in them
    assert sum(len(d["groups"]) for d in datas) == len(groups)
    assert Counter(tuple(p["keys"]) for d in datas for p in d["pairs"]) == Counter(
        {tuple(k): 1 for k in per_pair.index})
    assert sorted(r["id"] for d in datas for chunk in d["runs"] for r in chunk) == sorted(
        runs["measurement_id"])
