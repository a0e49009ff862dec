"""The ``tribopipe`` command line: thin click commands over the library.

Each command lives in its own module of this package and is imported only when it is
invoked or listed, and those modules import only click and the standard library at module
level, so ``tribopipe --help`` never loads numpy, pandas, scipy or matplotlib.
"""

from __future__ import annotations

import importlib

import click

from .. import __version__

#: command name -> "module:attribute", in the order ``--help`` lists them
COMMANDS: dict[str, str] = {
    "inspect": "tribopipe.cli.inspect:inspect_cmd",
    "reduce": "tribopipe.cli.reduce:reduce_cmd",
    "batch": "tribopipe.cli.campaign:batch_cmd",
    "campaign": "tribopipe.cli.campaign:campaign_group",
    "map": "tribopipe.cli.map:map_group",
    "materials": "tribopipe.cli.materials:materials_group",
    "query": "tribopipe.cli.query:query_cmd",
    "explore": "tribopipe.cli.explore:explore_cmd",
    "export": "tribopipe.cli.export:export_group",
    "plot": "tribopipe.cli.plot:plot_group",
    "report": "tribopipe.cli.report:report_cmd",
    "review": "tribopipe.cli.review:review_cmd",
    "hub": "tribopipe.cli.hub:hub_group",
}


class LazyGroup(click.Group):
    """A group that imports a command's module only when the command is needed."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return list(COMMANDS)

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        target = COMMANDS.get(cmd_name)
        if target is None:
            return None
        module_name, attr = target.split(":")
        return getattr(importlib.import_module(module_name), attr)


@click.group(cls=LazyGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="tribopipe")
def main() -> None:
    """Turn rheometer pin-on-disc friction exports into a friction map.

    \b
    Typical use:
      tribopipe inspect run.csv              what a raw export holds
      tribopipe reduce run.csv --pin "Ecoflex 00-50" --disc steel --force 3 --temperature 20
      tribopipe batch configs/example.toml   a whole campaign, incrementally
      tribopipe map table --format markdown  the friction map's group table
      tribopipe export abaqus -o friction.inp
    """
