"""``tribopipe export FORMAT``: simulator input from the map, one command per format of
:data:`tribopipe.export.formats.ENTRIES`, its options those the format declares.

The formats are imported when a command is listed or run (that module imports only the
standard library), so that ``tribopipe --help`` stays light.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import click

from ._common import friendly_errors, map_option, material_filters, say

if TYPE_CHECKING:
    from ..export.formats import Format, Option


class _FormatGroup(click.Group):
    """The ``export`` group: one command per registered format, built when needed."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        from ..export.formats import FORMATS

        return list(FORMATS)

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        from ..export.formats import ENTRIES

        for entry in ENTRIES:
            if entry.name == cmd_name:
                return _command(entry)
        return None


@click.group("export", cls=_FormatGroup)
def export_group() -> None:
    """Simulator input from the friction map (μ_K tables or single values).

    Every file says in its header which engine version it was checked against, which
    coefficient it holds (μ_K or μ_S) and how the engine combines two surfaces' values.
    """


def _selection(func: Callable[..., Any]) -> Callable[..., Any]:
    """--pin/--disc/--temperature/--pressure, --map and -o shared by every format."""
    from ..export.formats import condition_labels

    for option in reversed(
        [
            click.option("--pin", help="Pin material. Default: every pin for a table; "
                         "for one condition, the map's only pin (else required)."),
            click.option("--disc", help="Disc material. Default: every disc for a table; "
                         "for one condition, the pin's only disc (else required)."),
            click.option(
                "--temperature",
                "temperature_C",
                type=float,
                help="One temperature [°C] (interpolated). Default: every measured one for "
                "a table; for one condition, the pair's only one (else required).",
            ),
            click.option(
                "--pressure",
                "pressure_kPa",
                type=float,
                help="Contact pressure [kPa] for single-condition input ("
                + ", ".join(condition_labels()) + "). Default: the pair's only measured "
                "pressure (else required).",
            ),
            click.option(
                "--speed",
                "speed_mm_s",
                type=float,
                help="Sliding speed [mm/s] for single-condition input (interpolated in "
                "log v). Default: the pair's only measured speed (else required).",
            ),
            click.option(
                "--method",
                "method",
                metavar="METHOD",
                help="Test method for single-condition input, e.g. 'sled D1894'. Default: "
                "the pair's only method (else required: methods are never pooled).",
            ),
            map_option,
            click.option(
                "-o",
                "--output",
                type=click.Path(dir_okay=False, writable=True),
                help="Write to FILE instead of standard output.",
            ),
        ]
    ):
        func = option(func)
    return func


def _click_option(option: Option) -> Callable[..., Any]:
    """The click option a writer's :class:`Option` declares."""
    if option.kind is bool:
        return click.option(option.flag, option.name, is_flag=True, help=option.help)
    kind: Any = click.Choice(option.choices) if option.choices else option.kind
    return click.option(option.flag, option.name, type=kind, default=option.default,
                        show_default=option.default is not None, help=option.help)


def _emit(text: str, output: str | None) -> None:
    """Print ``text`` or write it to ``output`` (UTF-8, LF, atomically)."""
    if output is None:
        click.echo(text, nl=False)
        return
    from ..files import write_text_atomic

    write_text_atomic(output, text, newline="\n")
    say(f"wrote {output}", err=True)


def _command(entry: Format) -> click.Command:
    """The ``export`` subcommand of format ``entry``: the selection, then its own options."""

    def run(output: str | None, map_path: str, **options: Any) -> None:
        from ..export.simulators import MAP_COLUMNS, export_from_map
        from ..frictionmap.snapshot import open_map

        def note(text: str) -> None:
            say(f"note: {text}", err=True)

        # the columns it reads: a map folder's groups are stored, not grouped again
        snap = open_map(map_path, MAP_COLUMNS)
        options["pin"], options["disc"] = material_filters(snap, options["pin"],
                                                           options["disc"])
        _emit(export_from_map(snap, entry.name, on_note=note, **options), output)

    run.__doc__ = entry.title + (f"\n\n{entry.description}" if entry.description else "")
    func: Callable[..., Any] = friendly_errors(run)
    for option in reversed(entry.options):
        func = _click_option(option)(func)
    return click.command(entry.name)(_selection(func))

