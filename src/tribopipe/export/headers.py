"""What every simulator file says of itself in its comments: the engine, the version it
was checked against, the coefficient it holds, how the engine combines two bodies'
values, the condition a single value was read at; comment blocks wrapped to a width.

Names that come from the map (pin, disc, the map's path) are data, never code: every
writer passes them through :func:`tribopipe.escape.sim_comment` (Python-repr escapes: no
newline, no control character survives), or its own ``safe`` function, before they reach
a comment, and they appear nowhere else except as a quoted literal (:func:`repr` in
Python, XML-escaped attributes) or as a sanitised identifier (letters, digits,
underscores).
"""

from __future__ import annotations

import textwrap
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from .. import __version__
from ..escape import sim_comment
from ..rounding import decimal_text
from .unit_systems import num

if TYPE_CHECKING:
    from ..query import QueryResult


@dataclass(frozen=True)
class Engine:
    """What a writer's header says about its engine (one line each)."""

    name: str
    checked: str
    combination: str


def header_bodies(
    engine: Engine,
    holds: str,
    source: str | None,
    safe: Callable[[object], str] = sim_comment,
) -> list[str]:
    """The comment bodies every file opens with: engine, version checked against,
    coefficient held, how the engine combines two surfaces' values, and where the
    numbers came from (``source``, the map's path, made inert by ``safe``)."""
    origin = f" {safe(source)}" if source else ""
    return [
        f"{engine.name} input written by tribopipe {__version__} from the friction "
        f"map{origin}",
        f"checked against: {engine.checked}",
        f"holds: {holds}",
        f"two surfaces: {engine.combination}",
        "values: group means of the runs (repeats) at each nominal condition",
    ]


#: :func:`condition_lines`' words for a pair without μ_S and for a value held at an edge
MU_S_UNKNOWN = "unknown (not in the map)"
HELD_LINE = "outside the measured range: edge value held constant"
#: :func:`condition_lines`' first line, naming the pair (the names escaped for the file)
PAIR_LINE = "pair: pin {pin} on disc {disc}"


def condition_lines(res: QueryResult, safe: Callable[[object], str] = sim_comment) -> list[str]:
    """Comment bodies naming the pair, the condition, both coefficients and the measured
    groups they were interpolated from."""
    def g(value: float, digits: int = 6) -> str:
        return decimal_text(value, digits=digits)

    t = "unknown" if res.temperature_C is None else f"{g(res.temperature_C)} C"
    lines = [
        PAIR_LINE.format(pin=safe(res.pin), disc=safe(res.disc)),
        f"condition: contact pressure {g(res.pressure_kPa)} kPa, temperature {t}",
        f"mu_k = {num(res.mu_k.value)}; {res.mu_k.text(ascii_only=True)}"
        + ("" if res.mu_k.expanded is None else " (U, k = 2)"),
        "mu_s = " + (MU_S_UNKNOWN if res.mu_s is None else
                     f"{num(res.mu_s.value)}; {res.mu_s.text(ascii_only=True)}"
                     + ("" if res.mu_s.expanded is None else " (U, k = 2)")),
    ]
    # one group a line: no line of numbers is ever long enough to wrap, so the
    # explorer's copy of these lines needs no line breaking of its own
    lines.append("from measured groups:")
    lines += [f"  {g(u.pressure_kPa)} kPa"
              + ("" if u.temperature_C is None else f"/{g(u.temperature_C)} C")
              + f" (w={g(u.weight, 3)})" for u in res.mu_k.used]
    if res.clamped:
        lines.append(HELD_LINE)
    return lines


def comment_block(comment: str, bodies: list[str], width: int = 100) -> list[str]:
    """``bodies`` as comment lines of at most ``width`` characters (long ones wrapped,
    continuation lines indented), each starting with ``comment`` and a space."""
    lines = []
    for body in bodies:
        indent = " " * (len(body) - len(body.lstrip(" ")))
        # words (a path, a name) are split only when longer than a whole line
        wrapped = textwrap.wrap(body, width=width - len(comment) - 1,
                                subsequent_indent=indent + "  ",
                                break_on_hyphens=False) or [""]
        lines += [f"{comment} {w}".rstrip() for w in wrapped]
    return lines
