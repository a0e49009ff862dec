"""Which friction map a command reads when it is given no ``--map``: one rule.

``tribopipe batch`` (and ``campaign run``) records the map it updated in a project file,
``.tribopipe-map``, in the folder it was run from. Every command run from that folder
without ``--map`` reads that map and says so. Without the file, the map is
``processed/friction_map.parquet``. ``--map`` always wins.

The project file holds one line: the map's path, relative to the folder when the map is
below it. It is read as outside text: more than one line, control characters or a name
that is not a ``.parquet`` file are refused in one line that says how to fix it.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from .errors import ConfigError
from .files import read_regular, write_text_atomic
from .layout import DEFAULT_OUTPUT_DIR, MAP_FILE

#: the project file, in the folder commands are run from
PROJECT_FILE = ".tribopipe-map"
#: the map when there is no project file (relative to the folder commands are run from)
DEFAULT_MAP = f"{DEFAULT_OUTPUT_DIR}/{MAP_FILE}"
#: a map's path is short; a larger project file is not ours
_MAX_BYTES = 4096


@dataclass(frozen=True)
class MapChoice:
    """The map a command reads, and why that one."""

    path: str
    #: ``"project"`` (named by the project file) or ``"default"``
    source: str

    def note(self) -> str:
        """One line saying which map is used and why (for standard error)."""
        why = (f"from ./{PROJECT_FILE}, written by the last `tribopipe batch` here"
               if self.source == "project" else
               f"the default; no ./{PROJECT_FILE} here, pass --map to choose")
        return f"map: {self.path} ({why})"


def find_map(folder: str | os.PathLike[str] = ".") -> MapChoice:
    """The map a command run from ``folder`` reads without ``--map``: the project file's,
    else :data:`DEFAULT_MAP`. :class:`ConfigError` naming the project file when it is not
    one line naming a ``.parquet`` file."""
    project = Path(folder) / PROJECT_FILE
    if not project.exists() and not project.is_symlink():
        return MapChoice(DEFAULT_MAP, "default")
    fix = "delete it, or run `tribopipe batch` here again"
    try:
        text = read_regular(project, max_bytes=_MAX_BYTES, what="a project file").decode("utf-8")
    except UnicodeDecodeError:
        raise ConfigError(f"not UTF-8; expected one line naming the map ({fix})",
                          path=project) from None
    lines = [line for line in text.splitlines() if line.strip()]
    if len(lines) != 1:
        raise ConfigError(f"holds {len(lines)} lines; expected one naming the map ({fix})",
                          path=project)
    name = lines[0].strip()
    if any(ord(c) < 32 or ord(c) == 127 for c in name) or not name.endswith(".parquet"):
        raise ConfigError(f"expected the path of a .parquet map ({fix})", path=project)
    return MapChoice(name, "project")


def remember_map(map_path: str | os.PathLike[str], folder: str | os.PathLike[str] = ".") -> Path:
    """Write the project file in ``folder``: later commands run there without ``--map`` read
    ``map_path``. Returns the project file; :class:`tribopipe.errors.OutputError` when it
    cannot be written."""
    base = Path(folder).resolve()
    target = Path(map_path).resolve()
    try:
        name = target.relative_to(base).as_posix()
    except ValueError:
        name = str(target)
    return write_text_atomic(base / PROJECT_FILE, name + "\n", newline="\n")
