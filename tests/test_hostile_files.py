"""Every file-system failure is one line, never a traceback, and fails only its file.

Real objects, no mocks: directories, FIFOs, devices, symlink loops, unreadable files,
names that are not UTF-8 or too long, damaged workbooks, and output folders that are
read-only or full (a real tmpfs in a private mount namespace where the machine allows it).
Cases that could hang or eat the memory of the code before the fix (a FIFO, /dev/zero)
run as a subprocess with a timeout and an address-space limit.
"""

from __future__ import annotations

import csv
import json
import os
import resource
import shutil
import stat
import subprocess
import sys
import zipfile
from dataclasses import replace
from pathlib import Path

import pytest

from hostile import (
    GOOD_RUN,
    assert_clean_failure,
    assert_one_line_each,
    error_lines,
    good_export,
    invoke,
    run_subprocess,
)
from tribopipe.frictionmap import read_map

DATA = Path(__file__).resolve().parent / "data"
PATTERN = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}_{note}"
IS_ROOT = hasattr(os, "geteuid") and os.geteuid() == 0
#: the memory a subprocess may map: enough to run, too little to read /dev/zero for long
ADDRESS_SPACE = 6 * 1024**3


def _limited() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))


def _unreadable(folder: Path, name: str, how: str) -> Path:
    """A file that cannot be read: ``chmod 000`` for a user; for root (who reads such a
    file anyway) a link to ``/proc/self/mem``, a regular file whose first read is an
    I/O error."""
    path = folder / name
    if how == "chmod":
        if IS_ROOT:
            pytest.skip("running as root: chmod 000 does not stop root from reading; the "
                        "/proc/self/mem case covers an unreadable file")
        path.write_text("secret", encoding="utf-8")
        path.chmod(0)
        return path
    if not Path("/proc/self/mem").exists():
        pytest.skip("no /proc/self/mem on this system")
    path.symlink_to("/proc/self/mem")
    return path


def _bad_object(folder: Path, kind: str) -> Path:
    """A path named like an export that is not a readable regular file."""
    name = f"bad_{kind}.csv"
    path = folder / name
    if kind == "missing":
        return path
    if kind == "directory":
        path.mkdir()
    elif kind == "fifo":
        os.mkfifo(path)
    elif kind == "symlink_loop":
        path.symlink_to(path.name)
    elif kind == "dangling_symlink":
        path.symlink_to("nowhere.csv")
    elif kind == "dev_zero":
        path.symlink_to("/dev/zero")
    elif kind in ("chmod", "proc_mem"):
        return _unreadable(folder, name, "chmod" if kind == "chmod" else "proc")
    elif kind == "name_too_long":
        return folder / ("n" * 300 + ".csv")
    else:  # pragma: no cover
        raise ValueError(kind)
    return path


KINDS = ["missing", "directory", "fifo", "symlink_loop", "dangling_symlink", "dev_zero",
         "chmod", "proc_mem", "name_too_long"]


@pytest.mark.slow
@pytest.mark.parametrize("kind", KINDS)
def test_reduce_fails_a_bad_path_alone(tmp_path: Path, kind: str) -> None:
    bad = _bad_object(tmp_path, kind)
    good = good_export(tmp_path / "good.csv")
    out = tmp_path / "out"
    done = run_subprocess("reduce", bad, good, "--no-map", "--output", out, timeout=90,
                          preexec_fn=_limited)
    stderr = done.stderr.decode("utf-8", "replace")
    assert b"Traceback" not in done.stderr and "Usage:" not in stderr, stderr
    assert done.returncode == 1, stderr
    assert_one_line_each(stderr, [bad.name[:60]])
    assert len(list((out / "summaries").glob("good_*.json"))) == 1, stderr


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["fifo", "dev_zero", "directory"])
def test_inspect_refuses_a_special_file_in_one_line(tmp_path: Path, kind: str) -> None:
    bad = _bad_object(tmp_path, kind)
    done = run_subprocess("inspect", bad, timeout=90, preexec_fn=_limited)
    stderr = done.stderr.decode("utf-8", "replace")
    assert b"Traceback" not in done.stderr and done.returncode != 0, stderr
    assert len(stderr.strip().splitlines()) == 1, stderr


def _campaign(tmp_path: Path) -> tuple[Path, Path]:
    raw = tmp_path / "raw"
    raw.mkdir()
    cfg = tmp_path / "c.toml"
    cfg.write_text(f'[campaign]\nname = "fs"\nraw_dir = "raw"\noutput_dir = "out"\n'
                   f'filename_pattern = "{PATTERN}"\nplots = false\n', encoding="utf-8")
    return cfg, raw


def test_batch_lists_every_bad_path_and_lands_the_good_ones(tmp_path: Path) -> None:
    cfg, raw = _campaign(tmp_path)
    good_export(raw / "DS30_steel_3N_20C_r1_a.csv", replace(GOOD_RUN, seed=21))
    # a name that is not UTF-8 and one near the 255-byte limit are kept and reduced
    odd = os.fsdecode(os.fsencode(str(raw)) + b"/DS30_steel_3N_20C_r2_\xff\xfe.csv")
    good_export(Path(odd), replace(GOOD_RUN, seed=22))
    long_name = "DS30_steel_3N_20C_r3_" + "l" * 220 + ".csv"
    good_export(raw / long_name, replace(GOOD_RUN, seed=23))
    bad = ["directory", "fifo", "symlink_loop", "dangling_symlink"]
    bad_paths = [_bad_object(raw, k) for k in bad]
    bad_paths.append(_unreadable(raw, "bad_unreadable.csv",
                                 "proc" if IS_ROOT else "chmod"))
    result = invoke("batch", str(cfg), "--jobs", "1")
    stderr = assert_clean_failure(result)
    assert_one_line_each(stderr, [p.name for p in bad_paths])
    runs = read_map(tmp_path / "out" / "friction_map.parquet")
    assert sorted(runs["repeat"].tolist()) == [1, 2, 3]
    assert "DS30_steel_3N_20C_r2_\\xff\\xfe.csv" in set(runs["source_file"])
    out = tmp_path / "out"
    for name in ("runs.csv", "failures.csv"):
        text = (out / name).read_bytes().decode("utf-8")   # strict UTF-8
        rows = list(csv.reader(text.splitlines()))
        assert len(rows) == (9 if name == "runs.csv" else 6), rows
    assert "DS30_steel_3N_20C_r2_\\xff\\xfe.csv" in (out / "runs.csv").read_text("utf-8")
    traces = sorted(p.name for p in (out / "traces").iterdir())
    assert len(traces) == 3 and all(len(t.encode()) < 120 and t.isprintable() for t in traces)
    # the next batch re-lists the same failures and reduces nothing again
    again = invoke("batch", str(cfg), "--jobs", "1")
    assert_one_line_each(assert_clean_failure(again), [p.name for p in bad_paths])
    assert "0 reduced, 3 skipped" in again.stdout


def test_reduce_keeps_a_name_that_is_not_utf8(tmp_path: Path) -> None:
    raw = os.fsencode(str(tmp_path)) + b"/caf\xe9_run.csv"
    good_export(Path(os.fsdecode(raw)))
    out = tmp_path / "out"
    result = invoke("reduce", os.fsdecode(raw), "--json", "--no-map", "--output", str(out))
    assert result.exit_code == 0, result.output
    rows = json.loads(result.stdout)
    assert rows[0]["file"].endswith("caf\\xe9_run.csv")
    assert [p.name.startswith("caf__run_") for p in (out / "traces").iterdir()] == [True]
    done = run_subprocess("reduce", raw, "--no-map", "--output", out)
    assert done.returncode == 0 and b"caf\\xe9_run.csv" in done.stdout, done.stderr


# ------------------------------------------------------------------ read-only and full


def _mount_namespace_works() -> bool:
    if not (IS_ROOT and shutil.which("unshare")):
        return False
    probe = subprocess.run(["unshare", "--mount", "sh", "-c",
                            "mount -t tmpfs -o size=16k tmpfs /mnt 2>/dev/null || "
                            "mount -t tmpfs -o size=16k tmpfs /tmp"],
                           capture_output=True, check=False)
    return probe.returncode == 0


MOUNTS = _mount_namespace_works()


def _run_on_small_disk(folder: Path, args: list, *, size_kb: int, read_only: bool,
                       cwd: Path | None = None) -> subprocess.CompletedProcess:
    """``tribopipe ARGS`` with ``folder`` a fresh tmpfs of ``size_kb`` (read-only when
    asked) in a private mount namespace; without one, the nearest real thing: a folder
    without write permission (a user) or a file-size limit (root)."""
    folder.mkdir(exist_ok=True)
    argv = [sys.executable, "-m", "tribopipe", *[os.fspath(a) for a in args]]
    if MOUNTS:
        options = f"size={size_kb}k" + (",ro" if read_only else "")
        script = f'mount -t tmpfs -o {options} tmpfs "$0" && exec "$@"'
        return subprocess.run(["unshare", "--mount", "sh", "-c", script, str(folder), *argv],
                              capture_output=True, cwd=cwd, timeout=180, check=False)
    if read_only and not IS_ROOT:
        folder.chmod(0o555)
        try:
            return subprocess.run(argv, capture_output=True, cwd=cwd, timeout=180,
                                  check=False)
        finally:
            folder.chmod(0o755)
    if read_only:
        pytest.skip("root without a private mount namespace: no read-only folder to use")

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (size_kb * 1024, size_kb * 1024))
    return subprocess.run(argv, capture_output=True, cwd=cwd, timeout=180, check=False,
                          preexec_fn=limit)


@pytest.mark.slow
@pytest.mark.parametrize("read_only", [True, False], ids=["read-only", "full"])
def test_reduce_to_an_unwritable_out_is_one_line_per_file(tmp_path: Path,
                                                          read_only: bool) -> None:
    a = good_export(tmp_path / "a.csv", replace(GOOD_RUN, seed=31))
    b = good_export(tmp_path / "b.csv", replace(GOOD_RUN, seed=32))
    done = _run_on_small_disk(tmp_path / "out", ["reduce", a, b, "--no-map", "--output",
                                                 tmp_path / "out"], size_kb=8,
                              read_only=read_only)
    stderr = done.stderr.decode()
    assert b"Traceback" not in done.stderr and done.returncode == 1, stderr
    assert_one_line_each(stderr, ["a.csv", "b.csv"])


@pytest.mark.slow
@pytest.mark.parametrize("read_only", [True, False], ids=["read-only", "full"])
def test_batch_to_an_unwritable_out_is_one_line(tmp_path: Path, read_only: bool) -> None:
    cfg, raw = _campaign(tmp_path)
    for i in range(3):
        good_export(raw / f"DS30_steel_3N_20C_r{i + 1}_x.csv", replace(GOOD_RUN, seed=40 + i))
    done = _run_on_small_disk(tmp_path / "out", ["batch", cfg, "--jobs", "1"], size_kb=48,
                              read_only=read_only)
    stderr = done.stderr.decode()
    assert b"Traceback" not in done.stderr and done.returncode == 1, stderr
    assert error_lines(stderr), stderr


def test_batch_whose_state_cannot_be_saved_is_one_line(tmp_path: Path) -> None:
    cfg, raw = _campaign(tmp_path)
    good_export(raw / "DS30_steel_3N_20C_r1_x.csv")
    out = tmp_path / "out"
    out.mkdir()
    (out / ".tribopipe-state.fs.sqlite").mkdir()   # the state's name is taken by a folder
    result = invoke("batch", str(cfg), "--jobs", "1")
    stderr = assert_clean_failure(result)
    assert ".tribopipe-state.fs.sqlite" in stderr and len(error_lines(stderr)) == 1, stderr
    assert (out / "runs.csv").is_file() and (out / "failures.csv").is_file()


# ------------------------------------------------------------------ damaged workbooks


def _rewrite(src: Path, dst: Path, change, compress: int = zipfile.ZIP_DEFLATED) -> Path:
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w", compress) as zout:
        for info in zin.infolist():
            zout.writestr(info.filename, change(info.filename, zin.read(info.filename)),
                          compress_type=compress)
    return dst


def _damaged_xlsx(tmp_path: Path, how: str) -> Path:
    src = DATA / "rheocompass_en_two_tests.xlsx"
    dst = tmp_path / f"damaged_{how}.xlsx"
    if how == "bad_crc":
        _rewrite(src, dst, lambda n, d: d, compress=zipfile.ZIP_STORED)
        raw = bytearray(dst.read_bytes())
        k = raw.find(b"<sheetData>") + 200
        raw[k] ^= 0x01      # a stored byte changed after its CRC was written
        dst.write_bytes(bytes(raw))
    elif how == "invalid_xml":
        _rewrite(src, dst, lambda n, d: d[: len(d) // 2] + b"<<<>"
                 if n.endswith("sheet1.xml") else d)
    elif how == "empty_column_name":
        import openpyxl

        book = openpyxl.load_workbook(src)
        for row in book.worksheets[0].iter_rows():
            if row[0].value and str(row[0].value).startswith("Interval data"):
                for cell in row[1:]:
                    cell.value = None
        book.save(dst)
    return dst


@pytest.mark.parametrize("how", ["bad_crc", "invalid_xml", "empty_column_name"])
def test_a_damaged_workbook_is_one_line_and_its_neighbour_reduces(tmp_path: Path,
                                                                  how: str) -> None:
    bad = _damaged_xlsx(tmp_path, how)
    good = good_export(tmp_path / "good.csv")
    result = invoke("reduce", str(bad), str(good), "--no-map", "--output", str(tmp_path / "o"))
    stderr = assert_clean_failure(result)
    assert_one_line_each(stderr, [bad.name])
    assert len(list((tmp_path / "o" / "summaries").glob("good_*.json"))) == 1


# ------------------------------------------------------------------ the map path


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["fifo", "directory", "dev_zero"])
def test_a_map_path_that_is_not_a_file_is_refused(tmp_path: Path, kind: str) -> None:
    target = _bad_object(tmp_path, kind)
    if kind == "directory":
        # a map is a folder of parts now, and an empty folder an empty map: a folder
        # holding anything but a map is what must be refused
        (target / "notes.txt").write_text("not a map\n", encoding="utf-8")
    done = run_subprocess("map", "show", "--map", target, timeout=90, preexec_fn=_limited)
    stderr = done.stderr.decode()
    assert b"Traceback" not in done.stderr and done.returncode == 1, stderr
    assert len(stderr.strip().splitlines()) == 1 and target.name in stderr, stderr
    if kind == "fifo":
        assert stat.S_ISFIFO(os.lstat(target).st_mode)   # left as it was
