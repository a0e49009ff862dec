"""Typed, user-facing errors.

Every problem a user can cause (a bad file, a bad config, a map that is not ours) is raised
as a :class:`TribopipeError` whose ``str()`` is one line naming the file, the place in it
(line and/or column where known) and what was expected. The CLI prints that line; it never
shows a traceback for these.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from os import PathLike

from .escape import display_path, printable


@dataclass(frozen=True)
class Failure:
    """What went wrong, as fields: the ``problem``, the file it concerns (``path``, as
    messages name it), the ``line`` and ``column`` in it and a ``hint`` for the fix.
    ``place`` says where in the file (``test / result / interval i`` of an export).
    :meth:`text` formats them, the one place a failure becomes a line (every
    :class:`TribopipeError`'s message too): nothing parses a line back into its parts."""

    problem: str
    path: str | None = None
    line: int | None = None
    column: str | None = None
    hint: str | None = None
    place: str | None = None

    def text(self) -> str:
        """``path [place]:line: problem (column 'c'); hint: ...``, leaving out what is
        unknown: one printable line whatever the fields hold."""
        where = ""
        if self.path is not None:
            where = display_path(self.path)
            if self.place:
                where += f" [{self.place}]"
            if self.line is not None:
                where += f":{self.line}"
            where += ": "
        elif self.place:
            where = f"{self.place}: " if self.line is None else f"{self.place}, line {self.line}: "
        elif self.line is not None:
            where = f"line {self.line}: "
        text = where + self.problem
        if self.column is not None:
            text += f" (column {self.column!r})"
        if self.hint:
            text += f"; hint: {self.hint}"
        # names and cells in a message are data: one printable line whatever they hold
        return printable(text.replace("\n", " "))


class TribopipeError(Exception):
    """Base class: a problem the user can fix, described in one line."""

    def __init__(
        self,
        problem: str,
        *,
        path: str | PathLike[str] | None = None,
        line: int | None = None,
        column: str | None = None,
        hint: str | None = None,
        place: str | None = None,
    ) -> None:
        self.problem = problem
        self.place = place
        self.path = None if path is None else os.fsdecode(path)
        self.line = line
        self.column = column
        self.hint = hint
        super().__init__(self.failure.text())

    @property
    def failure(self) -> Failure:
        """The error's fields as a :class:`Failure`."""
        return Failure(self.problem, self.path, self.line, self.column, self.hint, self.place)


class ValidationError(TribopipeError, ValueError):
    """A value (a name, a number, a count) is not what its key or column expects."""


class OutputError(TribopipeError):
    """An output file or folder cannot be written (read-only, full, not a folder...)."""


class ReadError(TribopipeError):
    """A raw export could not be read: wrong encoding, not an export, truncated, ..."""


class MissingQuantityError(ReadError):
    """A required quantity (torque, normal force, ...) has no matching column."""


class NotFrictionTestError(ReadError):
    """The export holds no pin-on-disc friction test: no steady rotation in one direction
    under normal force (an oscillation, a flow curve, a relaxation test ...); ``looks_like``
    names what its test looks like instead, where that is known."""

    def __init__(self, problem: str, *, looks_like: str | None = None,
                 path: str | PathLike[str] | None = None, line: int | None = None,
                 column: str | None = None, hint: str | None = None,
                 place: str | None = None) -> None:
        self.looks_like = looks_like
        super().__init__(problem, path=path, line=line, column=column, hint=hint, place=place)


class ConfigError(TribopipeError):
    """A config file (instrument, campaign, aliases) is missing a key or has a bad value."""


class ReductionError(TribopipeError):
    """A measurement could be read but not reduced to mu_s / mu_k (no contact, no sliding...)."""


class MapError(TribopipeError):
    """The friction map at a path is corrupt, foreign, or an operation on it was refused."""


class RowError(MapError):
    """A map row breaks a rule of the row table: ``row`` names the row (``"row 3
    (ab12…)"``), ``row_problem`` says what is wrong with it, as fields; the message joins
    them once."""

    def __init__(self, row_problem: str, *, row: str, column: str | None = None,
                 path: str | PathLike[str] | None = None, hint: str | None = None) -> None:
        self.row = row
        self.row_problem = row_problem
        super().__init__(f"{row}: {row_problem}", path=path, column=column, hint=hint)


class CampaignError(TribopipeError):
    """A campaign's files or metadata are missing or contradictory."""


class ExportError(TribopipeError):
    """Simulator input or a table cannot be written for the requested selection."""
