"""``tribopipe inspect``: what a raw export holds, as ``reduce`` will read it."""

from __future__ import annotations

import json

import click

from ._common import friendly_errors, read_options


@click.command("inspect")
@click.argument("file", type=click.Path())  # checked by the reader, one line
@read_options
@click.option(
    "--format",
    "fmt",
    metavar="NAME",
    help="Force the export format instead of detecting it (a name `inspect` prints as "
    "'format:'; an unknown name is refused with the list).",
)
@click.option(
    "--aliases",
    "aliases_path",
    type=click.Path(exists=True, dir_okay=False),
    help="A column-alias file extending the built-in names (default: configs/aliases.toml).",
)
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@friendly_errors
def inspect_cmd(
    file: str,
    encoding: str | None,
    delimiter: str | None,
    decimal: str | None,
    fmt: str | None,
    aliases_path: str | None,
    as_json: bool,
) -> None:
    """List what an export holds: detected format, encoding, delimiter and decimal mark,
    its tests, results and intervals with their point counts, every column with its
    original unit and the SI column it becomes, and the intervals `reduce` will read (one
    run per friction interval of every test)."""
    from ..escape import printable
    from ..readers import describe_export
    from ..reduction.intervals import all_friction_intervals

    summary = describe_export(
        file,
        encoding=encoding,
        delimiter=delimiter,
        decimal=decimal,
        fmt=fmt,
        aliases=aliases_path,
        choose=all_friction_intervals,
    )
    if as_json:
        click.echo(json.dumps(summary.to_dict(), indent=2, ensure_ascii=False,
                              allow_nan=False))
    else:
        # names and units come from the file: one printable line each (no terminal escapes)
        click.echo("\n".join(printable(line) for line in summary.to_text().splitlines()))
