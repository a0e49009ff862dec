"""The plot of one reduced run (Fig. 3 style), drawn per run by the pipeline and the batch.

Two panels over one sliding-distance axis — μ (raw and smoothed, the μ_S peak, the μ_K
window and level) above, the measured normal force (and the nominal force when known)
below — under a header naming the file, the run's conditions (pin, disc, nominal force and
pressure, temperature, repeat), what was read (μ_S and where, μ_K and over which window)
and the run's flags.

A batch draws one per run, so the figure is built for speed without losing anything a
reader sees:

* **one figure per process and resolution** (:func:`trace_figure`), built once with a
  fixed layout (no layout engine, no ``tight_layout``); a plot only updates its artists;
* **min–max decimation per pixel column** (:func:`~tribopipe.figures.decimate.minmax_decimate`):
  at most two points per pixel column, the same pixels drawn;
* **one kept background**: what does not change from run to run (spines, axis labels,
  legend rows) is drawn once per set of legend entries and restored for every PNG; the
  run's own artists are drawn on it — the data, the μ_S/μ_K marks, and also the grid and
  the tick marks (one line collection each) at the axes' own tick locations;
* **text typeset by Pillow** on the PNG (FreeType, well under 1 ms a line; matplotlib's
  text layout costs several ms a line): the header and the tick labels, at the position,
  size and colour matplotlib would use. SVG and PDF are drawn whole by matplotlib, with its
  own tick labels from the same locators and formatters.
"""

from __future__ import annotations

import threading
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

from ..escape import picture_text
from ..labels import flag_list
from ..numeric import finite_or_none, is_finite
from .canvas import (
    MU_LABEL,
    Target,
    image_format,
    png_palette,
    prepare_target,
    save_figure,
    write_png,
)
from .decimate import Columns
from .runinfo import StoredRun, TraceConditions, TraceMarks, shorten
from .typeset import Typesetter

if TYPE_CHECKING:
    import numpy as np
    import pandas as pd
    from PIL.Image import Image

    from ..reduction.reduce import ReductionResult


#: the per-run plot's resolution: 700 × 530 px, about the pixels of the single-panel plot
#: it replaced (840 × 432 at 120 dpi); every step of a PNG costs in proportion to them
TRACE_DPI = 100


def _fraction(box_in: tuple[float, float, float, float], width_in: float,
              height_in: float) -> tuple[float, float, float, float]:
    """An axes box in inches as figure fractions."""
    left, bottom, width, height = box_in
    return (left / width_in, bottom / height_in, width / width_in, height / height_in)


class TraceFigure:
    """The reusable figure of a run's trace plot (Agg canvas, fixed layout).

    Built once per process and resolution (:func:`trace_figure`). :meth:`draw` sets every
    artist from one run (nothing of an earlier run survives), :meth:`save` writes it.
    7.0 × 5.3 in: header (four lines), μ legend, μ panel, force legend, force panel.
    """

    WIDTH_IN = 7.0
    HEIGHT_IN = 5.3
    #: axes boxes in inches from the figure's left and bottom: (left, bottom, width, height)
    MU_BOX_IN = (0.75, 1.95, 6.1, 2.3)
    FORCE_BOX_IN = (0.75, 0.5, 6.1, 1.05)
    #: where the axis labels sit [in from their axes' left or bottom edge]
    YLABEL_IN = 0.5
    XLABEL_IN = 0.3
    #: tick marks and the gap to their labels [pt] (matplotlib's defaults)
    TICK_PT = 3.5
    TICK_PAD_PT = 3.5

    def __init__(self, dpi: int = TRACE_DPI) -> None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.colors import to_rgb
        from matplotlib.figure import Figure
        from matplotlib.lines import Line2D
        from matplotlib.patches import Patch, Rectangle
        from matplotlib.ticker import MaxNLocator, ScalarFormatter
        from matplotlib.transforms import IdentityTransform

        self.dpi = dpi
        w, h = self.WIDTH_IN, self.HEIGHT_IN
        fig = Figure(figsize=(w, h), dpi=dpi)
        #: the figure's canvas (a plot draws on it and reads its pixels)
        self.canvas = FigureCanvasAgg(fig)
        self.figure = fig
        mu_ax = fig.add_axes(_fraction(self.MU_BOX_IN, w, h))
        f_ax = fig.add_axes(_fraction(self.FORCE_BOX_IN, w, h), sharex=mu_ax)
        self.mu_ax, self.force_ax = mu_ax, f_ax
        #: pixel columns of the panels at this resolution (what decimation aims at)
        self.columns = int(round(self.MU_BOX_IN[2] * dpi))
        # matplotlib's automatic ticks, the bin count fixed once (it depends only on the
        # axis' length), plain numbers (no offset, no power of ten for 1e-5..1e6)
        for axis in (mu_ax.xaxis, mu_ax.yaxis, f_ax.yaxis):
            nbins = int(min(max(axis.get_tick_space(), 1), 9))
            axis.set_major_locator(MaxNLocator(nbins=nbins, steps=[1, 2, 2.5, 5, 10]))
            formatter = ScalarFormatter(useOffset=False)
            formatter.set_powerlimits((-5, 6))
            axis.set_major_formatter(formatter)

        mu_ax.set_ylabel(MU_LABEL)
        f_ax.set_ylabel("normal force $F_N$ [N]")
        f_ax.set_xlabel("sliding distance s [mm]")
        # fixed label places (matplotlib would move them with the tick labels' width)
        for ax, box in ((mu_ax, self.MU_BOX_IN), (f_ax, self.FORCE_BOX_IN)):
            ax.yaxis.set_label_coords(-self.YLABEL_IN / box[2], 0.5)
        f_ax.xaxis.set_label_coords(0.5, -self.XLABEL_IN / self.FORCE_BOX_IN[3])

        blue, red, green = "tab:blue", "tab:red", "tab:green"
        # the μ_K window: tab:blue at 12 % over white, opaque (five times cheaper to fill
        # than a transparent span; the grid and the lines are drawn over it), clear of the
        # spines' inner half
        r, g, b = to_rgb(blue)
        tint = (1.0 - 0.12 * (1.0 - r), 1.0 - 0.12 * (1.0 - g), 1.0 - 0.12 * (1.0 - b))
        self.window = mu_ax.axvspan(0.0, 1.0, *_inside(self.MU_BOX_IN[3]), color=tint,
                                    lw=0, zorder=0.5)
        self.force_window = f_ax.axvspan(0.0, 1.0, *_inside(self.FORCE_BOX_IN[3]),
                                         color=tint, lw=0, zorder=0.5)
        self.window.set_hatchcolor((*to_rgb(blue), 0.45))
        # the grid and the tick marks of a PNG, in pixels (they move with the run's
        # limits); SVG and PDF use matplotlib's own, at the same places
        # (each one path of NaN-separated segments: one draw call)
        self.grid = Line2D([], [], color="#b0b0b0", lw=0.8, alpha=0.3,
                           transform=IdentityTransform())
        self.ticks = Line2D([], [], color="black", lw=0.8, transform=IdentityTransform())
        fig.add_artist(self.grid)
        fig.add_artist(self.ticks)
        (self.raw,) = mu_ax.plot([], [], color="0.75", lw=0.8)
        (self.smooth,) = mu_ax.plot([], [], color="0.15", lw=1.2)
        (self.mu_k,) = mu_ax.plot([], [], color=blue, lw=2.0)
        # U (k = 2): a band on μ_K over its window, a capped bar on μ_S
        self.mu_k_band = Rectangle((0.0, 0.0), 1.0, 1.0, color=blue, alpha=0.18, lw=0)
        mu_ax.add_patch(self.mu_k_band)
        (self.mu_s_bar,) = mu_ax.plot([], [], color=red, lw=1.2, marker="_", ms=7)
        (self.mu_s,) = mu_ax.plot([], [], "o", color=red, ms=7)
        # boundary flags: μ_S on its search limit (hollow marker, dotted line, note); the
        # μ_K window at the trace's end (hatched window, dashed line at its end, note)
        self.limit_line = mu_ax.axvline(0.0, color=red, lw=1.0, ls=":")
        self.limit_note = mu_ax.annotate("$\\mu_S$ at search limit", (0.0, 0.0),
                                         xytext=(6, 6), textcoords="offset points",
                                         fontsize="small", color=red)
        self.end_line = mu_ax.axvline(0.0, color="tab:orange", lw=1.2, ls="--")
        self.end_note = mu_ax.annotate("$\\mu_K$ window at trace end", (0.0, 0.0),
                                       xytext=(-4, 8), textcoords="offset points", ha="right",
                                       fontsize="small", color="tab:orange")
        # the nominal force under the measured one: where they agree, both show
        (self.nominal,) = f_ax.plot([], [], color=green, lw=1.3, ls="--")
        (self.force,) = f_ax.plot([], [], color="0.3", lw=0.8)
        self.no_force = f_ax.text(0.5, 0.5, "no normal force in the trace",
                                  transform=f_ax.transAxes, ha="center", va="center",
                                  color="0.4", fontsize="small")
        #: legend rows per panel: (the run's artist, a handle like it, label); an entry is
        #: shown when the run has that artist
        self._entries = {
            "mu": (
                (self.raw, Line2D([], [], color="0.75", lw=0.8), "μ (raw)"),
                (self.smooth, Line2D([], [], color="0.15", lw=1.2), "μ (smoothed)"),
                (self.window, Patch(color=tint), "$\\mu_K$ window"),
                (self.mu_k, Line2D([], [], color=blue, lw=2.0), "$\\mu_K$ (plateau mean)"),
                (self.mu_s, Line2D([], [], ls="", marker="o", color=red, ms=7),
                 "$\\mu_S$ (static peak)"),
            ),
            "force": (
                (self.force, Line2D([], [], color="0.3", lw=0.8), "$F_N$ measured"),
                (self.nominal, Line2D([], [], color=green, lw=1.3, ls="--"),
                 "$F_N$ nominal"),
            ),
        }
        self._legends: dict[str, Any] = {}
        self._legend_keys: dict[str, tuple[str, ...]] = {}

        # the header: names from users are never parsed as mathtext
        top, line = 1.0 - 0.08 / h, 0.18 / h
        kw: dict[str, Any] = {"ha": "center", "va": "top", "parse_math": False}
        self.title = fig.text(0.5, top, "", fontsize="medium", **kw)
        self.conditions = fig.text(0.5, top - 1.1 * line, "", fontsize="small", **kw)
        self.readings = fig.text(0.5, top - 2.1 * line, "", fontsize="small", **kw)
        self.flags = fig.text(0.5, top - 3.1 * line, "", fontsize="small", **kw)
        self.header = (self.title, self.conditions, self.readings, self.flags)
        self._typesetter = Typesetter(dpi)

        #: the run's own artists, in drawing order (grid above the window's tint)
        self._artists = (self.window, self.force_window, self.grid, self.ticks, self.raw,
                         self.smooth, self.end_line, self.limit_line, self.mu_k_band,
                         self.mu_k, self.mu_s_bar, self.mu_s, self.nominal, self.force,
                         self.limit_note, self.end_note)
        self._shown: dict[Any, bool] = {}
        self._tick_labels: list[tuple[str, float, float, str]] = []
        self._backgrounds: dict[tuple[Any, ...], Any] = {}
        self._background_key: tuple[Any, ...] = ()
        self._vector_axes(False)
        self._palette: Image | None = None
        self._palette = self._calibrate()

    # ------------------------------------------------------------------ one run

    def draw(
        self,
        distance_mm: Any,
        mu: Any,
        marks: TraceMarks,
        *,
        mu_smooth: Any = None,
        normal_force_N: Any = None,
        conditions: TraceConditions | None = None,
        title: str | None = None,
    ) -> TraceFigure:
        """Set every artist from one run; returns ``self`` (ready to :meth:`save`).

        ``distance_mm``, ``mu``, ``mu_smooth`` and ``normal_force_N`` are sample arrays of
        one length (shape (n,); distance in mm, force in N); ``mu_smooth`` and
        ``normal_force_N`` may be ``None``. ``title`` (default: the conditions' source)
        heads the figure; the conditions, the readings and the flags follow.
        """
        import numpy as np

        s = np.asarray(distance_mm, dtype=float)
        mu_v = np.asarray(mu, dtype=float)
        cond = conditions or TraceConditions()
        finite_s = s[np.isfinite(s)]
        data_x = (float(finite_s.min()), float(finite_s.max())) if finite_s.size else (0., 1.)
        x_range = _padded(*data_x, 0.02)
        self.mu_ax.set_xlim(*x_range)

        thin = Columns(s, x_range, self.columns).thin

        shown = dict.fromkeys(self._artists, False)
        for line in (self.raw, self.grid, self.ticks):
            shown[line] = True
        self.raw.set_data(*thin(mu_v))
        if mu_smooth is not None:
            self.smooth.set_data(*thin(mu_smooth))
            shown[self.smooth] = True
        low, high = self._draw_readings(marks, data_x, shown)
        finite = mu_v[np.isfinite(mu_v)]
        top = max(float(finite.max()) if finite.size else 1.0, high)
        bottom = min(0.0, float(finite.min()) if finite.size else 0.0, low)
        self.mu_ax.set_ylim(bottom - 0.02 * (top - bottom), top + 0.08 * (top - bottom))
        self._draw_force(s, normal_force_N, cond.normal_force_N, data_x, thin, shown)
        self._set_ticks()

        # names from users: one printable line each (a line break fails Pillow's layout)
        self.title.set_text(_header(title if title is not None else (cond.source or "")))
        self.conditions.set_text(_header(cond.line()))
        self.readings.set_text(_header(marks.line()))
        self.flags.set_text(_header("flags: " + (", ".join(marks.flags) or "none")))
        self.flags.set_color("tab:red" if marks.flags else "0.4")
        for artist, visible in shown.items():
            artist.set_visible(visible)
        self._shown = shown
        self._background_key = (self._set_legend("mu", shown, self.MU_BOX_IN),
                                self._set_legend("force", shown, self.FORCE_BOX_IN),
                                self.no_force.get_visible())
        return self

    def _draw_readings(self, marks: TraceMarks, data_x: tuple[float, float],
                       shown: dict[Any, bool]) -> tuple[float, float]:
        """The μ_K window (shaded on both panels; hatched, with a dashed line at its end,
        when it ends with the trace), the μ_K level over it (dashed over the whole run
        without a window) with its U band, the μ_S marker with its U bar (hollow, with a
        dotted line, when read on a limit of its search). Returns the lowest and highest
        value drawn [COF]."""
        values = [0.0]
        window = marks.window
        if window is not None:
            for span in (self.window, self.force_window):
                span.set_x(window[0])
                span.set_width(window[1] - window[0])
                shown[span] = True
            # matplotlib's stub takes str only; None (no hatch, the default) is valid
            self.window.set_hatch("//" if marks.window_at_end else None)  # type: ignore[arg-type]
            if marks.window_at_end:
                self.end_line.set_xdata([window[1], window[1]])
                shown[self.end_line] = True
        level = finite_or_none(marks.mu_k)
        if level is not None:
            self.mu_k.set_data(list(window or data_x), [level, level])
            self.mu_k.set_linestyle("-" if window else "--")
            shown[self.mu_k] = True
            values.append(level)
            band = marks.expanded(marks.u_mu_k)
            if band is not None and window is not None:
                self.mu_k_band.set_bounds(window[0], level - band, window[1] - window[0],
                                          2.0 * band)
                shown[self.mu_k_band] = True
                values += [level - band, level + band]
            if marks.window_at_end:
                self.end_note.xy = ((window or data_x)[1], level)
                shown[self.end_note] = True
        x, y = finite_or_none(marks.mu_s_distance_mm), finite_or_none(marks.mu_s)
        if x is not None and y is not None:
            self.mu_s.set_data([x], [y])
            self.mu_s.set_markerfacecolor("white" if marks.peak_at_limit else "tab:red")
            shown[self.mu_s] = True
            values.append(y)
            bar = marks.expanded(marks.u_mu_s)
            if bar is not None:
                self.mu_s_bar.set_data([x, x], [y - bar, y + bar])
                shown[self.mu_s_bar] = True
                values += [y - bar, y + bar]
            if marks.peak_at_limit:
                self.limit_line.set_xdata([x, x])
                self.limit_note.xy = (x, y)
                shown[self.limit_line] = shown[self.limit_note] = True
        return min(values), max(values)

    def _draw_force(self, s: np.ndarray, force: Any, nominal_N: float | None,
                    data_x: tuple[float, float], thin: Any, shown: dict[Any, bool]) -> None:
        """The normal-force panel: the measured force, the nominal force when known (over
        the run's distance). Limits: the measured extremes and, when the nominal force is
        known, ±25 % of it (so a force within the map's 10 % tolerance looks steady and one
        outside it does not)."""
        import numpy as np

        f_v = None if force is None else np.asarray(force, dtype=float)
        finite = f_v[np.isfinite(f_v)] if f_v is not None else np.empty(0)
        values: list[float] = []
        if finite.size:
            self.force.set_data(*thin(f_v))
            shown[self.force] = True
            values += [float(finite.min()), float(finite.max())]
        self.no_force.set_visible(not finite.size)
        if nominal_N is not None and is_finite(nominal_N):
            nominal = float(nominal_N)
            self.nominal.set_data(list(data_x), [nominal, nominal])
            shown[self.nominal] = True
            values += [0.75 * nominal, 1.25 * nominal]
        self.force_ax.set_ylim(*_padded(min(values, default=0.0), max(values, default=1.0),
                                        0.05))

    def _set_ticks(self) -> None:
        """The PNG's grid lines, tick marks and tick labels at the axes' locators' ticks
        within their limits, in pixels, as matplotlib places them: tick marks outside the
        panels, the force panel's x labels below it, both panels' y labels left of them.
        Labels are kept as (text, x, y from the top left, Pillow anchor)."""
        import numpy as np

        tick = self.TICK_PT * self.dpi / 72.0
        offset = (self.TICK_PT + self.TICK_PAD_PT) * self.dpi / 72.0
        height = self.HEIGHT_IN * self.dpi
        grid: list[Any] = []  # (x0, y0, x1, y1) per segment, in pixels
        marks: list[Any] = []
        labels: list[tuple[str, float, float, str]] = []
        for ax in (self.mu_ax, self.force_ax):
            (left, bottom), (right, top) = ax.bbox.get_points()
            for axis, (lo, hi) in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
                locs = np.asarray(axis.get_major_locator().tick_values(lo, hi), dtype=float)
                slack = 1e-10 * (hi - lo)
                inside = locs[(locs >= lo - slack) & (locs <= hi + slack)]
                texts = axis.get_major_formatter().format_ticks(list(inside))
                if axis is ax.xaxis:  # linear axes: data to pixels by proportion
                    xs = left + (inside - lo) / (hi - lo) * (right - left)
                    grid += [(x, bottom, x, top) for x in xs]
                    marks += [(x, bottom, x, bottom - tick) for x in xs]
                    if ax is self.force_ax:
                        labels += [(text, x, height - bottom + offset, "ma")
                                   for text, x in zip(texts, xs, strict=True)]
                else:
                    ys = bottom + (inside - lo) / (hi - lo) * (top - bottom)
                    grid += [(left, y, right, y) for y in ys]
                    marks += [(left, y, left - tick, y) for y in ys]
                    labels += [(text, left - offset, height - y, "rm")
                               for text, y in zip(texts, ys, strict=True)]
        for line, segments in ((self.grid, grid), (self.ticks, marks)):
            # one path: x0 x1 NaN per segment
            xy = np.full((len(segments), 3, 2), np.nan)
            if segments:
                xy[:, :2] = np.asarray(segments, dtype=float).reshape(-1, 2, 2)
            line.set_data(xy[..., 0].ravel(), xy[..., 1].ravel())
        self._tick_labels = labels

    def _set_legend(self, panel: str, shown: Mapping[Any, bool],
                    box_in: tuple[float, float, float, float]) -> tuple[str, ...]:
        """The legend row just above a panel (``"mu"`` or ``"force"``), outside it so the
        data never hides it: one entry per kind of artist the run has, rebuilt only when
        that set changes. Returns the labels shown."""
        entries = [(handle, label) for artist, handle, label in self._entries[panel]
                   if shown[artist]]
        key = tuple(label for _, label in entries)
        if self._legend_keys.get(panel) == key:
            return key
        old = self._legends.pop(panel, None)
        if old is not None:
            old.remove()
        if entries:
            centre = (box_in[0] + box_in[2] / 2) / self.WIDTH_IN
            self._legends[panel] = self.figure.legend(
                [h for h, _ in entries], [label for _, label in entries], loc="lower center",
                bbox_to_anchor=(centre, (box_in[1] + box_in[3]) / self.HEIGHT_IN),
                ncols=len(entries), fontsize="small", frameon=False, borderaxespad=0.1,
                borderpad=0.1, columnspacing=1.4, handlelength=1.8)
        self._legend_keys[panel] = key
        return key

    # ------------------------------------------------------------------ output

    def save(self, target: Target, fmt: str | None = None) -> Target:
        """Write the run set by :meth:`draw` to ``target`` and return the target: a PNG
        from the kept background (:meth:`render`) in the figure's palette
        (:meth:`palette`); SVG and PDF drawn whole by matplotlib, with its own tick marks
        and labels."""
        fmt = image_format(target, fmt)
        if fmt != "png":
            self._vector_axes(True)
            try:
                return save_figure(self.figure, target, fmt, self.dpi)
            finally:
                self._vector_axes(False)
        target = prepare_target(target, fmt)
        write_png(self.render(), target, palette=self._palette)
        return target

    def palette(self) -> Image:
        """The 256 colours every PNG of this figure is written in (see
        :meth:`_calibrate`)."""
        if self._palette is None:
            self._palette = self._calibrate()
        return self._palette

    def _calibrate(self) -> Image:
        """The fast-octree palette of one calibration plot that has every artist, colour
        and overlap a run can have: raw and smoothed μ with a spike, the μ_K window and
        level with their U, the μ_S marker hollow on its limit line, the window hatched
        at the trace's end, the measured force crossing the nominal one, the notes and a
        red flag line. A run's picture holds the same colours (the same artists on the same
        background), and mapping it to this palette costs a sixth of finding its own; the
        tests bound the difference. Leaves the figure set to the calibration plot."""
        import numpy as np

        rng = np.random.default_rng(0)
        s = np.linspace(0.0, 6.0, 6000)
        mu = 0.55 + 0.03 * rng.standard_normal(s.size) + 0.3 * np.exp(-((s - 0.4) / 0.1) ** 2)
        mu[:300] = np.linspace(0.0, 0.9, 300)
        mu[3000] = 1.05
        smooth = np.convolve(mu, np.ones(25) / 25, mode="same")
        force = 3.0 * (1.0 + 0.15 * np.sin(9.0 * s)) + 0.02 * rng.standard_normal(s.size)
        flags = ("calibration", "peak_at_search_limit", "plateau_at_trace_end")
        self.draw(s, mu, TraceMarks(0.87, 0.4, 0.55, (1.0, 5.8), flags, 0.01, 0.004),
                  mu_smooth=smooth, normal_force_N=force,
                  conditions=TraceConditions("calibration.csv", "pin", "disc", 3.0, 35.4,
                                             20.0, 1))
        return png_palette(self.render())

    def _vector_axes(self, on: bool) -> None:
        """matplotlib's own grid, tick marks and labels (``on``: for SVG and PDF), or only
        its axis labels (PNG: the run's grid, tick marks and typeset labels stand in)."""
        length = self.TICK_PT if on else 0.0
        self.mu_ax.tick_params(length=length, labelleft=on, labelbottom=False)
        self.force_ax.tick_params(length=length, labelleft=on, labelbottom=on)
        for ax in (self.mu_ax, self.force_ax):
            if on:
                ax.grid(True, alpha=0.3)
            else:
                ax.grid(False)
        for collection in (self.grid, self.ticks):
            collection.set_visible(not on and self._shown.get(collection, False))

    def render(self) -> Image:
        """The run set by :meth:`draw` as an RGB image: the background kept for its legend
        rows restored (drawn once, without the run's artists, when new), the run's artists
        drawn on it, the header and tick labels typeset."""
        from PIL import Image as PILImage

        canvas = self.canvas
        background = self._backgrounds.get(self._background_key)
        if background is None:
            for artist in (*self._artists, *self.header):
                artist.set_visible(False)
            canvas.draw()
            background = canvas.copy_from_bbox(self.figure.bbox)
            self._backgrounds[self._background_key] = background
            for artist in self.header:
                artist.set_visible(True)
            for artist, visible in self._shown.items():
                artist.set_visible(visible)
        else:
            canvas.restore_region(background)
        renderer = canvas.get_renderer()
        for artist in self._artists:
            if self._shown[artist]:
                artist.draw(renderer)
        rgba = canvas.buffer_rgba()
        image = PILImage.frombuffer("RGBA", (rgba.shape[1], rgba.shape[0]), rgba, "raw",
                                    "RGBA", 0, 1).convert("RGB")
        self._typeset(image)
        return image

    def _typeset(self, image: Image) -> None:
        """Draw the header texts (centred, at their own position, size and colour) and
        the tick labels on ``image`` with Pillow."""
        from matplotlib.colors import to_rgb
        from matplotlib.font_manager import findfont

        width, height = image.size
        for text in self.header:
            if text.get_text():
                x, y = text.get_position()
                colour = tuple(round(255 * c) for c in to_rgb(text.get_color()))
                self._typesetter.paste(image, text.get_text(), findfont(text.get_fontproperties()),
                            float(text.get_fontsize()), "ma", x * width, (1.0 - y) * height,
                            colour)
        label = self.force_ax.yaxis.get_major_ticks()[0].label1
        path, size = findfont(label.get_fontproperties()), float(label.get_fontsize())
        for content, x, y, anchor in self._tick_labels:
            self._typesetter.paste(image, content, path, size, anchor, x, y, (0, 0, 0))


def _header(text: str) -> str:
    """A header line of the figure: :func:`~tribopipe.escape.picture_text` as it is drawn
    (no mathtext), shortened to :data:`~tribopipe.figures.runinfo.HEADER_CHARS`."""
    return shorten(picture_text(text, mathtext=False))


def _padded(lo: float, hi: float, fraction: float) -> tuple[float, float]:
    """``(lo, hi)`` widened by ``fraction`` of its span on each side (by ±0.5 around a
    single value)."""
    if not hi > lo:
        return lo - 0.5, hi + 0.5
    pad = fraction * (hi - lo)
    return lo - pad, hi + pad


def _inside(axes_height_in: float) -> tuple[float, float]:
    """The vertical extent (axes fractions) of a span that fills a panel but leaves its
    top and bottom spines (0.8 pt, centred on the edge) untouched."""
    half_spine = 0.4 / 72.0 / axes_height_in
    return half_spine, 1.0 - half_spine


_FIGURES = threading.local()

def trace_figure(dpi: int = TRACE_DPI) -> TraceFigure:
    """This thread's trace figure at ``dpi`` (built on first use, then reused)."""
    cache: dict[int, TraceFigure] | None = getattr(_FIGURES, "by_dpi", None)
    if cache is None:
        cache = _FIGURES.by_dpi = {}
    if dpi not in cache:
        cache[dpi] = TraceFigure(dpi)
    return cache[dpi]


def _column(trace: pd.DataFrame, name: str) -> Any:
    """A trace column as a NumPy array, or ``None`` when the trace has none."""
    return trace[name].to_numpy() if name in trace.columns else None


def plot_trace(
    result: ReductionResult,
    target: Target,
    *,
    title: str | None = None,
    conditions: TraceConditions | None = None,
    flags: Sequence[str] | None = None,
    fmt: str | None = None,
    dpi: int = TRACE_DPI,
) -> Target:
    """Plot a reduced run to ``target``: μ over sliding distance with the μ_S peak and the
    μ_K window, the normal force below, file, conditions, readings and flags above.
    ``flags`` are the run's flags as decided for every output
    (:func:`tribopipe.labels.decide_run`); default: the reduction's own."""
    trace = result.trace
    marks = TraceMarks(mu_s=result.mu_s, mu_s_distance_mm=result.mu_s_distance_mm,
                       mu_k=result.mu_k, mu_k_window_mm=result.mu_k_window_mm,
                       flags=tuple(flag_list(result.flags if flags is None else flags)),
                       u_mu_s=finite_or_none(result.u_mu_s),
                       u_mu_k=finite_or_none(result.u_mu_k))
    figure = trace_figure(dpi).draw(
        trace["sliding_distance_mm"].to_numpy(), trace["mu"].to_numpy(), marks,
        mu_smooth=_column(trace, "mu_smooth"), normal_force_N=_column(trace, "normal_force_N"),
        conditions=conditions, title=title,
    )
    return figure.save(target, fmt)


def plot_trace_row(
    trace: pd.DataFrame,
    row: StoredRun,
    target: Target,
    *,
    title: str | None = None,
    fmt: str | None = None,
    dpi: int = TRACE_DPI,
) -> Target:
    """Plot a stored trace (Parquet columns) with its friction-map row's readings.

    ``row`` is the run's map row (:class:`~tribopipe.figures.runinfo.StoredRun`: the
    readings, flags, review and conditions it holds); ``trace`` needs
    ``sliding_distance_mm`` and ``mu`` (``mu_smooth`` and ``normal_force_N`` drawn when
    present)."""
    marks = TraceMarks(
        mu_s=finite_or_none(row.mu_s),
        mu_s_distance_mm=finite_or_none(row.mu_s_distance_mm),
        mu_k=finite_or_none(row.mu_k),
        mu_k_window_mm=(row.mu_k_window_start_mm, row.mu_k_window_end_mm),
        flags=tuple(flag_list(row.flags)),
        u_mu_s=finite_or_none(row.u_mu_s),
        u_mu_k=finite_or_none(row.u_mu_k),
        review=row.review,
    )
    figure = trace_figure(dpi).draw(
        trace["sliding_distance_mm"].to_numpy(), trace["mu"].to_numpy(), marks,
        mu_smooth=_column(trace, "mu_smooth"), normal_force_N=_column(trace, "normal_force_N"),
        conditions=TraceConditions.from_row(row), title=title,
    )
    return figure.save(target, fmt)
