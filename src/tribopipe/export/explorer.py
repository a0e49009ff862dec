"""The friction-map explorer: one self-contained HTML page to browse a map in a browser.

The page needs no network and no server (it opens from disk or from any static host) and
uses plain JavaScript and SVG. Its parts are package data beside this module
(``assets/js/*.js``, ``explorer.css``, ``explorer.html``, ``explorer_fragment.html``);
this module fills them with the map's data:

* what :func:`tribopipe.query.query` interpolates over — each pair's measured points
  (:func:`tribopipe.query.pair_points`: pressure [kPa], temperature [°C], group mean, 95 %
  CI half-width, standard uncertainty u of the mean and whether it holds the runs'
  budgets, n), in the order the interpolation sums them, and the map's curvature κ
  (:func:`tribopipe.query.map_curvature`). The page redoes ``query``'s interpolation on
  them (:mod:`tribopipe.interpolation`: linear in temperature, log p – log μ in pressure,
  held at the ends and said so) and shows value ± U (k = 2) rounded by
  :mod:`tribopipe.rounding`'s rule, with the repeats' interval apart; a node test and a
  browser test hold the page equal to ``query``.
* each pair's included runs (the repeats), the group table of
  :func:`tribopipe.stats.group_statistics` (with each group mean's U, k = 2, from
  :func:`tribopipe.stats.group_u`) and the power-law fits of
  :func:`tribopipe.fit.fit_power_law` with their curves sampled here in Python.

The data travel as one JSON document in a ``<script type="application/json">`` element.
Everything in it may come from someone else's map, so
:func:`tribopipe.escape.script_json` escapes ``<``, ``>``, ``&``, U+2028 and U+2029 (a name
cannot close the element), and the page's script puts text into the DOM with
``textContent`` only. The standalone page carries a Content-Security-Policy that allows
its own script and style (by hash) and nothing else: no request leaves the page.

:func:`explorer_data` is pure (tables in, a JSON-ready dict out); :func:`explorer_page` and
:func:`explorer_fragment` turn it into HTML; :func:`write_explorer` reads a map and writes
the page.
"""

from __future__ import annotations

import base64
import hashlib
import json
import math
import re
from datetime import UTC, datetime
from importlib.resources import files
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .. import __version__
from ..errors import ExportError
from ..escape import html_text, printable, script_json
from ..files import write_text_atomic
from ..fit import fit_power_law, power_law
from ..frictionmap import read_map
from ..labels import flag_list
from ..query import (
    groups_at_speed,
    map_curvature,
    pair_points,
    pair_speeds,
    pairs,
    select_pair,
)
from ..rounding import known_u
from ..stats import NOMINAL_SPEED, TEST_METHOD, group_statistics, group_u, test_methods
from .registry import WRITERS
from .simulators import snippet_header

if TYPE_CHECKING:
    import pandas as pd

#: identifies the embedded JSON document and its layout
DATA_FORMAT = "tribopipe-explorer/1"
#: id of the ``<script type="application/json">`` element that holds the data
DATA_ELEMENT_ID = "explorer-data"
#: the parts of the page's script (``assets/js/``), in the order they are joined
SCRIPT_PARTS = (
    "prelude.js", "pyformat.js", "query.js", "snippets.js", "dom.js", "plots.js", "table.js",
    "page.js",
)
#: points per fitted power-law curve (log-spaced over the fitted pressure range)
FIT_CURVE_POINTS = 48

_PLACEHOLDER = re.compile(r"\{\{(\w+)\}\}")
#: group-table columns carried to the page (the others stay in the map's own tables)
GROUP_FIELDS = (
    "normal_force_N", "pressure_kPa", "temperature_C",
    "mu_k_n", "mu_k_mean", "mu_k_std", "mu_k_ci95_low", "mu_k_ci95_high", "mu_k_cv",
    "mu_s_n", "mu_s_mean", "mu_s_std", "mu_s_ci95_low", "mu_s_ci95_high",
    "range_exceeds_r", "qc_flagged",
)
FIT_FIELDS = (
    "temperature_C", "k", "k_ci95_low", "k_ci95_high", "exponent", "exponent_ci95_low",
    "exponent_ci95_high", "r_squared", "n_points", "pressure_min_kPa", "pressure_max_kPa",
    "note",
)


# ---------------------------------------------------------------------------- the data


def _plain(value: Any) -> Any:
    """``value`` as a JSON-ready Python value: NaN/inf and missing → ``None``, numpy
    scalars → ``int``/``float``/``bool``."""
    if value is None:
        return None
    if isinstance(value, bool | str):
        return value
    if hasattr(value, "item"):  # numpy scalar
        value = value.item()
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, int | bool):
        return value
    try:
        import pandas as pd

        if pd.isna(value):
            return None
    except (TypeError, ValueError):
        pass
    return str(value)


def _key(name: Any) -> str:
    """A pin or disc name as :func:`tribopipe.query.select_pair` matches it."""
    return str(name).strip().casefold()


def _points(points: pd.DataFrame, pair_groups: pd.DataFrame) -> list[dict[str, Any]]:
    """Rows of :func:`tribopipe.query.pair_points` as dicts, in their order, each with the
    ids of the runs behind it (``run_ids`` of the groups at its pressure and temperature)."""
    import pandas as pd

    p = pd.to_numeric(pair_groups["pressure_kPa"], errors="coerce").to_numpy(dtype=float)
    t = pd.to_numeric(pair_groups["temperature_C"], errors="coerce").to_numpy(dtype=float)
    ids = pair_groups["run_ids"].astype(str).to_numpy() if "run_ids" in pair_groups else None
    out = []
    for r in points.to_dict(orient="records"):
        at = p == r["pressure_kPa"]
        at &= (t == r["temperature_C"]) if math.isfinite(r["temperature_C"]) else (t != t)
        run_ids = [] if ids is None else [i for cell in ids[at] for i in cell.split(";") if i]
        out.append(
            {
                "pressure_kPa": _plain(r["pressure_kPa"]),
                "temperature_C": _plain(r["temperature_C"]),
                "mean": _plain(r["mean"]),
                "half": _plain(r["half"]),
                "u": _plain(r["u"]) if "u" in r else None,
                "budget": bool(r.get("budget", False)),
                "n": int(r["n"]),
                "run_ids": run_ids,
            }
        )
    return out


def _speed_points(at_speed: pd.DataFrame, speed_mm_s: float) -> dict[str, Any]:
    """One measured speed [mm/s] of a pair: its μ_K and μ_S points (:func:`_points`)."""
    return {
        "speed_mm_s": float(speed_mm_s),
        "mu_k_points": _points(pair_points(at_speed, "mu_k"), at_speed),
        "mu_s_points": _points(pair_points(at_speed, "mu_s"), at_speed)
        if "mu_s_mean" in at_speed.columns else [],
    }


def _left_out(pair_groups: pd.DataFrame) -> int:
    """How many μ_K points of a pair :func:`tribopipe.query.query` leaves out for lack of
    a temperature (points: distinct pressures of the groups without one)."""
    import pandas as pd

    p = pd.to_numeric(pair_groups["pressure_kPa"], errors="coerce")
    t = pd.to_numeric(pair_groups["temperature_C"], errors="coerce")
    m = pd.to_numeric(pair_groups["mu_k_mean"], errors="coerce")
    finite = m.notna() & p.notna() & m.abs().ne(math.inf) & p.abs().ne(math.inf)
    if not (finite & t.notna()).any():
        return 0
    return int(p[finite & t.isna()].nunique())


def _runs(pair_runs: pd.DataFrame) -> list[dict[str, Any]]:
    """The pair's included runs (the repeats) for the page, in a stable order, each with
    the file, test and result it came from (``None`` where the map does not say)."""
    ordered = pair_runs.sort_values(
        ["temperature_C", "pressure_kPa", "repeat", "measurement_id"], kind="mergesort"
    )
    return [
        {
            "id": str(r["measurement_id"]),
            "pressure_kPa": _plain(r["pressure_kPa"]),
            "temperature_C": _plain(r["temperature_C"]),
            "mu_k": _plain(r["mu_k"]),
            "mu_s": _plain(r["mu_s"]),
            "repeat": _plain(r["repeat"]),
            "flags": flag_list(r.get("flags")),
            # a file's own name, raw in the map: shown as one printable line
            "file": printable(r["source_file"]) if isinstance(r.get("source_file"), str)
            else None,
            "test": _plain(r.get("test")),
            "result": _plain(r.get("result")),
            "test_method": method,
            # a reviewer's decision (tribopipe.review): accept or window; None when none
            "review": _plain(r.get("review")),
        }
        for r, method in zip(ordered.to_dict(orient="records"), test_methods(ordered),
                             strict=True)
    ]


def _fits(pair_fits: pd.DataFrame) -> list[dict[str, Any]]:
    """The pair's power-law fits with their curves μ = k·p^(n−1) sampled over the fitted
    pressure range (log-spaced, :data:`FIT_CURVE_POINTS` points)."""
    import numpy as np

    out = []
    for f in pair_fits.to_dict(orient="records"):
        row = {name: _plain(f[name]) for name in FIT_FIELDS}
        curve: list[list[float]] = []
        k, exponent = row["k"], row["exponent"]
        lo, hi = row["pressure_min_kPa"], row["pressure_max_kPa"]
        if None not in (k, exponent, lo, hi) and 0 < lo < hi:
            p = np.geomspace(lo, hi, FIT_CURVE_POINTS)
            mu = power_law(p, k, exponent)
            curve = [[float(a), float(b)] for a, b in zip(p, mu, strict=True)]
        row["curve"] = curve
        out.append(row)
    return out


def explorer_data(
    runs: pd.DataFrame,
    *,
    groups: pd.DataFrame | None = None,
    fits: pd.DataFrame | None = None,
    title: str = "tribopipe friction-map explorer",
    source: str | None = None,
) -> dict[str, Any]:
    """The explorer's JSON document for friction-map ``runs`` (excluded runs left out).

    ``groups`` defaults to :func:`tribopipe.stats.group_statistics` of the included runs
    and ``fits`` to :func:`tribopipe.fit.fit_power_law` of ``runs``. Returns a dict of
    plain values (``None`` for missing numbers): ``format, title, source,
    tribopipe_version, generated, pairs`` (per pair: ``pin, disc, mu_k_points,
    mu_s_points, speed_mm_s, speeds, left_out, runs, fits``; ``speeds`` lists
    ``speed_mm_s, mu_k_points, mu_s_points`` per measured nominal speed where the pair
    has several, else it is empty; each run with its ``test_method``), ``groups`` (the
    group table, each row with the index of its ``pair`` and its ``test_method``),
    ``methods`` (the test methods of the included runs, in the map's order: the page
    filters the group table by them where there are several), ``snippets`` (the
    simulator formats the page copies: name, label, file suffix) and ``snippet_headers``
    (the opening lines of :func:`tribopipe.export.simulators.snippet` per format). Pressures in kPa,
    temperatures in °C. Raises :class:`ExportError` when no run is left. Inputs are not
    modified.
    """
    included = runs
    if "excluded" in runs.columns:
        included = runs[~runs["excluded"].fillna(False).astype(bool)]
    if included.empty:
        raise ExportError(
            "the friction map holds no included run to explore",
            hint="reduce runs first (tribopipe reduce / batch) or import the published map",
        )
    if groups is None:
        groups = group_statistics(included, show_method=True)
    run_methods = test_methods(included)
    methods = list(dict.fromkeys(str(m) for m in run_methods))
    if fits is None:
        fits = fit_power_law(runs)
    run_pin, run_disc = included["pin"].map(_key), included["disc"].map(_key)
    fit_pin, fit_disc = fits["pin"].map(_key), fits["disc"].map(_key)

    pair_index: dict[tuple[str, str], int] = {}
    pair_rows: list[dict[str, Any]] = []
    for pin, disc in pairs(groups):
        key = (_key(pin), _key(disc))
        if key in pair_index:  # another spelling of a pair already listed (query merges them)
            continue
        pair_groups = select_pair(groups, pin, disc)
        mu_k_points = pair_points(pair_groups, "mu_k")
        if mu_k_points.empty:
            continue
        first = pair_groups.iloc[0]
        pair_index[key] = len(pair_rows)
        speeds = [_speed_points(groups_at_speed(pair_groups, v), v)
                  for v in pair_speeds(pair_groups)]
        pair_rows.append(
            {
                "pin": str(first["pin"]),
                "disc": str(first["disc"]),
                # a pair of several speeds shows its first speed's points until one is chosen
                **({k: speeds[0][k] for k in ("mu_k_points", "mu_s_points")}
                   if len(speeds) > 1 else {
                    "mu_k_points": _points(mu_k_points, pair_groups),
                    "mu_s_points": _points(pair_points(pair_groups, "mu_s"), pair_groups)
                    if "mu_s_mean" in pair_groups.columns else []}),
                "speed_mm_s": speeds[0]["speed_mm_s"],
                "speeds": speeds if len(speeds) > 1 else [],
                "left_out": _left_out(pair_groups),
                "runs": _runs(included[(run_pin == key[0]) & (run_disc == key[1])]),
                "fits": _fits(fits[(fit_pin == key[0]) & (fit_disc == key[1])]),
            }
        )
    group_rows = []
    expanded = {q: 2.0 * group_u(groups, q)[0] for q in ("mu_k", "mu_s")}
    for i, g in enumerate(groups.to_dict(orient="records")):
        index = pair_index.get((_key(g["pin"]), _key(g["disc"])))
        if index is None:
            continue
        row = {"pin": str(g["pin"]), "disc": str(g["disc"]), "pair": index}
        row.update({name: _plain(g.get(name)) for name in GROUP_FIELDS})
        if NOMINAL_SPEED in g:  # a map with a pair of several speeds
            row[NOMINAL_SPEED] = _plain(g[NOMINAL_SPEED])
        # the group's one test method (groups never pool two; a table that does not
        # show it comes from a map of one method)
        row[TEST_METHOD] = str(g[TEST_METHOD]) if isinstance(g.get(TEST_METHOD), str) \
            else methods[0]
        for q, values in expanded.items():  # U (k = 2) of the group mean, where known
            row[f"{q}_U"] = float(values.iloc[i]) if known_u(float(values.iloc[i])) else None
        group_rows.append(row)
    return {
        "format": DATA_FORMAT,
        "title": title,
        "source": source,
        "tribopipe_version": __version__,
        "generated": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "pairs": pair_rows,
        "groups": group_rows,
        # the test methods of the included runs, in the map's order (the page filters
        # the group table by them where there are several)
        "methods": methods,
        # the map's κ for the interpolation's own uncertainty (tribopipe.interpolation)
        "curvature": {q: map_curvature(groups, q) for q in ("mu_k", "mu_s")},
        # the simulator formats the page copies (every registered format with a
        # snippet); the opening lines of each do not depend on the condition: rendered
        # here by the writer itself, the page adds the rest (snippets.js)
        "snippets": [{"name": w.name, "label": w.snippet_label, "suffix": w.snippet_suffix}
                     for w in WRITERS if w.snippet is not None],
        "snippet_headers": {w.name: snippet_header(w.name, source)
                            for w in WRITERS if w.snippet is not None},
    }


# ---------------------------------------------------------------------------- the page


def _asset(name: str) -> str:
    """The text of one of the page's package-data files (``assets/<name>``)."""
    return files("tribopipe.export").joinpath("assets", *name.split("/")).read_text(
        encoding="utf-8")


def _fill(template: str, values: dict[str, str]) -> str:
    """``template`` with each ``{{name}}`` replaced by ``values[name]``, in one pass (a
    value that itself contains ``{{...}}`` is never expanded)."""
    return _PLACEHOLDER.sub(lambda m: values[m.group(1)], template)


def _script() -> str:
    """The page's JavaScript: :data:`SCRIPT_PARTS` in one function scope, checked to be
    safe inside a ``<script>`` element."""
    parts = [_asset(f"js/{name}") for name in SCRIPT_PARTS]
    js = '(function () {\n"use strict";\n\n' + "\n".join(parts) + "})();\n"
    if re.search(r"</script|<!--", js, re.IGNORECASE):
        raise AssertionError("the explorer's script may not contain '</script' or '<!--'")
    return js


def _style() -> str:
    """The page's CSS, checked to be safe inside a ``<style>`` element."""
    css = _asset("explorer.css")
    if "</style" in css.lower():
        raise AssertionError("explorer.css may not contain '</style'")
    return css


def _sha256(text: str) -> str:
    """A Content-Security-Policy source expression for inline ``text``."""
    digest = hashlib.sha256(text.encode("utf-8")).digest()
    return "'sha256-" + base64.b64encode(digest).decode("ascii") + "'"


def explorer_fragment(data: dict[str, Any]) -> str:
    """The explorer as a block of HTML for a page that already has a ``<head>``: its
    markup, the data element and the script. The page must also carry
    :func:`explorer_style` (the rules are scoped to the block's ``.tpx`` class). One
    explorer per page (its elements have fixed ids such as ``mu-k``)."""
    return _fragment(data, _script())


def _fragment(data: dict[str, Any], js: str) -> str:
    """The fragment template filled with ``data`` (embedded JSON) and the script ``js``."""
    options = "".join(
        f'\n   <option value="{html_text(s["name"])}">{html_text(s["label"])}</option>'
        for s in data["snippets"])
    return _fill(_asset("explorer_fragment.html"),
                 {"data": script_json(data), "script": js, "data_id": DATA_ELEMENT_ID,
                  "snippet_options": options})


def explorer_style() -> str:
    """The explorer's CSS (rules scoped to ``.tpx``), for a page embedding the fragment."""
    return _style()


def explorer_page(data: dict[str, Any]) -> str:
    """The standalone explorer page (UTF-8 HTML text) for :func:`explorer_data` ``data``.

    Its Content-Security-Policy allows only its own inline script and style (by SHA-256)
    and ``data:`` images: the page loads nothing from anywhere.
    """
    js, css = _script(), _style()
    csp = (
        f"default-src 'none'; script-src {_sha256(js)}; style-src {_sha256(css)}; "
        "img-src data:; base-uri 'none'; form-action 'none'"
    )
    source = data.get("source")
    subtitle = (
        f"tribopipe {__version__}" + (f" · map {source}" if source else "")
        + f" · {data.get('generated', '')}"
    )
    return _fill(
        _asset("explorer.html"),
        {
            "csp": html_text(csp),
            "title": html_text(str(data.get("title", ""))),
            "subtitle": html_text(subtitle),
            "style": css,
            "fragment": _fragment(data, js),
        },
    )


def read_embedded_data(html: str) -> dict[str, Any]:
    """The JSON document embedded in an explorer page or a report that holds one.

    Raises :class:`ExportError` when the page has no explorer data element.
    """
    match = re.search(
        r'<script type="application/json" id="' + re.escape(DATA_ELEMENT_ID) + r'">(.*?)</script>',
        html,
        re.DOTALL,
    )
    if match is None:
        raise ExportError(f"no explorer data (script element #{DATA_ELEMENT_ID}) in the page")
    return json.loads(match.group(1))


# ---------------------------------------------------------------------------- I/O edge


def build_explorer(map_path: str | Path, *, title: str | None = None) -> str:
    """The explorer page (HTML text) of the friction map (Parquet) at ``map_path``."""
    runs = read_map(map_path)
    if runs.empty:
        raise ExportError(
            "the friction map is empty or absent",
            path=map_path,
            hint="reduce runs first (tribopipe reduce / batch) or import the published map",
        )
    data = explorer_data(
        runs, title=title or "tribopipe friction-map explorer", source=str(map_path)
    )
    return explorer_page(data)


def write_explorer(map_path: str | Path, output: str | Path, *, title: str | None = None) -> Path:
    """Write the explorer page of the map at ``map_path`` to ``output`` (atomically)."""
    return write_text_atomic(output, build_explorer(map_path, title=title))
