"""A friction map's bytes on disk, whatever its format, for tests that assert a map was
left alone; and a single-file copy of a map, for tests that edit a map as another program
would (a map folder's parts are refused by their checksums before their rows are read)."""

from __future__ import annotations

from pathlib import Path

from tribopipe import frictionmap as fm


def map_bytes(path: Path) -> bytes | dict[str, bytes]:
    """The bytes of the map at ``path``: the file's, or every file of a map folder by name
    (the manifest, its backup and the parts)."""
    if path.is_dir():
        return {p.name: p.read_bytes() for p in sorted(path.iterdir()) if p.is_file()}
    return path.read_bytes()


def single_file(path: Path, dst: Path) -> Path:
    """The map at ``path`` written as one friction-map Parquet file at ``dst`` (the format
    maps had before they were folders of parts, and still read in)."""
    return fm.store.write_map_copy(dst, fm.read_map(path))


def the_part(path: Path) -> Path:
    """The one part of a map folder ``path`` (a map written in one commit)."""
    manifest = fm.parts.read_manifest(path)
    assert len(manifest.parts) == 1, manifest.parts
    return path / manifest.parts[0].file
