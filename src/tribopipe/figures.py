"""Headless figures: the canvas and file writing every plot shares, and the plot of one run.

Rendering is headless: figures are built with :class:`matplotlib.figure.Figure` on the
Agg canvas, never through ``pyplot`` (no global state, no display needed, safe in worker
processes), and matplotlib is imported only inside the functions. Output format follows
the target's suffix (``.png``, ``.svg``, ``.pdf``) or ``fmt``; a file-like target (e.g.
``io.BytesIO`` for the HTML report) needs ``fmt``.

The plot of one reduced run — μ over sliding distance with the μ_S peak and the μ_K window,
Fig. 3 style — is here, below :mod:`tribopipe.pipeline`, which draws it per run; the
friction map's plots are in :mod:`tribopipe.export.plots`.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from .errors import ExportError
from .numeric import is_finite

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

    from .reduce import ReductionResult

FORMATS = ("png", "svg", "pdf")
DPI = 120
#: μ axis label used on every plot
MU_LABEL = "coefficient of friction μ"

Target = str | Path | IO[bytes]


def new_figure(width_in: float, height_in: float) -> Figure:
    """A new figure on the Agg canvas (headless)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width_in, height_in), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def image_format(target: Target, fmt: str | None) -> str:
    """The image format of ``target`` (suffix) or ``fmt``, checked."""
    if fmt is None:
        if isinstance(target, str | Path):
            fmt = Path(target).suffix.lstrip(".").lower() or "png"
        else:
            raise ExportError("a plot written to a stream needs a format (png, svg or pdf)")
    fmt = fmt.lower()
    if fmt not in FORMATS:
        raise ExportError(f"unknown plot format {fmt!r}; expected one of {', '.join(FORMATS)}")
    return fmt


def save_figure(fig: Figure, target: Target, fmt: str | None, dpi: int = DPI) -> Target:
    """Write ``fig`` to ``target`` (creating parent folders) and return the target."""
    fmt = image_format(target, fmt)
    if isinstance(target, str | Path):
        target = Path(target)
        if target.suffix.lower() != f".{fmt}":
            target = target.with_suffix(f".{fmt}")
        target.parent.mkdir(parents=True, exist_ok=True)
    # a fixed date keeps PDF/SVG output byte-stable for identical input
    metadata: dict[str, Any] = {"png": {"Software": "tribopipe"}, "svg": {"Date": None},
                                "pdf": {"CreationDate": None}}[fmt]
    fig.savefig(target, format=fmt, dpi=dpi, metadata=metadata)
    return target


#: flags that say a reading sits on a boundary of its search; marked on the trace plot
BOUNDARY_FLAGS: tuple[str, ...] = ("peak_at_search_limit", "plateau_at_trace_end")


def draw_trace(
    ax: Any,
    trace: pd.DataFrame,
    *,
    mu_s: float | None,
    mu_s_distance_mm: float | None,
    mu_k: float | None,
    mu_k_window_mm: tuple[float, float] | None,
    flags: str = "",
    u_mu_s: float | None = None,
    u_mu_k: float | None = None,
) -> None:
    """Draw μ over sliding distance on ``ax`` with the μ_S peak and the μ_K window.

    ``trace`` needs ``sliding_distance_mm`` and ``mu`` (``mu_smooth`` drawn when present);
    distances in mm. ``u_mu_s``/``u_mu_k`` (standard uncertainties) draw the expanded
    uncertainty U = 2u (k = 2) as an error bar on μ_S and a band on μ_K. A boundary flag
    (:data:`BOUNDARY_FLAGS`) is marked where it applies: ``peak_at_search_limit`` as a
    hollow μ_S marker with a dotted line at the limit, ``plateau_at_trace_end`` as a
    hatched window against a line at the trace's end, each with a note.
    """
    import numpy as np

    flag_set = {f for f in flags.split(";") if f}
    s = np.asarray(trace["sliding_distance_mm"], dtype=float)
    mu = np.asarray(trace["mu"], dtype=float)
    ax.plot(s, mu, color="0.75", lw=0.8, label="μ (raw)")
    if "mu_smooth" in trace.columns:
        ax.plot(s, np.asarray(trace["mu_smooth"], dtype=float), color="0.15", lw=1.2,
                label="μ (smoothed)")
    at_end = "plateau_at_trace_end" in flag_set
    if mu_k_window_mm is not None and all(is_finite(v) for v in mu_k_window_mm):
        start, end = (float(v) for v in mu_k_window_mm)
        ax.axvspan(start, end, color="tab:blue", alpha=0.12, hatch="//" if at_end else None,
                   label="$\\mu_K$ window" + (" (at trace end)" if at_end else ""))
        if is_finite(mu_k):
            label = f"$\\mu_K$ = {float(mu_k):.3f}"
            if is_finite(u_mu_k):
                U = 2.0 * float(u_mu_k)
                ax.fill_between([start, end], float(mu_k) - U, float(mu_k) + U,
                                color="tab:blue", alpha=0.18, lw=0)
                label += f" ± {U:.3f} (k = 2)"
            ax.hlines(float(mu_k), start, end, color="tab:blue", lw=2.0, label=label)
        if at_end:
            ax.axvline(end, color="tab:orange", lw=1.2, ls="--")
            level = float(mu_k) if is_finite(mu_k) else 0.0
            ax.annotate("$\\mu_K$ window at trace end", (end, level),
                        xytext=(-4, 8), textcoords="offset points", ha="right",
                        fontsize="small", color="tab:orange")
    elif is_finite(mu_k):
        ax.axhline(float(mu_k), color="tab:blue", lw=1.5, ls="--",
                   label=f"$\\mu_K$ = {float(mu_k):.3f}")
    if is_finite(mu_s) and is_finite(mu_s_distance_mm):
        x, y = float(mu_s_distance_mm), float(mu_s)
        at_limit = "peak_at_search_limit" in flag_set
        label = f"$\\mu_S$ = {y:.3f}"
        yerr = None
        if is_finite(u_mu_s):
            yerr = 2.0 * float(u_mu_s)
            label += f" ± {yerr:.3f} (k = 2)"
        ax.errorbar([x], [y], yerr=yerr, fmt="o", color="tab:red", ms=7, capsize=3,
                    mfc="white" if at_limit else "tab:red", label=label)
        if at_limit:
            ax.axvline(x, color="tab:red", lw=1.0, ls=":")
            ax.annotate("$\\mu_S$ at search limit", (x, y), xytext=(6, 6),
                        textcoords="offset points", fontsize="small", color="tab:red")
    ax.set_xlabel("sliding distance s [mm]")
    ax.set_ylabel(MU_LABEL)
    finite = mu[np.isfinite(mu)]
    if finite.size:
        top = max(float(finite.max()), float(mu_s) if is_finite(mu_s) else 0.0)
        ax.set_ylim(min(0.0, float(finite.min())), top * 1.15 + 1e-9)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="lower right", fontsize="small")
    if flags:
        ax.text(0.01, 0.98, "flags: " + flags.replace(";", ", "), transform=ax.transAxes,
                va="top", ha="left", fontsize="small", color="tab:red")


def plot_trace(
    result: ReductionResult,
    target: Target,
    *,
    title: str | None = None,
    fmt: str | None = None,
) -> Target:
    """Plot a reduced run (μ over sliding distance, μ_S peak, μ_K window) to ``target``."""
    fig = new_figure(7.0, 3.6)
    ax = fig.add_subplot()
    draw_trace(ax, result.trace, mu_s=result.mu_s, mu_s_distance_mm=result.mu_s_distance_mm,
               mu_k=result.mu_k, mu_k_window_mm=result.mu_k_window_mm,
               flags=";".join(result.flags), u_mu_s=result.u_mu_s, u_mu_k=result.u_mu_k)
    if title:
        ax.set_title(title, fontsize="medium")
    return save_figure(fig, target, fmt)


def plot_trace_row(
    trace: pd.DataFrame,
    row: Mapping[str, Any],
    target: Target,
    *,
    title: str | None = None,
    fmt: str | None = None,
    dpi: int = DPI,
) -> Target:
    """Plot a stored trace (Parquet columns) with its friction-map row's μ_S and μ_K window.

    ``row`` needs ``mu_s, mu_s_distance_mm, mu_k, mu_k_window_start_mm,
    mu_k_window_end_mm`` and optionally ``flags``, ``u_mu_s`` and ``u_mu_k``.
    """
    fig = new_figure(7.0, 3.6)
    ax = fig.add_subplot()
    flags = row.get("flags")
    draw_trace(
        ax, trace, mu_s=row.get("mu_s"), mu_s_distance_mm=row.get("mu_s_distance_mm"),
        mu_k=row.get("mu_k"),
        mu_k_window_mm=(row.get("mu_k_window_start_mm"), row.get("mu_k_window_end_mm")),
        flags=flags if isinstance(flags, str) else "",
        u_mu_s=row.get("u_mu_s"), u_mu_k=row.get("u_mu_k"),
    )
    if title:
        ax.set_title(title, fontsize="medium")
    return save_figure(fig, target, fmt, dpi)
