"""Text on a rendered PNG, typeset with Pillow (FreeType) instead of matplotlib.

matplotlib lays out every text anew on every draw (several ms a line in 3.11); a trace plot
has some twenty short texts per picture, most of which repeat from run to run. A
:class:`Typesetter` renders each text once into a coverage mask and pastes it, placed as
matplotlib places the same text.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from PIL.Image import Image


class Typesetter:
    """Typeset texts at ``dpi`` (fonts and coverage masks kept)."""

    #: typeset texts kept (tick labels and most header lines repeat from run to run)
    MASKS_KEPT = 1024

    def __init__(self, dpi: float) -> None:
        self.dpi = dpi
        self._fonts: dict[tuple[str, float], tuple[Any, float]] = {}
        self._masks: dict[tuple[Any, ...], tuple[Image, int, int]] = {}

    def paste(self, image: Image, text: str, path: str, size_pt: float, anchor: str,
              x: float, y: float, colour: tuple[int, ...]) -> None:
        """Put ``text`` on ``image`` at pixel ``(x, y)`` (from the top left) in ``colour``.
        ``anchor`` ``"ma"`` hangs the text centred below the point from the top of an
        ``l`` (as matplotlib aligns a top-aligned line, not from the font's taller
        ascender); ``"rm"`` ends it at the point, centred vertically. Each text is
        typeset once (an ``L`` coverage image) and pasted after."""
        from PIL import Image as PILImage
        from PIL import ImageDraw

        key = (text, path, size_pt, anchor)
        cached = self._masks.get(key)
        if cached is None:
            font, ascent = self.font(path, size_pt)
            anchor_pil, shift = ("ms", ascent) if anchor == "ma" else (anchor, 0.0)
            left, top, right, bottom = font.getbbox(text, anchor=anchor_pil)
            mask = PILImage.new("L", (int(right - left) + 2, int(bottom - top) + 2), 0)
            ImageDraw.Draw(mask).text((-left, -top), text, fill=255, font=font,
                                      anchor=anchor_pil)
            cached = (mask, int(left), int(round(top + shift)))
            if len(self._masks) >= self.MASKS_KEPT:
                self._masks.pop(next(iter(self._masks)))
            self._masks[key] = cached
        mask, dx, dy = cached
        image.paste(colour, (round(x) + dx, round(y) + dy), mask)

    def font(self, path: str, size_pt: float) -> tuple[Any, float]:
        """A Pillow font of the file at ``path`` and ``size_pt`` at this resolution, and
        the height of an ``l`` above its baseline [px]."""
        from PIL import ImageFont

        size_px = size_pt * self.dpi / 72.0
        cached = self._fonts.get((path, size_px))
        if cached is None:
            font = ImageFont.truetype(path, size_px)
            cached = self._fonts[(path, size_px)] = (font, -font.getbbox("l", anchor="ls")[1])
        return cached
