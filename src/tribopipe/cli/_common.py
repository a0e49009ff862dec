"""Shared pieces of the CLI: error translation and common options.

Only click and the standard library are imported here (see ``tribopipe.cli``).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any, TypeVar

import click

F = TypeVar("F", bound=Callable[..., Any])

DEFAULT_MAP = "processed/friction_map.parquet"


def friendly_errors(func: F) -> F:
    """Turn library errors (:class:`tribopipe.errors.TribopipeError`) into one clean line."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        from ..errors import TribopipeError

        try:
            return func(*args, **kwargs)
        except TribopipeError as exc:
            raise click.ClickException(str(exc)) from None

    return wrapper  # type: ignore[return-value]


def say(message: str, *, err: bool = False) -> None:
    """Print one message line as a terminal line (:func:`tribopipe.escape.printable`): a
    newline, a carriage return or a bidi override in a name or path can neither split the
    line nor hide or reorder what follows."""
    from ..escape import printable

    click.echo(printable(message), err=err)


def map_option(func: F) -> F:
    """``--map PATH``: the friction map every map-touching command takes."""
    return click.option(
        "--map",
        "map_path",
        # checked by the library (a folder that is not a map, a FIFO, a device: one line)
        type=click.Path(),
        default=DEFAULT_MAP,
        show_default=True,
        help="The friction map (a Parquet folder of parts; a single file still reads).",
    )(func)


def read_options(func: F) -> F:
    """``--encoding``, ``--delimiter``, ``--decimal``: force what the readers detect."""
    func = click.option("--decimal", type=click.Choice([".", ","]),
                        help="Force the decimal mark.")(func)
    func = click.option("--delimiter",
                        help="Force the cell delimiter (e.g. ';', ',' or 'tab').")(func)
    return click.option(
        "--encoding", help="Force the file encoding (e.g. utf-16, utf-8-sig, cp1252)."
    )(func)


def config_option(func: F) -> F:
    """``--config FILE``: an instrument config (TOML); default: the founding T-PID/44 cell."""
    return click.option(
        "--config",
        "config_path",
        type=click.Path(exists=True, dir_okay=False),
        default=None,
        help="Instrument config (TOML, see configs/instruments/). Default: T-PID/44, 3 pins.",
    )(func)
