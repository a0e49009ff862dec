"""Min–max decimation: a long line reduced to the samples that decide its pixels.

A trace of 15,000 samples drawn 730 pixels wide puts about 20 samples in every pixel
column; the anti-aliased line through them fills, in that column, the pixels between their
lowest and highest value (and the joins to the neighbouring columns). Keeping, per column,
only the lowest and the highest sample — in their order — fills the same pixels, spikes
included, with at most two points per column.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np


def minmax_decimate(
    x: Any, y: Any, x_range: tuple[float, float], columns: int
) -> tuple[np.ndarray, np.ndarray]:
    """The samples of the line ``(x, y)`` worth drawing on ``columns`` pixel columns.

    The x range ``(x0, x1)`` (data units, e.g. mm) is cut into ``columns`` equal columns
    (samples outside it count to the nearest edge column). For every contiguous run of
    samples in one column, the sample with the lowest and the one with the highest finite
    ``y`` are kept (once when they are the same sample), in their original order; so every
    column keeps its samples' minimum and maximum, and a line through the kept samples
    covers the pixels the full line covers. A run whose ``y`` are all non-finite, or whose
    ``x`` is, keeps one sample with ``y`` NaN: the line breaks there as it did. For ``x``
    that never decreases (a sliding distance) every column is one run, so at most
    ``2 · columns`` samples are kept. Lines of at most ``2 · columns`` samples come back
    whole. Returns new arrays (shape (m,)); the inputs are not modified.
    """
    import numpy as np

    xs = np.asarray(x, dtype=float)
    ys = np.asarray(y, dtype=float)
    if xs.shape != ys.shape or xs.ndim != 1:
        raise ValueError(f"x and y must be 1-D of one length, got {xs.shape} and {ys.shape}")
    n = xs.size
    columns = max(1, int(columns))
    if n <= 2 * columns:
        return xs.copy(), ys.copy()
    x0, x1 = float(x_range[0]), float(x_range[1])
    scale = columns / (x1 - x0) if x1 > x0 else 0.0
    with np.errstate(invalid="ignore"):
        position = (xs - x0) * scale
    bad_x = ~np.isfinite(position)
    # column -1 holds the samples without a finite x; the others are clipped to the range
    col = np.where(bad_x, -1, np.clip(np.floor(np.where(bad_x, 0.0, position)), 0,
                                      columns - 1)).astype(np.int64)
    yy = np.where(bad_x | ~np.isfinite(ys), np.nan, ys)
    starts = np.flatnonzero(np.r_[True, col[1:] != col[:-1]])
    lengths = np.diff(np.r_[starts, n])
    low = np.fmin.reduceat(yy, starts)  # fmin/fmax skip NaN; all-NaN runs give NaN
    high = np.fmax.reduceat(yy, starts)
    index = np.arange(n)
    # the first sample of each run equal to its min (max): n where none is
    i_low = np.minimum.reduceat(np.where(yy == np.repeat(low, lengths), index, n), starts)
    i_high = np.minimum.reduceat(np.where(yy == np.repeat(high, lengths), index, n), starts)
    empty = i_low == n
    i_low[empty] = starts[empty]
    i_high[empty] = starts[empty]
    keep = np.sort(np.stack([i_low, i_high], axis=1), axis=1).ravel()
    keep = keep[np.r_[True, keep[1:] != keep[:-1]]]
    return xs[keep], yy[keep]
