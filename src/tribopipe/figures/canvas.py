"""The headless canvas and the file writing every plot shares.

Figures are built with :class:`matplotlib.figure.Figure` on the Agg canvas, never through
``pyplot`` (no global state, no display needed, safe in worker processes), and matplotlib
is imported only inside the functions. Output format follows the target's suffix
(``.png``, ``.svg``, ``.pdf``) or ``fmt``; a file-like target (e.g. ``io.BytesIO`` for the
HTML report) needs ``fmt``.
"""

from __future__ import annotations

from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from ..errors import ExportError

if TYPE_CHECKING:
    from matplotlib.figure import Figure
    from PIL.Image import Image

FORMATS = ("png", "svg", "pdf")
DPI = 120
#: μ axis label used on every plot
MU_LABEL = "coefficient of friction μ"
#: zlib level of the trace plots' palette PNGs: 1 writes about 3× faster than the default
#: 6, for files about 10 % larger (about 40 kB a plot)
PNG_COMPRESS_LEVEL = 1

Target = str | Path | IO[bytes]


def new_figure(width_in: float, height_in: float) -> Figure:
    """A new figure on the Agg canvas (headless), laid out by matplotlib's constrained
    layout engine (for one-off plots; the per-run trace plot has its own fixed layout)."""
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


def prepare_target(target: Target, fmt: str) -> Target:
    """A path target with the format's suffix and its parent folder created; a stream as
    given."""
    if isinstance(target, str | Path):
        target = Path(target)
        if target.suffix.lower() != f".{fmt}":
            target = target.with_suffix(f".{fmt}")
        target.parent.mkdir(parents=True, exist_ok=True)
    return target


def save_figure(fig: Figure, target: Target, fmt: str | None, dpi: int = DPI) -> Target:
    """Write ``fig`` to ``target`` (creating parent folders) and return the target."""
    fmt = image_format(target, fmt)
    target = prepare_target(target, fmt)
    # a fixed date keeps PDF/SVG output byte-stable for identical input
    metadata_by_format: dict[str, dict[str, Any]] = {
        "png": {"Software": "tribopipe"}, "svg": {"Date": None}, "pdf": {"CreationDate": None}}
    metadata = metadata_by_format[fmt]
    fig.savefig(target, format=fmt, dpi=dpi, metadata=metadata)
    return target


def png_palette(image: Image) -> Image:
    """The fast-octree 256-colour palette of an RGB image (as a ``P`` image, what
    :func:`write_png` takes as ``palette``)."""
    from PIL import Image as PILImage

    return image.quantize(256, method=PILImage.Quantize.FASTOCTREE)


def write_png(image: Image, target: str | Path | IO[bytes], *,
              palette: Image | None = None) -> None:
    """Write an opaque RGB image as a 256-colour PNG (``Software: tribopipe``).

    A chart holds a few colours and their anti-aliased blends: an adaptive palette keeps
    every pixel within a few levels per channel, and the file is about a third of an RGB
    PNG's size, written in a fraction of the time. The palette is the image's own
    (:func:`png_palette`), or ``palette`` (a ``P`` image) when given: then every pixel
    takes its nearest colour there, without dithering (much faster than finding the
    image's own palette; for pictures of one kind, e.g. trace plots).
    """
    from PIL import Image as PILImage
    from PIL.PngImagePlugin import PngInfo

    if palette is None:
        indexed = png_palette(image)
    else:
        indexed = image.quantize(palette=palette, dither=PILImage.Dither.NONE)
    info = PngInfo()
    info.add_text("Software", "tribopipe")
    indexed.save(target, format="png", compress_level=PNG_COMPRESS_LEVEL, pnginfo=info)
