"""The command line as a whole: help, version, and that --help stays light."""

from __future__ import annotations

import subprocess
import sys

from click.testing import CliRunner

from tribopipe import __version__
from tribopipe.cli import COMMANDS, main

HEAVY = ("pandas", "numpy", "scipy", "matplotlib", "pyarrow")


def test_help_lists_every_command() -> None:
    result = CliRunner().invoke(main, ["--help"])
    assert result.exit_code == 0, result.output
    for name in COMMANDS:
        assert name in result.output


def test_every_command_answers_help() -> None:
    runner = CliRunner()
    for name in COMMANDS:
        result = runner.invoke(main, [name, "--help"])
        assert result.exit_code == 0, f"{name}: {result.output}"
        assert "Usage:" in result.output


def test_version() -> None:
    result = CliRunner().invoke(main, ["--version"])
    assert result.exit_code == 0
    assert __version__ in result.output


def test_help_imports_no_heavy_library() -> None:
    # `tribopipe --help` and each command's --help must not load numpy/pandas/... (speed).
    code = (
        "import contextlib, io, sys\n"
        "from tribopipe.cli import main\n"
        "for args in (['--help'],) + tuple([c, '--help'] for c in "
        f"{list(COMMANDS)!r}):\n"
        "    with contextlib.redirect_stdout(io.StringIO()):\n"
        "        try:\n"
        "            main(args, standalone_mode=False)\n"
        "        except SystemExit:\n"
        "            pass\n"
        f"loaded = [m for m in {HEAVY!r} if m in sys.modules]\n"
        "print('LOADED=' + ','.join(loaded))\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    )
    assert proc.stdout.strip() == "LOADED=", f"heavy imports: {proc.stdout}"


def test_console_script_runs_as_subprocess() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "tribopipe", "--help"], capture_output=True, text=True
    )
    assert proc.returncode == 0
    assert "friction map" in proc.stdout


def test_unknown_command_is_a_usage_error() -> None:
    result = CliRunner().invoke(main, ["frobnicate"])
    assert result.exit_code == 2
    assert "No such command" in result.output


def test_cli_reference_in_docs_is_current() -> None:
    from pathlib import Path

    # a fresh process: click caches help options on command objects that other tests invoke
    proc = subprocess.run(
        [sys.executable, "-m", "tribopipe.cli.reference"], capture_output=True, check=True
    )
    doc = Path(__file__).resolve().parents[1] / "docs" / "CLI.md"
    assert doc.read_bytes() == proc.stdout, (
        "docs/CLI.md is stale: run `python -m tribopipe.cli.reference > docs/CLI.md`"
    )
