"""Output files are replaced whole: no temp file left behind, the folder made if needed."""

from pathlib import Path

from tribopipe.files import write_text_atomic


def test_write_creates_the_folder_and_leaves_no_temp_file(tmp_path: Path) -> None:
    target = tmp_path / "deep" / "er" / "table.md"
    assert write_text_atomic(target, "| a |\n") == target
    assert target.read_text(encoding="utf-8") == "| a |\n"
    assert [p.name for p in target.parent.iterdir()] == ["table.md"]


def test_write_replaces_the_old_content_entirely(tmp_path: Path) -> None:
    target = tmp_path / "state.json"
    write_text_atomic(target, "x" * 1000)
    write_text_atomic(target, "µ_K ≈ 0.55")
    assert target.read_text(encoding="utf-8") == "µ_K ≈ 0.55"


def test_newline_empty_keeps_line_ends_as_given(tmp_path: Path) -> None:
    target = tmp_path / "t.csv"
    write_text_atomic(target, "a,b\r\n1,2\n", newline="")
    assert target.read_bytes() == b"a,b\r\n1,2\n"


def test_file_sha256_is_the_content_hash(tmp_path: Path) -> None:
    import hashlib

    from tribopipe.files import file_sha256

    a, b = tmp_path / "a.csv", tmp_path / "renamed.csv"
    a.write_bytes(b"x" * 3_000_000)  # more than one read chunk
    b.write_bytes(a.read_bytes())
    assert file_sha256(a) == file_sha256(b) == hashlib.sha256(b"x" * 3_000_000).hexdigest()


def test_atomic_text_writes_as_it_goes_and_keeps_an_equal_target(tmp_path: Path) -> None:
    import os

    from tribopipe.files import atomic_text

    target = tmp_path / "out" / "t.csv"
    with atomic_text(target, keep_same=True) as fh:
        fh.write("a,b\n")
        fh.write("1,2\n")
    assert target.read_bytes() == b"a,b\n1,2\n"
    os.utime(target, ns=(1_000_000_000, 1_000_000_000))
    with atomic_text(target, keep_same=True) as fh:  # the same bytes: left as it is
        fh.write("a,b\n1,2\n")
    assert target.stat().st_mtime_ns == 1_000_000_000
    with atomic_text(target, keep_same=True) as fh:  # other bytes: replaced
        fh.write("a,b\n1,3\n")
    assert target.read_text() == "a,b\n1,3\n"
    assert target.stat().st_mtime_ns != 1_000_000_000
    assert sorted(p.name for p in target.parent.iterdir()) == ["t.csv"]


def test_atomic_text_error_in_the_block_leaves_the_target(tmp_path: Path) -> None:
    import pytest

    from tribopipe.files import atomic_text

    target = tmp_path / "t.csv"
    target.write_text("old\n")
    with pytest.raises(RuntimeError), atomic_text(target) as fh:
        fh.write("half")
        raise RuntimeError("stopped")
    assert target.read_text() == "old\n"
    assert [p.name for p in tmp_path.iterdir()] == ["t.csv"]


def test_atomic_text_names_the_target_it_cannot_write(tmp_path: Path) -> None:
    import pytest

    from tribopipe.errors import OutputError
    from tribopipe.files import atomic_text

    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(OutputError) as err, atomic_text(blocker / "t.csv") as fh:
        fh.write("never")
    assert "t.csv" in str(err.value)


def test_a_page_and_its_files_are_written_as_they_come_the_page_last(tmp_path: Path) -> None:
    import pytest

    from tribopipe.files import write_page_and_files

    seen: list[tuple[list[str], list[str]]] = []

    def on_disk() -> tuple[list[str], list[str]]:
        """The texts written so far (anywhere under the folder), and the files in place."""
        files = [p for p in tmp_path.rglob("*") if p.is_file()]
        return (sorted(p.read_text(encoding="utf-8") for p in files),
                sorted(str(p.relative_to(tmp_path)) for p in files
                       if not any(part.startswith(".") for part in p.relative_to(tmp_path).parts)))

    def parts():  # what is on disk when each part is handed over
        for name, text in (("p_runs/a.js", "a"), ("page.html", "<p>"), ("p_runs/b.js", "b")):
            seen.append(on_disk())
            yield name, text

    assert write_page_and_files(tmp_path / "page.html", parts()) == tmp_path / "page.html"
    # each file is on disk (staged) before the next is made, none in place until every
    # one is made; the page last
    assert seen == [([], []), (["a"], []), (["a"], [])]
    assert on_disk() == (["<p>", "a", "b"], ["p_runs/a.js", "p_runs/b.js", "page.html"])
    # a mapping as before; no page among the files: refused, and no page written
    write_page_and_files(tmp_path / "m.html", {"m.html": "m", "m_runs/c.js": "c"})
    assert (tmp_path / "m.html").read_text(encoding="utf-8") == "m"
    with pytest.raises(ValueError, match="no page 'x.html'"):
        write_page_and_files(tmp_path / "x.html", [("x_runs/d.js", "d")])
    assert not (tmp_path / "x.html").exists() and not (tmp_path / "x_runs").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_a_page_whose_files_fail_while_made_stays_as_it_was(tmp_path: Path) -> None:
    """A page's files named by number (a pair's index) must never mix two pages: when
    making them fails half-way (a trace that does not read), the page and every file
    beside it stay as the last complete write left them, and nothing is left staged."""
    import pytest

    from tribopipe.files import write_page_and_files

    write_page_and_files(tmp_path / "r.html", {"r_runs/0.js": "old 0", "r_runs/1.js": "old 1",
                                                "r.html": "old page"})

    def failing():
        yield "r_runs/0.js", "new 0"
        raise OSError("the trace does not read")

    with pytest.raises(OSError, match="does not read"):
        write_page_and_files(tmp_path / "r.html", failing())
    assert {p.name: p.read_text(encoding="utf-8") for p in tmp_path.rglob("*") if p.is_file()} \
        == {"0.js": "old 0", "1.js": "old 1", "r.html": "old page"}
