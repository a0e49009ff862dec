"""Rows that are not a lab's measurements: runs reduced from synthetic exports.

A campaign whose config says ``synthetic = true`` (the shipped demo, ``configs/example.toml``)
flags every run it records with :data:`FLAG_SYNTHETIC`. The flag is the one rule: ``query``,
``report`` and ``map show`` say when a map holds such rows (:func:`synthetic_note`), and
``map publish`` refuses them under a lab's name unless told otherwise.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from ..labels import FLAG_SYNTHETIC, flag_list
from .snapshot import MapSnapshot, MapSource, as_snapshot

if TYPE_CHECKING:
    import pandas as pd

#: what synthetic runs are, worded once for every output that says so
SYNTHETIC_MEANS = f"SYNTHETIC (demo data flagged '{FLAG_SYNTHETIC}'), not measurements"


def campaign_note() -> str:
    """What a campaign with ``synthetic = true`` says once after its batch."""
    return (f"the campaign says synthetic = true: its runs are {SYNTHETIC_MEANS}; they are "
            "never published as a lab's measurements")


def synthetic_mask(runs: pd.DataFrame) -> pd.Series:
    """Boolean Series over ``runs`` (map rows): True where ``flags`` holds
    :data:`FLAG_SYNTHETIC`."""
    flags = runs["flags"]
    # each distinct flags text read once (a map holds few of them)
    synthetic = {text: FLAG_SYNTHETIC in flag_list(text) for text in flags.dropna().unique()}
    return flags.map(synthetic).fillna(False).astype(bool)


def synthetic_count(runs: pd.DataFrame) -> int:
    """How many of ``runs`` (map rows) are synthetic."""
    if runs.empty or "flags" not in runs:
        return 0
    return int(synthetic_mask(runs).sum())


def synthetic_note(runs: pd.DataFrame, of: str = "") -> str | None:
    """One line saying how many of ``runs`` are synthetic (``None`` when none are);
    ``of`` names whose runs they are (e.g. ``"this map"``)."""
    n = synthetic_count(runs)
    if n == 0:
        return None
    whole = f"all {n}" if n == len(runs) else f"{n} of {len(runs)}"
    runs_of = f"runs of {of}" if of else "runs"
    return f"note: {whole} {runs_of} are {SYNTHETIC_MEANS}"


def map_synthetic_note(path: MapSource) -> str | None:
    """:func:`synthetic_note` of the map at ``path`` (``None`` for a map without synthetic
    rows, or no map)."""
    if not (isinstance(path, MapSnapshot) and path.exists or Path(path).exists()):
        return None
    return synthetic_note(as_snapshot(path).runs, of="this map")
