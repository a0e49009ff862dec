"""``hub build``: the merged map of a hub and its static site.

The merged map holds each lab's newest release (:func:`tribopipe.hub.folder.latest_releases`),
a run that several packages hold once (the first, by lab). The site is plain files with
relative links, so it works from ``file://`` and on GitHub Pages::

    index.html                  the labs (filter and colour by lab) over the merged groups
    explorer.html               the explorer over all labs (tribopipe explore)
    labs/<lab>.html             a lab: contact, citation (BibTeX and CFF), releases, conditions
    comparisons.html            the conditions two or more labs share, side by side
    changelog.html              one section per release: runs added, removed, changed
    downloads/friction_map.parquet, downloads/friction_map.csv   the merged map
    downloads/<lab>-<release>.zip                                every package
    downloads/<lab>-<release>-CITATION.cff                       every package's citation

The group statistics are :func:`tribopipe.stats.group_statistics`, each lab's runs apart
(``by_lab``); the comparisons are :func:`tribopipe.stats.lab_comparison`, the table
``map compare`` prints (ISO 13528's En and z, the labs-disagree flag of ISO 5725-6).
Every text from a package is escaped where it is written (:mod:`tribopipe.escape`).
"""

from __future__ import annotations

import json
import math
import shutil
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .. import __version__
from ..errors import ExportError
from ..escape import html_text, latex_cell, script_json
from ..export.explorer import explorer_data, explorer_page
from ..export.publish import table_csv
from ..files import write_text_atomic
from ..frictionmap.package import package_runs
from ..frictionmap.schema import KIND
from ..frictionmap.store import write_map_copy
from ..rounding import plus_minus, round_gum
from ..stats import LAB, group_statistics, group_u, lab_comparison, reproducibility
from .folder import HubPackage, hub_packages, hub_title, lab_slug, latest_releases

if TYPE_CHECKING:
    import pandas as pd

#: the colours of the labs, in lab order (colour-blind safe, Okabe–Ito)
LAB_COLOURS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9",
               "#F0E442", "#000000")
#: the site's downloads folder
DOWNLOADS = "downloads"


@dataclass(frozen=True)
class BuiltSite:
    """What :func:`build_site` wrote: the site folder, the labs, the merged runs."""

    path: Path
    labs: tuple[str, ...]
    n_runs: int
    n_packages: int


@dataclass(frozen=True)
class LabRelease:
    """A package of the hub with its runs and its CITATION.cff text."""

    package: HubPackage
    runs: pd.DataFrame
    descriptor: dict[str, Any]
    cff: str


def build_site(hub: Path, out: Path) -> BuiltSite:
    """Write the merged map and the site of ``hub`` into ``out`` (absent or a site this
    wrote: replaced whole). :class:`ExportError` for a hub without packages."""
    import pandas as pd

    title = hub_title(hub)
    packages = hub_packages(hub)
    if not packages:
        raise ExportError("the hub holds no package yet", path=hub,
                          hint="add one with `tribopipe hub add PACKAGE --hub DIR`")
    releases = [_release(p) for p in packages]
    latest = latest_releases(packages)
    newest = [r for r in releases if r.package in latest]
    merged = pd.concat([r.runs for r in sorted(newest, key=lambda r: r.package.slug)],
                       ignore_index=True)
    merged = merged.drop_duplicates("measurement_id", keep="first").reset_index(drop=True)
    labs = sorted(set(merged["lab"].astype(str)))
    colours = {lab: LAB_COLOURS[i % len(LAB_COLOURS)] for i, lab in enumerate(labs)}
    out = Path(out)
    if out.exists() and not (out / ".tribopipe-hub-site").is_file():
        raise ExportError("exists and is not a site hub build wrote; refusing to replace it",
                          path=out, hint="pass a new folder")
    tmp = out.with_name(f".{out.name}.tmp")
    shutil.rmtree(tmp, ignore_errors=True)
    (tmp / DOWNLOADS).mkdir(parents=True)
    (tmp / "labs").mkdir()
    write_text_atomic(tmp / ".tribopipe-hub-site", f"tribopipe {__version__}\n")
    write_text_atomic(tmp / ".nojekyll", "")
    write_map_copy(tmp / DOWNLOADS / "friction_map.parquet", merged)
    write_text_atomic(tmp / DOWNLOADS / "friction_map.csv",
                      table_csv(merged, [KIND[c] for c in merged.columns]))
    for r in releases:
        _zip_package(r.package, tmp / DOWNLOADS / f"{_name(r.package)}.zip")
        write_text_atomic(tmp / DOWNLOADS / f"{_name(r.package)}-CITATION.cff", r.cff)
    groups = lab_groups(merged)
    write_text_atomic(tmp / "explorer.html", explorer_page(explorer_data(
        merged, title=f"{title}: explorer over all labs", source=", ".join(labs))))
    write_text_atomic(tmp / "index.html", index_page(title, groups, colours, releases,
                                                     len(merged)))
    by_lab: dict[str, list[LabRelease]] = {}
    for r in releases:
        by_lab.setdefault(r.package.slug, []).append(r)
    for slug, lab_releases in by_lab.items():
        write_text_atomic(tmp / "labs" / f"{slug}.html",
                          lab_page(title, lab_releases, groups, colours))
    write_text_atomic(tmp / "comparisons.html", comparisons_page(
        title, lab_comparison(merged, "mu_k"), colours,
        reproducibility(group_statistics(merged), "mu_k").s_R))
    write_text_atomic(tmp / "changelog.html", changelog_page(title, releases))
    if out.exists():
        shutil.rmtree(out)
    tmp.rename(out)
    return BuiltSite(out, tuple(labs), len(merged), len(releases))


def _name(package: HubPackage) -> str:
    return f"{package.slug}-{package.release}"


def _release(package: HubPackage) -> LabRelease:
    runs, _ = package_runs(package.path)
    descriptor = json.loads((package.path / "datapackage.json").read_text(encoding="utf-8"))
    cff_path = package.path / "CITATION.cff"
    cff = cff_path.read_text(encoding="utf-8") if cff_path.is_file() else ""
    return LabRelease(package, runs, descriptor, cff)


def _zip_package(package: HubPackage, target: Path) -> None:
    with zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as zf:
        for path in sorted(package.path.rglob("*")):
            if path.is_file() and not path.is_symlink():
                zf.write(path, f"{_name(package)}/{path.relative_to(package.path).as_posix()}")


# --------------------------------------------------------------------------- statistics


def lab_groups(runs: pd.DataFrame) -> list[dict[str, Any]]:
    """One row per lab and condition group: ``lab, pin, disc, pressure_kPa,
    temperature_C, n`` and μ_K, μ_S with their standard uncertainty ``u`` (k = 1; NaN
    when unknown), from :func:`tribopipe.stats.group_statistics` with each lab's runs
    apart (``by_lab``)."""
    groups = group_statistics(runs, by_lab=True)
    u_k, _ = group_u(groups, "mu_k")
    u_s, _ = group_u(groups, "mu_s")
    out: list[dict[str, Any]] = []
    for i, g in enumerate(groups.to_dict("records")):
        out.append({
            "lab": str(g[LAB]), "pin": g["pin"], "disc": g["disc"],
            "pressure_kPa": float(g["pressure_kPa"]),
            "temperature_C": float(g["temperature_C"]),
            "n": int(g["mu_k_n"]),
            "mu_k": float(g["mu_k_mean"]), "u_mu_k": float(u_k.iloc[i]),
            "mu_s": float(g["mu_s_mean"]), "u_mu_s": float(u_s.iloc[i]),
        })
    return out


# --------------------------------------------------------------------------- pages


def _pm(value: float, u: float) -> str:
    if not math.isfinite(value):
        return "–"
    if not math.isfinite(u) or u <= 0:
        return f"{value:.3f} (U unknown)"
    return plus_minus(value, 2.0 * u)


def _page(title: str, heading: str, body: str, *, up: str = "") -> str:
    nav = (f'<nav><a href="{up}index.html">labs</a> · <a href="{up}explorer.html">explorer'
           f'</a> · <a href="{up}comparisons.html">comparisons</a> · '
           f'<a href="{up}changelog.html">changelog</a> · '
           f'<a href="{up}{DOWNLOADS}/friction_map.csv">merged map (CSV)</a></nav>')
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{html_text(heading)} · {html_text(title)}</title>
<style>
body{{font-family:system-ui,sans-serif;margin:0 auto;max-width:70em;padding:0 1em;line-height:1.4}}
nav{{margin:1em 0;display:flex;flex-wrap:wrap;gap:.3em}}
table{{border-collapse:collapse;margin:.5em 0;display:block;overflow-x:auto}}
td,th{{border-bottom:1px solid #ccc;padding:.2em .5em;text-align:left;white-space:nowrap}}
pre{{background:#f4f4f4;padding:.6em;overflow-x:auto;white-space:pre-wrap;word-break:break-word}}
.swatch{{display:inline-block;width:.9em;height:.9em;border-radius:.2em;margin-right:.3em;vertical-align:middle}}
.labs label{{margin-right:1em;display:inline-block}}
</style></head>
<body><header><h1>{html_text(heading)}</h1><p>{html_text(title)}</p>{nav}</header>
<main>
{body}
</main>
<footer><p>Built by tribopipe {html_text(__version__)}.</p></footer>
</body></html>
"""


def _swatch(colour: str) -> str:
    return f'<span class="swatch" style="background:{colour}"></span>'


def index_page(title: str, groups: list[dict[str, Any]], colours: dict[str, str],
               releases: list[LabRelease], n_runs: int) -> str:
    """The front page: the labs with their colour and a filter, and every lab's groups
    (the filter hides a lab's rows)."""
    boxes = "".join(
        f'<label>{_swatch(colour)}<input type="checkbox" class="lab-filter" checked '
        f'value="{html_text(lab)}"> <a href="labs/{lab_slug(lab)}.html">'
        f'{html_text(lab)}</a></label>' for lab, colour in colours.items())
    rows = "".join(
        f'<tr data-lab="{html_text(g["lab"])}" style="border-left:4px solid '
        f'{colours[g["lab"]]}"><td>{_swatch(colours[g["lab"]])}{html_text(g["lab"])}</td>'
        f'<td>{html_text(g["pin"])}</td><td>{html_text(g["disc"])}</td>'
        f'<td>{g["pressure_kPa"]:.2f}</td><td>{g["temperature_C"]:g}</td><td>{g["n"]}</td>'
        f'<td>{html_text(_pm(g["mu_k"], g["u_mu_k"]))}</td>'
        f'<td>{html_text(_pm(g["mu_s"], g["u_mu_s"]))}</td></tr>' for g in groups)
    downloads = "".join(
        f'<li><a href="{DOWNLOADS}/{_name(r.package)}.zip">{html_text(r.package.lab)}, '
        f'release {html_text(r.package.release)}</a> ({len(r.runs)} runs)</li>'
        for r in releases)
    body = f"""<section><h2>Labs</h2>
<p>{n_runs} runs from {len(colours)} labs, each lab's newest release. Untick a lab to hide
its rows; the <a href="explorer.html">explorer</a> shows all labs' runs.</p>
<p class="labs" id="lab-filter">{boxes}</p>
<p id="shown-count"></p>
<table id="groups"><thead><tr><th>lab</th><th>pin</th><th>disc</th><th>p [kPa]</th>
<th>T [°C]</th><th>n</th><th>μ_K ± U (k = 2)</th><th>μ_S ± U (k = 2)</th></tr></thead>
<tbody>{rows}</tbody></table></section>
<section><h2>Downloads</h2><ul>
<li><a id="download-parquet" download href="{DOWNLOADS}/friction_map.parquet">merged map
(Parquet)</a></li>
<li><a id="download-csv" download href="{DOWNLOADS}/friction_map.csv">merged map (CSV)</a>
</li>
{downloads}</ul></section>
<script id="hub-labs" type="application/json">{script_json(sorted(colours))}</script>
<script>
(function () {{
  var boxes = document.querySelectorAll('input.lab-filter');
  function apply() {{
    var on = {{}};
    boxes.forEach(function (b) {{ on[b.value] = b.checked; }});
    var rows = document.querySelectorAll('#groups tbody tr'), shown = 0;
    rows.forEach(function (r) {{
      var show = on[r.getAttribute('data-lab')] !== false;
      r.hidden = !show; if (show) shown++;
    }});
    document.getElementById('shown-count').textContent =
      shown + ' of ' + rows.length + ' lab groups shown';
  }}
  boxes.forEach(function (b) {{ b.addEventListener('change', apply); }});
  apply();
}})();
</script>"""
    return _page(title, "Friction map hub", body)


def bibtex(release: LabRelease) -> str:
    """A BibTeX ``@misc`` entry of a lab's release (values escaped for LaTeX)."""
    p = release.package
    key = f"{p.slug.replace('-', '')}{p.release.replace('-', '')}"
    fields = {
        "author": "{" + latex_cell(p.lab) + "}",
        "title": latex_cell(p.title),
        "year": p.release[:4],
        "month": str(int(p.release[5:7])),
        "note": latex_cell(f"Friction-map data package, release {p.release}, written by "
                           "tribopipe"),
        "howpublished": latex_cell("friction map hub: labs/" + p.slug + "/" + p.release),
    }
    lines = [f"@misc{{{key},"] + [f"  {k} = {{{v}}}," for k, v in fields.items()]
    return "\n".join(lines) + "\n}\n"


def lab_page(title: str, releases: list[LabRelease], groups: list[dict[str, Any]],
             colours: dict[str, str]) -> str:
    """A lab's page: contact, citation (BibTeX and CFF) of its newest release, its
    releases and its conditions."""
    releases = sorted(releases, key=lambda r: r.package.release)
    newest = releases[-1]
    lab = newest.package.lab
    contributors = newest.descriptor.get("contributors") or [{}]
    who = contributors[0] if isinstance(contributors[0], dict) else {}
    contact = str(who.get("title") or lab)
    email = who.get("email")
    mail = (f' · <a id="lab-email" href="mailto:{html_text(str(email))}">'
            f'{html_text(str(email))}</a>' if isinstance(email, str) else "")
    licences = ", ".join(str(x.get("name")) for x in newest.descriptor.get("licenses") or []
                         if isinstance(x, dict))
    rel_rows = "".join(
        f'<tr><td>{html_text(r.package.release)}</td><td>{len(r.runs)}</td>'
        f'<td><a href="../{DOWNLOADS}/{_name(r.package)}.zip">package (zip)</a></td>'
        f'<td><a download href="../{DOWNLOADS}/{_name(r.package)}-CITATION.cff">'
        'CITATION.cff</a></td>'
        f'<td><a href="../changelog.html#{_name(r.package)}">changelog</a></td></tr>'
        for r in reversed(releases))
    lab_rows = [g for g in groups if g["lab"] == lab]
    cond_rows = "".join(
        f'<tr><td>{html_text(g["pin"])}</td><td>{html_text(g["disc"])}</td>'
        f'<td>{g["pressure_kPa"]:.2f}</td><td>{g["temperature_C"]:g}</td><td>{g["n"]}</td>'
        f'<td>{html_text(_pm(g["mu_k"], g["u_mu_k"]))}</td></tr>' for g in lab_rows)
    colour = colours.get(lab, "#777")
    body = f"""<section><h2>{_swatch(colour)}Contact</h2>
<p id="lab-contact">{html_text(contact)}{mail} · data licence {html_text(licences)}</p></section>
<section><h2>How to cite</h2>
<h3>BibTeX</h3><pre id="bibtex">{html_text_block(bibtex(newest))}</pre>
<h3>Citation File Format</h3><pre id="cff">{html_text_block(newest.cff)}</pre></section>
<section><h2>Releases</h2><table id="releases"><thead><tr><th>release</th><th>runs</th>
<th></th><th></th><th></th></tr></thead><tbody>{rel_rows}</tbody></table></section>
<section><h2>Conditions</h2><table id="conditions"><thead><tr><th>pin</th><th>disc</th>
<th>p [kPa]</th><th>T [°C]</th><th>n</th><th>μ_K ± U (k = 2)</th></tr></thead>
<tbody>{cond_rows}</tbody></table></section>"""
    return _page(title, lab, body, up="../")


def html_text_block(text: str) -> str:
    """Several lines of outside text for a ``<pre>``: each line made inert by
    :func:`tribopipe.escape.html_text`."""
    return "\n".join(html_text(line) for line in text.splitlines())


def comparisons_page(title: str, table: pd.DataFrame, colours: dict[str, str],
                     s_R: float) -> str:
    """Where labs share a condition: the rows of :func:`tribopipe.stats.lab_comparison`
    (its condition columns; each lab's n and μ_K ± U, k = 2; the difference ± U; En with
    its verdict; each lab's z; the labs-disagree flag), and the map's s_R (σ_pt of z)."""
    rows = []
    for r in table.to_dict(orient="records"):
        en = float(r["En"])
        verdict = ("–" if not math.isfinite(en) else "agree" if abs(en) <= 1
                   else "disagree")
        rows.append(
            f'<tr><td>{html_text(str(r["pin"]))}</td><td>{html_text(str(r["disc"]))}</td>'
            f'<td>{_number(float(r["normal_force_N"]))}</td>'
            f'<td>{_number(float(r["pressure_kPa"]))}</td>'
            f'<td>{_number(float(r["temperature_C"]))}</td>'
            f'<td>{_number(float(r["nominal_speed_mm_s"]))}</td>'
            + "".join(
                f'<td>{_lab_swatch(colours, r["lab_" + s])}{html_text(str(r["lab_" + s]))}'
                f' (n = {int(r["n_" + s])}): '
                f'{html_text(_expanded(float(r["mean_" + s]), float(r["U_" + s])))}</td>'
                for s in ("a", "b"))
            + f'<td>{html_text(_difference(float(r["difference"]), float(r["U_difference"])))}'
            f'</td><td>{_signed(en)}</td><td>{verdict}</td>'
            f'<td>{_signed(float(r["z_a"]))}</td><td>{_signed(float(r["z_b"]))}</td>'
            f'<td>{"yes" if r["labs_disagree"] else "no"}</td></tr>')
    table_html = ("<p>No condition is shared by two labs yet.</p>" if not rows else
                  '<table id="comparisons"><thead><tr><th>pin</th><th>disc</th>'
                  "<th>F [N]</th><th>p [kPa]</th><th>T [°C]</th><th>v [mm/s]</th>"
                  "<th>lab 1 μ_K ± U</th><th>lab 2 μ_K ± U</th><th>difference ± U</th>"
                  "<th>En</th><th></th><th>z lab 1</th><th>z lab 2</th>"
                  "<th>labs disagree (ISO 5725-6)</th></tr></thead><tbody>"
                  + "".join(rows) + "</tbody></table>")
    body = f"""<section><p>Each pair of labs at each condition both measured (the map's
condition groups: pin, disc, nominal force, temperature, nominal sliding speed and test
method), as <code>tribopipe map compare</code> prints it: each lab's number of runs and
mean μ_K with its expanded uncertainty U (k = 2), the difference and its
U = √(U₁² + U₂²), and ISO 13528's En = difference / U: |En| ≤ 1 agree, |En| &gt; 1
disagree beyond the labs' stated uncertainties. Each lab's z score is its mean less the
condition's pooled mean over σ_pt, the map's reproducibility standard deviation
s_R = {_number(s_R)} (ISO 5725-2). The last column says whether the labs' means differ by
more than the critical difference of ISO 5725-6, as the map's statistics decide it.</p>
{table_html}</section>"""
    return _page(title, "Inter-lab comparisons", body)


def _lab_swatch(colours: dict[str, str], lab: Any) -> str:
    colour = colours.get(str(lab))
    return _swatch(colour) if colour else ""


def _expanded(value: float, expanded: float) -> str:
    """``value ± U`` of a mean (U at k = 2 already), or the mean alone when U is unknown."""
    if not math.isfinite(value):
        return "–"
    if not math.isfinite(expanded) or expanded <= 0:
        return f"{value:.3f} (U unknown)"
    return plus_minus(value, expanded)


def _difference(value: float, expanded: float) -> str:
    """A signed difference ± its U, by :func:`tribopipe.rounding.round_gum`."""
    if not math.isfinite(value):
        return "–"
    if not math.isfinite(expanded) or expanded <= 0:
        return f"{value:+.3f} (U unknown)"
    v_text, u_text = round_gum(value, expanded)
    return f"{'' if v_text.startswith('-') else '+'}{v_text} ± {u_text}"


def _signed(value: float) -> str:
    return f"{value:+.2f}" if math.isfinite(value) else "–"


def _number(value: Any) -> str:
    return f"{value:.3g}" if isinstance(value, float) and math.isfinite(value) else "–"


def changelog_page(title: str, releases: list[LabRelease]) -> str:
    """One section per release: the runs it adds, removes and changes against the lab's
    previous release."""
    sections = []
    previous: dict[str, LabRelease] = {}
    for r in sorted(releases, key=lambda r: (r.package.slug, r.package.release)):
        before = previous.get(r.package.slug)
        now = {str(m): row for m, row in zip(r.runs["measurement_id"],
                                              r.runs.to_dict("records"), strict=True)}
        old = {} if before is None else {
            str(m): row for m, row in zip(before.runs["measurement_id"],
                                          before.runs.to_dict("records"), strict=True)}
        added = sorted(set(now) - set(old))
        removed = sorted(set(old) - set(now))
        changed = sorted(m for m in set(now) & set(old)
                         if (now[m]["mu_k"], now[m]["mu_s"], now[m]["excluded"])
                         != (old[m]["mu_k"], old[m]["mu_s"], old[m]["excluded"]))
        pairs = sorted({(str(now[m]["pin"]), str(now[m]["disc"])) for m in added})
        since = "first release" if before is None else f"since {before.package.release}"
        items = [f"<li>{len(added)} runs added ({since})"
                 + (": " + html_text("; ".join(f"{p} on {d}" for p, d in pairs)) if pairs
                    else "") + "</li>",
                 f"<li>{len(removed)} runs removed</li>",
                 f"<li>{len(changed)} runs changed (μ or exclusion)</li>"]
        sections.append(
            f'<section id="{_name(r.package)}"><h2>{html_text(r.package.lab)}, release '
            f'{html_text(r.package.release)}</h2><ul>{"".join(items)}</ul>'
            f'<p><a href="{DOWNLOADS}/{_name(r.package)}.zip">the package</a></p></section>')
        previous[r.package.slug] = r
    return _page(title, "Changelog", "\n".join(sections))
