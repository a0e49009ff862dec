"""Fuzzing the reader: whatever bytes it is given, it returns measurements or raises a
ReadError (one line naming the file), never another exception."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tribopipe.errors import ReadError
from tribopipe.readers import read_export

DATA = Path(__file__).resolve().parent / "data"
SMALL_FILES = [
    "rheocompass_en_utf16_small.txt",
    "rheocompass_en_utf16_amplitude_sweep.csv",
    "rheocompass_resaved_cp1252.txt",
]
REAL = {name: (DATA / name).read_bytes() for name in SMALL_FILES}
#: more examples for a long local run: TRIBOPIPE_FUZZ_EXAMPLES=600 pytest tests/test_readers_fuzz.py
FUZZ = settings(
    max_examples=int(os.environ.get("TRIBOPIPE_FUZZ_EXAMPLES", "60")),
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)


def read_or_refuse(content: bytes, suffix: str = ".csv") -> list | None:
    """Read bytes as an export; ``None`` when refused with a proper one-line ReadError."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"fuzz{suffix}"
        path.write_bytes(content)
        try:
            measurements = read_export(path)
        except ReadError as exc:
            message = str(exc)
            assert "\n" not in message and str(path) in message, message
            return None
    assert measurements, "read_export must never return an empty list"
    for m in measurements:
        assert m.meta.source_file == str(path)
        assert len(m.data) + m.meta.n_invalid_points >= (m.meta.n_points_declared or 0)
    return measurements


@FUZZ
@given(st.binary(max_size=2000))
def test_random_bytes(content: bytes) -> None:
    read_or_refuse(content)


@FUZZ
@given(st.text(max_size=800), st.sampled_from(["utf-8", "utf-16", "cp1252"]))
def test_random_text(text: str, encoding: str) -> None:
    read_or_refuse(text.encode(encoding, errors="replace"))


_CELL = st.sampled_from(["", "1", "0,5", "2.5", "******", "#NAME?", "x", "(invalid)",
                         "[s]", "[mN·m]", "Torque", "Time", "Interval data:", "Test:",
                         "1  (invalide)", "1,460", "-", "nan", "1e400",
                         "99999999999999999999999", "Point No.", "[µN·m]"])


@FUZZ
@given(st.lists(st.lists(_CELL, min_size=1, max_size=6), min_size=1, max_size=12),
       st.sampled_from(["\t", ",", ";"]))
def test_random_tables_of_plausible_cells(rows: list[list[str]], sep: str) -> None:
    text = "\n".join(sep.join(r) for r in rows)
    read_or_refuse(text.encode("utf-8"))


@FUZZ
@given(st.sampled_from(SMALL_FILES), st.integers(min_value=0, max_value=20000))
def test_truncated_real_exports(name: str, cut: int) -> None:
    raw = REAL[name]
    read_or_refuse(raw[: cut % (len(raw) + 1)])


@FUZZ
@given(st.sampled_from(SMALL_FILES), st.data())
def test_mutated_real_exports(name: str, data: st.DataObject) -> None:
    raw = bytearray(REAL[name])
    for _ in range(data.draw(st.integers(min_value=1, max_value=4))):
        position = data.draw(st.integers(min_value=0, max_value=len(raw) - 1))
        action = data.draw(st.sampled_from(["flip", "delete", "insert"]))
        if action == "flip":
            raw[position] = data.draw(st.integers(min_value=0, max_value=255))
        elif action == "delete":
            del raw[position : position + data.draw(st.integers(1, 40))]
        else:
            raw[position:position] = data.draw(st.binary(min_size=1, max_size=8))
        if not raw:
            break
    read_or_refuse(bytes(raw))


@FUZZ
@given(st.sampled_from(SMALL_FILES), st.data())
def test_real_exports_with_a_line_replaced(name: str, data: st.DataObject) -> None:
    text = REAL[name].decode("utf-16" if "utf16" in name else "cp1252")
    lines = text.splitlines()
    k = data.draw(st.integers(min_value=0, max_value=len(lines) - 1))
    lines[k] = data.draw(st.sampled_from(
        ["", "\t\t\t", "Interval data:\tPoint No.\tTime", "Test:\tX", "\t1\tx\ty",
         "Interval and data points:\t1\tmany", "\t\t[s]\t[furlong]", lines[k] * 2]))
    encoding = "utf-16" if "utf16" in name else "cp1252"
    read_or_refuse("\r\n".join(lines).encode(encoding, errors="replace"))


def test_an_unmodified_real_export_still_reads() -> None:
    """The fuzz harness itself: the originals read without error."""
    for name in SMALL_FILES:
        assert read_or_refuse(REAL[name]) is not None
