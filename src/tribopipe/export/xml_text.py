"""Outside text in the XML files of the scene writers (MJCF, SOFA, URDF, SDFormat): as a
comment no content can close, or as an attribute value."""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

from ..errors import ExportError
from ..escape import sim_comment


def xml_comment(text: str, *, ascii_only: bool = False) -> str:
    """``text`` as one XML comment that no content can close or break (``ascii_only``:
    every non-ASCII character escaped too)."""
    return "<!-- " + sim_comment(text, "<!--", ascii_only=ascii_only) + " -->"


def xml_name(name: str, what: str) -> str:
    """An XML attribute value for a user-given element name, or an :class:`ExportError`
    when it holds a control character (which XML cannot carry)."""
    if any(not ch.isprintable() for ch in name):
        raise ExportError(
            f"{what} {name!r} holds a control character; a name must be printable"
        )
    return quoteattr(name)
