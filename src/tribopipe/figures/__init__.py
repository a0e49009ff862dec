"""Headless figures: the canvas and file writing every plot shares, and the plot of one run.

``canvas`` holds the Agg canvas, the formats and the writers; ``decimate`` the min–max
decimation of long lines; ``runinfo`` what a trace plot says of a run (conditions,
readings, flags); ``typeset`` text on a PNG with Pillow; ``trace`` the per-run trace plot
(μ and normal force over sliding distance, Fig. 3 style) that :mod:`tribopipe.pipeline`
draws per run, on one reused figure per process. The friction map's plots are in
:mod:`tribopipe.export.plots`.
"""

from .canvas import (
    DPI,
    FORMATS,
    MU_LABEL,
    PNG_COMPRESS_LEVEL,
    Target,
    image_format,
    new_figure,
    png_palette,
    prepare_target,
    save_figure,
    write_png,
)
from .decimate import minmax_decimate
from .runinfo import TraceConditions, TraceMarks
from .trace import TRACE_DPI, TraceFigure, plot_trace, plot_trace_row, trace_figure

__all__ = [
    "DPI", "FORMATS", "TRACE_DPI", "MU_LABEL", "PNG_COMPRESS_LEVEL", "Target", "TraceConditions",
    "TraceFigure", "TraceMarks", "image_format", "minmax_decimate",
    "new_figure", "plot_trace", "plot_trace_row", "png_palette", "prepare_target", "save_figure",
    "trace_figure", "write_png",
]
