"""Files on disk: looked at before they are opened, written so a reader never sees half of
one, and hashed by content.

Every input file is ``stat``-ed before it is opened (:func:`regular_file`): a directory, a
FIFO (which would block the read forever), a device (``/dev/zero`` would fill the memory),
a socket, a symlink loop or a name too long is refused in one line naming the path, never
opened. :func:`read_regular` reads such a file up to a size limit.

Every text output (summaries, tables, reports, a campaign's CSVs and state) is written to a
temporary file beside its target and renamed over it: the rename is atomic, so a crash or
a concurrent reader sees the old file or the new one, never a mix; a folder that is
read-only or full is one :class:`~tribopipe.errors.OutputError` line. (The friction map has
its own, stricter writer with fsync and a lock: :mod:`tribopipe.frictionmap`.)
"""

from __future__ import annotations

import filecmp
import hashlib
import os
import stat
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Any, TextIO

from .errors import OutputError, ReadError

_KINDS = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)


def os_reason(exc: OSError) -> str:
    """The operating system's one-line reason for an error (``Permission denied``...)."""
    return exc.strerror or str(exc) or type(exc).__name__


def file_kind(mode: int) -> str:
    """What a ``st_mode`` is: ``"a regular file"``, ``"a directory"``, ``"a FIFO (named
    pipe)"``, ``"a character device"``..."""
    for test, kind in _KINDS:
        if test(mode):
            return kind
    return "a regular file" if stat.S_ISREG(mode) else "not a regular file"


def regular_file(path: str | os.PathLike[str], *, what: str = "a file") -> os.stat_result:
    """``os.stat(path)`` of a regular file (symlinks followed); otherwise
    :class:`ReadError` naming the path and what it is (missing, a directory, a FIFO, a
    device, a symlink loop, a name too long, no permission). Nothing is opened."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise ReadError(f"file not found, expected {what}", path=path) from None
    except OSError as exc:  # ELOOP, ENAMETOOLONG, EACCES, ENOTDIR ...
        raise ReadError(f"cannot read: {os_reason(exc)}", path=path) from None
    if not stat.S_ISREG(st.st_mode):
        raise ReadError(f"is {file_kind(st.st_mode)}, expected {what}; not opened", path=path)
    return st


def read_regular(path: str | os.PathLike[str], *, max_bytes: int,
                 what: str = "a file") -> bytes:
    """The bytes of a regular file (:func:`regular_file`) of at most ``max_bytes``;
    :class:`ReadError` naming the path otherwise (too large, unreadable)."""
    st = regular_file(path, what=what)
    if st.st_size > max_bytes:
        raise ReadError(f"is {st.st_size:,} bytes; at most {max_bytes:,} are read", path=path)
    try:
        with open(path, "rb") as fh:
            if not stat.S_ISREG(os.fstat(fh.fileno()).st_mode):  # swapped since the stat
                raise ReadError(f"is not {what}; not read", path=path)
            data = fh.read(max_bytes + 1)
    except OSError as exc:
        raise ReadError(f"cannot read: {os_reason(exc)}", path=path) from None
    if len(data) > max_bytes:
        raise ReadError(f"is more than {max_bytes:,} bytes", path=path)
    return data


def write_text_atomic(
    target: str | os.PathLike[str], text: str, *, newline: str | None = None
) -> Path:
    """Write ``text`` (UTF-8) to ``target`` via a temporary file and an atomic rename,
    creating the folder if needed; ``newline`` as for :func:`open`. Returns the path.

    Raises :class:`OutputError` (one line naming the target) when the folder cannot be
    made or written (read-only, full, a file in the way, a name too long); the target is
    then untouched and no temporary file is left behind."""
    with _atomic(target, binary=False, newline=newline) as fh:
        fh.write(text)
    return Path(target)


def write_page_and_files(page: str | os.PathLike[str],
                         files: Mapping[str, str] | Iterable[tuple[str, str]]) -> Path:
    """Write a page with the files beside it: ``files`` maps names relative to the page's
    folder to UTF-8 text (a mapping, or (name, text) pairs written as they come, so that
    no more than one is held at a time) and holds the page under its own name. Each file
    is written, as it comes, into a hidden staging folder beside the page, the page too;
    only when every one is written are they renamed into place (each atomically, and a
    rename needs no space), the page last, so a page is never there before what it loads,
    and an error while they are made or written (raised on: a full disk too) leaves the
    page and its files as they were, with no staging folder behind. Returns the page's
    path."""
    import shutil
    import tempfile

    out = Path(page)
    text_of_page = None
    staged: list[str] = []
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        stage = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".staging",
                                      dir=out.parent))
    except OSError as exc:
        raise OutputError(f"cannot write: {os_reason(exc)}", path=out) from None
    try:
        for name, text in (files.items() if isinstance(files, Mapping) else files):
            if name == out.name:
                text_of_page = text
            else:
                write_text_atomic(stage / name, text)
                staged.append(name)
        if text_of_page is None:
            raise ValueError(f"no page {out.name!r} among the files to write")
        write_text_atomic(stage / out.name, text_of_page)  # no file beside has its name
        for name in [*staged, out.name]:
            target = out.parent / name
            try:
                target.parent.mkdir(parents=True, exist_ok=True)
                os.replace(stage / name, target)
            except OSError as exc:
                raise OutputError(f"cannot write: {os_reason(exc)}", path=target) from None
    finally:
        shutil.rmtree(stage, ignore_errors=True)
    return out


def write_bytes_atomic(target: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``target`` as :func:`write_text_atomic` writes text (a binary
    output: a spreadsheet)."""
    with _atomic(target, binary=True) as fh:
        fh.write(data)
    return Path(target)


@contextmanager
def atomic_text(target: str | os.PathLike[str], *, keep_same: bool = False,
                newline: str | None = None) -> Iterator[TextIO]:
    """A text handle (UTF-8; ``newline`` as for :func:`open`) whose content replaces ``target``
    atomically when the block ends, written as it goes (a table of 10⁵ rows is never one
    string); with ``keep_same``, a target whose bytes equal it is left as it is (its
    ``mtime`` too). Raises :class:`OutputError` as :func:`write_text_atomic` does; an
    error in the block leaves the target untouched and no temporary file behind."""
    with _atomic(target, binary=False, keep_same=keep_same, newline=newline) as fh:
        yield fh


@contextmanager
def _atomic(target: str | os.PathLike[str], *, binary: bool, keep_same: bool = False,
            newline: str | None = None) -> Iterator[Any]:
    """The one temp-file-and-rename writer behind :func:`atomic_text`,
    :func:`write_text_atomic` and :func:`write_bytes_atomic`: a handle (binary, or UTF-8
    text) on a temporary file beside ``target`` that replaces it when the block ends."""
    path = Path(target)
    # the process id keeps two processes writing the same target off each other's temp file
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fh = open(tmp, "wb") if binary else open(tmp, "w", encoding="utf-8", newline=newline)
    except OSError as exc:
        raise OutputError(f"cannot write: {os_reason(exc)}", path=path) from None
    try:
        try:
            with fh:
                yield fh
            if keep_same and path.is_file() and filecmp.cmp(tmp, path, shallow=False):
                tmp.unlink()
            else:
                os.replace(tmp, path)
        except OSError as exc:
            raise OutputError(f"cannot write: {os_reason(exc)}", path=path) from None
    finally:
        with suppress(OSError):
            tmp.unlink(missing_ok=True)


def fsync_dir(directory: Path) -> None:
    """Make a rename or a new file in ``directory`` durable (fsync of the folder itself);
    a platform that cannot open a folder is passed over (the rename is atomic anyway)."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def file_sha256(path: str | os.PathLike[str]) -> str:
    """SHA-256 hex digest of a regular file's bytes; :class:`ReadError` naming the path
    when it is not a regular file or cannot be read."""
    regular_file(path)
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            for chunk in iter(lambda: fh.read(1 << 20), b""):
                digest.update(chunk)
    except OSError as exc:
        raise ReadError(f"cannot read: {os_reason(exc)}", path=path) from None
    return digest.hexdigest()
