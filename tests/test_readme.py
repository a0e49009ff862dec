"""The README's commands work as printed, in order, on a fresh copy: the demo's five
commands, then the lines under "After the demo", each as a user types it.

The demo runs as ``make demo`` runs it (``scripts/demo.py``) in a fresh folder holding only
what a clone holds (configs, raw/example, scripts); then each README line runs there, the
``tribopipe`` lines through the real command line. ``source .venv/bin/activate`` is what
the demo's last lines tell the user; that the ``tribopipe`` it puts on the PATH works is
held by one line run as a real process through the installed entry point.
"""

from __future__ import annotations

import importlib.util
import os
import re
import shlex
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

import pytest
from click.testing import CliRunner

from tribopipe.cli import main

REPO = Path(__file__).resolve().parents[1]
README = REPO / "README.md"


def _block_after(heading: str) -> list[str]:
    """The command lines of the first code block after ``heading`` (comments dropped)."""
    text = README.read_text(encoding="utf-8")
    section = text[text.index(f"\n{heading}\n"):]
    body = re.search(r"^```[^\n]*\n(.*?)^```", section, re.M | re.S)
    assert body is not None, heading
    lines = [re.sub(r"\s+#.*$", "", line).strip() for line in body.group(1).splitlines()]
    return [line for line in lines if line]


def _demo_module() -> ModuleType:
    spec = importlib.util.spec_from_file_location("demo", REPO / "scripts" / "demo.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def after_demo(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """A fresh copy of what a clone holds, after the demo ran in it."""
    root = tmp_path_factory.mktemp("clone")
    shutil.copytree(REPO / "configs", root / "configs")
    shutil.copytree(REPO / "raw" / "example", root / "raw" / "example")
    shutil.copytree(REPO / "scripts", root / "scripts")
    cwd = os.getcwd()
    os.chdir(root)
    try:
        assert _demo_module().run() == 0
    finally:
        os.chdir(cwd)
    yield root


def test_the_readme_shows_the_demo_s_commands() -> None:
    shown = _block_after("## The demo")
    assert shown == [f"tribopipe {shlex.join(c)}" for c in _demo_module().COMMANDS]


def test_the_demo_ends_by_saying_how_to_put_tribopipe_on_the_path() -> None:
    makefile = (REPO / "Makefile").read_text(encoding="utf-8")
    demo = makefile[makefile.index("\ndemo:"):makefile.index("\ntest:")]
    assert "source $(VENV)/bin/activate" in demo
    assert _block_after("## After the demo")[0] == "source .venv/bin/activate"
    assert "VENV   := .venv" in makefile


@pytest.mark.slow  # the demo: 48 exports reduced
def test_the_readme_commands_after_the_demo_work_as_printed(
        after_demo: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(after_demo)
    lines = _block_after("## After the demo")
    assert lines[0] == "source .venv/bin/activate"
    commands = lines[1:]
    assert len(commands) >= 5
    runner = CliRunner()
    for line in commands:
        args = shlex.split(line)
        assert args[0] == "tribopipe", line
        result = runner.invoke(main, args[1:])
        assert result.exit_code == 0, f"{line}\n{result.output}"
        assert "Traceback" not in result.output
        if args[1:2] != ["--help"]:
            # without --map each one reads the demo's map, and says so
            assert "map: processed/demo/friction_map.parquet (from ./.tribopipe-map" \
                in result.stderr, line
        if "-o" in args:
            written = after_demo / args[args.index("-o") + 1]
            assert written.is_file() and written.stat().st_size > 0, line
    assert "Dragonskin 30 on steel" in runner.invoke(main, shlex.split(
        next(c for c in commands if c.startswith("tribopipe query")))[1:]).stdout


@pytest.mark.slow  # the demo, then a real process
def test_tribopipe_on_the_path_reads_the_demo_map(after_demo: Path) -> None:
    """The entry point a venv puts on the PATH (or ``python -m tribopipe`` where the
    package runs from a source tree), as a real process in the demo's folder."""
    script = Path(sys.executable).with_name("tribopipe")
    command = [str(script)] if script.is_file() else [sys.executable, "-m", "tribopipe"]
    env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
    done = subprocess.run([*command, "map", "show"], cwd=after_demo, env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "runs: 48" in done.stdout
    assert done.stderr.startswith("map: processed/demo/friction_map.parquet")
