"""The hub's folder: its layout, the files ``hub init`` writes, its packages, and filing a
new one (``hub add``).

A lab's packages sit in ``labs/<lab>/<release>/``: ``<lab>`` is the lab's name made a
folder name (:func:`lab_slug`), ``<release>`` the package's release date (its
descriptor's ``version``, ``YYYY-MM-DD``). A lab's releases are successive versions of its
map: the newest one is the lab's part of the merged map (:func:`latest_releases`).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import stat
import tempfile
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .. import __version__
from ..errors import ExportError, MapError
from ..escape import markdown_cell, yaml_text
from ..files import write_text_atomic
from ..frictionmap.datapackage import DESCRIPTOR, PackageRefused, load_descriptor

#: the hub's own files
HUB_FILE = "hub.toml"
LABS_DIR = "labs"
WORKFLOW = ".github/workflows/hub-check.yml"
#: the command the workflow runs on every pull request (held by a test that runs it)
CHECK_COMMAND = "tribopipe hub check --hub ."
_RELEASE = re.compile(r"\d{4}-\d{2}-\d{2}")


def lab_slug(lab: str) -> str:
    """A lab's folder name: lower-case letters and digits joined by ``-`` (never empty,
    never a path)."""
    return re.sub(r"[^a-z0-9]+", "-", lab.casefold()).strip("-")[:80] or "lab"


@dataclass(frozen=True)
class HubPackage:
    """A package filed in the hub: its folder, lab folder name, release, and the lab and
    title its descriptor names."""

    path: Path
    slug: str
    release: str
    lab: str
    title: str

    @property
    def where(self) -> str:
        """Its place in the hub: ``labs/<lab>/<release>``."""
        return f"{LABS_DIR}/{self.slug}/{self.release}"


def hub_title(hub: Path) -> str:
    """The hub's title from ``hub.toml``; :class:`MapError` when ``hub`` is not a hub."""
    path = Path(hub) / HUB_FILE
    if not path.is_file():
        raise MapError(f"not a tribopipe hub (no {HUB_FILE})", path=hub,
                       hint="make one with `tribopipe hub init DIR`")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise MapError(f"not valid TOML: {exc}", path=path) from None
    title = data.get("hub", {}).get("title") if isinstance(data.get("hub"), dict) else None
    return str(title) if isinstance(title, str) and title.strip() else "Friction map hub"


def package_identity(path: Path) -> tuple[str, str, str]:
    """``(lab, release, title)`` of a package's descriptor; :class:`MapError` when it has
    none (the package check says why in full)."""
    try:
        descriptor, _ = load_descriptor(Path(path) / DESCRIPTOR if Path(path).is_dir()
                                        else Path(path))
    except PackageRefused as exc:
        raise MapError(exc.problem, path=path) from None
    info = descriptor.get("tribopipe")
    lab = info.get("lab") if isinstance(info, dict) else None
    release = descriptor.get("version")
    if not isinstance(lab, str) or not lab.strip():
        raise MapError("the package names no lab", path=path)
    if not isinstance(release, str) or not _RELEASE.fullmatch(release):
        raise MapError(f"release {release!r}, expected the package's date YYYY-MM-DD",
                       path=path)
    title = descriptor.get("title")
    return lab.strip(), release, str(title) if isinstance(title, str) else lab


def hub_packages(hub: Path) -> list[HubPackage]:
    """Every package of the hub, by release date then lab folder."""
    hub_title(hub)
    out = []
    for desc in sorted((Path(hub) / LABS_DIR).glob(f"*/*/{DESCRIPTOR}")):
        folder = desc.parent
        if folder.is_symlink() or folder.parent.is_symlink():
            continue
        try:
            lab, _, title = package_identity(folder)
        except MapError:
            lab, title = folder.parent.name, folder.parent.name
        out.append(HubPackage(folder, folder.parent.name, folder.name, lab, title))
    return sorted(out, key=lambda p: (p.release, p.slug))


def latest_releases(packages: list[HubPackage]) -> list[HubPackage]:
    """Each lab's newest release (by lab folder), in lab order."""
    newest: dict[str, HubPackage] = {}
    for p in packages:
        if p.slug not in newest or p.release > newest[p.slug].release:
            newest[p.slug] = p
    return [newest[k] for k in sorted(newest)]


# --------------------------------------------------------------------------- hub init


def init_hub(folder: Path, *, title: str) -> list[str]:
    """Write a new hub in ``folder`` (absent or empty): the layout, README, citation,
    Zenodo metadata and the pull-request workflow; returns the files written.
    :class:`ExportError` when ``folder`` holds anything already."""
    folder = Path(folder)
    if folder.exists() and (not folder.is_dir() or any(folder.iterdir())):
        raise ExportError("exists and is not an empty folder; a hub starts empty",
                          path=folder)
    title = " ".join(title.split())
    if not title or len(title) > 200:
        raise ExportError("a hub needs a title of one line, at most 200 characters")
    files = {
        HUB_FILE: f"[hub]\ntitle = {json.dumps(title, ensure_ascii=False)}\n",
        "README.md": hub_readme(title),
        "CITATION.cff": hub_citation(title),
        ".zenodo.json": json.dumps(zenodo_metadata(title), indent=2, ensure_ascii=False)
        + "\n",
        WORKFLOW: workflow_yaml(),
        f"{LABS_DIR}/README.md": "One folder per lab, one sub-folder per release "
                                 "(`tribopipe hub add` files them).\n",
        ".gitignore": "site/\n",
    }
    for rel, text in files.items():
        target = folder / rel
        target.parent.mkdir(parents=True, exist_ok=True)
        write_text_atomic(target, text)
    return list(files)


def hub_readme(title: str) -> str:
    """The contributor README of a new hub."""
    return f"""# {markdown_cell(title)}

A friction map that many labs grow together. Each lab's contributions are friction-map
data packages written by tribopipe, one folder per lab and release under `labs/`. Every
value in them can be re-derived from the lab's own reduced traces (and raw exports, where
the lab includes them).

## Contribute your lab's runs

1. Reduce your campaign with tribopipe (`tribopipe batch configs/mine.toml`).
2. Publish it with its evidence:
   `tribopipe map publish -o my-package --lab "Your Lab" --contact "Name"
   --email you@lab.example --with-raw --raw-dir raw/mine`
3. Check it against this hub: `tribopipe hub check my-package --hub .`
   It prints one line per problem and exits non-zero on any.
4. File it: `tribopipe hub add my-package --hub .` (it lands in `labs/<lab>/<release>/`).
5. Open a pull request. The workflow in `{WORKFLOW}` runs `{CHECK_COMMAND}` on it.

A new release of your lab is a new package with a new date; the newest release of each
lab makes up the merged map.

Pin and disc names must be canonical names of tribopipe's materials vocabulary. A material
it does not know yet is one line in this hub's `materials.toml`, e.g.
`"Mold Star 15" = {{ class = "silicone elastomer", supplier = "Smooth-On" }}` under
`[materials]`, added in the same pull request.

## Build the site

`tribopipe hub build . -o site` writes the merged map (Parquet and CSV) and a static site:
the explorer over all labs, one page per lab with its citation, the inter-lab
comparisons, the downloads and a changelog per release. Open `site/index.html`, or serve
`site/` with GitHub Pages.

## Cite

Cite the hub with `CITATION.cff` and each lab's data with the citation on its page.
"""


def hub_citation(title: str) -> str:
    """The hub's ``CITATION.cff`` (CFF 1.2.0, a dataset by its contributors)."""
    return "\n".join([
        f"# CITATION.cff, written by tribopipe {__version__}",
        'cff-version: "1.2.0"',
        'message: "If you use this friction map, please cite it as below and each lab\'s '
        'data as its page says."',
        'type: "dataset"',
        f"title: {yaml_text(title)}",
        "authors:",
        '  - name: "The contributing labs"',
        'keywords: ["friction", "tribology", "coefficient of friction", "soft robotics"]',
        'license: "CC-BY-4.0"',
    ]) + "\n"


def zenodo_metadata(title: str) -> dict[str, Any]:
    """The ``.zenodo.json`` of a hub: what Zenodo's GitHub integration gives each
    release's DOI."""
    return {
        "title": title,
        "upload_type": "dataset",
        "description": "A friction map grown by many labs: friction-map data packages "
                       "written by tribopipe, each value re-derivable from its traces.",
        "creators": [{"name": "The contributing labs"}],
        "license": "CC-BY-4.0",
        "keywords": ["friction", "tribology", "coefficient of friction", "soft robotics"],
    }


def workflow_yaml() -> str:
    """The GitHub Actions workflow that checks every pull request with
    :data:`CHECK_COMMAND`."""
    return f"""# Written by tribopipe {__version__}: each pull request is checked as `hub add` would
name: hub check
on:
  pull_request:
  push:
    branches: [main]
jobs:
  check:
    runs-on: ubuntu-latest
    steps:
      - uses: actions/checkout@v4
      - uses: actions/setup-python@v5
        with:
          python-version: "3.12"
      - name: Install tribopipe
        run: python -m pip install "tribopipe=={__version__}"
      - name: Check every package of the hub
        run: {CHECK_COMMAND}
"""


def workflow_command(text: str) -> str:
    """The command the workflow's check step runs (what a test runs to hold it)."""
    lines = text.splitlines()
    for i, line in enumerate(lines):
        if line.strip() == "- name: Check every package of the hub":
            run = lines[i + 1].strip()
            if run.startswith("run: "):
                return run[len("run: "):]
    raise MapError("the workflow has no 'Check every package of the hub' step")


# --------------------------------------------------------------------------- hub add


def file_package(package: Path, hub: Path) -> HubPackage:
    """Copy ``package`` into ``labs/<lab>/<release>/`` of ``hub`` (whole or not at all);
    :class:`ExportError` when that release is there already. Check it first
    (:func:`tribopipe.hub.check.check_against_hub`)."""
    lab, release, title = package_identity(package)
    slug = lab_slug(lab)
    target = Path(hub) / LABS_DIR / slug / release
    if target.exists():
        raise ExportError(f"the hub holds a release {release} of {lab} already",
                          path=target, hint="publish the new release with a new date")
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{release}.", dir=target.parent))
    try:
        copy_regular_files(Path(package), tmp / "pkg")
        (tmp / "pkg").rename(target)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return HubPackage(target, slug, release, lab, title)


def copy_regular_files(source: Path, target: Path) -> None:
    """Copy the regular files below ``source`` to ``target`` (made); symbolic links and
    anything else that is not a plain file or folder are left behind, never followed."""
    target.mkdir(parents=True)
    for root, dirs, names in os.walk(source, followlinks=False):
        here = Path(root)
        dest = target / here.relative_to(source)
        dirs[:] = [d for d in dirs if not (here / d).is_symlink()]
        for d in dirs:
            (dest / d).mkdir(exist_ok=True)
        for name in names:
            path = here / name
            if not path.is_symlink() and stat.S_ISREG(path.lstat().st_mode):
                shutil.copyfile(path, dest / name)
