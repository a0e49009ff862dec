"""A campaign as a table, before anything runs: one row per file, its metadata and status.

Incremental state
-----------------
``<output_dir>/.tribopipe-state.<name>.json`` remembers, per file: size, ``mtime_ns``,
SHA-256, the config hash, a recipe hash (config + labels + QC tolerances), the status and
the measurement id (one state per campaign name, so campaigns may share an output folder
and a map). Like git's index, the cached hash is trusted while size and ``mtime_ns`` are
unchanged, so an unchanged campaign is checked with one ``stat`` per file.
"""

from __future__ import annotations

import functools
import hashlib
import json
from collections.abc import Mapping
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

from ..errors import CampaignError
from ..files import file_sha256, write_text_atomic
from ..frictionmap.records import RunLabels
from .metadata import labels_from, merge_metadata, read_manifest
from .patterns import LABEL_FIELDS, match_pattern
from .spec import Campaign

STATE_VERSION = 1

#: the statuses of a campaign row before a batch (``campaign list``)
NEW, REDUCED, CHANGED, FAILED = "new", "reduced", "changed", "failed"
#: what a batch did with a run (``runs.csv``)
SKIPPED = "skipped"



@dataclass(frozen=True)
class RunEntry:
    """What the state keeps of a reduced run (and ``runs.csv`` shows), as its worker
    found it: the labels, the id, the trace (relative to the output folder), μ_S and μ_K,
    the nominal pressure [kPa], the measured pressure [kPa], normal force [N] and
    temperature [°C] (``None`` when not finite) and the ``;``-joined flags."""

    labels: dict[str, Any]
    measurement_id: str
    trace: str
    mu_s: float | None
    mu_k: float | None
    pressure_kPa: float | None
    pressure_measured_kPa: float | None
    normal_force_measured_N: float | None
    temperature_measured_C: float | None
    flags: str

    def as_dict(self) -> dict[str, Any]:
        """The entry's fields as the state's JSON keys."""
        return asdict(self)


#: the keys of a state entry that come from a :class:`RunEntry`
_SUMMARY_KEYS: tuple[str, ...] = tuple(f.name for f in fields(RunEntry))


@dataclass(frozen=True)
class CampaignRow:
    """One file of a campaign: its metadata (as known before reading it) and status.

    ``sources`` are the metadata sources consulted so far (name, fields) in priority order;
    ``problem`` is a metadata error known before reading; ``status`` is one of
    ``new, reduced, changed, failed``; ``reason`` why a run failed (last batch or now);
    ``previous`` the file's entry in the state; ``hints`` why a source said nothing.
    """

    file: str
    path: Path
    size: int
    mtime_ns: int
    sources: tuple[tuple[str, dict[str, Any]], ...]
    merged: dict[str, Any]
    problem: str | None
    status: str
    reason: str | None = None
    sha256: str | None = None
    previous: dict[str, Any] | None = None
    hints: tuple[str, ...] = ()

    @property
    def labels(self) -> RunLabels:
        """The nominal labels known before reading (missing fields are ``None``)."""
        m = self.merged
        return RunLabels(
            pin=m.get("pin"), disc=m.get("disc"), normal_force_N=m.get("normal_force_N"),
            temperature_C=m.get("temperature_C"), repeat=m.get("repeat"),
        )


def discover_files(campaign: Campaign) -> list[Path]:
    """The campaign's raw exports: ``raw_dir`` globbed, sorted, without the manifest,
    hidden files and folders."""
    manifest = campaign.manifest
    files = [
        p for p in campaign.raw_dir.glob(campaign.glob)
        if p.is_file() and not p.name.startswith(".")
        # resolving costs a few syscalls per file: only when there is a manifest to skip
        and (manifest is None or p.resolve() != manifest)
    ]
    return sorted(files, key=lambda p: p.relative_to(campaign.raw_dir).as_posix())


def recipe_hash(campaign: Campaign, merged: Mapping[str, Any]) -> str:
    """Hash of everything besides the raw bytes that a run's record depends on: the
    settings' config hash, the labels known before reading, the QC tolerances and the
    export-name rules (16 hex digits)."""
    payload = {"campaign": _campaign_key(campaign),
               "labels": {k: merged.get(k) for k in LABEL_FIELDS}}
    text = json.dumps(payload, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


@functools.lru_cache(maxsize=8)
def _campaign_key(campaign: Campaign) -> str:
    # the part of recipe_hash shared by every run of a campaign, computed once per campaign
    payload = {
        "config": campaign.settings.config_hash,
        "tolerances": asdict(campaign.tolerances),
        # the labels in recipe_hash already carry the [names] aliases, except those read
        # from export names, so the aliases only matter with use_export_names
        "export_names": [campaign.export_pattern, list(campaign.names)]
        if campaign.use_export_names else None,
        "read": asdict(campaign.read_options),
    }
    return hashlib.sha256(json.dumps(payload, sort_keys=True, default=str).encode()).hexdigest()


def _relative(path: Path, root: Path) -> str:
    return path.relative_to(root).as_posix()


def campaign_table(campaign: Campaign, *, state: Mapping[str, Any] | None = None
                   ) -> list[CampaignRow]:
    """The campaign as a table, before anything runs: one row per file with its metadata
    and status (``new, reduced, changed, failed``).

    A file counts as ``reduced`` when its content (SHA-256, trusted from the state while
    size and ``mtime_ns`` are unchanged) and its recipe hash match the last successful
    batch and its trace still exists; ``failed`` when the same holds for a failed run or
    its metadata is already known to be wrong. ``state`` defaults to the campaign's state
    file.
    """
    entries = (state if state is not None else load_state(campaign)).get("entries", {})
    manifest = read_manifest(campaign.manifest) if campaign.manifest else {}
    rows: list[CampaignRow] = []
    for path in discover_files(campaign):
        rel = _relative(path, campaign.raw_dir)
        st = path.stat()
        sources: list[tuple[str, dict[str, Any]]] = []
        hints: list[str] = []
        problem: str | None = None
        if campaign.manifest is not None:
            row = manifest.get(rel) or manifest.get(path.name)
            if row is None:
                hints.append(f"no row for it in manifest {campaign.manifest.name}")
            else:
                sources.append((f"manifest line {row.line}", dict(row.fields)))
                problem = row.problem
        if campaign.filename_pattern is not None:
            found = match_pattern(campaign.filename_pattern, path.stem)
            if found is None:
                hints.append(f"name does not match pattern {campaign.filename_pattern!r}")
            else:
                sources.append(("file name", found))
        merged: dict[str, Any] = {}
        if problem is None:
            try:
                merged = merge_metadata(rel, sources, campaign)
                if not campaign.use_export_names:
                    labels_from(rel, merged, hints=hints)
            except CampaignError as exc:
                problem = str(exc)
        previous = entries.get(rel)
        sha = None
        status = NEW
        reason = None
        if previous is not None:
            same_stat = previous.get("size") == st.st_size and \
                previous.get("mtime_ns") == st.st_mtime_ns
            sha = previous.get("sha256") if same_stat else file_sha256(path)
            same = sha is not None and sha == previous.get("sha256") and \
                previous.get("recipe") == recipe_hash(campaign, merged)
            if same and previous.get("status") == REDUCED:
                trace = previous.get("trace")
                status = REDUCED if trace and (campaign.output_dir / trace).is_file() \
                    else CHANGED
            elif same and previous.get("status") == FAILED:
                status, reason = FAILED, previous.get("reason")
            else:
                status = CHANGED
        if problem is not None:
            status, reason = FAILED, problem
        rows.append(CampaignRow(
            file=rel, path=path, size=st.st_size, mtime_ns=st.st_mtime_ns,
            sources=tuple(sources), merged=merged, problem=problem, status=status,
            reason=reason, sha256=sha, previous=previous, hints=tuple(hints),
        ))
    return rows


# --------------------------------------------------------------------------- state


def load_state(campaign: Campaign) -> dict[str, Any]:
    """The incremental state of a campaign (empty when there is none or it is unreadable:
    a lost state only costs a full re-run)."""
    try:
        data = json.loads(campaign.state_path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {"version": STATE_VERSION, "entries": {}}
    if not isinstance(data, dict) or data.get("version") != STATE_VERSION or \
            not isinstance(data.get("entries"), dict):
        return {"version": STATE_VERSION, "entries": {}}
    return data


def save_state(campaign: Campaign, state: Mapping[str, Any]) -> None:
    """Write the incremental state atomically (temporary file + rename)."""
    write_text_atomic(campaign.state_path, json.dumps(state, indent=1, sort_keys=True))


def campaign_listing(campaign: Campaign) -> list[dict[str, Any]]:
    """The campaign table as JSON-ready dicts, for ``tribopipe campaign list``.

    Keys: ``file, status, pin, disc, normal_force_N, temperature_C, repeat, mu_s, mu_k,
    flags, measurement_id, sources, reason``. Labels of reduced runs come from the last
    batch (so they include fields read from export names); μ values only for reduced runs.
    """
    out: list[dict[str, Any]] = []
    for row in campaign_table(campaign):
        entry = row.previous or {}
        reduced = row.status == REDUCED
        labels = (entry.get("labels") if reduced else None) or {
            k: row.merged.get(k) for k in LABEL_FIELDS
        }
        out.append({
            "file": row.file,
            "status": row.status,
            **{k: labels.get(k) for k in LABEL_FIELDS},
            "mu_s": entry.get("mu_s") if reduced else None,
            "mu_k": entry.get("mu_k") if reduced else None,
            "flags": entry.get("flags") if reduced else None,
            "measurement_id": entry.get("measurement_id") if reduced else None,
            "sources": [name for name, _ in row.sources],
            "reason": row.reason,
        })
    return out
