"""Who published a friction-map package, under which licence, and how to cite it: the
``CITATION.cff`` (Citation File Format 1.2.0) and the package's README.

:class:`Publisher` holds the lab, a contact and the data licence (default CC-BY-4.0: others
may reuse the data with attribution). :func:`citation_cff` writes the CFF as YAML by hand —
block style, every text a double-quoted scalar with YAML's escapes, so a name can never
become YAML structure — and always cites the founding paper under ``references``.
:func:`package_readme` is the human-readable account of a package.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from .. import __version__
from ..errors import ExportError
from ..escape import markdown_cell, yaml_text
from ..frictionmap.published import FOUNDING_PAPER

#: SPDX id → (title, URL) of the licences a package may carry; the default first
LICENCES: dict[str, tuple[str, str]] = {
    "CC-BY-4.0": ("Creative Commons Attribution 4.0",
                  "https://creativecommons.org/licenses/by/4.0/"),
    "CC0-1.0": ("Creative Commons Zero v1.0 Universal",
                "https://creativecommons.org/publicdomain/zero/1.0/"),
    "CC-BY-SA-4.0": ("Creative Commons Attribution Share Alike 4.0",
                     "https://creativecommons.org/licenses/by-sa/4.0/"),
    "ODC-By-1.0": ("Open Data Commons Attribution License v1.0",
                   "https://opendatacommons.org/licenses/by/1-0/"),
    "ODbL-1.0": ("Open Data Commons Open Database License v1.0",
                 "https://opendatacommons.org/licenses/odbl/1-0/"),
    "PDDL-1.0": ("Open Data Commons Public Domain Dedication & License 1.0",
                 "https://opendatacommons.org/licenses/pddl/1-0/"),
}
DEFAULT_LICENCE = "CC-BY-4.0"
#: the licence of tribopipe's own code (the explorer page's script)
CODE_LICENCE = ("MIT", "MIT License", "https://opensource.org/license/mit")
_EMAIL = re.compile(r"[^@\s<>\"'`]+@[^@\s<>\"'`]+\.[^@\s<>\"'`]+")
_CONTROL = re.compile(r"[\x00-\x1f\x7f\u2028\u2029]")


@dataclass(frozen=True)
class Publisher:
    """Who publishes a package: the ``lab`` (required), a ``contact`` person and ``email``
    (optional), the data ``licence`` (an SPDX id of :data:`LICENCES`) and the package's
    ``title`` (default: ``"<lab> friction map"``)."""

    lab: str
    contact: str | None = None
    email: str | None = None
    licence: str = DEFAULT_LICENCE
    title: str | None = None

    def checked(self) -> Publisher:
        """This publisher with names stripped; :class:`ExportError` for an empty lab, a
        line break or control character in any name, a malformed email or an unknown
        licence."""
        values: dict[str, str | None] = {}
        for name in ("lab", "contact", "email", "title"):
            value = getattr(self, name)
            if value is None:
                values[name] = None
                continue
            text = str(value).strip()
            if _CONTROL.search(text):
                raise ExportError(f"--{name} holds a line break or control character; "
                                  "expected one line of text")
            if len(text) > 300:
                raise ExportError(f"--{name} is longer than 300 characters")
            values[name] = text or None
        lab, email = values["lab"], values["email"]
        if not lab:
            raise ExportError("a package needs the name of the lab that measured it",
                              hint="pass --lab NAME")
        if email and not _EMAIL.fullmatch(email):
            raise ExportError(f"--email {email!r} is not an email address")
        licence = next((k for k in LICENCES if k.casefold() == self.licence.casefold()), None)
        if licence is None:
            raise ExportError(f"unknown licence {self.licence!r}; expected one of "
                              f"{', '.join(LICENCES)}")
        return Publisher(lab, values["contact"], email, licence, values["title"])

    @property
    def package_title(self) -> str:
        """The package's title."""
        return self.title or f"{self.lab} friction map"

    def licence_entry(self) -> dict[str, str]:
        """The Data Package ``licenses`` entry of the data licence."""
        title, url = LICENCES[self.licence]
        return {"name": self.licence, "title": title, "path": url}


def founding_paper_text() -> str:
    """The founding paper as one citation line."""
    names = ", ".join(f"{given} {family}" for family, given in FOUNDING_PAPER["authors"])
    return (f"{names}: \"{FOUNDING_PAPER['title']}\" ({FOUNDING_PAPER['year']}); "
            f"friction map and MATLAB app: {FOUNDING_PAPER['data']}")


def citation_text(publisher: Publisher, year: int) -> str:
    """How to cite the package, one line."""
    return (f"{publisher.lab} ({year}): {publisher.package_title}. Friction-map data "
            f"package written by tribopipe {__version__}.")


# --------------------------------------------------------------------------- CITATION.cff

def _yaml(value: Any, indent: int) -> list[str]:
    """Block-style YAML lines of a value made of dicts, lists, text and integers."""
    pad = " " * indent
    lines: list[str] = []
    if isinstance(value, dict):
        for key, item in value.items():
            if isinstance(item, dict | list):
                lines.append(f"{pad}{key}:")
                lines.extend(_yaml(item, indent + 2))
            else:
                lines.append(f"{pad}{key}: {_scalar(item)}")
    else:
        for item in value:
            sub = _yaml(item, indent + 2) if isinstance(item, dict | list) else [
                f"{pad}  {_scalar(item)}"]
            lines.append(f"{pad}- {sub[0].lstrip()}")
            lines.extend(sub[1:])
    return lines


def _scalar(value: Any) -> str:
    if isinstance(value, bool) or not isinstance(value, int | str):
        raise TypeError(f"no YAML for {value!r}")
    return str(value) if isinstance(value, int) else yaml_text(value)


def citation_cff(publisher: Publisher, *, date: str, n_runs: int,
                 pairs: Sequence[tuple[str, str]]) -> str:
    """The package's ``CITATION.cff`` (CFF 1.2.0, type ``dataset``): the lab as author (an
    entity), the contact, the data licence, the release ``date`` (``YYYY-MM-DD``), and the
    founding paper and tribopipe under ``references``."""
    author: dict[str, Any] = {"name": publisher.lab}
    if publisher.email:
        author["email"] = publisher.email
    doc: dict[str, Any] = {
        "cff-version": "1.2.0",
        "message": ("If you use these friction data, please cite them as below, and the "
                    "founding paper under references."),
        "type": "dataset",
        "title": publisher.package_title,
        "abstract": (f"Friction map of soft pins on discs from pin-on-disc rheometer runs: "
                     f"{n_runs} runs of {len(pairs)} contact pairs, static and kinetic "
                     "coefficients of friction by contact pressure and temperature, with "
                     "their provenance."),
        "authors": [author],
    }
    if publisher.contact or publisher.email:
        contact: dict[str, Any] = {"name": publisher.contact or publisher.lab}
        if publisher.email:
            contact["email"] = publisher.email
        doc["contact"] = [contact]
    doc.update({
        "license": publisher.licence,
        "date-released": date,
        "keywords": ["friction", "tribology", "coefficient of friction", "soft robotics",
                     "silicone", "pin-on-disc"],
        "references": [
            {"type": "article", "title": FOUNDING_PAPER["title"],
             "authors": [{"family-names": family, "given-names": given}
                         for family, given in FOUNDING_PAPER["authors"]],
             "year": FOUNDING_PAPER["year"], "url": FOUNDING_PAPER["data"]},
            {"type": "software", "title": "tribopipe",
             "authors": [{"name": "tribopipe contributors"}], "version": __version__},
        ],
    })
    return "# CITATION.cff, written by tribopipe " + __version__ + "\n" + "\n".join(
        _yaml(doc, 0)) + "\n"


# --------------------------------------------------------------------------- README.md


def package_readme(publisher: Publisher, *, date: str, n_runs: int, n_excluded: int,
                   n_published: int, pairs: Sequence[tuple[str, str]],
                   files: Sequence[tuple[str, str]],
                   fields: Sequence[dict[str, Any]]) -> str:
    """The README of a package: who, what, licence, how to cite, the files (``(path,
    what)``), the runs table's columns with units, how to check and merge it."""
    year = int(date[:4])
    licence_title, licence_url = LICENCES[publisher.licence]
    contact = ", ".join(markdown_cell(x) for x in (publisher.contact, publisher.email) if x)
    lines = [
        f"# {markdown_cell(publisher.package_title)}",
        "",
        f"Friction data measured by **{markdown_cell(publisher.lab)}**"
        + (f" (contact: {contact})" if contact else "")
        + f", published {date} with tribopipe {__version__} as a Frictionless Data Package "
        "(`datapackage.json` describes every file, its columns, units, licence, size and "
        "SHA-256).",
        "",
        f"{n_runs} runs ({n_excluded} excluded from the statistics, kept with their reason) "
        f"of {len(pairs)} contact pairs: "
        + "; ".join(f"{markdown_cell(pin)} on {markdown_cell(disc)}" for pin, disc in pairs) + ".",
        "",
        "## Licence",
        "",
        f"The data are licensed under {licence_title} (`{publisher.licence}`, "
        f"<{licence_url}>). The explorer page's script is tribopipe's code (MIT licence).",
    ]
    if n_published:
        lines += [
            "",
            f"{n_published} rows (`source` = `published:Berthold2023`) are the founding "
            "paper's published friction map, republished here with its citation; the "
            "original map states no licence of its own, so the licence above covers the "
            "other rows, and reuse of those rows is a matter of citing the paper.",
        ]
    lines += [
        "",
        "## How to cite",
        "",
        f"> {markdown_cell(citation_text(publisher, year))}",
        "",
        "and the founding paper these measurements build on:",
        "",
        f"> {markdown_cell(founding_paper_text())}",
        "",
        "`CITATION.cff` holds the same in the Citation File Format.",
        "",
        "## Files",
        "",
        "| file | what |",
        "|---|---|",
        *[f"| `{path}` | {markdown_cell(what)} |" for path, what in files],
        "",
        "## Columns of `data/runs.csv`",
        "",
        "One row per run; empty cells are missing values; booleans are `true`/`false`.",
        "",
        "| column | type | unit | meaning |",
        "|---|---|---|---|",
        *[f"| `{f['name']}` | {f['type']} | {markdown_cell(f.get('unit', ''))} | "
          f"{markdown_cell(f['description'])} |" for f in fields],
        "",
        "## Using it",
        "",
        "```",
        "tribopipe map validate .                      # schema, units, ranges, ids, "
        "provenance, checksums",
        "tribopipe map merge . --map friction_map.parquet   # into your map, each lab's "
        "rows kept as theirs",
        "tribopipe query --map data/runs.parquet --pin PIN --disc DISC --pressure 40 "
        "--temperature 20",
        "```",
        "",
        "`explorer.html` opens in any browser, from disk, without network. "
        "`data/frictionmap.csv` is the 7-column table of the founding paper's MATLAB "
        "FrictionMap app. The checksums show that a file is the one described (nothing lost "
        "or changed on the way); they are not a signature.",
        "",
    ]
    return "\n".join(lines)
