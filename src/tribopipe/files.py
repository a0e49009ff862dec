"""Files on disk: written so a reader never sees half of one, and hashed by content.

Every text output (summaries, tables, reports, a campaign's CSVs and state) is written to a
temporary file beside its target and renamed over it: the rename is atomic, so a crash or
a concurrent reader sees the old file or the new one, never a mix. (The friction map has its
own, stricter writer with fsync and a lock: :mod:`tribopipe.frictionmap`.)
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path


def write_text_atomic(target: str | Path, text: str, *, newline: str | None = None) -> Path:
    """Write ``text`` (UTF-8) to ``target`` via a temporary file and an atomic rename,
    creating the folder if needed; ``newline`` as for :func:`open`. Returns the path."""
    path = Path(target)
    path.parent.mkdir(parents=True, exist_ok=True)
    # the process id keeps two processes writing the same target off each other's temp file
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "w", encoding="utf-8", newline=newline) as fh:
        fh.write(text)
    os.replace(tmp, path)
    return path


def file_sha256(path: str | Path) -> str:
    """SHA-256 hex digest of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()
