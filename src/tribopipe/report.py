"""A self-contained HTML report of a campaign or a map: one file, plots embedded, no
external resources.

Sections: summary, the friction-map explorer (:mod:`tribopipe.export.explorer`, inline),
group table (each group links to its runs; downloadable as CSV), the repeats of groups
whose range exceeds r overlaid (μ over sliding distance from their traces), power-law fits
(downloadable as CSV), per-pair plots (μ_K against pressure), flagged runs, failures with
their reasons, and every run: with its trace plot (μ over sliding distance, μ_S peak, μ_K
window) where its trace is found, else as a row of a table. A report of a map without any
trace (an imported map: μ_K only) says so — "friction-map report", not a campaign — and
leaves out what it cannot fill: the μ_S columns when no group has μ_S, the overlays and
the per-run plots. Images are base64 PNG ``data:`` URIs, the CSV downloads ``data:`` URIs
whose text cells cannot run as spreadsheet formulas
(:func:`tribopipe.export.tables.spreadsheet_csv`); every piece of text from the map or the
file system is written with :func:`tribopipe.escape.html_text` (the explorer's data travel
as :func:`tribopipe.escape.script_json` and reach the page as text only).

A map of up to :data:`RUNS_INLINE_LIMIT` runs and
:data:`~tribopipe.export.explorer.GROUPS_PAGE_LIMIT` condition groups gets one page that
carries everything. A larger map's page keeps the summary, the list of its pairs (their
counts, a filter by name), the flagged runs and the failures; each pair's group rows, fits
and runs lie beside the page, in the folder the explorer's runs use
(:func:`tribopipe.export.explorer.runs_folder`): one script file per pair
(:func:`pair_files`), added when the pair is opened or a link to one of its runs is
followed (a run link names its pair's file), as the explorer loads its own runs
(:func:`tribopipe.export.explorer.runs_files`, in the same folder). A map of more
condition groups than one explorer page shows gets its explorer beside the report
(:func:`~tribopipe.export.explorer.explorer_parts`), linked; a map of more pairs than
:data:`PAIR_PLOTS_LIMIT` leaves its pair plots to the explorer, and says so.

:func:`report_parts` turns tables into the page and the files beside it, one at a time
(it renders plots but writes no file; :func:`report_files` collects them),
:func:`build_report` into the page of a report that needs no file beside it;
:func:`write_report` (each file written as it is made, the page last) and
:func:`make_report` read the map, ``failures.csv`` and the traces of a processed folder
and write the page.
"""

from __future__ import annotations

import base64
import io
import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, replace
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any
from urllib.parse import quote

from . import __version__
from .campaign import load_campaign
from .errors import ExportError, MapError
from .escape import html_text, script_json
from .export.explorer import (
    GROUPS_PAGE_LIMIT,
    explorer_data,
    explorer_fragment,
    explorer_parts,
    explorer_style,
    runs_files,
    runs_folder,
)
from .export.plots import plot_group_overlay, plot_pair, slug
from .export.tables import spreadsheet_csv
from .figures.trace import plot_trace_row
from .files import write_page_and_files
from .fit import fit_power_law
from .frictionmap.schema import MapRow, frame_rows
from .frictionmap.snapshot import as_snapshot
from .frictionmap.synthetic_rows import synthetic_note
from .labels import flag_list, quality_flags
from .layout import OutputLayout, find_traces, read_failures
from .query import estimate_text, pairs
from .rounding import known_u, plus_minus
from .stats import group_u, repeatability, run_ids_of

if TYPE_CHECKING:
    import pandas as pd

#: resolution of embedded plots: pairs sharp, traces small (there can be hundreds)
PAIR_DPI = 100
TRACE_DPI = 80
#: a report carries its runs in the page up to this many; a larger map's runs lie beside
#: the page, one file per pair, loaded when opened (a run costs about 600 bytes of page:
#: its row, its link in the group table and its point in the explorer)
RUNS_INLINE_LIMIT = 5_000
#: a report embeds the plots of a map of up to this many pairs (a PNG of 60–80 kB each,
#: drawn in about 0.2 s); the explorer draws any pair's plot of a larger map
PAIR_PLOTS_LIMIT = 50
#: what a report's files beside its page are named in its runs folder: ``report-<k>.js``,
#: the condition groups, fits and runs of its k-th pair
PAIR_FILE = "report-{k}.js"
#: default titles of the two kinds of report
CAMPAIGN_TITLE = "tribopipe campaign report"
MAP_TITLE = "tribopipe friction-map report"

_CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',Roboto,Helvetica,Arial,sans-serif;
 margin:0 auto;max-width:1200px;padding:1.5em;color:#1d1d1f;line-height:1.4}
h1{font-size:1.6em;margin-bottom:.2em}h2{border-bottom:2px solid #d0d7de;padding-bottom:.2em;
 margin-top:2em}nav a{margin-right:1em}
table{border-collapse:collapse;font-size:.88em;margin:.5em 0}
th,td{border:1px solid #d0d7de;padding:.25em .5em;text-align:right;vertical-align:top}
th{background:#f6f8fa;position:sticky;top:0}td.t,th.t{text-align:left}.w{white-space:nowrap}
@media (max-width:1000px){body{padding:.8em}table{font-size:.74em}th,td{padding:.2em .28em}}
tr.flag td{background:#fff4e5}tr.excl td{background:#f0f0f0;color:#666}
.muted{color:#666}.bad{color:#b42318;font-weight:600}
dl.summary{display:grid;grid-template-columns:max-content auto;gap:.2em 1.5em}
dl.summary dt{font-weight:600}dl.summary dd{margin:0}
.pairs{display:grid;grid-template-columns:repeat(auto-fill,minmax(520px,1fr));gap:1em}
.pairs figure{margin:0}
figure img{max-width:100%;height:auto;border:1px solid #e5e5e5}
figcaption{font-size:.85em;color:#444}
details.run{border:1px solid #d0d7de;border-radius:4px;margin:.4em 0;padding:.3em .6em}
details.run summary{cursor:pointer}details.run div:target{outline:3px solid #0969da}
details.runs{margin:.3em 0}details.runs>summary{cursor:pointer}
"""
#: the style a report whose pairs lie beside its page adds: each pair a collapsible block
#: whose wide tables scroll within it; a text cell breaks a long word (a file's path)
#: rather than widen the page, where a link to a run (8 characters of its id) stays whole
_PAIRS_CSS = (
    "details.pair{margin:.3em 0}details.pair>summary{cursor:pointer}"
    "td.t{overflow-wrap:anywhere}td.t a[href^=\"#run-\"]{white-space:nowrap}"
    ".pair-body{overflow-x:auto}#pair-filter{width:16em;max-width:100%}"
)

#: the script of a one-page report: opens the run a link points to, for browsers that do
#: not expand <details> themselves (its branch for runs beside the page, ``data-runs-beside``,
#: finds nothing there: a report with files beside its page carries :data:`_PAIRS_JS`)
_OPEN_TARGET_JS = (
    "var S=document.getElementById('runs'),B=S&&S.getAttribute('data-runs-beside'),W={};"
    "function L(k,f){var d=document.getElementById('runs-'+k);if(!d)return;"
    "if(d.hasAttribute('data-loaded')){if(f)f();return;}if(f)W[k]=f;"
    "if(document.getElementById('runs-load-'+k))return;"
    "var s=document.createElement('script');s.id='runs-load-'+k;"
    "s.src=B+'/report-'+k+'.js';s.onerror=function(){d.querySelector('.runs-body')"
    ".textContent='the runs of this pair are not beside the report ('+B+'/report-'+k+"
    "'.js)';};document.head.appendChild(s);}"
    "window.tribopipeReportRuns=function(k,h){var d=document.getElementById('runs-'+k);"
    "if(!d||d.hasAttribute('data-loaded'))return;var t=document.createElement('template');"
    "t.innerHTML=h;d.querySelector('.runs-body').replaceChildren(t.content);"
    "d.setAttribute('data-loaded','');var f=W[k];delete W[k];if(f)f();};"
    "if(B)document.addEventListener('toggle',function(ev){var d=ev.target;"
    "if(d.classList&&d.classList.contains('runs')&&d.open)L(d.getAttribute('data-runs'));},"
    "true);"
    "function o(){var i=decodeURIComponent(location.hash.slice(1)),"
    "e=i&&document.getElementById(i);"
    "if(!e&&B&&i.indexOf('run-')===0){var a=document.querySelector('a[data-runs][href=\"#'"
    "+CSS.escape(i)+'\"]');if(a){var k=a.getAttribute('data-runs');"
    "document.getElementById('runs-'+k).open=true;L(k,o);}return;}"
    "if(e){var d=e.closest('details');while(d){d.open=true;"
    "d=d.parentElement&&d.parentElement.closest('details');}e.scrollIntoView();}}"
    "window.addEventListener('hashchange',o);o();"
)

#: the script of a report whose pairs lie beside its page (``data-pairs-beside`` on the
#: list of pairs): loads a pair's file (``report-<k>.js``, which calls
#: ``tribopipeReportPair``) when the pair is opened or a link (``data-pair="<k>"``) to one
#: of its runs is followed, and puts the file's tables and runs in place (markup the
#: library made and escaped, parsed inert in a template); opens the run a link points to
#: (once its pair is loaded; a run its pair's file does not hold is left unopened);
#: shows only the pairs whose pin or disc holds what is typed in the pair filter
_PAIRS_JS = (
    "var S=document.getElementById('groups'),B=S.getAttribute('data-pairs-beside'),W={},"
    "N=document.querySelectorAll('details.pair').length;"
    "function L(k,f){var d=document.getElementById('pair-'+k);if(!d)return;"
    "if(d.hasAttribute('data-loaded')){if(f)f();return;}if(f)W[k]=f;"
    "if(document.getElementById('pair-load-'+k))return;"
    "var b=d.querySelector('.pair-body'),s=document.createElement('script');"
    "b.textContent='loading…';s.id='pair-load-'+k;"
    "s.src=encodeURIComponent(B)+'/report-'+k+'.js';"
    "s.onerror=function(){b.textContent='the groups, fits and runs of this pair are not "
    "beside the report ('+B+'/report-'+k+'.js)';};document.head.appendChild(s);}"
    "window.tribopipeReportPair=function(k,h){var d=document.getElementById('pair-'+k);"
    "if(!d||d.hasAttribute('data-loaded'))return;var t=document.createElement('template');"
    "t.innerHTML=h;d.querySelector('.pair-body').replaceChildren(t.content);"
    "d.setAttribute('data-loaded','');var f=W[k];delete W[k];if(f)f();};"
    "document.addEventListener('toggle',function(ev){var d=ev.target;"
    "if(d.classList&&d.classList.contains('pair')&&d.open)L(d.id.slice(5));},true);"
    "var F=document.getElementById('pair-filter');F.addEventListener('input',function(){"
    "var q=F.value.trim().toLowerCase(),n=0;"
    "document.querySelectorAll('details.pair').forEach(function(d){"
    "var m=!q||d.firstElementChild.textContent.toLowerCase().indexOf(q)>=0;d.hidden=!m;"
    "if(m)n++;});document.getElementById('pair-count').textContent=q?n+' of '+N+' pairs':"
    "N+' pairs';});"
    "function o(){var i=decodeURIComponent(location.hash.slice(1)),"
    "e=i&&document.getElementById(i);"
    "if(!e&&i.indexOf('run-')===0){var a=document.querySelector('a[data-pair][href=\"#'"
    "+CSS.escape(i)+'\"]');if(a){var k=a.getAttribute('data-pair'),"
    "d=document.getElementById('pair-'+k);d.hidden=false;d.open=true;"
    "if(!d.hasAttribute('data-loaded'))L(k,o);}return;}"
    "if(e){var d=e.closest('details');while(d){d.hidden=false;d.open=true;"
    "d=d.parentElement&&d.parentElement.closest('details');}e.scrollIntoView();}}"
    "window.addEventListener('hashchange',o);o();"
)


@dataclass(frozen=True)
class ReportInputs:
    """Everything a report shows: runs (map rows), groups, fits, failures and traces.

    ``failures`` is a list of ``(file, reason)``; ``traces_dir`` the folder with
    ``<stem>_<id8>.parquet`` traces (``None``: no trace plots); ``trace_paths`` the trace of
    each run found there (filled by :func:`build_report` when ``None``); ``title`` the
    page's title (``None``: :data:`CAMPAIGN_TITLE` or, without any trace, :data:`MAP_TITLE`);
    ``source`` a label (config or map path) for the header.
    """

    runs: pd.DataFrame
    groups: pd.DataFrame
    fits: pd.DataFrame
    failures: tuple[tuple[str, str], ...] = ()
    failures_known: bool = False
    traces_dir: Path | None = None
    title: str | None = None
    source: str | None = None
    trace_paths: Mapping[str, Path] | None = None

    @property
    def map_report(self) -> bool:
        """True when no run has a trace: a report of a map (e.g. imported), not a campaign."""
        return not self.trace_paths

    @property
    def page_title(self) -> str:
        """The title shown."""
        return self.title or (MAP_TITLE if self.map_report else CAMPAIGN_TITLE)


@dataclass(frozen=True)
class _Pairs:
    """The pairs of a report whose pairs lie beside its page, in its order: ``names``
    (pin, disc) as the map spells them, ``of`` the index of each (its file
    ``report-<k>.js``), and by index the positions of its rows among the runs (``runs``,
    in the order the report lists them), in the group table (``groups``) and in the fit
    table (``fits``)."""

    names: tuple[tuple[str, str], ...]
    of: Mapping[tuple[str, str], int]
    runs: Mapping[int, Any]
    groups: Mapping[int, Any]
    fits: Mapping[int, Any]


@dataclass(frozen=True)
class _Layout:
    """Where a report's parts travel: ``pairs_beside`` the folder (relative to the page)
    holding each pair's condition groups, fits and runs, one file per pair (``None``: the
    tables and runs in the page), ``pairs`` the pairs those files hold (a run link finds
    its file by the pair its run belongs to), ``explorer`` the embedded explorer's data
    (``None`` where the explorer lies beside the page, at ``explorer_page``),
    ``pair_plots`` whether the page embeds the pairs' plots (which the group table
    links), ``tables_beside`` the folder holding the group and fit tables' CSV downloads
    (``None``: in the page)."""

    pairs_beside: str | None = None
    pairs: _Pairs | None = None
    explorer: dict[str, Any] | None = None
    explorer_page: str | None = None
    pair_plots: bool = True
    tables_beside: str | None = None


# ---------------------------------------------------------------------------- helpers


def _e(value: Any) -> str:
    """Escaped text of a cell: '' for missing, 3 decimals for floats."""
    if value is None:
        return ""
    if isinstance(value, float):
        return "" if math.isnan(value) else f"{value:.3f}"
    try:
        import pandas as pd

        if pd.isna(value):
            return ""
    except (TypeError, ValueError):
        pass
    return html_text(str(value))


def _name(value: Any) -> str:
    """A pin or disc name for a table cell: escaped, each word kept whole (a name breaks
    between its words, never inside one, nor at a hyphen such as "00-50")."""
    return " ".join(f"<span class=w>{word}</span>" for word in _e(value).split(" ") if word)


def _num(value: Any, spec: str) -> str:
    """``value`` formatted with ``spec``; '' when missing or NaN."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        return ""
    return "" if math.isnan(v) else format(v, spec)


def _interval(low: Any, high: Any) -> str:
    """``[low, high]`` with 3 decimals; '' when either end is missing."""
    lo, hi = _num(low, ".3f"), _num(high, ".3f")
    return f"[{lo}, {hi}]" if lo and hi else ""


def _span(low: Any, high: Any) -> str:
    """``low–high`` with 3 decimals; '' when either end is missing."""
    lo, hi = _num(low, ".3f"), _num(high, ".3f")
    return f"{lo}–{hi}" if lo and hi else ""


def _run_value(value: Any, u: Any) -> str:
    """A run's ``μ ± U`` (U = 2u, k = 2) rounded the GUM way
    (:func:`tribopipe.rounding.plus_minus`); the value to 3 decimals where u is unknown;
    '' when the value is missing."""
    if not _num(value, ".3f"):
        return ""
    expanded = 2.0 * float(u) if _num(u, "g") else None
    if expanded is None or not known_u(expanded):
        return _num(value, ".3f")
    return plus_minus(float(value), expanded)


def _group_value(value: Any, u: Any, n: Any) -> str:
    """A group mean's ``μ ± U`` (:func:`tribopipe.query.estimate_text`: U = 2u, k = 2,
    GUM-rounded; "n = 1, no repeat scatter" where U is unknown for a single run)."""
    if not _num(value, ".3f"):
        return ""
    expanded = 2.0 * float(u) if _num(u, "g") else None
    return estimate_text(float(value), expanded if known_u(expanded) else None, int(n))


def run_anchor(measurement_id: str) -> str:
    """The HTML id of a run's section: ``run-<measurement_id>``."""
    return "run-" + "".join(c if c.isalnum() or c in "-_" else "_" for c in measurement_id)


def _run_link(mid: str, pin: Any, disc: Any, layout: _Layout) -> str:
    """A link to a run's section (its id's first 8 characters), with the index of its
    pair's file (the run's ``pin`` on ``disc``) where the runs lie beside the page."""
    chunk = None if layout.pairs is None else layout.pairs.of.get((str(pin), str(disc)))
    data = "" if chunk is None else f' data-pair="{chunk}"'
    return f'<a href="#{run_anchor(mid)}"{data}>{html_text(mid[:8])}</a>'


def pair_anchor(pin: str, disc: str) -> str:
    """The HTML id of a pair's plot: ``pair-<pin>--<disc>`` (slugs)."""
    return f"pair-{slug(pin)}--{slug(disc)}"


def _png_data_uri(draw: Any) -> str:
    """Call ``draw(buffer)`` (which writes a PNG into it) and return a ``data:`` URI."""
    buf = io.BytesIO()
    draw(buf)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def _img(uri: str, alt: str) -> str:
    """An ``<img>`` element for a ``data:`` URI."""
    return f'<img src="{uri}" alt="{html_text(alt)}">'


def _csv_link(table: pd.DataFrame, name: str, element_id: str, layout: _Layout) -> str:
    """A link that downloads ``table`` as ``name`` (CSV in a ``data:`` URI, formula-safe),
    or the file ``name`` beside the page where the report has files beside it
    (:func:`report_files` writes it there)."""
    if layout.tables_beside is not None:
        href = html_text(quote(f"{layout.tables_beside}/{name}", safe="/"))
    else:
        data = base64.b64encode(spreadsheet_csv(table).encode("utf-8")).decode("ascii")
        href = f"data:text/csv;charset=utf-8;base64,{data}"
    return (f'<p><a id="{element_id}" download="{html_text(name)}" '
            f'href="{href}">Download this table as CSV</a></p>')


def group_anchor(group: Mapping[str, Any]) -> str:
    """The HTML id of a group's overlay of repeats: ``spread-<pin>--<disc>-<F>N-<T>C``."""
    return (f"spread-{slug(str(group['pin']))}--{slug(str(group['disc']))}-"
            f"{slug(_num(group['normal_force_N'], 'g'))}N-"
            f"{slug(_num(group['temperature_C'], 'g') or 'unknown')}C")


# ---------------------------------------------------------------------------- sections


def _summary(inp: ReportInputs, layout: _Layout) -> str:
    """The campaign-summary section."""
    runs = inp.runs
    excluded = runs["excluded"].fillna(False).astype(bool)
    flagged = runs["flags"].map(lambda f: bool(quality_flags(f)))
    pairs = runs[["pin", "disc"]].drop_duplicates()
    temps = sorted({float(t) for t in runs["temperature_C"] if not math.isnan(float(t))})
    p = runs["pressure_kPa"].astype(float)
    rep = repeatability(inp.groups, "mu_k") if len(inp.groups) else None
    sources = runs["source"].value_counts().to_dict()
    labs = runs["lab"].fillna("this lab").value_counts().to_dict() if "lab" in runs else {}
    items = [
        ("runs", f"{len(runs)} ({int(excluded.sum())} excluded)"),
        ("contact pairs", str(len(pairs))),
        ("condition groups", str(len(inp.groups))),
        ("pins", ", ".join(sorted(runs["pin"].astype(str).unique()))),
        ("discs", ", ".join(sorted(runs["disc"].astype(str).unique()))),
        ("contact pressure", f"{p.min():.4g} – {p.max():.4g} kPa" if len(p) else "–"),
        ("temperatures", ", ".join(f"{t:g} °C" for t in temps) or "unknown"),
        ("sources", ", ".join(f"{k}: {v}" for k, v in sorted(sources.items()))),
        ("labs", ", ".join(f"{k}: {v}" for k, v in sorted(labs.items()))),
        ("runs with QC flags", str(int(flagged.sum()))),
        *([("reviewed runs", reviewed)] if (reviewed := _review_count(runs)) else []),
        *([("synthetic runs", note)] if (note := synthetic_note(runs)) else []),
        ("failures", str(len(inp.failures)) if inp.failures_known else "no failures.csv"),
    ]
    if rep is not None and not math.isnan(rep.s_r):
        items.append(
            ("repeatability of μ_K",
             f"s_r = {rep.s_r:.4f}, r = 2.8·s_r = {rep.r:.4f} ({rep.n_groups} groups, "
             f"{rep.dof} degrees of freedom)")
        )
    if inp.map_report:
        items.append(("traces", "none in this map (μ_K per run, nothing to plot per run)"))
    body = "".join(f"<dt>{html_text(k)}</dt><dd>{html_text(v)}</dd>" for k, v in items)
    heading = "Map summary" if inp.map_report else "Campaign summary"
    return (
        f'<section id="summary"><h2>{heading}</h2>'
        f'<dl class="summary">{body}</dl></section>'
    )


@dataclass(frozen=True)
class _GroupCells:
    """What every row of the group table needs from the whole table: whether it shows
    μ_S (some group has one), the groups whose repeats are overlaid (their anchors), and
    each group's standard uncertainty of μ_K and μ_S (by row position; the map's pooled
    repeatability enters them, so they are computed once over every group)."""

    with_mu_s: bool
    overlaid: frozenset[str]
    u_k: Any
    u_s: Any


#: the group table's columns a row reads
_GROUP_COLUMNS = (
    "pin", "disc", "normal_force_N", "pressure_kPa", "temperature_C", "mu_k_n", "mu_k_mean",
    "mu_k_std", "mu_k_ci95_low", "mu_k_ci95_high", "mu_k_min", "mu_k_max", "mu_k_cv",
    "mu_s_n", "mu_s_mean", "range_exceeds_r", "qc_flagged", "reviewed", "run_ids")


def _group_cells(inp: ReportInputs) -> _GroupCells:
    """:class:`_GroupCells` of the report's group table."""
    u_k, _ = group_u(inp.groups, "mu_k")
    u_s, _ = group_u(inp.groups, "mu_s")
    return _GroupCells(
        with_mu_s=bool(len(inp.groups)) and bool((inp.groups["mu_s_n"] > 0).any()),
        overlaid=frozenset(_overlay_groups(inp)), u_k=u_k.to_numpy(), u_s=u_s.to_numpy())


def _group_records(groups: pd.DataFrame) -> list[dict[str, Any]]:
    """The rows of (part of) the group table as dicts of the columns a row reads."""
    present = [c for c in _GROUP_COLUMNS if c in groups.columns]
    return groups[present].to_dict(orient="records", into=dict)


def _group_head(with_mu_s: bool) -> str:
    """The group table's head row."""
    return (
        "<tr><th class=t>pin</th><th class=t>disc</th><th>F [N]</th><th>p [kPa]</th>"
        "<th>T [°C]</th><th>n</th><th>μ_K ± U (k = 2)</th><th>μ_K SD</th>"
        "<th>μ_K 95 % CI of the repeats</th><th>μ_K min–max</th><th>μ_K CV</th>"
        + ("<th>μ_S n</th><th>μ_S ± U (k = 2)</th>" if with_mu_s else "")
        + "<th class=t>QC</th><th class=t>runs</th></tr>"
    )


def _group_row(i: int, g: Mapping[str, Any], cells: _GroupCells, layout: _Layout) -> str:
    """The row of the group at position ``i`` of the group table: its figures, its QC
    (linking the overlay of its repeats where there is one) and links to its runs."""
    ids = run_ids_of(g.get("run_ids"))
    links = " ".join(_run_link(i, g["pin"], g["disc"], layout) for i in ids)
    qc = []
    if g.get("range_exceeds_r"):
        anchor = group_anchor(g)
        qc.append(f'<a href="#{anchor}">range &gt; r</a>' if anchor in cells.overlaid
                  else "range &gt; r")
    if g.get("qc_flagged"):
        qc.append("flagged run")
    if g.get("reviewed"):
        qc.append(f"{int(g['reviewed'])} reviewed")
    ci = _interval(g["mu_k_ci95_low"], g["mu_k_ci95_high"])
    pair = (f'<a href="#{pair_anchor(str(g["pin"]), str(g["disc"]))}">{_name(g["disc"])}</a>'
            if layout.pair_plots else _name(g["disc"]))
    cls = ' class="flag"' if qc else ""
    return (
        f"<tr{cls}><td class=t>{_name(g['pin'])}</td><td class=t>{pair}</td>"
        f"<td>{_num(g['normal_force_N'], 'g')}</td><td>{_num(g['pressure_kPa'], '.4g')}</td>"
        f"<td>{_num(g['temperature_C'], 'g')}</td><td>{g['mu_k_n']}</td>"
        f"<td>{_group_value(g['mu_k_mean'], cells.u_k[i], g['mu_k_n'])}</td>"
        f"<td>{_num(g['mu_k_std'], '.3f')}</td><td>{ci}</td>"
        f"<td>{_span(g['mu_k_min'], g['mu_k_max'])}</td>"
        f"<td>{_num(g['mu_k_cv'], '.3f')}</td>"
        + (f"<td>{g['mu_s_n']}</td>"
           f"<td>{_group_value(g['mu_s_mean'], cells.u_s[i], g['mu_s_n'])}</td>"
           if cells.with_mu_s else "")
        + f"<td class=t>{', '.join(qc)}</td>"
        f"<td class=t>{links}</td></tr>"
    )


def _group_note(inp: ReportInputs, with_mu_s: bool) -> str:
    """What the group table shows, above it."""
    return (
        "<p class=muted>One row per pair, nominal force and temperature; statistics over "
        "the repeats (excluded runs left out). ± U (k = 2): the expanded combined uncertainty "
        "of the group mean, from the runs' own budgets beside the repeat scatter (the repeat "
        "scatter alone where the runs carry no budget, e.g. imported rows), U rounded to two "
        "significant digits and the mean to the same decimal. The repeats' 95 % t-interval "
        "is its own column; with n = 2 it uses t = 12.7, and its lower end is bounded at 0 "
        "(a coefficient of friction is never negative): the min–max range beside it is the "
        "plainer picture. QC: the group's range exceeds the repeatability limit r, or it holds a "
        "run with QC flags. Run ids link to the "
        "runs" + ("" if inp.map_report else " and their trace plots") + "."
        + ("" if with_mu_s else " The map holds no μ_S, so its columns are left out.")
        + "</p>"
    )


def _group_table(inp: ReportInputs, layout: _Layout) -> str:
    """The group-table section; each group links to its pair plot and runs (and to the
    overlay of its repeats where their range exceeds r). The μ_S columns are left out when
    no group has a μ_S. Where the report's pairs lie beside the page, the list of its
    pairs instead (:func:`_pairs_list`)."""
    cells = _group_cells(inp)
    if layout.pairs_beside is not None:
        return _pairs_list(inp, layout, cells)
    rows = [_group_row(i, g, cells, layout) for i, g in enumerate(_group_records(inp.groups))]
    return (
        '<section id="groups"><h2>Condition groups</h2>'
        + _group_note(inp, cells.with_mu_s)
        + _csv_link(inp.groups, "groups.csv", "group-csv", layout)
        + f"<table id=group-table><thead>{_group_head(cells.with_mu_s)}</thead>"
        f"<tbody>{''.join(rows)}</tbody></table></section>"
    )


#: the fit table's head row
_FIT_HEAD = (
    "<tr><th class=t>pin</th><th class=t>disc</th><th>T [°C]</th><th>k</th>"
    "<th>k 95 % CI</th><th>n−1</th><th>n−1 95 % CI</th><th>R²</th><th>runs</th>"
    "<th class=t>note</th></tr>"
)

#: what the fit table shows, above it
_FIT_NOTE = (
    "<p class=muted>Least squares in log–log space on the individual runs, p in kPa "
    "(k is μ_K at 1 kPa); 95 % intervals from the t-distribution. Hertz-type contact "
    "of an elastomer gives n−1 ≈ −1/3.</p>")


def _fit_row(f: Mapping[Any, Any]) -> str:
    """One power-law fit as a row of the fit table."""
    return (
        f"<tr><td class=t>{_name(f['pin'])}</td><td class=t>{_name(f['disc'])}</td>"
        f"<td>{_num(f['temperature_C'], 'g')}</td><td>{_num(f['k'], '.3f')}</td>"
        f"<td>{_interval(f['k_ci95_low'], f['k_ci95_high'])}</td>"
        f"<td>{_num(f['exponent'], '.3f')}</td>"
        f"<td>{_interval(f['exponent_ci95_low'], f['exponent_ci95_high'])}</td>"
        f"<td>{_num(f['r_squared'], '.3f')}</td><td>{f['n_points']}</td>"
        f"<td class=t>{_e(f['note'])}</td></tr>"
    )


def _fits_table(inp: ReportInputs, layout: _Layout) -> str:
    """The power-law fit section; where the report's pairs lie beside the page, each
    pair's fits are in its block of the list of pairs and this section says so."""
    head = '<section id="fits"><h2>Pressure dependence: μ_K = k·p<sup>n−1</sup></h2>'
    link = _csv_link(inp.fits, "fits.csv", "fit-csv", layout)
    if layout.pairs_beside is not None:
        return (head + _FIT_NOTE + link
                + f"<p>The map's {len(inp.fits)} fits are listed per pair: each pair's "
                "fits load with its condition groups and runs when it is opened in "
                '<a href="#groups">the list of pairs</a>.</p></section>')
    rows = [_fit_row(f) for f in inp.fits.to_dict(orient="records")]
    return (
        head + _FIT_NOTE + link
        + f"<table id=fit-table><thead>{_FIT_HEAD}</thead><tbody>{''.join(rows)}</tbody></table>"
        "</section>"
    )


def _pair_plots(inp: ReportInputs, layout: _Layout) -> str:
    """The per-pair μ_K(p) plots, embedded as PNG, each drawn from its own pair's runs and
    fits (selected once); up to :data:`PAIR_PLOTS_LIMIT` pairs, beyond which the section
    says that the explorer draws them."""
    kept = ~inp.runs["excluded"].fillna(False).astype(bool)
    held = pairs(inp.runs.loc[kept, ["pin", "disc"]])
    if not layout.pair_plots:
        return (
            '<section id="pairs"><h2>μ_K against contact pressure, per pair</h2>'
            f"<p class=muted>This map holds {len(held)} pairs, more than the "
            f"{PAIR_PLOTS_LIMIT} whose plots a report embeds: the explorer draws any "
            "pair's μ_K against contact pressure with its fits, and <code>tribopipe plot "
            "pairs</code> writes every pair's plot as a file.</p></section>"
        )

    def by_key(table: pd.DataFrame) -> dict[tuple[str, str], pd.DataFrame]:
        keys = [table["pin"].astype(str).str.casefold(), table["disc"].astype(str).str.casefold()]
        return {(str(p), str(d)): part for (p, d), part in table.groupby(keys, sort=False)}

    runs_of, fits_of = by_key(inp.runs[kept]), by_key(inp.fits) if len(inp.fits) else {}
    figures = []
    for pin, disc in held:
        key = (pin.casefold(), disc.casefold())
        uri = _png_data_uri(
            lambda buf, pin=pin, disc=disc, key=key: plot_pair(
                runs_of[key], pin, disc, buf, fits=fits_of.get(key, inp.fits.iloc[:0]),
                fmt="png", dpi=PAIR_DPI)
        )
        figures.append(
            f'<figure id="{pair_anchor(pin, disc)}">{_img(uri, f"{pin} on {disc}")}'
            f"<figcaption>{html_text(pin)} on {html_text(disc)}: μ_K against contact pressure, "
            "mean ± SD of repeats per temperature, fitted power law</figcaption></figure>"
        )
    return (
        '<section id="pairs"><h2>μ_K against contact pressure, per pair</h2>'
        f'<div class="pairs">{"".join(figures)}</div></section>'
    )


def _flagged(inp: ReportInputs, layout: _Layout) -> str:
    """The flagged and excluded runs section."""
    runs = inp.runs
    # a provenance flag (synthetic) is said once, in the summary: no run is listed for it
    mask = runs["flags"].map(lambda f: bool(quality_flags(f))) | runs["excluded"].fillna(
        False).astype(bool)
    if "review" in runs:
        mask |= runs["review"].notna()
    sel = runs[mask]
    if sel.empty:
        body = "<p>No run carries a QC flag or is excluded.</p>"
    else:
        rows = []
        for r in frame_rows(sel):
            mid = r.measurement_id
            excluded = r.excluded
            reason = _e(r.exclusion_reason) if excluded else ""
            rows.append(
                f'<tr class="{"excl" if excluded else "flag"}"><td class=t>'
                f"{_run_link(mid, r.pin, r.disc, layout)}</td>"
                f"<td class=t>{_e(r.source_file)}</td><td class=t>{_name(r.pin)}</td>"
                f"<td class=t>{_name(r.disc)}</td><td>{_num(r.pressure_kPa, '.4g')}</td>"
                f"<td>{_run_value(r.mu_k, r.u_mu_k)}</td>"
                f"<td class=t>{html_text(', '.join(flag_list(r.flags)))}</td>"
                f"<td class=t>{'excluded: ' + reason if excluded else ''}</td>"
                f"<td class=t>{html_text(_review_text(r))}</td></tr>"
            )
        body = (
            "<table id=flagged-table><thead><tr><th class=t>run</th><th class=t>file</th>"
            "<th class=t>pin</th><th class=t>disc</th><th>p [kPa]</th><th>μ_K ± U</th>"
            "<th class=t>flags</th><th class=t>exclusion</th><th class=t>review</th>"
            "</tr></thead>"
            f"<tbody>{''.join(rows)}</tbody></table>"
        )
    return f'<section id="flagged"><h2>Flagged and excluded runs</h2>{body}</section>'


def _failures(inp: ReportInputs, layout: _Layout) -> str:
    """The failures section (``failures.csv`` of the last batch)."""
    if not inp.failures_known:
        body = "<p class=muted>No failures.csv in the processed folder (no batch run).</p>"
    elif not inp.failures:
        body = "<p>Every file of the last batch was reduced.</p>"
    else:
        rows = "".join(
            f"<tr><td class=t>{html_text(f)}</td><td class=t>{html_text(r)}</td></tr>"
            for f, r in inp.failures
        )
        body = (
            "<table id=failure-table><thead><tr><th class=t>file</th><th class=t>reason</th>"
            f"</tr></thead><tbody>{rows}</tbody></table>"
        )
    return f'<section id="failures"><h2>Failures</h2>{body}</section>'


def _review_count(runs: pd.DataFrame) -> str:
    """``N (accept a, exclude b, window c)`` for the reviewed runs; '' when none."""
    if "review" not in runs or not runs["review"].notna().any():
        return ""
    counts = runs["review"].dropna().astype(str).value_counts().sort_index()
    return f"{int(counts.sum())} (" + ", ".join(f"{a} {n}" for a, n in counts.items()) + ")"


def _review_text(r: MapRow) -> str:
    """What a reviewer decided on a run, by whom, when and why, with the automatic
    values beside the reviewed ones (plain text); '' for a run not reviewed."""
    action = r.review
    if action is None:
        return ""
    text = f"reviewed: {action}"
    if action == "window":
        text += (f" {_num(r.mu_k_window_start_mm, '.4g')}–"
                 f"{_num(r.mu_k_window_end_mm, '.4g')} mm, μ_K {_num(r.mu_k, '.4f')}"
                 f" (automatic {_num(r.auto_mu_k, '.4f')} over "
                 f"{_num(r.auto_mu_k_window_start_mm, '.4g')}–"
                 f"{_num(r.auto_mu_k_window_end_mm, '.4g')} mm)")
        peak = r.review_static_peak_mm
        if peak is not None:
            text += (f", μ_S {_num(r.mu_s, '.4f')} at {_num(peak, '.4g')} mm (automatic "
                     f"{_num(r.auto_mu_s, '.4f')})")
    for value, label in ((r.review_by, "by"), (r.review_date, "on"), (r.review_reason, "why:")):
        if value is not None:
            text += f" {label} {value}"
    return text


#: the order the report lists runs in
_RUN_ORDER = ["pin", "disc", "temperature_C", "pressure_kPa", "repeat"]


def _ordered_runs(inp: ReportInputs) -> pd.DataFrame:
    """The runs in the order the report lists them: pin, disc, temperature, pressure,
    repeat."""
    return inp.runs.sort_values(_RUN_ORDER, kind="mergesort")


def _run_order(inp: ReportInputs) -> Any:
    """The positions of the runs in the order :func:`_ordered_runs` lists them (the same
    stable sort on the sorting columns alone: no copy of the runs)."""
    keys = inp.runs[_RUN_ORDER].reset_index(drop=True)
    return keys.sort_values(_RUN_ORDER, kind="mergesort").index.to_numpy()


def _run_columns(inp: ReportInputs) -> tuple[bool, bool]:
    """Whether the runs' table shows μ_S (some run has one) and the test and result a run
    came from (some run without a trace names one)."""
    traces = inp.trace_paths or {}
    with_mu_s = bool(inp.runs["mu_s"].notna().any())
    plain_runs = inp.runs[~inp.runs["measurement_id"].astype(str).isin(traces)]
    with_test = bool(plain_runs[["test", "result"]].notna().any(axis=None))
    return with_mu_s, with_test


def _plain_row(r: MapRow, with_mu_s: bool, with_test: bool) -> str:
    """A run without a trace as a row of the runs' table."""
    mid = r.measurement_id
    repeat = "" if r.repeat is None else str(r.repeat)
    return (
        f'<tr id="{run_anchor(mid)}"><td class=t>{html_text(mid[:8])}</td>'
        f"<td class=t>{_name(r.pin)}</td><td class=t>{_e(r.disc)}</td>"
        f"<td>{_num(r.pressure_kPa, '.4g')}</td>"
        f"<td>{_num(r.temperature_C, 'g')}</td><td>{html_text(repeat)}</td>"
        f"<td>{_run_value(r.mu_k, r.u_mu_k)}</td>"
        + (f"<td>{_run_value(r.mu_s, r.u_mu_s)}</td>" if with_mu_s else "")
        + f"<td class=t>{_e(r.source)}</td><td class=t>{_e(r.lab)}</td>"
        + (f"<td class=t>{_e(r.test)}</td><td class=t>{_e(r.result)}</td>"
           if with_test else "")
        + f"<td class=t>{html_text(', '.join(flag_list(r.flags)))}</td></tr>"
    )


def _trace_block(r: MapRow, trace_path: Path) -> str:
    """A run with a trace: a collapsible block with its facts and its trace plot."""
    import pandas as pd

    mid = r.measurement_id
    repeat = "" if r.repeat is None else str(r.repeat)
    trace = pd.read_parquet(trace_path)
    uri = _png_data_uri(
        lambda buf: plot_trace_row(trace, r, buf, fmt="png", dpi=TRACE_DPI)
    )
    flags = ", ".join(flag_list(r.flags)) or "none"
    summary = (
        f"{html_text(mid[:8])} · {_e(r.pin)} on {_e(r.disc)} · "
        f"{_num(r.pressure_kPa, '.4g')} kPa · {_num(r.temperature_C, 'g')} °C"
        f"{html_text(', repeat ' + repeat if repeat else '')} · "
        f"μ_K {_run_value(r.mu_k, r.u_mu_k)}"
        + (f" · μ_S {_run_value(r.mu_s, r.u_mu_s)}"
           if _num(r.mu_s, ".3f") else "")
    )
    facts = (
        f"<p>file: {_e(r.source_file)}; test: {_e(r.test)}; result: "
        f"{_e(r.result)}; interval: {_e(r.interval)}; source: "
        f"{_e(r.source)}; "
        f"flags: {html_text(flags)}; μ_K window: {_num(r.mu_k_window_start_mm, '.3f')}"
        f"–{_num(r.mu_k_window_end_mm, '.3f')} mm; method: {_e(r.method)}"
        + (f"; <strong class=reviewed>{html_text(_review_text(r))}</strong>"
           if _review_text(r) else "")
        + "</p>"
    )
    # the id sits inside the <details> so that following a link opens it
    return (
        f'<details class="run"><summary>{summary}</summary>'
        f'<div id="{run_anchor(mid)}">{facts}{_img(uri, f"trace of run {mid}")}</div>'
        "</details>"
    )


#: what the trace plots show, above them
_TRACE_NOTE = ("<p class=muted>μ over sliding distance with the μ_S peak (red) and the "
               "μ_K window (blue), each ± U (k = 2); a reading at a search limit or a "
               "window at the trace's end is marked. Click a run to open it.</p>")


def _runs_table(rows: Sequence[str], with_mu_s: bool, with_test: bool,
                element: str) -> str:
    """The table of runs without a trace (``element``: its id or class attribute)."""
    return (
        f"<table {element}><thead><tr><th class=t>run</th><th class=t>pin</th>"
        "<th class=t>disc</th><th>p [kPa]</th><th>T [°C]</th><th>repeat</th><th>μ_K</th>"
        + ("<th>μ_S</th>" if with_mu_s else "")
        + "<th class=t>source</th><th class=t>lab</th>"
        + ("<th class=t>test</th><th class=t>result</th>" if with_test else "")
        + "<th class=t>flags</th>"
        f"</tr></thead><tbody>{''.join(rows)}</tbody></table>"
    )


def _listed(inp: ReportInputs, runs: pd.DataFrame | Sequence[MapRow], element: str,
            columns: tuple[bool, bool]) -> str:
    """``runs`` (a map frame, or its rows) as the report lists them (their trace blocks,
    then the table of the runs without a trace) with the runs' table's ``columns``
    (:func:`_run_columns` of every run, computed once per report, not once per pair)."""
    traces = inp.trace_paths or {}
    with_mu_s, with_test = columns
    blocks, plain = [], []
    for r in (runs if isinstance(runs, Sequence) else frame_rows(runs)):
        if r.measurement_id in traces:
            blocks.append(_trace_block(r, traces[r.measurement_id]))
        else:
            plain.append(_plain_row(r, with_mu_s, with_test))
    html = ""
    if blocks:
        html += _TRACE_NOTE + "".join(blocks)
    if plain:
        html += ("" if not blocks else
                 f"<h3>Runs without a trace ({len(plain)}: imported rows or traces not "
                 "found)</h3>") + _runs_table(plain, with_mu_s, with_test, element)
    return html


def _pair_index(inp: ReportInputs) -> _Pairs:
    """The report's pairs in its order (the runs' order: pin, then disc), any pair that
    only the groups or fits name after them, with each one's runs, groups and fits."""
    order = _run_order(inp)
    names_in_order = inp.runs[["pin", "disc"]].take(order)
    of: dict[tuple[str, str], int] = {}

    def positions(table: pd.DataFrame) -> dict[int, Any]:
        """Each pair's rows of ``table`` (positions), pairs numbered as first met."""
        if not len(table):
            return {}
        found = table.groupby([table["pin"].astype(str), table["disc"].astype(str)],
                              sort=False).indices
        out = {}
        for key, at in sorted(found.items(), key=lambda item: int(item[1][0])):
            names: tuple[Any, Any] = key  # type: ignore[assignment]
            out[of.setdefault((str(names[0]), str(names[1])), len(of))] = at
        return out

    runs_at = {k: order[at] for k, at in positions(names_in_order).items()}
    groups_at, fits_at = positions(inp.groups), positions(inp.fits)
    return _Pairs(names=tuple(of), of=of, runs=runs_at, groups=groups_at, fits=fits_at)


def _counted(n: int, word: str) -> str:
    """``n word`` with the word's plural ``s`` where n is not 1."""
    return f"{n} {word}{'' if n == 1 else 's'}"


def _pairs_list(inp: ReportInputs, layout: _Layout, cells: _GroupCells) -> str:
    """The list of a report's pairs whose groups, fits and runs lie beside the page: one
    collapsible block per pair (its names and counts) that loads its file when opened, a
    filter by pin or disc name, and the group table's CSV download."""
    pairs = layout.pairs
    assert pairs is not None and layout.pairs_beside is not None
    folder = html_text(layout.pairs_beside)
    blocks = [
        f'<details class="pair" id="pair-{k}"><summary>{_e(pin)} on {_e(disc)}: '
        f"{_counted(len(pairs.groups.get(k, ())), 'group')}, "
        f"{_counted(len(pairs.fits.get(k, ())), 'fit')}, "
        f"{_counted(len(pairs.runs.get(k, ())), 'run')}</summary>"
        '<div class="pair-body"></div></details>'
        for k, (pin, disc) in enumerate(pairs.names)]
    return (
        f'<section id="groups" data-pairs-beside="{folder}">'
        "<h2>Condition groups, fits and runs, per pair</h2>"
        + _group_note(inp, cells.with_mu_s)
        + f"<p>This map's {_counted(len(inp.groups), 'condition group')}, "
        f"{_counted(len(inp.fits), 'fit')} and {_counted(len(inp.runs), 'run')} are more "
        "than one page carries: each pair's lie beside this page, in "
        f"<code>{folder}/</code>, and load when the pair is opened or when a link to one "
        "of its runs is followed.</p>"
        + _csv_link(inp.groups, "groups.csv", "group-csv", layout)
        + '<p><label>Find a pair: <input id="pair-filter" type="search" '
        'placeholder="pin or disc" autocomplete="off"></label> '
        f'<span id="pair-count">{_counted(len(pairs.names), "pair")}</span></p>'
        f'<div id="pair-list">{"".join(blocks)}</div></section>'
    )


#: how many rows of a table :func:`_rows_by_pair` turns into Python objects at a time
_ROWS_BLOCK = 2_000


def _rows_by_pair(table: pd.DataFrame, at: Mapping[int, Any], n_pairs: int,
                  convert: Any) -> Iterator[list[tuple[int, Any]]]:
    """For each pair 0 … ``n_pairs`` − 1 in turn, its rows of ``table`` (positions ``at``
    by pair) as (position, ``convert``-ed row): ``convert`` turns a frame of rows into
    a list, called on :data:`_ROWS_BLOCK` rows at a time (in pairs' order), so that
    neither a frame per pair nor the whole table's Python objects are ever made."""
    import itertools

    import numpy as np

    none = np.empty(0, dtype=np.intp)
    order = [at.get(k, none) for k in range(n_pairs)]
    flat = np.concatenate(order) if order else none

    def items() -> Iterator[tuple[int, Any]]:
        for start in range(0, len(flat), _ROWS_BLOCK):
            block = flat[start:start + _ROWS_BLOCK]
            yield from zip((int(i) for i in block), convert(table.take(block)), strict=True)

    stream = items()
    for positions in order:
        yield list(itertools.islice(stream, len(positions)))


def _pair_html(inp: ReportInputs, groups: Sequence[tuple[int, Mapping[Any, Any]]],
               fits: Sequence[tuple[int, Mapping[Any, Any]]], runs: Sequence[MapRow],
               cells: _GroupCells, columns: tuple[bool, bool], layout: _Layout) -> str:
    """The markup of a pair's file: its ``groups`` (rows of the group table with their
    positions), its ``fits`` and its ``runs`` as the report lists them (markup made and
    escaped here, as in a page)."""
    group_rows = [_group_row(i, g, cells, layout) for i, g in groups]
    fit_rows = [_fit_row(f) for _, f in fits]
    html = f"<h3>Condition groups ({len(group_rows)})</h3>" + (
        f"<table class=group-table><thead>{_group_head(cells.with_mu_s)}</thead>"
        f"<tbody>{''.join(group_rows)}</tbody></table>" if group_rows else
        "<p class=muted>No condition group: every run of this pair is excluded.</p>")
    html += f"<h3>Fits ({len(fit_rows)})</h3>" + (
        f"<table class=fit-table><thead>{_FIT_HEAD}</thead><tbody>{''.join(fit_rows)}"
        "</tbody></table>" if fit_rows else "<p class=muted>No power-law fit.</p>")
    html += f"<h3>Runs ({len(runs)})</h3>" + (
        _listed(inp, runs, "class=runs-table", columns) if runs else
        "<p class=muted>No run.</p>")
    return html


def pair_files(inp: ReportInputs, layout: _Layout) -> Iterator[tuple[str, str]]:
    """The file of each pair (:data:`PAIR_FILE` → text) of a report whose pairs lie beside
    it, made one at a time, each table read in blocks in the pairs' order
    (:func:`_rows_by_pair`): each hands the pair's group rows, fits and runs
    (:func:`_pair_html`; JSON escaped by :func:`tribopipe.escape.script_json`) to
    ``window.tribopipeReportPair``."""
    pairs = layout.pairs
    assert pairs is not None
    n = len(pairs.names)
    cells = _group_cells(inp)
    columns = _run_columns(inp)
    by_pair = zip(
        _rows_by_pair(inp.groups, pairs.groups, n, _group_records),
        _rows_by_pair(inp.fits, pairs.fits, n, lambda t: t.to_dict(orient="records")),
        _rows_by_pair(inp.runs, pairs.runs, n, frame_rows), strict=True)
    for k, (groups, fits, runs) in enumerate(by_pair):
        html = _pair_html(inp, groups, fits, [r for _, r in runs], cells, columns, layout)
        yield PAIR_FILE.format(k=k), f"window.tribopipeReportPair({k}, {script_json(html)});\n"


def _runs(inp: ReportInputs, layout: _Layout) -> str:
    """Every run: a collapsible block with its embedded trace plot where its trace was
    found, the others (imported rows, lost traces) as rows of one table; where the pairs
    lie beside the page, each pair's runs are in its block of the list of pairs."""
    traces = inp.trace_paths or {}
    with_traces = int(inp.runs["measurement_id"].astype(str).isin(traces).sum())
    head = f"<h2>Runs ({len(inp.runs)}; {with_traces} with trace plots)</h2>"
    if layout.pairs_beside is None:
        html = _listed(inp, _ordered_runs(inp), "id=runs-table", _run_columns(inp))
        return f'<section id="runs">{head}{html}</section>'
    return (
        f'<section id="runs">{head}<p>Each pair\'s runs load with its condition groups and '
        'fits when it is opened in <a href="#groups">the list of pairs</a>.</p></section>')


def _overlay_groups(inp: ReportInputs) -> dict[str, tuple[dict[str, Any], list[str]]]:
    """The groups whose range exceeds r and that have traces to overlay: anchor → (group
    row, ids of its runs with a trace)."""
    out: dict[str, tuple[dict[str, Any], list[str]]] = {}
    if inp.map_report or not len(inp.groups):
        return out
    traces = inp.trace_paths or {}
    exceeding = inp.groups[inp.groups["range_exceeds_r"].astype(bool)]
    for g in exceeding.to_dict(orient="records", into=dict):
        ids = [i for i in run_ids_of(g.get("run_ids")) if i in traces]
        if ids:
            out[group_anchor(g)] = (g, ids)
    return out


def _spread(inp: ReportInputs, layout: _Layout) -> str:
    """The repeats of each group flagged "range > r", overlaid on shared axes (left out of
    a map report, which has no traces)."""
    import pandas as pd

    if inp.map_report:
        return ""
    groups = _overlay_groups(inp)
    wanted = {i for _, ids in groups.values() for i in ids}
    ids_column = inp.runs["measurement_id"].astype(str)
    rows = {r.measurement_id: r for r in frame_rows(inp.runs[ids_column.isin(wanted)])}
    rep = repeatability(inp.groups, "mu_k") if len(inp.groups) else None
    limit = f"{rep.r:.4f}" if rep is not None and not math.isnan(rep.r) else "?"
    figures = []
    for anchor, (g, ids) in groups.items():
        title = (f"{g['pin']} on {g['disc']}, {_num(g['pressure_kPa'], '.4g')} kPa, "
                 f"{_num(g['temperature_C'], 'g') or '?'} °C: range "
                 f"{float(g['mu_k_max']) - float(g['mu_k_min']):.4f} > r = {limit}")
        pairs_ = [(rows[i], pd.read_parquet(inp.trace_paths[i])) for i in ids]  # type: ignore[index]
        uri = _png_data_uri(lambda buf, t=title, p=pairs_: plot_group_overlay(
            p, buf, title=t, fmt="png", dpi=PAIR_DPI))
        links = " ".join(_run_link(i, g["pin"], g["disc"], layout) for i in ids)
        figures.append(f'<figure id="{anchor}">{_img(uri, f"repeats of {title}")}'
                       f"<figcaption>{html_text(title)}; runs {links}</figcaption></figure>")
    body = ("".join(figures) if figures else
            "<p>No group's repeats spread beyond the repeatability limit r.</p>")
    return (
        '<section id="spread"><h2>Repeats that disagree (range &gt; r)</h2>'
        "<p class=muted>The runs of each group whose μ_K range exceeds r = 2.8·s_r, "
        "overlaid: μ over sliding distance, each run's μ_K dashed over its window.</p>"
        f'<div class="pairs">{body}</div></section>'
    )


def _explorer(inp: ReportInputs, layout: _Layout) -> str:
    """The friction-map explorer of :mod:`tribopipe.export.explorer` for the report's runs,
    inline (its style, data and script travel with it; its runs too, or beside the page
    with the report's), or, for a map of more groups than one explorer page shows, a link
    to its pages beside the report."""
    if layout.explorer is None:
        href = html_text(quote(layout.explorer_page or "", safe="/"))
        return (
            '<section id="explorer"><h2>Explorer</h2>'
            f"<p>This map's {len(inp.groups)} condition groups are more than one explorer "
            f"page shows ({GROUPS_PAGE_LIMIT}): its explorer lies beside this report, as "
            f'pages of whole pins: <a id="explorer-link" href="{href}">'
            f"{html_text(layout.explorer_page or '')}</a>.</p></section>"
        )
    return (
        '<section id="explorer"><h2>Explorer</h2>'
        "<p class=muted>μ_K and μ_S at any pressure and temperature, interpolated as "
        "<code>tribopipe query</code> does; the selection is kept in the page's address, so "
        "a link reproduces it. The same page stands alone with <code>tribopipe explore</code>."
        f"</p><style>{explorer_style()}</style>"
        f"{explorer_fragment(layout.explorer, runs_beside=layout.pairs_beside)}</section>"
    )


#: the page's sections in order: (id, navigation label, builder)
_SECTIONS = (
    ("summary", "Summary", _summary), ("explorer", "Explorer", _explorer),
    ("groups", "Groups", _group_table), ("spread", "Range > r", _spread),
    ("fits", "Fits", _fits_table), ("pairs", "Pair plots", _pair_plots),
    ("flagged", "Flagged", _flagged), ("failures", "Failures", _failures),
    ("runs", "Runs", _runs),
)


def with_traces(inp: ReportInputs) -> ReportInputs:
    """``inp`` with ``trace_paths`` filled from ``traces_dir`` (unchanged when given)."""
    if inp.trace_paths is not None:
        return inp
    found = ({} if inp.traces_dir is None else
             find_traces(inp.traces_dir, inp.runs["measurement_id"].astype(str)))
    return replace(inp, trace_paths=found)


def _page(inp: ReportInputs, layout: _Layout) -> str:
    """The report's page (UTF-8 HTML text) as ``layout`` places its parts."""
    stamp = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    source = f" from {html_text(inp.source)}" if inp.source else ""
    built = [(a, t, build(inp, layout)) for a, t, build in _SECTIONS]
    shown = [(a, t, html) for a, t, html in built if html]
    nav = "".join(f'<a href="#{a}">{t}</a>' for a, t, _ in shown)
    title = html_text(inp.page_title)
    note = synthetic_note(inp.runs)
    banner = f'<p class="synthetic"><strong>{html_text(note)}</strong></p>' if note else ""
    beside = layout.pairs is not None
    css, script = (_PAIRS_CSS, _PAIRS_JS) if beside else ("", _OPEN_TARGET_JS)
    return (
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
        "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
        f"<title>{title}</title><style>{_CSS}{css}</style></head><body>"
        f"<header><h1>{title}</h1><p class=muted>tribopipe {html_text(__version__)}"
        f"{source}, {stamp}</p>{banner}<nav>{nav}</nav></header>"
        + "".join(html for _, _, html in shown)
        + f"<script>{script}</script></body></html>\n"
    )


def report_parts(
    inp: ReportInputs,
    name: str = "report.html",
    *,
    runs_inline_limit: int = RUNS_INLINE_LIMIT,
    groups_page_limit: int = GROUPS_PAGE_LIMIT,
) -> Iterator[tuple[str, str]]:
    """Every file of the report whose page is ``name`` as (relative path, text), made one
    at a time, the page last (:func:`report_files` says what they are). Inputs are not
    modified."""
    inp = with_traces(inp)
    runs_beside = len(inp.runs) > runs_inline_limit
    explorer_beside = len(inp.groups) > groups_page_limit
    beside = runs_beside or explorer_beside
    folder = runs_folder(name)
    explorer = None
    explorer_page = None
    if explorer_beside:
        explorer_page = Path(name).with_name(Path(name).stem + "_explorer.html").as_posix()
        yield from explorer_parts(inp.runs, explorer_page, title=f"{inp.page_title}: explorer",
                                  source=inp.source, groups=inp.groups, fits=inp.fits,
                                  groups_page_limit=groups_page_limit)
        explorer_page = Path(explorer_page).name
    else:
        explorer = explorer_data(inp.runs, groups=inp.groups, fits=inp.fits,
                                 title=inp.page_title, source=inp.source)
        if runs_beside:
            for f, text in runs_files(explorer).items():
                yield (folder / f).as_posix(), text
    kept = ~inp.runs["excluded"].fillna(False).astype(bool)
    layout = _Layout(pairs_beside=folder.name if beside else None,
                     pairs=_pair_index(inp) if beside else None,
                     explorer=explorer, explorer_page=explorer_page,
                     pair_plots=len(pairs(inp.runs.loc[kept, ["pin", "disc"]]))
                     <= PAIR_PLOTS_LIMIT,
                     tables_beside=folder.name if beside else None)
    if beside:  # a report with files beside: its pairs and its tables' downloads there
        yield (folder / "groups.csv").as_posix(), spreadsheet_csv(inp.groups)
        yield (folder / "fits.csv").as_posix(), spreadsheet_csv(inp.fits)
        for f, text in pair_files(inp, layout):
            yield (folder / f).as_posix(), text
    yield name, _page(inp, layout)


def report_files(
    inp: ReportInputs,
    name: str = "report.html",
    *,
    runs_inline_limit: int = RUNS_INLINE_LIMIT,
    groups_page_limit: int = GROUPS_PAGE_LIMIT,
) -> dict[str, str]:
    """Every file of the report whose page is ``name`` (relative paths → text, the page
    last). Inputs are not modified; sections with nothing to show in this kind of report
    are left out, with their links.

    Up to ``runs_inline_limit`` runs and ``groups_page_limit`` condition groups the page
    carries everything and is the only file. Beyond either, each pair's condition groups,
    fits and runs lie beside it in :func:`tribopipe.export.explorer.runs_folder`
    (``<name>_runs/``), one file per pair (:func:`pair_files`) loaded when the pair is
    opened: the page keeps the summary, the list of pairs (with their counts, and a
    filter) and what links to runs (the flagged runs, the overlays), each link naming
    its run's pair. The group and fit tables' CSV downloads lie there too (``groups.csv``,
    ``fits.csv``). Above ``runs_inline_limit`` runs the embedded explorer's runs lie in the
    same folder (:func:`tribopipe.export.explorer.runs_files`); a map of more than
    ``groups_page_limit`` condition groups gets its explorer beside the report
    (``<name>_explorer.html`` and its pages,
    :func:`~tribopipe.export.explorer.explorer_parts`) instead of in it."""
    return dict(report_parts(inp, name, runs_inline_limit=runs_inline_limit,
                             groups_page_limit=groups_page_limit))


def build_report(inp: ReportInputs, *, runs_inline_limit: int = RUNS_INLINE_LIMIT,
                 groups_page_limit: int = GROUPS_PAGE_LIMIT) -> str:
    """The report's HTML text (UTF-8, self-contained) for a map whose report is one page
    (:func:`report_files`, with the same limits, puts nothing beside it). Inputs are not
    modified. Raises :class:`ExportError` for a map whose report needs files beside its
    page (:func:`write_report` writes them)."""
    files = report_files(inp, runs_inline_limit=runs_inline_limit,
                         groups_page_limit=groups_page_limit)
    if len(files) > 1:
        raise ExportError("this map's report needs files beside its page "
                          f"({len(inp.runs)} runs, {len(inp.groups)} groups)",
                          hint="write it with tribopipe report")
    return files["report.html"]


# ---------------------------------------------------------------------------- I/O edge


def report_inputs(
    map_path: str | Path,
    processed_dir: str | Path | None = None,
    *,
    title: str | None = None,
    source: str | None = None,
) -> ReportInputs:
    """Read what a report shows from a map and a processed folder (default: the map's)."""
    snap = as_snapshot(map_path)
    runs = snap.runs
    if runs.empty:
        raise MapError("the friction map is empty or absent", path=map_path,
                       hint="run tribopipe batch first, or pass --map")
    processed = OutputLayout(
        Path(processed_dir) if processed_dir is not None else Path(map_path).parent)
    failures = read_failures(processed.failures_csv)
    traces = processed.traces_dir
    return ReportInputs(
        runs=runs,
        groups=snap.groups(),  # a map folder's are stored, not grouped again
        fits=fit_power_law(runs),
        failures=failures or (),
        failures_known=failures is not None,
        traces_dir=traces if traces.is_dir() else None,
        title=title,
        source=source or str(map_path),
    )


def write_report(output: str | Path, inputs: ReportInputs, *,
                 runs_inline_limit: int = RUNS_INLINE_LIMIT,
                 groups_page_limit: int = GROUPS_PAGE_LIMIT) -> Path:
    """Write :func:`report_files` (with these limits) beside ``output`` and the page at
    ``output`` (each atomically as it is made, the page last: :func:`report_parts`) and
    return the page's path."""
    out = Path(output)
    return write_page_and_files(out, report_parts(inputs, out.name,
                                                  runs_inline_limit=runs_inline_limit,
                                                  groups_page_limit=groups_page_limit))


def make_report(
    output: str | Path | None = None,
    *,
    config: str | Path | None = None,
    map_path: str | Path | None = None,
    processed_dir: str | Path | None = None,
) -> Path:
    """Write the HTML report of a campaign config or of a map + processed folder.

    With ``config`` (a campaign TOML) the map and processed folder come from it (explicit
    ``map_path`` / ``processed_dir`` win); ``output`` defaults to
    ``<processed>/report.html``.
    """
    title = None
    source = None
    if config is not None:

        campaign = load_campaign(config)
        map_path = map_path or campaign.map_path
        processed_dir = processed_dir or campaign.output_dir
        title = f"{campaign.name}: campaign report"
        source = str(config)
    if map_path is None:
        raise ExportError("no friction map given", hint="pass a campaign CONFIG or --map")
    inputs = report_inputs(map_path, processed_dir, title=title, source=source)
    if output is None:
        base = Path(processed_dir) if processed_dir is not None else Path(map_path).parent
        output = OutputLayout(base).report_html
    return write_report(output, inputs)


def report_sections(*, map_report: bool = False) -> Sequence[str]:
    """The ids of the report's sections, in page order (a map report has no overlays)."""
    return tuple(a for a, _, _ in _SECTIONS if not (map_report and a == "spread"))
