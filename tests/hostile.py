"""What the hostile-input tests share: small real exports, the CLI run in-process and as a
subprocess, and the one rule every failure must keep (one line naming the file, no
traceback, good neighbours still land)."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path

from click.testing import CliRunner, Result

from generators.synthetic import SyntheticRun, rheocompass_text, write_rheocompass_export
from tribopipe.cli import main

#: a short good run (60 s at 0.005 rpm: 0.4 mm, enough for a plateau) with a set-up interval
GOOD_RUN = SyntheticRun(mu_s=0.8, mu_k=0.55, noise=0.004, normal_force_N=3.0,
                        temperature_C=20.0, duration_s=90.0, setup_interval=True, seed=3)


def good_export(path: Path, run: SyntheticRun = GOOD_RUN) -> Path:
    """Write a RheoCompass export of a run that reduces cleanly (UTF-16, TAB)."""
    return write_rheocompass_export(path, run, project="hostile", test="t", sample="DS30")


def good_text(run: SyntheticRun = GOOD_RUN) -> str:
    """The text of :func:`good_export` (CRLF, no BOM), for mutations."""
    return rheocompass_text(run, project="hostile", test="t", sample="DS30")


def invoke(*args: str | os.PathLike[str], cwd: Path | None = None) -> Result:
    """The CLI in this process, as a user types it (exceptions are kept in the result)."""
    runner = CliRunner()
    argv = [os.fsdecode(a) for a in args]
    if cwd is None:
        return runner.invoke(main, argv)
    old = os.getcwd()
    os.chdir(cwd)
    try:
        return runner.invoke(main, argv)
    finally:
        os.chdir(old)


def run_subprocess(*args: str | os.PathLike[str], cwd: Path | None = None,
                   timeout: float = 120, preexec_fn=None) -> subprocess.CompletedProcess:
    """``python -m tribopipe ARGS`` in a real process (bytes arguments kept as bytes)."""
    argv: list[str | bytes] = [sys.executable, "-m", "tribopipe"]
    argv += [a if isinstance(a, bytes) else os.fspath(a) for a in args]
    return subprocess.run(argv, capture_output=True, cwd=cwd, timeout=timeout,
                          preexec_fn=preexec_fn, check=False)


def assert_clean_failure(result: Result, *, exit_code: int = 1) -> str:
    """The CLI refused in one line, without a traceback; returns its stderr."""
    output = result.output
    assert "Traceback" not in output, output
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise AssertionError(f"uncaught {type(result.exception).__name__}: "
                             f"{result.exception}\n{output}")
    assert result.exit_code == exit_code, output
    return result.stderr


def error_lines(stderr: str) -> list[str]:
    """The lines of ``stderr`` that report a problem."""
    return [ln for ln in stderr.splitlines()
            if ln.startswith(("error:", "Error:", "failed:"))]


def assert_one_line_each(stderr: str, names: Sequence[str]) -> None:
    """Every name in ``names`` is reported by exactly one error line."""
    lines = error_lines(stderr)
    for name in names:
        hits = [ln for ln in lines if name in ln]
        assert len(hits) == 1, f"{name}: {len(hits)} error lines in\n{stderr}"
