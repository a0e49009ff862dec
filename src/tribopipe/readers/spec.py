"""What a format reader declares: how its files are recognised and read.

Each format module (``rheocompass``, ``xlsx``, ``rheoplus``, ``plaincsv``) defines one
:class:`Reader`; :data:`tribopipe.readers.READERS` lists them, and detection, the
``fmt``/``--format`` names, the suffixes a campaign discovers and the "not a recognised
export" hint all read that list. A new format is one module and one entry there.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from .aliases import AliasTable
from .interval import RawInterval
from .textio import DataLine, Row, Run


@dataclass(frozen=True)
class Reader:
    """One export format.

    A text format is recognised from its first rows (``looks_like(rows, aliases)``), its
    data lines start as ``data_line(delimiter)`` says, and ``decimal`` is its decimal
    mark where the cells do not tell. A binary format is recognised by the bytes its
    files start with (``magic``) and gives its rows through ``rows(path)``. Either way
    ``parse(rows, path, aliases)`` returns the file's intervals. ``suffixes`` are the
    file suffixes (lower case) its files carry; ``expects`` says in a few words what a
    file of the format looks like (for the hint when no format recognises a file).
    """

    name: str
    suffixes: tuple[str, ...]
    expects: str
    parse: Callable[[list[Row | Run], str, AliasTable], list[RawInterval]]
    looks_like: Callable[[list[Row], AliasTable], bool] | None = None
    data_line: Callable[[str], DataLine] | None = None
    decimal: str = ","
    magic: bytes | None = None
    rows: Callable[[str], list[Row]] | None = None
