"""Pictures of the friction map: per-pair μ_K(p) (Fig. 5 style) and its runs' traces.

The figure of one run (μ over sliding distance, Fig. 3 style) and the headless canvas every
plot shares live in :mod:`tribopipe.figures`, below the pipeline that draws it per run;
they are importable from here too. Output format follows the target's suffix (``.png``,
``.svg``, ``.pdf``) or ``fmt``; a file-like target (e.g. ``io.BytesIO`` for the HTML
report) needs ``fmt``.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import ExportError
from ..escape import picture_text
from ..figures import (
    DPI,
    MU_LABEL,
    Target,
    image_format,
    new_figure,
    plot_trace_row,
    save_figure,
)
from ..fit import fit_power_law, power_law
from ..frictionmap.schema import MapRow, frame_rows
from ..frictionmap.snapshot import MapSource, as_snapshot
from ..layout import find_trace
from ..mastercurve import MasterCurve
from ..numeric import finite_or_none, is_finite
from ..query import pairs

if TYPE_CHECKING:
    import pandas as pd


def slug(text: str) -> str:
    """A file-name-safe slug: ``'Dragonskin 30'`` → ``'dragonskin-30'``."""
    return re.sub(r"[^a-z0-9]+", "-", text.casefold()).strip("-") or "x"


# ---------------------------------------------------------------------------- per run


def plot_runs(
    runs: pd.DataFrame,
    traces_dir: str | Path,
    out_dir: str | Path,
    *,
    fmt: str = "png",
) -> tuple[list[Path], list[str]]:
    """Trace plots of every run of ``runs`` whose trace Parquet is in ``traces_dir``.

    Returns ``(written paths, measurement ids without a trace)``; files are named like
    the traces (``<stem>_<id8>.<fmt>``) in ``out_dir``.
    """
    import pandas as pd

    image_format("x", fmt)
    written: list[Path] = []
    missing: list[str] = []
    for row in frame_rows(runs):
        mid = row.measurement_id
        path = find_trace(traces_dir, mid)
        if path is None:
            missing.append(mid)
            continue
        trace = pd.read_parquet(path)
        title = f"{row.source_file or path.stem}: {row.pin} on {row.disc}"
        target = Path(out_dir) / f"{path.stem}.{fmt}"
        written.append(_path(plot_trace_row(trace, row, target, title=title, fmt=fmt)))
    return written, missing


def _path(target: Target) -> Path:
    """The file a plot given a path was written to (a stream has none: TypeError)."""
    if isinstance(target, str | Path):
        return Path(target)
    raise TypeError(f"a plot written to a stream has no path: {target!r}")


# ---------------------------------------------------------------------------- per group


def plot_group_overlay(
    traces: Sequence[tuple[MapRow, pd.DataFrame]],
    target: Target,
    *,
    title: str,
    fmt: str | None = None,
    dpi: int = DPI,
) -> Target:
    """The repeats of one condition group on shared axes: μ over sliding distance [mm] of
    each run (``traces``: its map row and its reduced trace), one colour per run, with its
    μ_K as a dashed line over its plateau window, so runs that disagree can be compared
    where they part. The per-run plot (:func:`plot_trace_row`) is not changed by this."""
    if not traces:
        raise ExportError("no traces to overlay")
    fig = new_figure(6.4, 3.8)
    ax = fig.add_subplot()
    colours = ["tab:blue", "tab:red", "tab:green", "tab:purple", "tab:orange", "tab:brown",
               "tab:pink", "tab:gray"]
    for i, (row, trace) in enumerate(traces):
        colour = colours[i % len(colours)]
        column = "mu_smooth" if "mu_smooth" in trace.columns else "mu"
        mu_k = finite_or_none(row.mu_k)
        label = (f"{row.measurement_id[:8]}"
                 + ("" if row.repeat is None else f", repeat {row.repeat}")
                 + ("" if mu_k is None else f": μ_K {mu_k:.3f}"))
        ax.plot(trace["sliding_distance_mm"], trace[column], "-", color=colour, lw=0.9,
                alpha=0.85, label=picture_text(label))
        # the μ_K window [mm]
        low, high = (finite_or_none(row.mu_k_window_start_mm),
                     finite_or_none(row.mu_k_window_end_mm))
        if mu_k is not None and low is not None and high is not None:
            ax.plot([low, high], [mu_k] * 2, "--", color=colour, lw=1.6)
    ax.set_xlabel("sliding distance s [mm]")
    ax.set_ylabel(MU_LABEL)
    ax.set_ylim(bottom=0)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small", loc="lower right")
    ax.set_title(picture_text(title), fontsize="medium")
    return save_figure(fig, target, fmt, dpi)


# ---------------------------------------------------------------------------- per pair


#: how each coefficient is drawn in a pair plot: μ_K filled markers and a solid fit, μ_S
#: open markers and a dashed fit, in the temperature's colour
_QUANTITIES: tuple[tuple[str, str, dict[str, Any], str], ...] = (
    ("mu_k", "$\\mu_K$", {"fmt": "o"}, "-"),
    ("mu_s", "$\\mu_S$", {"fmt": "s", "mfc": "white"}, "--"),
)


def fit_label(symbol: str, k: float, exponent: float, r_squared: float) -> str:
    """The legend text of a power-law fit with its units: μ = k·(p / 1 kPa)^(n−1), so the
    reader knows k is μ at 1 kPa (mathtext for the exponent)."""
    return (f"fit {symbol} = {k:.2f}·(p / kPa)$^{{{exponent:.3f}}}$, "
            f"R² = {r_squared:.3f}")


def draw_pair(ax: Any, runs: pd.DataFrame, fits: pd.DataFrame | None,
              fits_s: pd.DataFrame | None = None) -> None:
    """Draw μ_K and, where measured, μ_S against contact pressure for one pair's runs on
    ``ax``.

    One colour per temperature: the runs (small dots), the group means with error bars of
    ±1 standard deviation of the repeats (μ_K filled, μ_S open markers), and the fitted
    power law over the measured pressure range (μ_K solid, μ_S dashed) where ``fits`` /
    ``fits_s`` (from :func:`tribopipe.fit.fit_power_law`) have a row for the
    temperature; the fit's legend says p is in kPa.
    """
    import numpy as np

    colours = ["tab:blue", "tab:red", "tab:green", "tab:purple", "tab:orange", "tab:brown"]
    temp = runs["temperature_C"].astype(float)
    temps = sorted(temp.dropna().unique()) + ([math.nan] if temp.isna().any() else [])
    tops: list[float] = []
    for quantity, symbol, style, line in _QUANTITIES:
        if quantity not in runs.columns:
            continue
        data = runs.assign(_t=temp, _p=runs["pressure_kPa"].astype(float),
                           _mu=runs[quantity].astype(float))
        data = data[data["_mu"].notna()]
        if data.empty:
            continue
        tops.append(float(np.nanmax(data["_mu"])))
        quantity_fits = fits if quantity == "mu_k" else fits_s
        for i, t in enumerate(temps):
            at = data[data["_t"].isna()] if math.isnan(t) else data[data["_t"] == t]
            if at.empty:
                continue
            colour = colours[i % len(colours)]
            label_t = "T unknown" if math.isnan(t) else f"{t:g} °C"
            ax.plot(at["_p"], at["_mu"], ".", color=colour, alpha=0.45, ms=5)
            stats = at.groupby("_p")["_mu"].agg(["mean", "std", "count"]).reset_index()
            ax.errorbar(stats["_p"], stats["mean"], yerr=stats["std"].fillna(0.0),
                        color=colour, capsize=3, ms=6, **style,
                        label=f"{label_t} {symbol}: mean ± SD of repeats")
            if quantity_fits is None or quantity_fits.empty:
                continue
            match = quantity_fits[quantity_fits["temperature_C"].isna()] if math.isnan(t) \
                else quantity_fits[quantity_fits["temperature_C"] == t]
            if match.empty or not is_finite(match["k"].iloc[0]):
                continue
            f = match.iloc[0]
            p = np.geomspace(float(f["pressure_min_kPa"]), float(f["pressure_max_kPa"]), 100)
            ax.plot(p, power_law(p, float(f["k"]), float(f["exponent"])), line,
                    color=colour, lw=1.3,
                    label=f"{label_t} " + fit_label(symbol, float(f["k"]),
                                                    float(f["exponent"]),
                                                    float(f["r_squared"])))
    ax.set_xlabel("contact pressure p [kPa]")
    with_s = len(tops) > 1
    ax.set_ylabel("coefficient of friction $\\mu_S$ (open), $\\mu_K$ (filled)" if with_s
                  else "kinetic coefficient of friction $\\mu_K$")
    ax.set_xlim(left=0, right=float(runs["pressure_kPa"].astype(float).max()) * 1.08)
    top = max(tops) if tops else 1.0
    ax.set_ylim(bottom=0, top=top * 1.1)
    ax.grid(True, alpha=0.3)
    # below the axes: the legend never hides a point, however many series
    ax.legend(fontsize="x-small", loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2,
              frameon=False)


def _pair_runs(runs: pd.DataFrame, pin: str, disc: str) -> pd.DataFrame:
    """The included runs of one pair; :class:`ExportError` listing the pairs if none."""
    included = runs
    if "excluded" in runs.columns:
        included = runs[~runs["excluded"].fillna(False).astype(bool)]
    mask = (included["pin"].astype(str).str.casefold() == pin.casefold()) & (
        included["disc"].astype(str).str.casefold() == disc.casefold()
    )
    sel = included[mask]
    if sel.empty:
        held = sorted({f"{p} on {d}" for p, d in zip(included["pin"], included["disc"],
                                                    strict=True)})
        raise ExportError(f"no runs for pin {pin!r} on disc {disc!r}; the map holds: "
                          + ("; ".join(held) or "nothing"))
    return sel


def plot_pair(
    runs: pd.DataFrame,
    pin: str,
    disc: str,
    target: Target,
    *,
    fits: pd.DataFrame | None = None,
    fmt: str | None = None,
    dpi: int = DPI,
) -> Target:
    """μ_K and μ_S (where measured) against contact pressure for one pair (Fig. 5 style)
    to ``target``, at ``dpi`` for a PNG.

    ``runs`` are friction-map rows (excluded runs are left out); ``fits`` (μ_K) defaults
    to :func:`tribopipe.fit.fit_power_law` of the pair's runs; μ_S is fitted here.
    """
    sel = _pair_runs(runs, pin, disc)
    if fits is None:
        fits = fit_power_law(sel)
    else:
        fits = fits[(fits["pin"].str.casefold() == pin.casefold())
                    & (fits["disc"].str.casefold() == disc.casefold())]
    fits_s = (fit_power_law(sel, quantity="mu_s")
              if "mu_s" in sel.columns and sel["mu_s"].notna().any() else None)
    fig = new_figure(6.4, 5.2)
    ax = fig.add_subplot()
    draw_pair(ax, sel, fits, fits_s)
    ax.set_title(picture_text(f"{sel['pin'].iloc[0]} on {sel['disc'].iloc[0]}"),
                 fontsize="medium")
    return save_figure(fig, target, fmt, dpi)


def plot_pairs(
    runs: pd.DataFrame, out_dir: str | Path, *, fmt: str = "png", dpi: int = DPI
) -> list[Path]:
    """One μ_K(p) plot per pair of ``runs`` in ``out_dir`` (``pair_<pin>__<disc>.<fmt>``),
    a PNG at ``dpi`` dots per inch."""
    image_format("x", fmt)
    fits = fit_power_law(runs)
    written = []
    for pin, disc in pairs(runs):
        target = Path(out_dir) / f"pair_{slug(pin)}__{slug(disc)}.{fmt}"
        written.append(_path(plot_pair(runs, pin, disc, target, fits=fits, fmt=fmt,
                                       dpi=dpi)))
    return written


def plot_map_pairs(map_path: MapSource, out_dir: str | Path, *, fmt: str = "png",
                   pin: str | None = None, disc: str | None = None,
                   dpi: int | None = None) -> list[Path]:
    """:func:`plot_pairs` for the friction map (Parquet) at ``map_path``, optionally one
    pin and/or disc; ``dpi``: a PNG's resolution (default :data:`DPI`)."""
    runs = _read_runs(map_path)
    if pin is not None:
        runs = runs[runs["pin"].str.casefold() == pin.casefold()]
    if disc is not None:
        runs = runs[runs["disc"].str.casefold() == disc.casefold()]
    if runs.empty:
        raise ExportError("no runs match the selection", path=map_path)
    return plot_pairs(runs, out_dir, fmt=fmt, dpi=DPI if dpi is None else dpi)


def plot_map_runs(map_path: MapSource, traces_dir: str | Path, out_dir: str | Path, *,
                  fmt: str = "png") -> tuple[list[Path], list[str]]:
    """:func:`plot_runs` for the friction map (Parquet) at ``map_path``."""
    if not Path(traces_dir).is_dir():
        raise ExportError("trace folder not found", path=traces_dir,
                          hint="pass --processed DIR, the campaign's output folder")
    return plot_runs(_read_runs(map_path), traces_dir, out_dir, fmt=fmt)


def _read_runs(map_path: MapSource) -> pd.DataFrame:
    """The runs of the map at ``map_path``; :class:`ExportError` when it is empty."""
    runs = as_snapshot(map_path).runs
    if runs.empty:
        raise ExportError("the friction map is empty or absent", path=map_path,
                          hint="reduce runs first (tribopipe reduce / batch)")
    return runs


def plot_master_curve(mc: MasterCurve, target: Target, *, fmt: str | None = None,
                      dpi: int = DPI) -> Target:
    """μ_K against log10 v (left, as measured) and against log10(a_T·v) (right, shifted
    onto the master curve, with the fitted curve per pressure) for one pair, one colour
    per temperature, one marker per pressure, to ``target``."""
    import numpy as np

    fig = new_figure(9.6, 4.2)
    before, after = fig.subplots(1, 2, sharey=True)
    temps = sorted({p.temperature_C for p in mc.points})
    pressures = [c.pressure_kPa for c in mc.curves]
    markers = "osD^v<>"
    colours = {t: f"C{i % 10}" for i, t in enumerate(temps)}
    for p in mc.points:
        level = min(range(len(pressures)), key=lambda i: abs(pressures[i] - p.pressure_kPa))
        style = {"color": colours[p.temperature_C], "marker": markers[level % len(markers)],
                 "linestyle": "none", "markersize": 5}
        before.plot(math.log10(p.speed_mm_s), p.mu_k, **style)
        after.plot(p.x, p.mu_k, **style)
    for i, c in enumerate(mc.curves):
        xs = np.linspace(c.x_range[0], c.x_range[1], 60)
        after.plot(xs, [c.value(float(x)) for x in xs], color="0.3", linewidth=1,
                   label=f"{c.pressure_kPa:.4g} kPa ({markers[i % len(markers)]})")
    for t in temps:
        before.plot([], [], color=colours[t], marker="o", linestyle="none",
                    label=f"{t:g} °C (log a_T = {mc.log10_aT[t]:+.2f})")
    before.set_xlabel("log10 v [mm/s]")
    before.set_ylabel(MU_LABEL)
    before.set_title("as measured", fontsize="medium")
    law = (f"Arrhenius, Ea = {mc.parameters['Ea_kJ_mol']:.1f} kJ/mol" if mc.shift == "arrhenius"
           else f"WLF, C1 = {mc.parameters['C1']:.3g}, C2 = {mc.parameters['C2_K']:.3g} K")
    after.set_title(f"shifted to {mc.reference_temperature_C:g} °C: {law}", fontsize="medium")
    after.set_xlabel("log10 (a_T · v) [mm/s]")
    before.legend(fontsize="small")
    after.legend(fontsize="small")
    fig.suptitle(picture_text(f"{mc.pin} on {mc.disc}: master curve"), fontsize="medium")
    return save_figure(fig, target, fmt, dpi)
