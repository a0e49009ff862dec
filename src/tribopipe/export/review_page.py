"""The review page: one self-contained HTML page to look at every run's trace and decide.

For each run of a map (with its trace Parquet under the traces folder): μ over sliding
distance with the static peak (± U, k = 2) and the μ_K window shaded, the normal force
below, the flags; flagged runs first, then the runs farthest from their group's mean (in
units of half the map's repeatability limit r, :func:`tribopipe.stats.repeatability`).
Filters by pair, condition and flag. The reviewer accepts a run, excludes it with a
reason, or sets its μ_K window (and μ_S peak) by dragging on the plot (a drag is the
window, a click the peak) or typing the distances; the page shows the new μ_K and μ_S at
once, computed as :mod:`tribopipe.reduction.manual` computes them (the script,
``assets/review.js``, is held equal to it by ``tests/test_review_browser.py``), and gives
the decisions as ``review.csv`` text (:func:`tribopipe.review.review_csv`'s format) to
download or copy; ``tribopipe batch --review`` applies it.

What travels in the page: per run, the full sliding samples (distance and μ as base64
little-endian float64, decoded only when the run is scrolled into view: the computation
uses every sample, and the plot draws μ from them, decimated min–max to the canvas's
pixel columns), and the normal force decimated min–max to :data:`DISPLAY_COLUMNS` pixel
columns (:mod:`tribopipe.figures.decimate`). Plots are drawn when scrolled into view.
Everything that came from outside (names, reasons) is embedded through
:func:`tribopipe.escape.script_json` and put into the page with ``textContent`` only; the
page's Content-Security-Policy allows its own script and style and nothing else.
"""

from __future__ import annotations

import base64
import hashlib
import math
import re
from datetime import UTC, datetime
from importlib.resources import files
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import __version__
from ..errors import ExportError
from ..escape import FORMULA_TRIGGERS, html_text, script_json
from ..figures.decimate import minmax_decimate
from ..files import write_text_atomic
from ..frictionmap import read_map
from ..frictionmap.schema import MapRow, frame_rows, is_missing
from ..labels import flag_list, quality_flags
from ..layout import find_trace
from ..review import (
    AUTO_OF,
    HEADER,
    Decision,
    Review,
    decision_of_row,
    read_review,
    trace_table,
)
from ..stats import group_statistics, repeatability, run_ids_of

if TYPE_CHECKING:
    import pandas as pd

#: the id of the page's data element
DATA_ELEMENT_ID = "tribopipe-review-data"
#: pixel columns the normal force is decimated to for drawing (μ is drawn from every
#: sliding sample, which the computation needs anyway, min–max per pixel column)
DISPLAY_COLUMNS = 300
_PLACEHOLDER = re.compile(r"\{\{(\w+)\}\}")


def _num(value: Any) -> float | None:
    """A finite float, else ``None`` (JSON null)."""
    if is_missing(value):
        return None
    v = float(value)
    return v if math.isfinite(v) else None


def _b64(values: np.ndarray) -> str:
    """``values`` as base64 of little-endian float64."""
    return base64.b64encode(np.ascontiguousarray(values, dtype="<f8").tobytes()).decode("ascii")


def _rounded(values: np.ndarray, digits: int = 5) -> list[float | None]:
    """Display values: rounded to ``digits`` significant digits, NaN as ``None``."""
    return [None if not math.isfinite(v) else float(f"{v:.{digits}g}") for v in values.tolist()]


def _trace_payload(where: str, traces_dir: Path, mid: str) -> dict[str, Any]:
    """The sliding samples (for the estimator, and drawn by the page min–max per pixel
    column) and the normal force decimated for drawing (:data:`DISPLAY_COLUMNS`)."""
    samples, terms, trace = trace_table(traces_dir, mid, where)
    s_all = trace["sliding_distance_mm"].to_numpy(dtype=float)
    finite = np.isfinite(s_all)
    x0 = float(np.min(s_all[finite])) if finite.any() else 0.0
    x1 = float(np.max(s_all[finite])) if finite.any() else 1.0
    s_f, force = minmax_decimate(s_all, trace["normal_force_N"].to_numpy(dtype=float), (x0, x1),
                                 DISPLAY_COLUMNS)
    return {
        "n": int(samples.s_mm.size),
        "s": _b64(samples.s_mm),
        "mu": _b64(samples.mu),
        "terms": {"u_relative": terms.u_relative, "u_absolute": terms.u_absolute,
                  "min_plateau_samples": terms.min_plateau_samples,
                  "peak_window_mm": terms.peak_window_mm},
        "show": {"x0": x0, "x1": x1, "s_f": _rounded(s_f, 5), "f": _rounded(force, 4)},
    }


def _outlying(runs: pd.DataFrame) -> dict[str, float]:
    """Per run id: |μ_K − its group's mean| over half the map's repeatability limit r
    (0 where the group or r is unknown)."""
    groups = group_statistics(runs)
    rep = repeatability(groups, "mu_k")
    half_r = rep.r / 2 if math.isfinite(rep.r) and rep.r > 0 else math.nan
    out: dict[str, float] = {}
    for g in groups.to_dict(orient="records", into=dict):
        mean = float(g["mu_k_mean"])
        ids = run_ids_of(g["run_ids"])
        sub = runs[runs["measurement_id"].isin(ids)]
        for mid, mu_k in zip(sub["measurement_id"], sub["mu_k"], strict=True):
            dev = abs(float(mu_k) - mean)
            out[str(mid)] = dev / half_r if math.isfinite(half_r) else 0.0
    return out


def _run_entry(row: MapRow, decision: Decision | None) -> dict[str, Any]:
    """A run's numbers, names and flags for the page (automatic and current values)."""
    reviewed = row.review is not None

    def auto(col: str) -> float | None:
        auto_col = next(a for a, c in AUTO_OF.items() if c == col)
        return _num(getattr(row, auto_col) if reviewed else getattr(row, col))

    place = [v for v in (row.test, row.result) if v is not None]
    if row.interval is not None:
        place.append(f"interval {row.interval}")
    return {
        "id": row.measurement_id,
        "file": row.source_file,
        "place": " / ".join(place),
        "pin": row.pin, "disc": row.disc,
        "force_N": _num(row.normal_force_N),
        "temperature_C": _num(row.temperature_C),
        "flags": flag_list(row.flags),
        "qc": bool(quality_flags(row.flags)),
        "excluded": row.excluded,
        "exclusion_reason": row.exclusion_reason,
        "auto": {"mu_s": auto("mu_s"), "u_mu_s": auto("u_mu_s"),
                 "peak_mm": auto("mu_s_distance_mm"), "mu_k": auto("mu_k"),
                 "u_mu_k": auto("u_mu_k"), "from_mm": auto("mu_k_window_start_mm"),
                 "to_mm": auto("mu_k_window_end_mm")},
        "decision": None if decision is None else {
            "action": decision.action, "from_mm": decision.kinetic_from_mm,
            "to_mm": decision.kinetic_to_mm, "peak_mm": decision.static_peak_mm,
            "reason": decision.reason, "who": decision.who, "date": decision.date},
    }


def review_data(runs: pd.DataFrame, traces_dir: Path | None, *, review: Review | None = None,
                title: str = "tribopipe review", source: str = "") -> dict[str, Any]:
    """The page's data (JSON-ready): every run of ``runs`` (a map), its trace where one
    lies under ``traces_dir``, sorted flagged first, then by how far it lies from its
    group's mean; the decisions of ``review`` (else those the rows hold) filled in."""
    outlying = _outlying(runs)
    decided: dict[str, Decision] = {}
    if review is not None:
        by_file: dict[str, list[str]] = {}
        for mid, f in zip(runs["measurement_id"], runs["source_file"], strict=True):
            by_file.setdefault(str(f), []).append(str(mid))
        for d in review.decisions:
            ids = [d.run] if d.run in set(runs["measurement_id"]) else by_file.get(d.run, [])
            if len(ids) == 1:
                decided[ids[0]] = d
    entries: list[dict[str, Any]] = []
    for row in frame_rows(runs):
        mid = row.measurement_id
        decision = decided.get(mid) if review is not None else decision_of_row(row)
        entry = _run_entry(row, decision)
        entry["outlying"] = round(outlying.get(mid, 0.0), 3)
        path = find_trace(traces_dir, mid) if traces_dir is not None else None
        entry["trace"] = None
        if path is not None:
            try:
                entry["trace"] = _trace_payload(f"run {mid}", path.parent, mid)
            except ExportError:
                raise
            except Exception as exc:  # a trace we cannot use is said on its card
                entry["trace_problem"] = str(exc).splitlines()[0][:300]
        entries.append(entry)
    entries.sort(key=lambda e: (not e["qc"], -e["outlying"], e["pin"], e["disc"],
                                e["force_N"] or 0.0, e["temperature_C"] or 0.0, e["id"]))
    return {"format": "tribopipe-review/1", "title": title, "source": source,
            "generated": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
            "version": __version__, "runs": entries,
            # review.csv's columns and the cell starts escape.csv_cell neutralises: the
            # page writes the decisions file by these, not by copies of its own
            "csv": {"header": list(HEADER), "formula": "".join(sorted(FORMULA_TRIGGERS))}}


def _asset(name: str) -> str:
    return files("tribopipe.export").joinpath("assets", name).read_text(encoding="utf-8")


def _sha256(text: str) -> str:
    digest = hashlib.sha256(text.encode("utf-8")).digest()
    return "'sha256-" + base64.b64encode(digest).decode("ascii") + "'"


def review_page(data: dict[str, Any]) -> str:
    """The standalone review page (UTF-8 HTML) for :func:`review_data` ``data``."""
    js = '(function () {\n"use strict";\n' + _asset("review.js") + "})();\n"
    css = _asset("review.css")
    if re.search(r"</script|<!--", js, re.IGNORECASE) or "</style" in css.lower():
        raise AssertionError("the review page's script or style would close its element")
    csp = (f"default-src 'none'; script-src {_sha256(js)}; style-src {_sha256(css)}; "
           "img-src data:; base-uri 'none'; form-action 'none'")
    values = {"csp": html_text(csp), "title": html_text(str(data.get("title", ""))),
              "subtitle": html_text(f"tribopipe {__version__} · {data.get('source', '')} · "
                                    f"{len(data['runs'])} runs · {data.get('generated', '')}"),
              "style": css, "script": js, "data": script_json(data),
              "data_id": DATA_ELEMENT_ID}
    return _PLACEHOLDER.sub(lambda m: values[m.group(1)], _asset("review.html"))


def build_review(map_path: str | Path, traces_dir: str | Path | None, *,
                 review_path: str | Path | None = None, title: str | None = None) -> str:
    """The review page (HTML text) of the map at ``map_path`` with the traces under
    ``traces_dir``; the decisions of ``review_path`` filled in when given."""
    runs = read_map(map_path)
    if runs.empty:
        raise ExportError("the friction map is empty or absent", path=map_path,
                          hint="reduce runs first (tribopipe batch)")
    review = read_review(review_path) if review_path is not None else None
    data = review_data(runs, None if traces_dir is None else Path(traces_dir), review=review,
                       title=title or "tribopipe review", source=str(map_path))
    return review_page(data)


def write_review_page(map_path: str | Path, traces_dir: str | Path | None, output: str | Path,
                      *, review_path: str | Path | None = None,
                      title: str | None = None) -> Path:
    """Write the review page (atomically) and return its path."""
    return write_text_atomic(output, build_review(map_path, traces_dir, review_path=review_path,
                                                  title=title))
