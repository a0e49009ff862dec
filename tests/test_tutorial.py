"""docs/tutorial.md cannot drift: its commands are run in a fresh folder, in order, and
each one's output must be what the tutorial shows.

The tutorial's ```console blocks hold ``$ command`` lines, each followed by its output;
a ```toml or ```csv block whose info string names a file (``toml file=lab/campaign.toml``)
is written to that file before the next command runs. ``tribopipe`` commands run through
the command line in this process; the others (``mkdir``, ``cp``, ``head``) through the
shell. An output line ``...`` stands for any lines, ``...`` inside a line for any text;
paths of the temporary folder, dates and times are normalised. A command that must fail
ends its output with ``[exit N]``.

To rewrite the outputs after a deliberate change of what a command prints:
``PYTHONPATH=src python tests/test_tutorial.py --update`` (then read the diff).
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
TUTORIAL = REPO / "docs" / "tutorial.md"
FENCE = re.compile(r"^```(\S*)(?:[ \t]+file=(\S+))?[ \t]*\n(.*?)^```[ \t]*$", re.M | re.S)
EXIT = re.compile(r"^\[exit (\d+)\]$")


@dataclass
class Step:
    """A command with the output the tutorial shows, or a file it writes."""

    command: str | None = None
    expected: list[str] = field(default_factory=list)
    exit_code: int = 0
    file: str | None = None
    text: str = ""
    span: tuple[int, int] = (0, 0)  # where the output lines sit in the tutorial's text


def steps(text: str) -> list[Step]:
    """The tutorial's steps in order."""
    out: list[Step] = []
    for m in FENCE.finditer(text):
        kind, name, body = m.group(1), m.group(2), m.group(3)
        if name:
            out.append(Step(file=name, text=body))
            continue
        if kind != "console":
            continue
        offset = m.start(3)
        current: Step | None = None
        pos = offset
        for line in body.splitlines(keepends=True):
            if line.startswith("$ "):
                current = Step(command=line[2:].strip(), span=(pos + len(line),) * 2)
                out.append(current)
            elif current is not None:
                stripped = line.rstrip("\n")
                found = EXIT.match(stripped)
                if found:
                    current.exit_code = int(found.group(1))
                    current.span = (current.span[0], pos + len(line))
                else:
                    current.expected.append(stripped)
                    current.span = (current.span[0], pos + len(line))
            pos += len(line)
    return out


def normalise(text: str, root: Path) -> list[str]:
    """Output lines with the temporary folder, dates, times and trailing blanks taken out."""
    text = text.replace(str(root) + os.sep, "").replace(str(root), ".")
    text = re.sub(r"\d{4}-\d{2}-\d{2}[T ]\d{2}:\d{2}(:\d{2})?Z?( UTC)?", "<time>", text)
    text = re.sub(r"\b\d{4}-\d{2}-\d{2}\b", "<date>", text)
    text = re.sub(r"\b\d+(\.\d+)? s\b", "<seconds>", text)  # durations
    lines = [line.rstrip() for line in text.splitlines()]
    while lines and not lines[-1]:
        lines.pop()
    return lines


def _line_matches(pattern: str, line: str) -> bool:
    parts = [re.escape(p) for p in pattern.split("...")]
    return re.fullmatch(".*".join(parts), line) is not None


def matches(expected: list[str], actual: list[str]) -> bool:
    """``actual`` fits ``expected``, where a line ``...`` stands for any lines."""
    if not expected:
        return not actual
    head, rest = expected[0], expected[1:]
    if head == "...":
        return any(matches(rest, actual[i:]) for i in range(len(actual) + 1))
    return bool(actual) and _line_matches(head, actual[0]) and matches(rest, actual[1:])


def run(step: Step, root: Path) -> tuple[int, str]:
    """Run a step's command in ``root``: its exit code and its output (stdout + stderr)."""
    argv = shlex.split(step.command or "")
    if argv[0] == "tribopipe":
        from click.testing import CliRunner

        from tribopipe.cli import main

        cwd = os.getcwd()
        os.chdir(root)
        try:
            result = CliRunner().invoke(main, argv[1:], prog_name="tribopipe",
                                        catch_exceptions=False)
        finally:
            os.chdir(cwd)
        return result.exit_code, result.output
    done = subprocess.run(step.command or "", shell=True, cwd=root, capture_output=True,
                          text=True, check=False)
    return done.returncode, done.stdout + done.stderr


def prepare(root: Path) -> None:
    """The folder a reader runs the tutorial from: a copy of the repository's example
    exports (standing in for a lab's own)."""
    shutil.copytree(REPO / "raw" / "example", root / "raw" / "example")


def play(root: Path) -> list[tuple[Step, int, list[str]]]:
    """Run every step of the tutorial in ``root``: each command step with its exit code
    and normalised output."""
    prepare(root)
    results = []
    for step in steps(TUTORIAL.read_text(encoding="utf-8")):
        if step.file is not None:
            target = root / step.file
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_text(step.text, encoding="utf-8")
            continue
        code, output = run(step, root)
        results.append((step, code, normalise(output, root)))
    return results


@pytest.mark.slow
def test_the_tutorial_shows_what_its_commands_print(tmp_path: Path) -> None:
    results = play(tmp_path)
    assert len(results) >= 10
    for step, code, actual in results:
        assert code == step.exit_code, f"$ {step.command}\n" + "\n".join(actual)
        assert matches(step.expected, actual), (
            f"docs/tutorial.md is stale at `$ {step.command}`; it prints:\n"
            + "\n".join(actual)
            + "\n(PYTHONPATH=src python tests/test_tutorial.py --update rewrites the outputs)"
        )


def test_the_matcher_takes_ellipses_and_nothing_else() -> None:
    assert matches(["a", "...", "d"], ["a", "b", "c", "d"])
    assert matches(["a ... c"], ["a b c"])
    assert not matches(["a", "d"], ["a", "b", "d"])
    assert not matches(["a"], ["a", "b"])


def update() -> None:
    """Rewrite the tutorial's outputs with what its commands print now, keeping every
    ``...`` line the author wrote where the output still fits it."""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        results = play(Path(tmp))
    text = TUTORIAL.read_text(encoding="utf-8")
    for step, code, actual in sorted(results, key=lambda r: -r[0].span[0]):
        if matches(step.expected, actual) and code == step.exit_code:
            continue
        lines = actual + ([f"[exit {code}]"] if code else [])
        block = "".join(line + "\n" for line in lines)
        start, end = step.span
        text = text[:start] + block + text[end:]
    TUTORIAL.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    if sys.argv[1:] != ["--update"]:
        sys.exit(__doc__)
    update()
