"""The simulator writers: which functions write each format of
:data:`tribopipe.export.formats.ENTRIES`, imported and typed, the one list
:mod:`tribopipe.export.simulators` and the explorer page read.

Each :class:`Writer` holds its :class:`~tribopipe.export.formats.Format`, the
:class:`~tribopipe.export.headers.Engine` its header describes and the writer functions
themselves (no function is named as text), each typed by a protocol below, so that mypy
checks every writer's signature where it is registered:

- :class:`TableWriter` ``(groups, *, pin, disc, temperature_C, source, **options)``: the
  group table, plus ``slip_rates`` (every pair's) where the format has ``slip_rate``;
- :class:`ConditionWriter` ``(res, *, source, **options)``: one query result
  (:class:`tribopipe.query.QueryResult`), plus ``slip_rate`` (the pair's
  :class:`~tribopipe.export.slip_rates.SlipRate`) where the format has ``slip_rate``, and
  ``speed_curve`` (μ_K at each measured sliding speed of the pair at the condition,
  :func:`~tribopipe.export.speed_tables.speed_curve`) where it has ``speed_curve``;
- :class:`SnippetWriter` ``(res, *, source)`` and :class:`SnippetHeader` ``(*, source)``:
  the text the explorer copies for one condition, and its lines that do not depend on the
  condition (rendered into the page).

``**options`` are the format's own (:class:`~tribopipe.export.formats.Option`), each a
keyword argument with a default; a test holds them equal to what the format declares.
A writer never queries the map itself. This module imports every writer (numpy and
pandas with them): the command line lists the formats from
:mod:`~tribopipe.export.formats` alone.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

from ..errors import ExportError
from .drake import DRAKE, drake_header, write_drake
from .fe_decks import (
    ABAQUS,
    ANSYS,
    LSDYNA,
    abaqus_snippet,
    abaqus_snippet_header,
    ansys_snippet,
    ansys_snippet_header,
    write_abaqus,
    write_abaqus_decay,
    write_ansys,
    write_lsdyna,
)
from .formats import ENTRIES, FORMATS, Format
from .headers import Engine
from .pybullet import PYBULLET, pybullet_header, write_pybullet
from .scenes import MUJOCO, PYELASTICA, SOFA, write_mujoco, write_pyelastica, write_sofa
from .usd import USD, usd_header, write_usd

if TYPE_CHECKING:
    import pandas as pd

    from ..query import QueryResult


class TableWriter(Protocol):
    """Every pair's table of a format (the format's own options as keyword arguments with
    defaults)."""

    def __call__(self, groups: pd.DataFrame, /, *, pin: str | None, disc: str | None,
                 temperature_C: float | None, source: str | None) -> str: ...


class ConditionWriter(Protocol):
    """One condition's file of a format (its own options as keyword arguments with
    defaults)."""

    def __call__(self, res: QueryResult, /, *, source: str | None) -> str: ...


class SnippetWriter(Protocol):
    """What the explorer page copies for one condition."""

    def __call__(self, res: QueryResult, /, *, source: str | None) -> str: ...


class SnippetHeader(Protocol):
    """The lines of a snippet that do not depend on the condition."""

    def __call__(self, *, source: str | None) -> list[str]: ...


@dataclass(frozen=True)
class Writer:
    """One simulator format's writers: the functions its :class:`Format` declares it has,
    and none it does not (checked when the entry is made)."""

    format: Format
    engine: Engine
    table: TableWriter | None = None
    condition: ConditionWriter | None = None
    snippet: SnippetWriter | None = None
    snippet_header: SnippetHeader | None = None

    def __post_init__(self) -> None:
        has = {"table": self.table is not None, "condition": self.condition is not None,
               "snippet": self.snippet is not None and self.snippet_header is not None}
        said = {"table": self.format.table, "condition": self.format.condition,
                "snippet": self.format.snippet}
        if has != said or (self.snippet is None) != (self.snippet_header is None):
            raise TypeError(f"the writers of {self.format.name} are not those its format "
                            f"declares: {has} against {said}")

    @property
    def name(self) -> str:
        """The format's name (``abaqus``)."""
        return self.format.name


def _entry(name: str) -> Format:
    """The :class:`Format` of :data:`~tribopipe.export.formats.ENTRIES` called ``name``."""
    return next(f for f in ENTRIES if f.name == name)


#: every simulator format's writers, in the order of :data:`~tribopipe.export.formats.ENTRIES`
WRITERS: tuple[Writer, ...] = (
    Writer(_entry("abaqus"), ABAQUS, table=write_abaqus, condition=write_abaqus_decay,
           snippet=abaqus_snippet, snippet_header=abaqus_snippet_header),
    Writer(_entry("ansys"), ANSYS, table=write_ansys,
           snippet=ansys_snippet, snippet_header=ansys_snippet_header),
    Writer(_entry("lsdyna"), LSDYNA, condition=write_lsdyna),
    Writer(_entry("mujoco"), MUJOCO, condition=write_mujoco),
    Writer(_entry("sofa"), SOFA, condition=write_sofa),
    Writer(_entry("pyelastica"), PYELASTICA, condition=write_pyelastica),
    Writer(_entry("usd"), USD, condition=write_usd,
           snippet=write_usd, snippet_header=usd_header),
    Writer(_entry("pybullet"), PYBULLET, condition=write_pybullet,
           snippet=write_pybullet, snippet_header=pybullet_header),
    Writer(_entry("drake"), DRAKE, condition=write_drake,
           snippet=write_drake, snippet_header=drake_header),
)


def writer_named(fmt: str) -> Writer:
    """The :class:`Writer` of format ``fmt``, or an :class:`ExportError` listing them."""
    for writer in WRITERS:
        if writer.name == fmt:
            return writer
    raise ExportError(f"unknown simulator {fmt!r}; expected one of {', '.join(FORMATS)}")
