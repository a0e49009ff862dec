"""Column-name alias tables: which export column holds which quantity, in any language.

The built-in table (``tribopipe/data/aliases.toml``) knows English, French and German
names; a user file with the same layout (``configs/aliases.toml`` in the working
directory, or one passed to :func:`load_aliases`) adds names to it. Names match whole
column names, ignoring case, accents, spaces and punctuation, so ``Intervalle Temps``
(interval time) is never taken for ``Temps`` (time).
"""

from __future__ import annotations

import functools
import os
import re
import tomllib
import unicodedata
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from ..errors import ConfigError
from ..measurement import (
    ANGLE,
    FRICTION_FORCE,
    NORMAL_FORCE,
    POSITION,
    SPEED,
    TEMPERATURE,
    TIME,
    TORQUE,
)

#: canonical quantity → its column name in a Measurement
CANONICAL_COLUMN: dict[str, str] = {
    "time": TIME,
    "torque": TORQUE,
    "normal_force": NORMAL_FORCE,
    "angle": ANGLE,
    "speed": SPEED,
    "temperature": TEMPERATURE,
    "friction_force": FRICTION_FORCE,
    "position": POSITION,
}

#: the user extension looked for when no alias file is given
DEFAULT_USER_FILE = Path("configs") / "aliases.toml"


@functools.lru_cache(maxsize=4096)
def name_key(name: str) -> str:
    """The matching key of a column name: accents stripped, case folded, only letters and
    digits kept (``"Température "`` → ``"temperature"``)."""
    text = unicodedata.normalize("NFKD", name)
    text = "".join(c for c in text if not unicodedata.combining(c))
    return re.sub(r"[^0-9a-z]+", "", text.casefold())


def snake_case(name: str) -> str:
    """A snake_case, ASCII identifier for a column name (``"Shear Stress"`` →
    ``"shear_stress"``); ``"column"`` when nothing is left."""
    text = unicodedata.normalize("NFKD", name)
    text = "".join(c for c in text if not unicodedata.combining(c))
    text = text.encode("ascii", "ignore").decode().lower()
    text = re.sub(r"[^0-9a-z]+", "_", text).strip("_")
    return text or "column"


@dataclass(frozen=True)
class AliasTable:
    """Name keys → canonical quantity (``"torque"``) or a plain snake name."""

    canonical: dict[str, str] = field(default_factory=dict)
    names: dict[str, str] = field(default_factory=dict)
    sources: tuple[str, ...] = ()

    def quantity(self, column: str) -> str | None:
        """The canonical quantity a column name stands for, or ``None``."""
        return self.canonical.get(name_key(column))

    def base_name(self, column: str) -> str:
        """The snake_case base name (no unit) a column gets: the canonical quantity, a
        known alias, or the column's own name in snake_case."""
        key = name_key(column)
        if key in self.canonical:
            return self.canonical[key]
        if key in self.names:
            return self.names[key]
        return snake_case(column)

    def extended(self, data: Mapping[str, Any], source: str) -> AliasTable:
        """A new table with the aliases of a parsed TOML document added."""
        canonical = dict(self.canonical)
        names = dict(self.names)
        for section, target in (("canonical", canonical), ("names", names)):
            table = data.get(section, {})
            if not isinstance(table, dict):
                raise ConfigError(f"[{section}] must be a table", path=source)
            for quantity, entry in table.items():
                if section == "canonical" and quantity not in CANONICAL_COLUMN:
                    raise ConfigError(
                        f"unknown canonical quantity [canonical.{quantity}]; expected one of "
                        f"{', '.join(CANONICAL_COLUMN)}",
                        path=source,
                    )
                values = entry.get("names") if isinstance(entry, dict) else None
                if not isinstance(values, list) or not all(isinstance(v, str) for v in values):
                    raise ConfigError(
                        f"[{section}.{quantity}] needs names = [\"...\", ...]", path=source
                    )
                for value in values:
                    key = name_key(value)
                    if not key:
                        raise ConfigError(f"empty alias in [{section}.{quantity}]", path=source)
                    # a user alias overrides a built-in one (last file wins)
                    canonical.pop(key, None)
                    names.pop(key, None)
                    target[key] = quantity if section == "canonical" else snake_case(quantity)
        unknown = set(data) - {"canonical", "names"}
        if unknown:
            raise ConfigError(
                f"unknown table(s) {', '.join(sorted(unknown))}; expected [canonical.*] "
                "and [names.*]",
                path=source,
            )
        return AliasTable(canonical, names, (*self.sources, source))


@functools.lru_cache(maxsize=1)
def builtin_aliases() -> AliasTable:
    """The built-in English/French/German alias table (read once per process)."""
    ref = resources.files("tribopipe").joinpath("data", "aliases.toml")
    data = tomllib.loads(ref.read_text(encoding="utf-8"))
    return AliasTable().extended(data, "tribopipe/data/aliases.toml")


def load_aliases(path: str | os.PathLike[str] | None = None) -> AliasTable:
    """The built-in table extended by a user file.

    ``path=None`` uses ``configs/aliases.toml`` in the working directory when it exists.
    Raises :class:`ConfigError` for a missing (explicit) or malformed file.
    """
    if path is None:
        if not DEFAULT_USER_FILE.is_file():
            return builtin_aliases()
        path = DEFAULT_USER_FILE
    p = Path(path)
    try:
        return _extend_builtin(p.read_text(encoding="utf-8"), str(p))
    except FileNotFoundError:
        raise ConfigError("alias file not found", path=p) from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError, OSError) as exc:
        raise ConfigError(f"cannot read alias file: {exc}", path=p) from None


@functools.lru_cache(maxsize=8)
def _extend_builtin(text: str, source: str) -> AliasTable:
    """The built-in table extended by a user file's text; parsed once per distinct text,
    since every file of a batch reads the same ``configs/aliases.toml``."""
    return builtin_aliases().extended(tomllib.loads(text), source)


def resolve_aliases(aliases: AliasTable | str | os.PathLike[str] | None) -> AliasTable:
    """Accept an :class:`AliasTable`, a path to a user alias file, or ``None``."""
    if isinstance(aliases, AliasTable):
        return aliases
    return load_aliases(aliases)
