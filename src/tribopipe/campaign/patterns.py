"""The label fields of a run, and the file-name patterns that give them.

A run's labels are :data:`REQUIRED_FIELDS` (pin, disc, nominal force [N] and temperature
[°C]) and an optional repeat number. A pattern such as
``{pin}_{disc}_{force}N_{temperature}C_r{repeat}`` names them in a file stem or an export's
Test name (:func:`match_pattern`); numbers may use ``.``, ``,`` or ``p`` as decimal mark.
"""

from __future__ import annotations

import difflib
import functools
import re
import sys
from pathlib import Path
from typing import Any

from ..errors import ConfigError

REQUIRED_FIELDS: tuple[str, ...] = ("pin", "disc", "normal_force_N", "temperature_C")
LABEL_FIELDS: tuple[str, ...] = (*REQUIRED_FIELDS, "repeat")

#: placeholder names a pattern may use -> label field
PATTERN_FIELDS: dict[str, str] = {
    "pin": "pin",
    "disc": "disc",
    "force": "normal_force_N",
    "normal_force_N": "normal_force_N",
    "temperature": "temperature_C",
    "temperature_C": "temperature_C",
    "repeat": "repeat",
}
_NUMBER = r"-?[0-9]+(?:[.,p][0-9]+)?"
_PATTERN_REGEX: dict[str, str] = {
    "normal_force_N": _NUMBER,
    "temperature_C": _NUMBER,
    "repeat": r"[0-9]+",
}


def compile_pattern(pattern: str, *, key: str, path: Path | None) -> re.Pattern[str]:
    """Turn ``{pin}_{disc}_{force}N_{temperature}C_r{repeat}`` into an anchored regex.

    Known placeholders (``pin, disc, force, temperature, repeat`` and the label names) are
    captured; any other ``{name}`` matches text that is ignored, unless it is a near miss
    of a known one (``{dsic}``): that is refused with a did-you-mean.
    """
    parts: list[str] = []
    seen: set[str] = set()
    pos = 0
    for match in re.finditer(r"\{([A-Za-z_][A-Za-z0-9_]*)\}", pattern):
        parts.append(re.escape(pattern[pos : match.start()]))
        name = match.group(1)
        target = PATTERN_FIELDS.get(name)
        near = difflib.get_close_matches(name, PATTERN_FIELDS, n=1, cutoff=0.7)
        if target is None and near:  # `{dsic}`: a typo, not text to ignore
            raise ConfigError(f"[campaign] {key}: unknown placeholder {{{name}}}",
                              path=path, hint=f"did you mean {{{near[0]}}}?")
        if target is None:
            parts.append(".+?")
        else:
            if target in seen:
                raise ConfigError(f"[campaign] {key}: placeholder {{{name}}} used twice",
                                  path=path)
            seen.add(target)
            parts.append(f"(?P<{target}>{_PATTERN_REGEX.get(target, '.+?')})")
        pos = match.end()
    parts.append(re.escape(pattern[pos:]))
    if "{" in pattern[pos:] or not seen:
        raise ConfigError(
            f"[campaign] {key} {pattern!r} has no usable placeholder",
            path=path,
            hint="use {pin}, {disc}, {force}, {temperature}, {repeat}",
        )
    return re.compile("".join(parts), re.IGNORECASE)


@functools.lru_cache(maxsize=32)
def _pattern_regex(pattern: str) -> re.Pattern[str]:
    # a campaign matches one pattern against every file: build its regex once
    return compile_pattern(pattern, key="pattern", path=None)


def parse_number(text: str) -> float:
    # file names cannot hold '.' comfortably in every lab: accept 0p5 and 0,5 too
    return float(text.strip().replace(",", ".").replace("p", "."))


def match_pattern(pattern: str, text: str) -> dict[str, Any] | None:
    """The label fields a pattern finds in ``text`` (e.g. a file stem), or ``None`` if the
    text does not match. Forces are in N, temperatures in °C, repeat an int."""
    regex = _pattern_regex(pattern)
    m = regex.fullmatch(text.strip())
    if m is None:
        return None
    found: dict[str, Any] = {}
    for key, value in m.groupdict().items():
        if key == "repeat":
            found[key] = int(value)
        elif key in ("normal_force_N", "temperature_C"):
            found[key] = parse_number(value)
        else:
            found[key] = sys.intern(value.strip())  # one copy of a name many files give
    return found


def _tokens(pattern: str) -> list[tuple[str, str]]:
    """A pattern as ``(its text, its regex)`` pieces: each placeholder, each literal
    character (as :func:`compile_pattern` reads it)."""
    out: list[tuple[str, str]] = []
    pos = 0
    for match in re.finditer(r"\{([A-Za-z_][A-Za-z0-9_]*)\}", pattern):
        out += [(ch, re.escape(ch)) for ch in pattern[pos:match.start()]]
        target = PATTERN_FIELDS.get(match.group(1))
        out.append((match.group(0), ".+?" if target is None
                    else f"(?:{_PATTERN_REGEX.get(target, '.+?')})"))
        pos = match.end()
    out += [(ch, re.escape(ch)) for ch in pattern[pos:]]
    return out


def pattern_break(pattern: str, text: str) -> str:
    """Where ``text`` (a file stem) stops following ``pattern``, in words that do not
    depend on the text's own values, so files that break alike read alike: ``"it follows
    '{pin}_{disc}_{force}', then the pattern expects 'N'"``."""
    tokens = _tokens(pattern)
    text = text.strip()
    followed = 0
    for k in range(len(tokens), 0, -1):
        if re.match("".join(r for _, r in tokens[:k]), text, re.IGNORECASE):
            followed = k
            break
    if followed == len(tokens):
        return "it follows the whole pattern, then goes on"
    piece = tokens[followed][0]
    kinds = {"normal_force_N": "a number", "temperature_C": "a number",
             "repeat": "a whole number"}
    name = PATTERN_FIELDS.get(piece.strip("{}")) if piece.startswith("{") else None
    expected = (f"{piece} ({kinds[name]})" if name in kinds else piece) \
        if piece.startswith("{") else repr(piece)
    if followed == 0:
        return f"it does not start as the pattern does: the pattern expects {expected} first"
    done = "".join(t for t, _ in tokens[:followed])
    return f"it follows {done!r}, then the pattern expects {expected}"
