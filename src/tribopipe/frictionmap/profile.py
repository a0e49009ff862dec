"""The package profile: what a friction-map package is, by version, as a JSON Schema.

A package names its profile in the descriptor's ``tribopipe`` block (``profile`` and
``profile_version``). Each version has a JSON Schema (draft 2020-12) of the descriptor,
generated here, written into every package (``profile/package-v<N>.schema.json``) and into
the docs (``docs/package-profile/``, held equal by a test):

====  =====================================================================================
 1    summary rows only: the runs (CSV and Parquet), the groups, the founding paper's
      7-column table, the explorer, README and CITATION.cff. The descriptor names no
      profile (every package tribopipe wrote before evidence was carried, map schema
      versions 2 to 5).
 2    version 1 plus the profile named in the descriptor, its JSON Schema in the package,
      and the evidence: ``evidence/index.csv`` and ``evidence/settings.json``
      (:mod:`tribopipe.evidence`).
 3    version 2 with no cell that grows with the number of runs: the group table numbers
      its groups (``group``) and no longer joins each group's run ids and values into one
      cell; ``data/group_runs.csv`` lists each group's runs, one row per (group, run).
====  =====================================================================================

Readers take every version: an older package is read as the current one with what it
lacks left empty, and :func:`upgrade_note` says so in one line.
"""

from __future__ import annotations

from typing import Any

from .datapackage import DESCRIPTOR, PROFILE, TRIBOPIPE_KEY
from .schema import ADDED_IN_VERSION, SCHEMA_NAME, SCHEMA_VERSION

#: the profile's name in the descriptor
PROFILE_NAME = "tribopipe-friction-map-package"
#: the version this tribopipe writes
PROFILE_VERSION = 3
#: what each version holds, one line (the module docstring's table)
PROFILE_VERSIONS: dict[int, str] = {
    1: "summary rows only (runs, groups, the 7-column table, explorer, README, citation)",
    2: "version 1 plus the profile and its JSON Schema, and the evidence (each run's trace "
       "and raw export with their SHA-256 and the settings that reduced them)",
    3: "version 2 with each group's runs in their own table (data/group_runs.csv: one row "
       "per group and run) instead of one cell of the group table",
}
#: the first version whose group table links its runs through ``group-runs``
LINKED_GROUPS_VERSION = 3
#: the first map schema version of a package (version 1 maps had no ``lab``)
FIRST_SCHEMA_VERSION = 2
#: the last map schema version of a profile version 1 package
LAST_V1_SCHEMA = 5
#: the resource names each version requires, and those it may add
REQUIRED_RESOURCES: dict[int, tuple[str, ...]] = {1: ("runs",), 2: ("runs",), 3: ("runs",)}
#: from :data:`LINKED_GROUPS_VERSION`: a resource that requires another beside it (the
#: group table its linking table)
COMPANION_RESOURCES: dict[str, str] = {"groups": "group-runs"}
#: the path of a version's JSON Schema inside a package
SCHEMA_FILE = "profile/package-v{version}.schema.json"


def schema_file(version: int = PROFILE_VERSION) -> str:
    """The path of version ``version``'s JSON Schema inside a package."""
    return SCHEMA_FILE.format(version=version)


def descriptor_profile_version(descriptor: dict[str, Any]) -> int | None:
    """The profile version a descriptor declares: 1 when its ``tribopipe`` block names
    none (written before profiles were named), ``None`` when it names another profile or
    a version that is not an integer ≥ 1."""
    info = descriptor.get(TRIBOPIPE_KEY)
    if not isinstance(info, dict):
        return None
    if "profile_version" not in info and "profile" not in info:
        return 1
    version = info.get("profile_version")
    if info.get("profile") != PROFILE_NAME or isinstance(version, bool) \
            or not isinstance(version, int) or version < 1:
        return None
    return version


def upgrade_note(version: int) -> str | None:
    """The line that says an older package was read as the current version, and what it
    lacks (``None`` for the current one)."""
    if version >= PROFILE_VERSION:
        return None
    lacks = []
    if version < 2:
        lacks.append("it carries no evidence, so `map validate --recompute` can check none "
                     "of its rows")
    if version < LINKED_GROUPS_VERSION:
        lacks.append("its group table joins each group's run ids and values into one cell "
                     "(read as they are; the groups are checked against its runs)")
    return (f"package profile version {version} ({PROFILE_VERSIONS[version]}), read as "
            f"version {PROFILE_VERSION}: " + "; ".join(lacks))


def map_upgrade_note(version: int) -> str | None:
    """The line that says a map of an older schema ``version`` was read as the current
    one, naming the columns it lacks (``None`` for the current version)."""
    if version >= SCHEMA_VERSION:
        return None
    added = [c for c, v in ADDED_IN_VERSION.items() if v > version]
    return (f"friction map schema version {version}, read as version {SCHEMA_VERSION}: the "
            f"columns added since ({', '.join(added)}) are empty for its rows")


def profile_schema(version: int = PROFILE_VERSION) -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of a version ``version`` package's descriptor."""
    if version not in PROFILE_VERSIONS:
        raise ValueError(f"no package profile version {version}")
    resource = {
        "type": "object",
        "required": ["name", "path", "bytes", "hash", "licenses"],
        "properties": {
            "name": {"type": "string", "pattern": "^[a-z0-9._-]+$"},
            "path": {"type": "string", "pattern": "^(?!/)(?!.*(^|/)\\.\\.(/|$))[^\\\\:]+$"},
            "bytes": {"type": "integer", "minimum": 0},
            "hash": {"type": "string", "pattern": "^sha256:[0-9a-f]{64}$"},
            "licenses": {"type": "array", "minItems": 1},
        },
    }
    block: dict[str, Any] = {
        "type": "object",
        "required": ["schema", "schema_version", "lab", "tribopipe_version"],
        "properties": {
            "schema": {"const": SCHEMA_NAME},
            # the map schema may grow within a profile version: the reader refuses a
            # newer one by name (version 1 packages were written up to schema 5)
            "schema_version": {"type": "integer", "minimum": FIRST_SCHEMA_VERSION,
                               **({"maximum": LAST_V1_SCHEMA} if version == 1 else {})},
            "lab": {"type": "string", "minLength": 1},
            "tribopipe_version": {"type": "string"},
            "n_runs": {"type": "integer", "minimum": 0},
            "labs": {"type": "array", "items": {"type": "string"}},
        },
    }
    if version >= 2:
        block["required"] += ["profile", "profile_version"]
        block["properties"]["profile"] = {"const": PROFILE_NAME}
        block["properties"]["profile_version"] = {"const": version}
    else:
        block["not"] = {"required": ["profile_version"]}
    def named(name: str) -> dict[str, Any]:
        return {"contains": {"type": "object", "properties": {"name": {"const": name}},
                             "required": ["name"]}}

    required = [named(name) for name in REQUIRED_RESOURCES[version]]
    if version >= LINKED_GROUPS_VERSION:
        required += [{"if": named(name), "then": named(companion)}
                     for name, companion in COMPANION_RESOURCES.items()]
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": f"tribopipe friction-map package, profile version {version}",
        "description": f"The {DESCRIPTOR} of a friction-map data package: "
                       + PROFILE_VERSIONS[version],
        "type": "object",
        "required": ["profile", "name", "licenses", "resources", TRIBOPIPE_KEY],
        "properties": {
            "profile": {"const": PROFILE},
            "name": {"type": "string"},
            "version": {"type": "string", "pattern": "^\\d{4}-\\d{2}-\\d{2}$"},
            "licenses": {"type": "array", "minItems": 1},
            TRIBOPIPE_KEY: block,
            "resources": {"type": "array", "minItems": 1, "items": resource,
                          "allOf": required},
        },
    }
