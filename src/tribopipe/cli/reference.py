"""The CLI reference (docs/CLI.md), generated from the commands' own ``--help``.

    python -m tribopipe.cli.reference > docs/CLI.md

A test regenerates it and fails when docs/CLI.md is stale, so the reference cannot drift.
"""

from __future__ import annotations

import click

from . import main

WIDTH = 100


def _context(command: click.Command, name: str, parent: click.Context | None) -> click.Context:
    # make_context applies the command's context_settings (e.g. -h as a help option),
    # as a real invocation does; resilient parsing tolerates the missing arguments
    return command.make_context(
        name, [], parent=parent, resilient_parsing=True,
        terminal_width=WIDTH, max_content_width=WIDTH,
    )


def _walk(command: click.Command, path: list[str], parent: click.Context | None) -> list[str]:
    ctx = _context(command, path[-1], parent)
    parts = [f"{'#' * min(len(path) + 1, 4)} `{' '.join(path)}`", "", "```",
             command.get_help(ctx), "```", ""]
    if isinstance(command, click.Group):
        for name in command.list_commands(ctx):
            sub = command.get_command(ctx, name)
            if sub is not None:
                parts += _walk(sub, [*path, name], ctx)
    return parts


def render_reference() -> str:
    """Markdown text of every command's ``--help``, in the order ``tribopipe --help`` lists."""
    header = [
        "# tribopipe command reference",
        "",
        "Generated from the commands' `--help` by `python -m tribopipe.cli.reference > "
        "docs/CLI.md`; a test fails when this file is stale.",
        "",
    ]
    return "\n".join(header + _walk(main, ["tribopipe"], None)).rstrip() + "\n"


if __name__ == "__main__":
    click.echo(render_reference(), nl=False)
