"""The user's documents: a README that is a short guide starting with the two commands,
links that lead somewhere, and no word of the project's own bookkeeping (issues,
branches, rebases) in anything a user reads."""

from __future__ import annotations

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
README = REPO / "README.md"
USER_DOCS = [README, *sorted((REPO / "docs").glob("*.md")), REPO / "bench" / "README.md"]
#: documents the README links to that come with other parts of the tool
WRITTEN_ELSEWHERE = {"docs/simulators.md", "docs/interpolation.md"}
BOOKKEEPING = re.compile(r"\b(issues?|branch(es)?|rebas(e|es|ed|ing))\b", re.IGNORECASE)


def test_the_readme_is_a_short_guide_that_starts_with_the_two_commands() -> None:
    lines = README.read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 250
    assert lines[0].startswith("# ")
    block = lines[lines.index("```") + 1:]
    assert block[:3] == ["make demo", "make test", "```"]
    for heading in ("## Install", "## The demo", "## Your own campaign, step by step",
                    "## What comes out", "## Where to read more", "## Speed and accuracy"):
        assert heading in lines


def test_no_user_document_speaks_of_issues_branches_or_rebases() -> None:
    found = []
    for doc in USER_DOCS:
        for number, line in enumerate(doc.read_text(encoding="utf-8").splitlines(), 1):
            # names in backticks (files, options, commits) are names, not words
            words = re.sub(r"`[^`]*`", "", line)
            if BOOKKEEPING.search(words):
                found.append(f"{doc.relative_to(REPO)}:{number}: {line.strip()}")
    assert found == []


def test_the_readme_links_lead_to_files() -> None:
    text = README.read_text(encoding="utf-8")
    targets = set(re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", text))
    assert "docs/tutorial.md" in targets
    missing = sorted(t for t in targets if not t.startswith("http")
                     and not (REPO / t).exists() and t not in WRITTEN_ELSEWHERE)
    assert missing == []
