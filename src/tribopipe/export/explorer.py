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
import functools
import hashlib
import json
import math
import re
import sys
from collections.abc import Iterator, Mapping
from datetime import UTC, datetime
from importlib.resources import files
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .. import __version__
from ..errors import ExportError
from ..escape import csv_cell, html_text, printable, script_json
from ..files import write_page_and_files
from ..fit import fit_power_law, power_law
from ..frictionmap.snapshot import MapSource, as_snapshot
from ..interpolation import EXTRAPOLATED, temperature_needed
from ..labels import flag_list
from ..physics import FOUNDING_SLIDING_SPEED_MM_S
from ..query import (
    NOTES,
    REQUEST_ERRORS,
    WHY_NO_U,
    estimate_text,
    map_curvature,
    name_key,
    pairs,
    pd_numeric,
    points_by,
    speed_needed,
)
from ..rounding import known_u
from ..stats import (
    LABS,
    LABS_DISAGREE,
    NOMINAL_SPEED,
    TEST_METHOD,
    group_statistics,
    group_u,
    nominal_speeds,
    run_ids_of,
    test_methods,
)
from .coefficients import STATIC_WHY
from .fe_decks import CONSTANT_NOTE, MATERIAL_LINE, abaqus_name, ansys_safe, deck_safe
from .formats import ENTRIES
from .headers import HELD_LINE, MU_S_UNKNOWN, PAIR_LINE, comment_block
from .simulators import snippet_header
from .tables import GROUP_FLAG_FIELDS, condition_text, group_flags
from .usd import comment as usd_comment
from .xml_text import xml_comment

if TYPE_CHECKING:
    import pandas as pd

#: identifies the embedded JSON document and its layout
DATA_FORMAT = "tribopipe-explorer/2"
#: id of the ``<script type="application/json">`` element that holds the data
DATA_ELEMENT_ID = "explorer-data"
#: id prefix of the data elements that hold each pair's runs (``tpx-runs-0``, …)
RUNS_ELEMENT_PREFIX = "tpx-runs-"
#: a page carries its runs up to this many; a larger map's runs lie beside it, one file
#: per pair (a run costs about 150 bytes of page: 20,000 keep a page near 3 MB)
RUNS_INLINE_LIMIT = 20_000
#: a page carries up to this many condition groups (about 2 kB of page each: 2,000 keep a
#: page near 4 MB); a map of more is split into pages of whole pins beside an index page
GROUPS_PAGE_LIMIT = 2_000
#: the parts of the page's script (``assets/js/``), in the order they are joined
SCRIPT_PARTS = (
    "prelude.js", "query.js", "snippets.js", "dom.js", "plots.js", "table.js", "page.js",
)
#: the columns of the page's CSV of one condition
CSV_COLUMNS = (
    "pin", "disc", "pressure_kPa", "temperature_C", "mu_k", "mu_k_U_k2", "mu_k_ci95_half_width",
    "mu_s", "mu_s_U_k2", "mu_s_ci95_half_width", "clamped_pressure", "clamped_temperature",
    "measured_groups", "notes", "map", "tribopipe_version",
)
#: points per fitted power-law curve (log-spaced over the fitted pressure range), each
#: coordinate to 4 significant digits (they are drawn, never computed with)
FIT_CURVE_POINTS = 24

#: the lists of interpolation points of each speed of a pair (packed in the page)
POINT_LISTS = ("mu_k_points", "mu_s_points")
#: the run columns the explorer reads of each run (its groups and fits given; with them,
#: the fits too): a map's other columns are left behind before its runs are made pages
EXPLORER_COLUMNS: tuple[str, ...] = (
    "measurement_id", "pin", "disc", "pressure_kPa", "temperature_C", "nominal_speed_mm_s",
    "test_method", "excluded", "repeat", "lab", "flags", "review", "mu_k", "mu_s",
    "source_file", "test", "result")
#: the order of a pair's runs on the page (a stable sort: ties keep the map's order)
RUN_ORDER = ("temperature_C", "pressure_kPa", "repeat", "measurement_id")
#: the column that carries each run's pair number while the runs are sorted
_PAIR = "\0pair"

_PLACEHOLDER = re.compile(r"\{\{(\w+)\}\}")
#: the page's own words around its numbers and what a user typed or a link asked for
#: (``{name}``: filled by the script's ``say``, in one pass, with text it never reads as
#: markup)
PAGE_TEXTS = {
    "link_pin_missing": "the link's pin “{pin}” is not in this map",
    "link_disc_other_pin": "the link's disc “{disc}” is not measured with {pin}",
    "link_disc_missing": "the link's disc “{disc}” is not in this map",
    "link_speed_missing": "the link's speed “{speed}” is not measured for this pair",
    "link_lab_missing": "the link's lab “{lab}” is not in this map",
    "link_not_number": "the link's {field} “{value}” is not a number",
    "no_mu_shown": "{missing}: no μ is shown; choose a pin and a disc above",
    "u_line": "interpolation u = {u}; repeats' 95 % CI half-width {half}",
    "unknown": "unknown",
    "mu_s_none": "unknown (no group of this pair holds it)",
    "clamped_yes": "yes: {what} outside the measured range, edge value held; {extrapolated}",
    "clamped_no": "no",
    "and": " and ",
    "pressure": "pressure",
    "temperature": "temperature",
    "speed": "speed",
    "loading": "loading the repeats…",
    "not_at_hand": "repeats not at hand",
    "copied": "copied",
    "copy_by_hand": "select the text below and copy it (Ctrl+C)",
    "downloaded": "downloaded {name}",
    "enter_pressure": "enter a contact pressure [kPa]",
    "pressure_nan": "the contact pressure is not a number",
    "temperature_nan": "the temperature is not a number",
    "every_lab": "every lab",
    "no_pair": "the map holds no pair with a finite μ_K",
    "measured_temperatures": "measured temperatures: ",
    "measured_pressures": "pressures: ",
    "temperature_chip": "{t} °C",
    "pressure_chip": "{p} kPa",
    "group_count": "{shown} of {total} groups",
    # the plots
    "pair_title": "{pin} on {disc}",
    "pair_title_speed": "{pin} on {disc}, {speed} mm/s",
    "speed_mark": "{speed} mm/s",
    "x_axis": "contact pressure p [kPa]",
    "y_axis": "μ_K",
    "t_label": "{t} °C",
    "t_unknown": "T unknown",
    "fit_tip": "fit: {legend}",
    "legend": "{t}",
    "legend_fit": "{t}: {fit}",
    "run_tip": "repeat {repeat}, {lab}: μ_K {line}",
    "run_tip_flags": "repeat {repeat}, {lab}: μ_K {line} ({flags})",
    "repeat_unknown": "?",
    "mean_tip": "{p} kPa, {t}: mean μ_K {mean} (SD {sd}), n = {n}",
    "sd_unknown": "–",
    "lab_legend": "repeats of {lab}",
    "chosen_tip": "chosen: {p} kPa, {t}: μ_K {mu}",
    "panel_label": "select disc {disc}",
    "panel_tip": "{disc}, {p} kPa, {t}: mean μ_K {mean}, n = {n}",
    "list_join": ", ",
}
#: the heads of the page's group table, by column
GROUP_TABLE_HEADS = {
    "pin": "pin", "disc": "disc", "test_method": "method", "normal_force_N": "F [N]",
    "pressure_kPa": "p [kPa]", "temperature_C": "T [°C]", "nominal_speed_mm_s": "v [mm/s]",
    "mu_k_n": "n", "mu_k_mean": "μ_K ± U (k = 2)", "mu_k_std": "μ_K SD",
    "mu_k_ci95_low": "μ_K 95 % CI low (repeats)", "mu_k_ci95_high": "μ_K 95 % CI high (repeats)",
    "mu_k_cv": "μ_K CV", "mu_s_n": "μ_S n", "mu_s_mean": "μ_S ± U (k = 2)", "qc": "QC",
    "labs": "labs",
}
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
    kind = value.__class__
    if kind is float:  # the common cases first (10⁶ cells of a map of 10⁵ groups)
        return value if math.isfinite(value) else None
    if value is None or kind is str or kind is int or kind is bool:
        return value
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
    return name_key(name)


@functools.cache
def name_rule() -> dict[str, Any]:
    """:func:`tribopipe.query.name_key` as data for the page's script, which has no
    ``casefold``: the characters ``str.strip`` removes (``space``) and every character
    whose casefold differs from its lower case (``fold``: character → its casefold; the
    script lower-cases the others one by one)."""
    import sys

    chars = (chr(i) for i in range(sys.maxunicode + 1) if not 0xD800 <= i <= 0xDFFF)
    space, fold = [], {}
    for c in chars:
        if c.isspace():
            space.append(c)
        if c.casefold() != c.lower():
            fold[c] = c.casefold()
    return {"space": "".join(space), "fold": fold}


def _text3(value: Any) -> str:
    """A coefficient or a CI half-width to three decimals, as the tables print one ('–'
    where unknown)."""
    v = _plain(value)
    return "–" if not isinstance(v, int | float) else f"{v:.3f}"


def _points(points: list[dict[str, Any]], runs_at: Mapping[tuple[float, float], list[str]],
            run_index: dict[str, int]) -> list[dict[str, Any]]:
    """Rows of :func:`tribopipe.query.pair_points` (as records), in their order, each with
    the positions (in the pair's runs, :func:`_runs`) of the runs behind it (``runs_at``:
    the run ids of the groups at each (pressure [kPa], temperature [°C] or −inf where
    unknown)) and its texts as the tables print them (``text``: ``p``, ``t``, ``mean``,
    ``half``, ``u``)."""
    out = []
    for r in points:
        temperature = _plain(r["temperature_C"])
        run_ids = runs_at.get((r["pressure_kPa"], _t_key(r["temperature_C"])), [])
        out.append(
            {
                "pressure_kPa": _plain(r["pressure_kPa"]),
                "temperature_C": temperature,
                "mean": _plain(r["mean"]),
                "half": _plain(r["half"]),
                "u": _plain(r["u"]) if "u" in r else None,
                "budget": bool(r.get("budget", False)),
                "n": int(r["n"]),
                "runs": [run_index[i] for i in run_ids if i in run_index],
                "text": {
                    "p": condition_text("pressure_kPa", r["pressure_kPa"]),
                    "t": "?" if temperature is None
                    else condition_text("temperature_C", temperature),
                    "mean": _text3(r["mean"]),
                    "half": _text3(r["half"]),
                    "u": _text3(r.get("u")),
                },
            }
        )
    return out


def _t_key(temperature_C: float) -> float:
    """A temperature [°C] as a point's key: −inf where unknown (NaN)."""
    return temperature_C if math.isfinite(temperature_C) else -math.inf


def _by_code(points: pd.DataFrame) -> dict[int, list[dict[str, Any]]]:
    """The records of :func:`tribopipe.query.points_by`, by their code (in their order)."""
    out: dict[int, list[dict[str, Any]]] = {}
    for r in points.to_dict(orient="records"):
        out.setdefault(int(r.pop("code")), []).append({str(k): v for k, v in r.items()})
    return out


def _measured(points: list[dict[str, Any]], column: str, text: str) -> list[dict[str, Any]]:
    """The distinct measured values of ``column`` among ``points`` (sorted), each with its
    text as the tables print it (the page's chips)."""
    seen: dict[float, str] = {}
    for q in points:
        if q[column] is not None:
            seen.setdefault(q[column], q["text"][text])
    return [{"value": v, "text": seen[v]} for v in sorted(seen)]


def _speed_points(mu_k_points: list[dict[str, Any]], mu_s_points: list[dict[str, Any]],
                  runs_at: Mapping[tuple[float, float], list[str]], speed_mm_s: float,
                  run_index: dict[str, int]) -> dict[str, Any]:
    """One measured speed [mm/s] of a pair: its μ_K and μ_S points (:func:`_points` of
    :func:`tribopipe.query.pair_points`' records), the measured temperatures and pressures
    with their texts, and what a request without a temperature is told (``None`` where
    one temperature leaves no choice)."""
    mu_k = _points(mu_k_points, runs_at, run_index)
    mu_s = _points(mu_s_points, runs_at, run_index)
    temperatures = _measured(mu_k, "temperature_C", "t")
    return {
        "speed_mm_s": float(speed_mm_s),
        "text": condition_text(NOMINAL_SPEED, speed_mm_s),
        "mu_k_points": mu_k,
        "mu_s_points": mu_s,
        "temperatures": temperatures,
        "pressures": _measured(mu_k, "pressure_kPa", "p"),
        "temperature_needed": temperature_needed([t["value"] for t in temperatures])
        if len(temperatures) > 1 else None,
    }


def _left_out(groups: pd.DataFrame, codes: Any) -> dict[int, int]:
    """How many μ_K points of each pair (``codes``: the pair's number per group row)
    :func:`tribopipe.query.query` leaves out for lack of a temperature (points: distinct
    pressures of the groups without one, where some of the pair's groups have one)."""
    import numpy as np

    p = pd_numeric(groups["pressure_kPa"])
    t = pd_numeric(groups["temperature_C"])
    m = pd_numeric(groups["mu_k_mean"])
    finite = np.isfinite(m) & np.isfinite(p)
    with_t = {int(c) for c in codes[finite & ~np.isnan(t)]}
    missing: dict[int, set[float]] = {}
    for c, v in zip(codes[finite & np.isnan(t)], p[finite & np.isnan(t)], strict=True):
        if int(c) in with_t:
            missing.setdefault(int(c), set()).add(float(v))
    return {c: len(v) for c, v in missing.items()}


def _origin(r: Mapping[Any, Any]) -> str:
    """Where a run came from, in words: ``file · test / result`` (the parts the map
    knows; a file's own name, raw in the map, as one printable line)."""
    file = printable(r["source_file"]) if isinstance(r.get("source_file"), str) else ""
    place = " / ".join(printable(str(v)) for v in (_plain(r.get("test")), _plain(r.get("result")))
                       if v)
    return " · ".join(v for v in (file, place) if v)


def _runs(ordered: pd.DataFrame, labs: dict[str, int]) -> list[dict[str, Any]]:
    """Included runs (the repeats) for the page, in their order (:data:`RUN_ORDER` within
    a pair): μ_K, μ_S, the condition, its speed [mm/s] and lab (an index into the page's
    ``labs``), its flags, and ``line``: its μ_K as the tables print it and the file, test
    and result it came from."""
    speeds = nominal_speeds(ordered)
    out = []
    for r, speed, method in zip(ordered.to_dict(orient="records"), speeds,
                                test_methods(ordered), strict=True):
        origin = _origin(r)
        lab = r.get("lab")
        review = _plain(r.get("review"))
        out.append({
            "id": str(r["measurement_id"]),
            "pressure_kPa": _plain(r["pressure_kPa"]),
            "temperature_C": _plain(r["temperature_C"]),
            "speed_mm_s": float(speed),
            "mu_k": _plain(r["mu_k"]),
            "mu_s": _plain(r["mu_s"]),
            "repeat": _plain(r["repeat"]),
            "lab": labs.get(_lab_name(lab), 0),
            "flags": flag_list(r.get("flags")),
            "test_method": method,
            # a reviewer's decision (tribopipe.review): accept or window; None when none
            "line": _text3(r["mu_k"]) + (f" (reviewed: {printable(str(review))})" if review
                                         else "") + (f" — {origin}" if origin else ""),
        })
    return out


def _lab_name(value: Any) -> str:
    """A row's lab as the page lists it: one printable line, or ``unknown lab``."""
    v = _plain(value)
    return printable(str(v)) if v not in (None, "") else "unknown lab"


def _fits(pair_fits: pd.DataFrame) -> list[dict[str, Any]]:
    """The pair's power-law fits with their curves μ = k·p^(n−1) sampled over the fitted
    pressure range (log-spaced, :data:`FIT_CURVE_POINTS` points), their speed [mm/s] and
    their legend as the page writes it."""
    import numpy as np

    out = []
    speeds = (pair_fits[NOMINAL_SPEED].to_numpy(dtype=float) if NOMINAL_SPEED in pair_fits
              else [FOUNDING_SLIDING_SPEED_MM_S] * len(pair_fits))
    for f, speed in zip(pair_fits.to_dict(orient="records"), speeds, strict=True):
        row = {name: _plain(f[name]) for name in FIT_FIELDS}
        row["speed_mm_s"] = float(speed)
        curve: list[list[float]] = []
        k, exponent = row["k"], row["exponent"]
        lo, hi = row["pressure_min_kPa"], row["pressure_max_kPa"]
        if None not in (k, exponent, lo, hi) and 0 < lo < hi:
            p = np.geomspace(lo, hi, FIT_CURVE_POINTS)
            mu = power_law(p, k, exponent)
            curve = [[float(f"{a:.4g}"), float(f"{b:.4g}")] for a, b in zip(p, mu, strict=True)]
        row["curve"] = curve
        row["legend"] = ("not fitted" if k is None else
                         f"μ_K = {k:.3f}·(p/kPa)^{exponent:.3f}, R² {row['r_squared']:.3f}"
                         if row["r_squared"] is not None else
                         f"μ_K = {k:.3f}·(p/kPa)^{exponent:.3f}")
        out.append(row)
    return out


#: the group-table columns the page reads (its fields, cells, flags, labs and runs)
_GROUP_READ = frozenset((
    "pin", "disc", *GROUP_FIELDS, *GROUP_FLAG_FIELDS, NOMINAL_SPEED, TEST_METHOD, LABS,
    "run_ids"))


def _group_texts(g: Mapping[Any, Any], expanded: dict[str, float | None]) -> dict[str, str]:
    """A group row's cells as the page's group table shows them (the tables' rounding:
    :func:`tribopipe.export.tables.condition_text`, GUM ``value ± U``, three decimals)."""
    def with_u(q: str) -> str:
        mean = _plain(g.get(f"{q}_mean"))
        if not isinstance(mean, int | float):
            return ""
        n = _plain(g.get(f"{q}_n"))
        return estimate_text(float(mean), expanded[q], int(n) if isinstance(n, int) else 0)

    def count(name: str) -> str:
        v = _plain(g.get(name))
        return "" if v is None else str(int(v))

    def num(name: str) -> str:
        v = _plain(g.get(name))
        return "" if v is None else f"{v:.3f}"

    qc = ", ".join(group_flags({k: _plain(g[k]) for k in GROUP_FLAG_FIELDS if k in g}))
    return {
        "normal_force_N": _cell_g(g.get("normal_force_N")),
        "pressure_kPa": condition_text("pressure_kPa", _plain(g.get("pressure_kPa"))),
        "temperature_C": condition_text("temperature_C", _plain(g.get("temperature_C"))),
        NOMINAL_SPEED: condition_text(NOMINAL_SPEED, _plain(g.get(NOMINAL_SPEED))),
        "mu_k_n": count("mu_k_n"),
        "mu_k_mean": with_u("mu_k"),
        "mu_k_std": num("mu_k_std"),
        "mu_k_ci95_low": num("mu_k_ci95_low"),
        "mu_k_ci95_high": num("mu_k_ci95_high"),
        "mu_k_cv": num("mu_k_cv"),
        "mu_s_n": count("mu_s_n"),
        "mu_s_mean": with_u("mu_s"),
        "qc": qc,
    }


def _cell_g(value: Any) -> str:
    """A number as format "g" writes it ('' where missing)."""
    v = _plain(value)
    return "" if not isinstance(v, int | float) else f"{v:g}"


def _pair_snippets(pin: str, disc: str) -> dict[str, dict[str, list[str]]]:
    """The lines of each page snippet that name the pair, escaped and laid out by the
    writers' own rules: ``head`` (:data:`~tribopipe.export.headers.PAIR_LINE`, the first
    of :func:`~tribopipe.export.headers.condition_lines`) and, for the decks, ``name``
    (ABAQUS's interaction name) and ``material`` (Ansys's material line)."""
    out: dict[str, dict[str, list[str]]] = {}
    for fmt, syntax, safe in (("abaqus", "**", deck_safe), ("ansys", "!", ansys_safe)):
        out[fmt] = {"head": comment_block(syntax, [PAIR_LINE.format(pin=safe(pin),
                                                                   disc=safe(disc))])}
    out["abaqus"]["name"] = [abaqus_name(pin, disc)]
    out["ansys"]["material"] = comment_block("!", [MATERIAL_LINE.format(
        number=1, pin=ansys_safe(pin), disc=ansys_safe(disc))])
    plain = PAIR_LINE.format(pin=pin, disc=disc)
    out["usd"] = {"head": [usd_comment(plain)]}
    for fmt in ("pybullet", "drake"):
        out[fmt] = {"head": [xml_comment(plain, ascii_only=True)]}
    return out


def _texts() -> dict[str, Any]:
    """The words the page shows around its numbers, each from where the library keeps it."""
    return {
        "notes": dict(NOTES),
        "why_no_u": dict(WHY_NO_U),
        "extrapolated": EXTRAPOLATED,
        "errors": {**REQUEST_ERRORS,
                   "no_pair": "no groups for pin {pin} on disc {disc} in this map"},
        "page": PAGE_TEXTS,
        "heads": GROUP_TABLE_HEADS,
        "names": name_rule(),
        "snippet": {
            # the decks' note, laid out as their comment lines
            "note_lines": {fmt: comment_block(syntax, [CONSTANT_NOTE.format(fmt=fmt)])
                           for fmt, syntax in (("abaqus", "**"), ("ansys", "!"))},
            "clamped": HELD_LINE,
            "mu_s_unknown": MU_S_UNKNOWN,
            "static": dict(STATIC_WHY),
        },
    }


def explorer_data(
    runs: pd.DataFrame,
    *,
    groups: pd.DataFrame | None = None,
    fits: pd.DataFrame | None = None,
    title: str = "tribopipe friction-map explorer",
    source: str | None = None,
    curvature: Mapping[str, float] | None = None,
) -> dict[str, Any]:
    """The explorer's JSON document for friction-map ``runs`` (excluded runs left out).

    ``groups`` defaults to :func:`tribopipe.stats.group_statistics` of the included runs
    and ``fits`` to :func:`tribopipe.fit.fit_power_law` of ``runs``. Returns a dict of
    plain values (``None`` for missing numbers): ``format, title, source,
    tribopipe_version, generated``; ``pairs`` (per pair: ``pin, disc``, ``keys`` (the
    casefolded names :func:`tribopipe.query.select_pair` matches), ``speeds`` (one entry
    per measured nominal speed: ``speed_mm_s, text, mu_k_points, mu_s_points,
    temperatures, pressures, temperature_needed``), ``speed_needed``, ``left_out``,
    ``fits``, ``labs`` and ``snippet`` (the lines of each snippet that name the pair));
    ``runs`` (per pair, the included runs, each with its ``test_method``: the page reads
    them when the pair is shown); ``groups`` (the group table, each row with the index of
    its ``pair``, its ``test_method`` and its cells' ``text``); ``labs``; ``methods`` (the
    test methods of the included runs, in the map's order: the page filters the group
    table by them where there are several); ``texts`` (the notes, errors and snippet words
    the page shows); ``csv`` (the CSV header and the cells that are text); ``snippets``
    and ``snippet_headers`` (the simulator formats the page copies and their opening
    lines). Every text is made here, by the library's own rules; the page's script only
    computes numbers and puts these texts around them. Pressures in kPa, temperatures in
    °C, speeds in mm/s. Raises :class:`ExportError` when no run is left. Inputs are not
    modified. ``curvature`` is the map's κ per quantity (``mu_k``, ``mu_s``), computed
    from ``groups`` when not given (a page of a split map is given the whole map's).
    """
    import numpy as np

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
    lab_names = sorted({_lab_name(v) for v in included["lab"]}) if "lab" in included else []
    labs = {name: i for i, name in enumerate(lab_names or ["unknown lab"])}

    # each pair's rows selected once: the pairs in query's order (one per casefolded
    # name, query merges spellings), each group, run and fit given its pair's number
    order: dict[tuple[str, str], int] = {}
    for pin, disc in pairs(groups):
        order.setdefault((_key(pin), _key(disc)), len(order))
    group_keys = list(zip(groups["pin"].map(_key), groups["disc"].map(_key), strict=True))
    codes = np.array([order[k] for k in group_keys], dtype=np.int64)
    shown = shown_pairs(groups, group_keys)
    first_row: dict[int, int] = {}
    for position, c in enumerate(codes.tolist()):
        first_row.setdefault(c, position)
    # each pair's measured speeds and its groups at each (query.pair_speeds and
    # query.groups_at_speed: a group of no valid speed is at none where the table has a
    # speed column)
    if NOMINAL_SPEED in groups.columns:
        speed_of = pd_numeric(groups[NOMINAL_SPEED])
        valid = np.isfinite(speed_of) & (speed_of > 0)
    else:
        speed_of = np.full(len(groups), FOUNDING_SLIDING_SPEED_MM_S)
        valid = np.ones(len(groups), dtype=bool)
    measured_of: dict[int, set[float]] = {}
    for c, v in zip(codes[valid].tolist(), speed_of[valid].tolist(), strict=True):
        measured_of.setdefault(c, set()).add(float(v))
    at_speed: dict[tuple[int, float], int] = {}
    for c in sorted(first_row):
        for v in sorted(measured_of.get(c, ())) or [FOUNDING_SLIDING_SPEED_MM_S]:
            at_speed[(c, v)] = len(at_speed)
    speed_codes = np.array([at_speed[(c, v)] if ok else -1 for c, v, ok in zip(
        codes.tolist(), speed_of.tolist(), valid.tolist(), strict=True)], dtype=np.int64)
    with_speed = speed_codes >= 0
    at_groups = groups[with_speed]
    points = {q: _by_code(points_by(at_groups, speed_codes[with_speed], q))
              for q in ("mu_k", "mu_s") if q == "mu_k" or "mu_s_mean" in groups.columns}
    runs_at: dict[int, dict[tuple[float, float], list[str]]] = {}
    ids = groups["run_ids"].tolist() if "run_ids" in groups.columns else [None] * len(groups)
    for sc, p, t, cell in zip(speed_codes.tolist(), pd_numeric(groups["pressure_kPa"]).tolist(),
                              pd_numeric(groups["temperature_C"]).tolist(), ids, strict=True):
        if sc >= 0:
            runs_at.setdefault(sc, {}).setdefault((p, _t_key(t)), []).extend(run_ids_of(cell))
    left_out = _left_out(groups, codes)
    # the included runs in the pages' order, each pair's together (one sort, one pass)
    run_codes = np.array([order.get(k, -1) for k in zip(
        included["pin"].map(_key), included["disc"].map(_key), strict=True)], dtype=np.int64)
    ordered = included[[c for c in EXPLORER_COLUMNS if c in included.columns]].assign(
        **{_PAIR: run_codes})  # what the page reads of a run (_runs), no more
    ordered = ordered[run_codes >= 0].sort_values(
        [_PAIR, *RUN_ORDER], kind="mergesort")
    runs_of: dict[int, list[dict[str, Any]]] = {}
    for c, r in zip(ordered[_PAIR].tolist(), _runs(ordered, labs), strict=True):
        runs_of.setdefault(c, []).append(r)
    fit_codes = [order.get(k, -1) for k in zip(fits["pin"].map(_key), fits["disc"].map(_key),
                                                strict=True)]
    fits_of: dict[int, list[dict[str, Any]]] = {}
    for c, f in zip(fit_codes, _fits(fits), strict=True):
        fits_of.setdefault(c, []).append(f)

    pair_index: dict[tuple[str, str], int] = {}
    pair_rows: list[dict[str, Any]] = []
    run_chunks: list[list[dict[str, Any]]] = []
    group_pins, group_discs = groups["pin"].tolist(), groups["disc"].tolist()
    for key, c in order.items():
        if key not in shown:  # a pair without a μ_K point (query.pair_points)
            continue
        pair_runs = runs_of.get(c, [])
        run_index = {r["id"]: i for i, r in enumerate(pair_runs)}
        measured = sorted(measured_of.get(c, ())) or [FOUNDING_SLIDING_SPEED_MM_S]
        speeds = []
        for v in measured:
            sc = at_speed[(c, v)]
            speeds.append(_speed_points(points["mu_k"].get(sc, []),
                                        points.get("mu_s", {}).get(sc, []),
                                        runs_at.get(sc, {}), v, run_index))
        pair_index[key] = len(pair_rows)
        run_chunks.append(pair_runs)
        # the names as the pair's first group spells them
        pin_name, disc_name = str(group_pins[first_row[c]]), str(group_discs[first_row[c]])
        pair_rows.append(
            {
                "pin": pin_name,
                "disc": disc_name,
                "keys": list(key),
                "speeds": speeds,
                "speed_needed": speed_needed(measured) if len(measured) > 1 else None,
                "left_out": left_out.get(c, 0),
                "labs": sorted({r["lab"] for r in pair_runs}),
                "fits": fits_of.get(c, []),
                "snippet": _pair_snippets(pin_name, disc_name),
                "csv": [_csv_field(pin_name), _csv_field(disc_name)],
                "slug": _slug(pin_name, disc_name),
            }
        )
    group_rows = []
    expanded = {q: 2.0 * group_u(groups, q)[0].to_numpy(dtype=float) for q in ("mu_k", "mu_s")}
    lab_of_run = {r["id"]: r["lab"] for chunk in run_chunks for r in chunk}
    read = [c for c in groups.columns if c in _GROUP_READ]  # the others are not read
    for i, g in enumerate(groups.loc[:, read].to_dict(orient="records")):
        index = pair_index.get(group_keys[i])
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
        u_known: dict[str, float | None] = {}
        for q, values in expanded.items():  # U (k = 2) of the group mean, where known
            u = float(values[i])
            row[f"{q}_U"] = u_known[q] = u if known_u(u) else None
        named = str(g.get(LABS) or "").split(";") if LABS in g else []
        row["labs"] = sorted({labs[n] for n in map(printable, named) if n in labs}) or sorted(
            {lab_of_run[r] for r in run_ids_of(g.get("run_ids")) if r in lab_of_run})
        row[LABS_DISAGREE] = bool(g.get(LABS_DISAGREE) is True)
        row["text"] = _group_texts(g, u_known)
        group_rows.append(row)
    return {
        "format": DATA_FORMAT,
        "title": title,
        "source": source,
        "tribopipe_version": __version__,
        "generated": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "pairs": pair_rows,
        "runs": run_chunks,
        "groups": group_rows,
        "labs": list(labs),
        # the test methods of the included runs, in the map's order (the page filters
        # the group table by them where there are several)
        "methods": methods,
        "texts": _texts(),
        "csv": {"header": ",".join(CSV_COLUMNS),
                "cells": [_csv_field(source or ""), _csv_field(__version__)]},
        # the map's κ for the interpolation's own uncertainty (tribopipe.interpolation)
        "curvature": dict(curvature) if curvature is not None else
        {q: map_curvature(groups, q) for q in ("mu_k", "mu_s")},
        # the simulator formats the page copies (every registered format with a
        # snippet); the opening lines of each do not depend on the condition: rendered
        # here by the writer itself, the page adds the rest (snippets.js)
        "snippets": [{"name": f.name, "label": f.snippet_label, "suffix": f.snippet_suffix}
                     for f in ENTRIES if f.snippet],
        "snippet_headers": {f.name: snippet_header(f.name, source)
                            for f in ENTRIES if f.snippet},
    }


def _csv_field(text: str) -> str:
    """``text`` as one field of a CSV line: :func:`tribopipe.escape.csv_cell`, quoted as
    the csv module quotes it (where it holds a comma, a quote or surrounding space)."""
    import csv
    import io

    out = io.StringIO()
    csv.writer(out, lineterminator="").writerow([csv_cell(text)])
    return out.getvalue()


def _slug(pin: str, disc: str) -> str:
    """The pair's part of a downloaded file's name: each name casefolded, runs of other
    characters than a–z and 0–9 as one hyphen, at most 40 characters (``x`` when empty)."""
    def one(name: str) -> str:
        return re.sub(r"[^a-z0-9]+", "-", _key(name)).strip("-")[:40] or "x"
    return f"{one(pin)}_{one(disc)}"


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


def explorer_fragment(data: dict[str, Any], *, runs_beside: str | None = None) -> str:
    """The explorer as a block of HTML for a page that already has a ``<head>``: its
    markup, the data element and the script. The page must also carry
    :func:`explorer_style` (the rules are scoped to the block's ``.tpx`` class). One
    explorer per page (its elements have fixed ids such as ``mu-k``). ``runs_beside``: the
    folder (relative to the page) where :func:`runs_files` were written, instead of
    carrying the runs in the page."""
    return _fragment(data, _script(), runs_beside)


def _packed(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Rows (a pair's runs, the groups) as columns and rows: each key written once, not
    once per row; a dict value's keys become columns ``name/key``."""
    columns: list[str] = []
    cells: list[tuple[str, str]] = []  # each column's key and, in a dict value, its key
    for name, value in (rows[0].items() if rows else ()):
        columns += [f"{name}/{k}" for k in value] if isinstance(value, dict) else [name]
        cells += [(name, k) for k in value] if isinstance(value, dict) else [(name, "")]
    return {"columns": columns,
            "rows": [[r[name][key] if key else r[name] for name, key in cells] for r in rows]}


def _unpacked(packed: dict[str, Any]) -> list[dict[str, Any]]:
    """:func:`_packed` undone."""
    out = []
    for row in packed["rows"]:
        item: dict[str, Any] = {}
        for column, value in zip(packed["columns"], row, strict=True):
            name, _, key = column.partition("/")
            if key:
                item.setdefault(name, {})[key] = value
            else:
                item[name] = value
        out.append(item)
    return out


def runs_files(data: dict[str, Any]) -> dict[str, str]:
    """The runs of each pair as a script file of its own (name → text), for a page whose
    runs lie beside it (:func:`explorer_page` ``runs_beside``): the page loads a pair's
    file when it shows that pair. Each file hands its data, JSON escaped as inside a page
    (:func:`tribopipe.escape.script_json`), to ``window.tribopipeRuns``."""
    return {f"pair-{i}.js": _runs_file(i, chunk) for i, chunk in enumerate(data.get("runs", []))}


def _runs_file(i: int, chunk: list[dict[str, Any]]) -> str:
    """The text of :func:`runs_files`' file of pair ``i`` of the page, its runs ``chunk``."""
    return f"window.tribopipeRuns({i}, {script_json(_packed(chunk))});\n"


def _fragment(data: dict[str, Any], js: str, runs_beside: str | None = None) -> str:
    """The fragment template filled with ``data`` (embedded JSON) and the script ``js``.

    Each pair's runs travel in their own data element (``#tpx-runs-<pair>``), which the
    page parses only when it shows that pair, or in files beside the page
    (``runs_beside``) which it loads then: a large map's page opens on its groups and
    fits, and reads the runs of one pair at a time."""
    options = "".join(
        f'\n   <option value="{html_text(s["name"])}">{html_text(s["label"])}</option>'
        for s in data["snippets"])
    head = {k: v for k, v in data.items() if k != "runs"}
    # each speed's interpolation points packed (the page unpacks them as it opens)
    head["pairs"] = [{**pair, "speeds": [{**sp, **{q: _packed(sp[q]) for q in POINT_LISTS}}
                                         for sp in pair["speeds"]]}
                     for pair in data["pairs"]]
    # the groups packed, their names left to their pair's (the page restores both)
    head["groups"] = _packed([{k: v for k, v in g.items() if k not in ("pin", "disc")}
                              for g in data["groups"]])
    chunks = ""
    if runs_beside is None:
        chunks = "".join(
            f'\n<script type="application/json" id="{RUNS_ELEMENT_PREFIX}{i}">'
            f"{script_json(_packed(chunk))}</script>"
            for i, chunk in enumerate(data.get("runs", [])))
    else:
        head["runs_beside"] = runs_beside
    return _fill(_asset("explorer_fragment.html"),
                 {"data": script_json(head), "script": js, "data_id": DATA_ELEMENT_ID,
                  "snippet_options": options, "runs": chunks})


def explorer_style() -> str:
    """The explorer's CSS (rules scoped to ``.tpx``), for a page embedding the fragment."""
    return _style()


def explorer_page(data: dict[str, Any], *, runs_beside: str | None = None) -> str:
    """The standalone explorer page (UTF-8 HTML text) for :func:`explorer_data` ``data``.

    Its Content-Security-Policy allows only its own inline script and style (by SHA-256)
    and ``data:`` images: the page loads nothing from anywhere. With ``runs_beside`` (a
    folder name relative to the page, holding :func:`runs_files`) the page carries no run
    and its script may add the scripts of that folder ('strict-dynamic': only what its
    own hashed script inserts runs, never markup).
    """
    js, css = _script(), _style()
    dynamic = " 'strict-dynamic'" if runs_beside is not None else ""
    csp = (
        f"default-src 'none'; script-src {_sha256(js)}{dynamic}; style-src {_sha256(css)}; "
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
            "fragment": _fragment(data, js, runs_beside),
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
    data: dict[str, Any] = json.loads(match.group(1))
    for pair in data["pairs"]:
        for speed in pair["speeds"]:
            speed.update({q: _unpacked(speed[q]) for q in POINT_LISTS})
    data["groups"] = [{"pin": data["pairs"][g["pair"]]["pin"],
                       "disc": data["pairs"][g["pair"]]["disc"], **g}
                      for g in _unpacked(data["groups"])]
    chunks = re.findall(
        r'<script type="application/json" id="' + re.escape(RUNS_ELEMENT_PREFIX)
        + r'(\d+)">(.*?)</script>', html, re.DOTALL)
    data["runs"] = [_unpacked(json.loads(text))
                    for _, text in sorted(chunks, key=lambda c: int(c[0]))]
    return data


# ---------------------------------------------------------------------------- I/O edge


def runs_folder(output: str | Path) -> Path:
    """The folder beside an explorer page ``output`` that holds its runs when the map is
    too large to carry them in the page: ``<name>_runs``."""
    out = Path(output)
    return out.with_name(out.stem + "_runs")


def pages_folder(output: str | Path) -> Path:
    """The folder beside an explorer page ``output`` that holds the pages of a map of more
    condition groups than one page carries: ``<name>_pages``."""
    out = Path(output)
    return out.with_name(out.stem + "_pages")


def _page_files(data: dict[str, Any], name: str,
                runs_inline_limit: int) -> Iterator[tuple[str, str]]:
    """The explorer page ``name`` (a relative path) of ``data`` and, where it has more
    runs than ``runs_inline_limit``, the files of its runs beside it (the page last), one
    (name, text) at a time."""
    if sum(len(chunk) for chunk in data["runs"]) <= runs_inline_limit:
        yield name, explorer_page(data)
        return
    folder = runs_folder(name)
    for i, chunk in enumerate(data["runs"]):
        yield (folder / f"pair-{i}.js").as_posix(), _runs_file(i, chunk)
    yield name, explorer_page(data, runs_beside=folder.name)


def shown_pairs(groups: pd.DataFrame,
                keys: list[tuple[str, str]] | None = None) -> set[tuple[str, str]]:
    """The pairs of ``groups`` the explorer shows, as casefolded (pin, disc) names
    (:func:`_key`; ``keys``: each group's, when the caller has them): those with a μ_K
    point to interpolate (:func:`tribopipe.query.pair_points`); each is a pair of the page
    and, where its runs lie beside the page, a file of its own."""
    import numpy as np

    if keys is None:
        keys = list(zip(groups["pin"].map(_key), groups["disc"].map(_key), strict=True))
    index: dict[tuple[str, str], int] = {}
    codes = np.array([index.setdefault(k, len(index)) for k in keys], dtype=np.int64)
    named = list(index)
    return {named[c] for c in points_by(groups, codes, "mu_k")["code"].tolist()}


def _pair_key(pins: pd.Series, discs: pd.Series) -> pd.Series:
    """Each row's pair as one text: its casefolded pin and disc names (:func:`_key`)."""
    return pins.map(_key) + "\0" + discs.map(_key)


def _shards(groups: pd.DataFrame, limit: int) -> list[list[str]]:
    """The pairs (:func:`_pair_key`, in the group table's order) split into pages of at
    most ``limit`` groups each, a pin's pairs together: whole pins to a page while they
    fit, and a pin of more groups than ``limit`` over pages of its own, its pairs kept
    whole (a pair of more groups is a page of its own)."""
    pair_keys = _pair_key(groups["pin"], groups["disc"])
    counts = pair_keys.value_counts(sort=False)
    of_pin: dict[str, list[str]] = {}
    for key in counts.index:
        of_pin.setdefault(str(key).split("\0")[0], []).append(str(key))
    shards: list[list[str]] = []
    size = 0
    for pin_pairs in of_pin.values():
        n = sum(int(counts[k]) for k in pin_pairs)
        if n <= limit:  # the pin's pairs together
            if not shards or size + n > limit:
                shards.append([])
                size = 0
            shards[-1] += pin_pairs
            size += n
            continue
        first = True
        for key in pin_pairs:  # a pin too large for one page: its pairs over pages
            m = int(counts[key])
            if first or size + m > limit:
                shards.append([])
                size = 0
                first = False
            shards[-1].append(key)
            size += m
        size = limit  # no other pin joins the last page of a split pin
    return shards


def explorer_parts(
    runs: pd.DataFrame,
    name: str,
    *,
    title: str = "tribopipe friction-map explorer",
    source: str | None = None,
    groups: pd.DataFrame | None = None,
    fits: pd.DataFrame | None = None,
    runs_inline_limit: int = RUNS_INLINE_LIMIT,
    groups_page_limit: int = GROUPS_PAGE_LIMIT,
    runs_beside_pages: bool = True,
    max_files: int | None = None,
) -> Iterator[tuple[str, str]]:
    """Every file of the explorer of ``runs`` whose page is ``name``, one (relative path,
    text) at a time as it is made (the page ``name`` last), so that no page grows with the
    map and no more than one page is held at a time.

    Up to ``groups_page_limit`` condition groups the explorer is one page
    (:func:`explorer_data`, ``groups`` and ``fits`` as it takes them), its runs in the page
    up to ``runs_inline_limit`` and beside it above (:func:`runs_files`, one file per pair,
    loaded when the pair is shown). A map of more groups gets, at ``name``, an index of its
    pins (each pin's name, discs, groups and runs, linking to its page), and its pins'
    explorers as pages of whole pins of at most ``groups_page_limit`` groups in
    :func:`pages_folder` (a pin of more groups over pages of its own, by whole pairs, one
    index row per page: :func:`_shards`), each with its runs beside it
    (``runs_beside_pages``; else as
    ``runs_inline_limit`` says); every page interpolates with the whole map's curvature,
    so each gives what ``query`` gives on the whole map.

    ``max_files`` (a package lists each file as a resource of its own, and lists few) bounds
    the number of files, decided before any page is made: pages of more groups each
    (``groups_page_limit`` doubled until the pages fit), then the runs in the pages
    instead of beside them."""
    included = runs
    if "excluded" in runs.columns:
        included = runs[~runs["excluded"].fillna(False).astype(bool)]
    if groups is None:
        groups = group_statistics(included, show_method=True)
    limit = groups_page_limit
    while max_files is not None and len(groups) > limit and len(
            _shards(groups, limit)) >= max_files:
        limit *= 2  # each page a file: fewer, larger pages
    if len(groups) <= limit:
        data = explorer_data(runs, groups=groups, fits=fits, title=title, source=source)
        if max_files is not None and 1 + len(data["runs"]) > max_files:
            runs_inline_limit = sys.maxsize
        yield from _page_files(data, name, runs_inline_limit)
        return
    if fits is None:
        fits = fit_power_law(runs)
    curvature = {q: map_curvature(groups, q) for q in ("mu_k", "mu_s")}
    shards = _shards(groups, limit)
    folder = pages_folder(name)
    run_pairs, group_pairs, fit_pairs = (_pair_key(t["pin"], t["disc"])
                                         for t in (included, groups, fits))
    if max_files is not None and runs_beside_pages and 1 + len(shards) + _files_beside(
            shards, shown_pairs(groups), run_pairs) > max_files:
        runs_beside_pages, runs_inline_limit = False, sys.maxsize
    rows: list[tuple[str, list[str], int, int, str]] = []
    for k, keys in enumerate(shards, 1):
        page = (folder / f"part-{k}.html").as_posix()
        in_groups, in_runs = group_pairs.isin(keys), run_pairs.isin(keys)
        shard_groups, shard_runs = groups[in_groups], included[in_runs]
        data = explorer_data(shard_runs, groups=shard_groups, fits=fits[fit_pairs.isin(keys)],
                             title=f"{title} — page {k} of {len(shards)}", source=source,
                             curvature=curvature)  # the whole map's: query's own
        yield from _page_files(data, page, 0 if runs_beside_pages else runs_inline_limit)
        del data
        # each pin's name (its first group's spelling), discs, groups and runs on this
        # page, counted in one pass over the page's groups and runs
        names: dict[str, str] = {}
        discs: dict[str, set[str]] = {}
        n_groups: dict[str, int] = {}
        for pin, disc in zip(shard_groups["pin"], shard_groups["disc"], strict=True):
            key = _key(pin)
            names.setdefault(key, str(pin))
            discs.setdefault(key, set()).add(str(disc))
            n_groups[key] = n_groups.get(key, 0) + 1
        n_runs = shard_runs["pin"].map(_key).value_counts()
        for key in names:
            rows.append((names[key], sorted(discs[key], key=_key), n_groups[key],
                         int(n_runs.get(key, 0)), f"{Path(page).parent.name}/part-{k}.html"))
    yield name, explorer_index(rows, title=title, source=source, n_groups=len(groups),
                               n_runs=len(included))


def _files_beside(shards: list[list[str]], shown: set[tuple[str, str]],
                  run_pairs: pd.Series) -> int:
    """How many files of runs lie beside the pages of ``shards`` (:func:`_shards`) when
    each page's runs lie beside it: one per shown pair (``shown``: :func:`shown_pairs`) of
    each page that has runs of its shown pairs (``run_pairs``: each run's
    :func:`_pair_key`), as :func:`_page_files` writes them."""
    n = 0
    for keys in shards:
        on_page = [k for k in keys if tuple(k.split("\0")) in shown]
        if on_page and run_pairs.isin(on_page).any():
            n += len(on_page)
    return n


def explorer_index(pins: list[tuple[str, list[str], int, int, str]], *, title: str,
                   source: str | None, n_groups: int, n_runs: int) -> str:
    """The index page of an explorer split into pages of pins: one row per pin (its name,
    its discs, its groups and runs) linking to its page (``href``, relative to the index)
    with the pin selected. Static HTML: every name escaped, no script."""
    from urllib.parse import quote

    css = _index_style()
    csp = f"default-src 'none'; style-src {_sha256(css)}; base-uri 'none'; form-action 'none'"
    body = "".join(
        f'<tr><td><a href="{html_text(quote(href, safe="/") + "?pin=" + quote(pin, safe=""))}'
        f'">{html_text(printable(pin))}</a></td>'
        f"<td>{html_text(', '.join(printable(d) for d in discs))}</td>"
        f'<td class="n">{n_groups_pin}</td><td class="n">{n_runs_pin}</td></tr>\n'
        for pin, discs, n_groups_pin, n_runs_pin, href in pins)
    subtitle = f"tribopipe {__version__}" + (f" · map {source}" if source else "")
    return (
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
        f'<meta http-equiv="Content-Security-Policy" content="{html_text(csp)}">\n'
        '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
        f"<title>{html_text(title)}</title>\n<style>{css}</style>\n</head>\n<body>\n"
        f"<h1>{html_text(title)}</h1>\n<p class=\"sub\">{html_text(subtitle)}</p>\n"
        f'<p id="tpx-index-note">{n_runs} runs in {n_groups} condition groups: more than one '
        "page shows at once. Each pin's explorer is a page of its own (its pairs, groups, "
        "fits and plots; the runs of a pair load when it is shown); choose a pin.</p>\n"
        '<table id="tpx-pins"><thead><tr><th>pin</th><th>discs</th><th>groups</th>'
        f"<th>runs</th></tr></thead>\n<tbody>\n{body}</tbody></table>\n</body>\n</html>\n")


def _index_style() -> str:
    return ("body{font-family:system-ui,sans-serif;margin:1.5rem;max-width:70rem}"
            "table{border-collapse:collapse}td,th{border-bottom:1px solid #ddd;"
            "padding:.2rem .6rem;text-align:left;vertical-align:top}"
            "td.n{text-align:right}.sub{color:#555}")


def write_explorer(
    map_path: MapSource,
    output: str | Path,
    *,
    title: str | None = None,
    runs_inline_limit: int = RUNS_INLINE_LIMIT,
    groups_page_limit: int = GROUPS_PAGE_LIMIT,
) -> Path:
    """Write the explorer of the map at ``map_path`` to ``output`` (atomically):
    :func:`explorer_parts`, each file written as it is made (atomically), the page
    last. A map of more than ``runs_inline_limit`` included runs gets its runs in
    :func:`runs_folder` beside the page, one file per pair; a map of more than
    ``groups_page_limit`` condition groups an index page at ``output`` and its pins'
    pages in :func:`pages_folder`; a smaller map's page carries everything and is one
    file."""
    snap = as_snapshot(map_path)
    runs = snap.runs
    if runs.empty:
        raise ExportError(
            "the friction map is empty or absent",
            path=map_path,
            hint="reduce runs first (tribopipe reduce / batch) or import the published map",
        )
    out = Path(output)
    groups = snap.groups(show_method=True)  # those of its included runs (stored in a folder)
    # the run columns the pages and the fits read, the others left behind
    shown = runs[[c for c in EXPLORER_COLUMNS if c in runs.columns]]
    del runs
    files = explorer_parts(shown, out.name,
                                title=title or "tribopipe friction-map explorer",
                                source=str(map_path), groups=groups,
                                runs_inline_limit=runs_inline_limit,
                                groups_page_limit=groups_page_limit)
    return write_page_and_files(out, files)  # each written as it is made
