"""The explorer's JavaScript copies of the simulator snippets equal the Python writers.

The page offers every format of :data:`tribopipe.export.registry.WRITERS` that has a
snippet; its text is the Python writer's opening lines (rendered into the page) plus what
``snippets.js`` adds for the condition (every line that names the pair comes escaped from
Python: the script holds no escaping rule). Here Node runs ``query.js`` and ``snippets.js``
on the page's own data and on query results of a grid of conditions (measured, between
groups, clamped, without and with μ_S, μ_S below μ_K, hostile names), and every text must
equal :func:`tribopipe.export.simulators.snippet`'s, byte for byte. (The browser tests
check the same through the page's controls where Chromium is installed.)
"""

from __future__ import annotations

import json
import shutil
import subprocess
from importlib.resources import files

import pandas as pd
import pytest

from helpers import with_mu_s
from published_map import PUBLISHED_CSV, published_runs
from tribopipe.export.explorer import explorer_data
from tribopipe.export.registry import WRITERS
from tribopipe.export.simulators import snippet
from tribopipe.query import query

PIN, DISC = "Dragonskin 30", "steel"
HOSTILE = "Evil\n*HEADING\r\n** x'\"</pair><!-- -->--$ import os\x00\x1b\u2028end é"
SOURCE = "maps/we$ird--<!-- name\u2028.parquet"

HARNESS = """
const fs = require("fs");
const input = JSON.parse(fs.readFileSync(0, "utf-8"));
var DATA = input.data;
var PAIRS = DATA.pairs;
%s
const out = input.results.map(res => input.formats.map(fmt => {
  res.pair = findPair(res.pin, res.disc);  // the page's own result knows its pair
  try { return EXPORTS[fmt].make(res); } catch (e) { return "ERROR " + e.message; }
}));
process.stdout.write(JSON.stringify({out: out, snippets: Object.keys(SNIPPETS)}));
"""


def _js(name: str) -> str:
    return files("tribopipe.export").joinpath("assets", "js", name).read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def node() -> str:
    found = shutil.which("node")
    if found is None:
        pytest.skip("node is not installed (Debian: apt-get install nodejs)")
    return found


@pytest.fixture(scope="module")
def groups(published_groups: pd.DataFrame) -> pd.DataFrame:
    g = published_groups
    hostile = g[(g.pin == PIN) & (g.disc == DISC)].copy()
    hostile["pin"] = HOSTILE
    return pd.concat([g, hostile], ignore_index=True)


def _run_js(node: str, data: dict, results: list, formats: list[str]) -> dict:
    script = HARNESS % "\n".join(_js(name) for name in ("query.js", "snippets.js"))
    proc = subprocess.run([node, "-e", script], input=json.dumps(
        {"data": data, "results": results, "formats": formats}),
        capture_output=True, text=True, check=True)
    return json.loads(proc.stdout)


def test_every_registered_snippet_has_its_javascript_and_equals_the_writer(node, groups):
    runs = published_runs(PUBLISHED_CSV)
    hostile = runs[(runs.pin == PIN) & (runs.disc == DISC)].copy()
    hostile["pin"] = HOSTILE
    hostile["measurement_id"] = hostile["measurement_id"] + "-hostile"
    data = explorer_data(pd.concat([runs, hostile], ignore_index=True), title="t", source=SOURCE)
    assert HOSTILE in [pair["pin"] for pair in data["pairs"]]
    formats = [w.name for w in WRITERS if w.snippet is not None]
    assert [s["name"] for s in data["snippets"]] == formats
    assert {"usd", "pybullet", "drake", "abaqus", "ansys"} <= set(formats)
    results = []
    for table in (groups, with_mu_s(groups, 1.4), with_mu_s(groups, 0.8)):
        for pin in (PIN, HOSTILE):
            for p, t in ((35.37, 20.0), (47.16, 20.0), (50.0, 15.0), (500.0, 40.0), (1.0, 5.0)):
                results.append(query(table, pin, DISC, p, t))
    answer = _run_js(node, data, [r.to_dict() for r in results], formats)
    assert sorted(answer["snippets"]) == sorted(formats)  # SNIPPETS is the registry's
    for res, texts in zip(results, answer["out"], strict=True):
        for fmt, text in zip(formats, texts, strict=True):
            assert text == snippet(fmt, res, source=SOURCE), (fmt, res.pin, res.pressure_kPa)
