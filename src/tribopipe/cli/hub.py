"""``tribopipe hub``: a friction map that many labs grow together, in one folder."""

from __future__ import annotations

from pathlib import Path

import click

from ._common import friendly_errors, say


@click.group("hub")
def hub_group() -> None:
    """A hub: one folder (kept in git) where many labs' friction-map packages meet,
    each checked from its own evidence, merged into one map and published as a site.

    \b
    tribopipe hub init DIR                 start a hub
    tribopipe hub check PACKAGE --hub DIR  check a contribution (one line per problem)
    tribopipe hub add PACKAGE --hub DIR    check it and file it under its lab and release
    tribopipe hub build DIR -o SITE        the merged map and the static site
    """


@hub_group.command("init")
@click.argument("folder", type=click.Path(file_okay=False))
@click.option("--title", default="Friction map hub", show_default=True,
              help="The hub's title (its README, citation and site).")
@friendly_errors
def init_cmd(folder: str, title: str) -> None:
    """Start a hub in FOLDER (new or empty): labs/ (one folder per lab and release), a
    README for contributors, CITATION.cff and .zenodo.json for release DOIs, and a GitHub
    Actions workflow that runs `tribopipe hub check --hub .` on every pull request."""
    from ..hub.folder import init_hub

    files = init_hub(Path(folder), title=title)
    say(f"started a hub in {folder}: {', '.join(files)}")


@hub_group.command("check")
@click.argument("package", required=False, type=click.Path())
@click.option("--hub", "hub_dir", required=True, type=click.Path(file_okay=False),
              help="The hub folder.")
@friendly_errors
def check_cmd(package: str | None, hub_dir: str) -> None:
    """Check PACKAGE as a contribution to the hub: the package's schema and row rules,
    every μ re-derived from its traces and raw exports (`map validate --recompute`), the
    materials vocabulary, raw content the hub holds under another lab (refused), and
    conflicts with the hub's rows. Without PACKAGE, every package of the hub is checked
    against those filed before it (what the pull-request workflow runs).

    Prints one line per problem; exit code 1 on any.
    """
    from ..hub.check import check_against_hub, check_hub

    checks = (check_hub(Path(hub_dir)) if package is None
              else [check_against_hub(Path(package), Path(hub_dir))])
    bad = 0
    for result in checks:
        for line in result.problems:
            say(line)
        if result.ok:
            say(result.verdict())
        else:
            bad += 1
            say(f"{result.path}: refused, {len(result.problems)} problem(s)")
    if package is None:
        say(f"{len(checks)} packages checked, {bad} refused")
    if bad:
        raise SystemExit(1)


@hub_group.command("add")
@click.argument("package", type=click.Path())
@click.option("--hub", "hub_dir", required=True, type=click.Path(file_okay=False),
              help="The hub folder.")
@friendly_errors
def add_cmd(package: str, hub_dir: str) -> None:
    """Check PACKAGE as `hub check` does and, when it passes, file it in the hub under
    labs/<lab>/<release>/. A package with any problem is not filed (exit code 1)."""
    from ..hub.check import check_against_hub
    from ..hub.folder import file_package

    result = check_against_hub(Path(package), Path(hub_dir))
    for line in result.problems:
        say(line)
    if not result.ok:
        say(f"{package}: not added, {len(result.problems)} problem(s)")
        raise SystemExit(1)
    filed = file_package(Path(package), Path(hub_dir))
    say(f"added {filed.lab}, release {filed.release}, as {filed.where}")


@hub_group.command("build")
@click.argument("hub_dir", metavar="DIR", type=click.Path(file_okay=False))
@click.option("-o", "--output", "output", required=True, type=click.Path(file_okay=False),
              help="The site folder to write (replaced whole when hub build wrote it).")
@friendly_errors
def build_cmd(hub_dir: str, output: str) -> None:
    """Write the hub's merged map (Parquet and CSV; each lab's newest release) and a static
    site into OUTPUT: the labs with a filter and colour per lab, the explorer over all
    labs, one page per lab (contact, citation as BibTeX and CFF, releases, conditions),
    the inter-lab comparisons, a changelog per release and the downloads of the merged
    map and every package. It works from file:// and on GitHub Pages."""
    from ..hub.site import build_site

    site = build_site(Path(hub_dir), Path(output))
    say(f"wrote {site.path}: {site.n_runs} runs of {len(site.labs)} labs from "
        f"{site.n_packages} packages (open {site.path}/index.html)")
