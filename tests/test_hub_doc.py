"""docs/hub.md cannot drift: its commands are run in a fresh folder, in order, and each
one's output must be what the page shows (the rules of ``tests/test_tutorial.py``: ``...``
stands for any lines or text, paths and dates are normalised, ``[exit N]`` ends a command
that must fail).

To rewrite the outputs after a deliberate change of what a command prints:
``PYTHONPATH=src:tests python tests/test_hub_doc.py --update`` (then read the diff).
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import pytest

from test_tutorial import REPO, matches, normalise, prepare, run, steps

HUB_DOC = REPO / "docs" / "hub.md"


def play(root: Path):
    """Every step of docs/hub.md run in ``root``: each command with its exit code and its
    normalised output."""
    prepare(root)
    results = []
    for step in steps(HUB_DOC.read_text(encoding="utf-8")):
        if step.file is not None:
            target = root / step.file
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_text(step.text, encoding="utf-8")
            continue
        code, output = run(step, root)
        results.append((step, code, normalise(output, root)))
    return results


@pytest.mark.slow
def test_the_hub_page_shows_what_its_commands_print(tmp_path: Path) -> None:
    results = play(tmp_path)
    assert len(results) >= 10
    assert any(code == 1 and "hub check" in (step.command or "")
               for step, code, _ in results)  # the refusal is shown, not only successes
    for step, code, actual in results:
        assert code == step.exit_code, f"$ {step.command}\n" + "\n".join(actual)
        assert matches(step.expected, actual), (
            f"docs/hub.md is stale at `$ {step.command}`; it prints:\n" + "\n".join(actual)
            + "\n(PYTHONPATH=src:tests python tests/test_hub_doc.py --update rewrites it)")
    assert (tmp_path / "site" / "index.html").is_file()


def update() -> None:
    """Rewrite the page's outputs with what its commands print now (``...`` lines kept
    where the output still fits them)."""
    with tempfile.TemporaryDirectory() as tmp:
        results = play(Path(tmp))
    text = HUB_DOC.read_text(encoding="utf-8")
    for step, code, actual in sorted(results, key=lambda r: -r[0].span[0]):
        if matches(step.expected, actual) and code == step.exit_code:
            continue
        lines = actual + ([f"[exit {code}]"] if code else [])
        start, end = step.span
        text = text[:start] + "".join(line + "\n" for line in lines) + text[end:]
    HUB_DOC.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    if sys.argv[1:] != ["--update"]:
        sys.exit(__doc__)
    update()
