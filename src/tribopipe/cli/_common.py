"""Shared pieces of the CLI: error translation and common options.

Only click and the standard library are imported here (see ``tribopipe.cli``).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any, TypeVar

import click

F = TypeVar("F", bound=Callable[..., Any])

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


#: what ``--help`` says of the map a command reads without ``--map`` (the rule is
#: :func:`tribopipe.project.find_map`)
MAP_DEFAULT_HELP = ("Default: the map the last `tribopipe batch` run in this folder updated "
                    "(named in ./.tribopipe-map), else processed/friction_map.parquet.")


def resolve_map(ctx: click.Context, param: click.Parameter, value: str | None) -> str | None:
    """The ``--map`` callback: without ``--map``, the map of :func:`tribopipe.project.find_map`,
    said on standard error."""
    if value is not None or ctx.resilient_parsing:
        return value
    return chosen_map(None)


def chosen_map(map_path: str | None) -> str:
    """``map_path`` when given, else the map of :func:`tribopipe.project.find_map`, said on
    standard error: for a command that reads the map only in some cases."""
    if map_path is not None:
        return map_path
    from ..errors import TribopipeError
    from ..project import find_map

    try:
        choice = find_map()
    except TribopipeError as exc:
        raise click.ClickException(str(exc)) from None
    say(choice.note(), err=True)
    return choice.path


def _map_option(func: F, callback: Any) -> F:
    return click.option(
        "--map",
        "map_path",
        # checked by the library (a folder that is not a map, a FIFO, a device: one line)
        type=click.Path(),
        default=None,
        callback=callback,
        help="The friction map (a folder of Parquet parts; a single file still reads). "
             + MAP_DEFAULT_HELP,
    )(func)


def map_option(func: F) -> F:
    """``--map PATH``: the friction map file every map-reading command takes; without it
    the map of :func:`tribopipe.project.find_map`, resolved (and said) as the command is
    parsed."""
    return _map_option(func, resolve_map)


def lazy_map_option(func: F) -> F:
    """``--map PATH`` left ``None`` when not given, for a command that reads the map only
    in some cases: it resolves it with :func:`chosen_map` when it needs it."""
    return _map_option(func, None)


def renamed(old: str, new: str, dest: str, **option: Any) -> Callable[[F], F]:
    """Keep the old spelling ``old`` of the option now called ``new`` (parameter ``dest``)
    working for one release: hidden from ``--help``, and a one-line note naming the new
    spelling when it is used. Giving both is refused."""

    def decorate(func: F) -> F:
        hidden = f"old_{dest}"

        @functools.wraps(func)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            value = kwargs.pop(hidden, None)
            if value is not None and value is not False:
                ctx = click.get_current_context()
                source = ctx.get_parameter_source(dest)
                if source is not None and source.name not in ("DEFAULT", "DEFAULT_MAP"):
                    raise click.UsageError(f"{old} is the old spelling of {new}: give one")
                say(f"note: {old} is now {new} (the old spelling works until the next "
                    "release)", err=True)
                kwargs[dest] = value
            return func(*args, **kwargs)

        return click.option(old, hidden, hidden=True, expose_value=True, **option)(
            wrapper)  # type: ignore[return-value]

    return decorate


def output_option(help_text: str, *, folder: bool = False) -> Callable[[F], F]:
    """``-o/--output PATH``: what a command writes (a file, or a folder with ``folder``)."""
    return click.option(
        "-o", "--output", "output",
        type=click.Path(file_okay=not folder, dir_okay=folder),
        default=None,
        help=help_text,
    )


def read_options(func: F) -> F:
    """``--encoding``, ``--delimiter``, ``--decimal``: force what the readers detect."""
    func = click.option("--decimal", type=click.Choice([".", ","]),
                        help="Force the decimal mark.")(func)
    func = click.option("--delimiter",
                        help="Force the cell delimiter (e.g. ';', ',' or 'tab').")(func)
    return click.option(
        "--encoding", help="Force the file encoding (e.g. utf-16, utf-8-sig, cp1252)."
    )(func)


def instrument_option(func: F) -> F:
    """``--instrument FILE``: an instrument file (TOML); default: the founding T-PID/44 cell.
    ``--config``, its old name, still works for one release."""
    func = renamed("--config", "--instrument", "instrument_path",
                   type=click.Path(exists=True, dir_okay=False))(func)
    return click.option(
        "--instrument",
        "instrument_path",
        type=click.Path(exists=True, dir_okay=False),
        default=None,
        help="Instrument file (TOML, see configs/instruments/). "
        "Default: the T-PID/44 cell, 3 pins, r = 3 mm.",
    )(func)


def material_filters(source: Any, pin: Any, disc: Any) -> tuple[Any, Any]:
    """``--pin`` and ``--disc`` of a command that reads the map (each a name, a tuple of
    names or ``None``) resolved through the materials vocabulary (the shipped one and
    ./materials.toml) against the names the map ``source`` (a path or an open snapshot)
    holds: :meth:`tribopipe.materials.Vocabulary.filter_name`, the one rule; an unknown
    name is refused in one line with a did-you-mean."""
    if pin is None and disc is None or pin == () and disc == ():
        return pin, disc
    from ..frictionmap.snapshot import as_snapshot
    from ..materials import lab_files, load_vocabulary

    vocabulary = load_vocabulary(lab_files("."))
    runs = as_snapshot(source, ["pin", "disc"]).runs

    def one(what: str, value: Any) -> Any:
        if value is None:
            return None
        held = runs[what].dropna().astype(str).unique().tolist() if what in runs else []
        if isinstance(value, tuple):
            return tuple(vocabulary.filter_name(v, what, held) for v in value)
        return vocabulary.filter_name(value, what, held)

    return one("pin", pin), one("disc", disc)
