"""``tribopipe materials``: the materials vocabulary (list, check a name, add one)."""

from __future__ import annotations

from typing import Any

import click

from ._common import friendly_errors, say

_FILE_HELP = ("A lab's materials file that extends the shipped vocabulary (repeatable); "
              "default: materials.toml in the current folder when it is there.")


def _vocabulary(files: tuple[str, ...]) -> Any:
    from pathlib import Path

    from ..materials import LAB_FILE, load_vocabulary

    chosen = list(files) or ([LAB_FILE] if Path(LAB_FILE).is_file() else [])
    return load_vocabulary(chosen)


@click.group("materials")
def materials_group() -> None:
    """The materials vocabulary: every pin and disc name is resolved through it.

    The package ships the materials of the founding map and a few more; a lab adds its
    own in materials.toml beside its campaign config (one line each).
    """


@materials_group.command("list")
@click.option("--materials", "files", multiple=True, type=click.Path(dir_okay=False),
              help=_FILE_HELP)
@friendly_errors
def list_cmd(files: tuple[str, ...]) -> None:
    """List every material: canonical name, class, identifying properties, aliases."""

    for m in _vocabulary(files).materials:
        aliases = f"  [{', '.join(m.aliases)}]" if m.aliases else ""
        say(f"{m.describe()}{aliases}")


@materials_group.command("check")
@click.argument("names", nargs=-1, required=True)
@click.option("--materials", "files", multiple=True, type=click.Path(dir_okay=False),
              help=_FILE_HELP)
@friendly_errors
def check_cmd(names: tuple[str, ...], files: tuple[str, ...]) -> None:
    """Resolve NAMES: print each one's canonical name, or why it does not resolve.

    Exits 1 when a name is unknown or ambiguous.
    """

    vocabulary = _vocabulary(files)
    bad = False
    for name in names:
        problem = vocabulary.problem(name)
        if problem is None:
            say(f"{name} -> {vocabulary.candidates(name)[0]}")
        else:
            bad = True
            say(problem, err=True)
    if bad:
        raise SystemExit(1)


@materials_group.command("add")
@click.argument("name")
@click.option("--class", "material_class", required=True,
              help="silicone elastomer, elastomer, metal, polymer, glass, ceramic, wood, "
                   "paper, composite or other.")
@click.option("--alias", "aliases", multiple=True,
              help="Another spelling, vendor code or translation (repeatable).")
@click.option("--supplier", default="", help="Who sells it.")
@click.option("--shore", default="", help="Shore hardness as the supplier states it (30A).")
@click.option("--finish", default="", help="The surface finish, for a disc.")
@click.option("--note", default="", help="Anything else that identifies it.")
@click.option("--file", "path", default="materials.toml", show_default=True,
              type=click.Path(dir_okay=False),
              help="The lab's materials file to add it to (created when missing).")
@friendly_errors
def add_cmd(name: str, material_class: str, aliases: tuple[str, ...], supplier: str,
            shore: str, finish: str, note: str, path: str) -> None:
    """Add a new material NAME to a lab's materials file, as one line.

    Refused when NAME or an alias already names a material.
    """
    from ..errors import ConfigError
    from ..materials import CLASSES, Material, add_material

    if material_class not in CLASSES:
        raise ConfigError(f"--class {material_class!r}: expected one of {', '.join(CLASSES)}")
    line = add_material(path, Material(name=name, material_class=material_class,
                                       aliases=aliases, supplier=supplier, shore=shore,
                                       finish=finish, note=note, origin=path))
    say(f"added to {path}: {line}")
