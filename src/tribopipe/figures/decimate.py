"""Min–max decimation: a long line reduced to the samples that decide its pixels.

A trace of 15,000 samples drawn 610 pixels wide puts about 25 samples in every pixel
column; the anti-aliased line through them fills, in that column, the pixels between their
lowest and highest value (and the joins to the neighbouring columns). Keeping, per column,
only the lowest and the highest sample — in their order — fills the same pixels, spikes
included, with at most two points per column.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import ArrayLike, NDArray


class Columns:
    """The pixel columns of the samples ``x`` (shape (n,)): the x range ``(x0, x1)``
    (data units, e.g. mm) cut into ``columns`` equal columns, samples outside it counted
    to the nearest edge column, samples without a finite x in a column of their own.
    Computed once per x, used for every line drawn over it (:meth:`thin`)."""

    def __init__(self, x: ArrayLike, x_range: tuple[float, float], columns: int) -> None:
        import numpy as np

        self.x = np.asarray(x, dtype=float)
        if self.x.ndim != 1:
            raise ValueError(f"x must be 1-D, got shape {self.x.shape}")
        self.columns = max(1, int(columns))
        n = self.x.size
        self.whole = n <= 2 * self.columns  # nothing to gain: lines come back whole
        if self.whole:
            return
        x0, x1 = float(x_range[0]), float(x_range[1])
        scale = self.columns / (x1 - x0) if x1 > x0 else 0.0
        with np.errstate(invalid="ignore"):
            position = (self.x - x0) * scale
        self.bad_x = ~np.isfinite(position)
        col = np.where(self.bad_x, -1, np.clip(np.floor(np.where(self.bad_x, 0.0, position)),
                                               0, self.columns - 1)).astype(np.int64)
        #: first sample of every contiguous run of samples in one column
        self.starts = np.flatnonzero(np.r_[True, col[1:] != col[:-1]])
        self.lengths = np.diff(np.r_[self.starts, n])
        self.index = np.arange(n)

    def thin(self, y: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The samples of the line ``(x, y)`` worth drawing: for every contiguous run of
        samples in one column, the one with the lowest and the one with the highest finite
        ``y`` (once when they are the same sample), in their original order. A run whose
        ``y`` are all non-finite, or whose ``x`` is, keeps one sample with ``y`` NaN: the
        line breaks there as it did. Returns new arrays (shape (m,)); ``y`` is not
        modified."""
        import numpy as np

        ys = np.asarray(y, dtype=float)
        if ys.shape != self.x.shape:
            raise ValueError(f"x and y must be of one length, got {self.x.shape} and {ys.shape}")
        if self.whole:
            return self.x.copy(), ys.copy()
        n = ys.size
        yy = np.where(self.bad_x | ~np.isfinite(ys), np.nan, ys)
        starts, lengths = self.starts, self.lengths
        low = np.fmin.reduceat(yy, starts)  # fmin/fmax skip NaN; all-NaN runs give NaN
        high = np.fmax.reduceat(yy, starts)
        # the first sample of each run equal to its min (max); n where there is none
        i_low = np.minimum.reduceat(np.where(yy == np.repeat(low, lengths), self.index, n),
                                    starts)
        i_high = np.minimum.reduceat(np.where(yy == np.repeat(high, lengths), self.index, n),
                                     starts)
        empty = i_low == n
        i_low[empty] = starts[empty]
        i_high[empty] = starts[empty]
        keep = np.sort(np.stack([i_low, i_high], axis=1), axis=1).ravel()
        keep = keep[np.r_[True, keep[1:] != keep[:-1]]]
        return self.x[keep], yy[keep]


def minmax_decimate(
    x: ArrayLike, y: ArrayLike, x_range: tuple[float, float], columns: int
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The samples of the line ``(x, y)`` worth drawing on ``columns`` pixel columns over
    ``x_range`` (:class:`Columns`, :meth:`Columns.thin`).

    Every column keeps its samples' minimum and maximum, so a line through the kept samples
    covers the pixels the full line covers, spikes included. For ``x`` that never decreases
    (a sliding distance) every column is one run, so at most ``2 · columns`` samples are
    kept; lines of at most ``2 · columns`` samples come back whole.
    """
    return Columns(x, x_range, columns).thin(y)
