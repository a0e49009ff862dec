"""Tables that go straight into a paper: the LaTeX table compiles as written with real TeX
(Debian's texlive: pdflatex, booktabs, siunitx), with exactly the packages its first lines
name; text is escaped, numbers align on the decimal point, the ± U note stays. Markdown
carries no HTML entity.

Where no ``pdflatex`` exists the compiling tests skip and say why; CI sets
``TRIBOPIPE_REQUIRE_TEX=1`` (``.ci/run`` installs texlive) and so fails instead.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pandas as pd
import pytest

from published_map import PUBLISHED_CSV, published_runs
from reduced_runs import SPREAD_RUNS, make_processed
from tribopipe.export import tables
from tribopipe.export.tables import LATEX_PACKAGES, PAPER_NOTE, render_table

HOSTILE = "Ecoflex #1 & 50% $x_y$ {a} ~^\\ <b> μ ±−° 中"


def _pdflatex() -> str:
    found = os.environ.get("TRIBOPIPE_PDFLATEX") or shutil.which("pdflatex")
    if found is None:
        reason = "no pdflatex on PATH (Debian: apt-get install texlive-latex-recommended " \
                 "texlive-science)"
        if os.environ.get("TRIBOPIPE_REQUIRE_TEX") == "1":
            pytest.fail(f"TRIBOPIPE_REQUIRE_TEX=1 but {reason}")
        pytest.skip(reason)
    return found


def _packages(tex: str) -> list[str]:
    """The packages the table's own first lines say it needs."""
    line = next(ln for ln in tex.splitlines() if ln.startswith("% Needs in the preamble:"))
    return re.findall(r"\\usepackage\{([^}]+)\}", line)


def _compile(tex: str, folder: Path) -> str:
    """Compile ``tex`` as its header says (\\input in a table, the named packages) in a
    plain article; the log. Fails on any LaTeX error or a missing character."""
    (folder / "table.tex").write_text(tex, encoding="utf-8")
    preamble = "".join(f"\\usepackage{{{p}}}\n" for p in _packages(tex))
    (folder / "doc.tex").write_text(
        "\\documentclass{article}\n" + preamble
        + "\\usepackage[a4paper,landscape,margin=1cm]{geometry}\n"
        + "\\begin{document}\n\\begin{table}\n\\input{table.tex}\n\\end{table}\n"
        + "\\end{document}\n", encoding="utf-8")
    done = subprocess.run([_pdflatex(), "-interaction=nonstopmode", "-halt-on-error",
                           "doc.tex"], cwd=folder, capture_output=True, text=True,
                          timeout=120)
    log = (folder / "doc.log").read_text(encoding="latin-1")
    assert done.returncode == 0, log[-3000:]
    assert (folder / "doc.pdf").stat().st_size > 1000
    assert "Missing character" not in log
    return log


@pytest.fixture(scope="module")
def runs() -> pd.DataFrame:
    return published_runs(PUBLISHED_CSV)


@pytest.fixture(scope="module")
def budget_runs(tmp_path_factory: pytest.TempPathFactory) -> pd.DataFrame:
    """Reduced runs with μ_S and U budgets, one pin named with every LaTeX special."""
    from tribopipe.frictionmap import read_map

    map_path, _ = make_processed(tmp_path_factory.mktemp("reduced"), SPREAD_RUNS)
    frame = read_map(map_path)
    frame.loc[frame.index[: len(frame) // 2], "pin"] = HOSTILE
    return frame


def test_the_table_states_its_packages() -> None:
    assert LATEX_PACKAGES == ("booktabs", "siunitx")
    text = tables.to_latex(pd.DataFrame({"pin": ["a"], "p": [1.5]}))
    assert _packages(text) == ["booktabs", "siunitx"]
    assert "\\toprule" in text and "S[table-format=1.1]" in text


@pytest.mark.parametrize("layout", ["paper", "group", "abstract"])
def test_every_layout_compiles_as_written(runs, layout: str, tmp_path: Path) -> None:
    _compile(render_table(runs, fmt="latex", layout=layout, disc=["steel"]), tmp_path)


def test_the_paper_table_with_mu_s_budgets_and_hostile_names_compiles(
        budget_runs, tmp_path: Path) -> None:
    tex = render_table(budget_runs, fmt="latex", layout="paper")
    assert r"\multicolumn{3}{c}{$\mu_S \pm U$}" in tex
    assert "\\#1 \\& 50\\% \\$x\\_y\\$ \\{a\\}" in tex and "[U+4E2D]" in tex
    assert "\\textgreater{}" in tex and "<" not in tex.replace("\\textless{}", "")
    _compile(tex, tmp_path)
    # the group table of the same runs (every statistic column) compiles too
    _compile(render_table(budget_runs, fmt="latex", layout="group"), tmp_path)


def test_numbers_align_on_the_decimal_point_and_the_note_stays(runs) -> None:
    tex = render_table(runs, fmt="latex", layout="paper", disc=["steel"])
    spec = re.search(r"\\begin\{tabular\}\{(.*)\}$", tex, re.M)
    assert spec is not None
    columns = re.findall(r"S\[table-format=[-\d.]+\]|@\{\\,\}c@\{\\,\}|[lrc]", spec.group(1))
    # p, T, n, then μ_K's value, ±, U: the numbers in siunitx S columns
    assert [c[0] for c in columns] == ["l", "l", "S", "S", "S", "S", "@", "S", "l"]
    every = render_table(runs, fmt="latex", layout="paper")
    assert "range \\textgreater{} r" in every  # never a raw ">" (OT1 prints it as ¿)
    note = tex.splitlines()[-1]
    assert note.startswith("{\\footnotesize \\ensuremath{\\pm} U: expanded uncertainty")
    assert "\\ensuremath{-}value" in note


def test_a_value_whose_interval_reaches_below_zero_is_bounded() -> None:
    assert tables._pm_cells("0.05", "0.11") == ("0.05", "", "{$^{+0.11}_{-0.05}$}")
    assert tables._pm_cells("0.50", "0.11") == ("0.50", "$\\pm$", "0.11")
    assert tables._pm_cells("0.550", "") == ("0.550", "", "")


def test_markdown_carries_no_html_entity(runs, budget_runs) -> None:
    for frame in (runs, budget_runs):
        for layout in ("paper", "group"):
            text = render_table(frame, fmt="markdown", layout=layout)
            assert re.search(r"&(#\d+|#x[0-9a-f]+|[a-z]+);", text, re.I) is None
            assert re.search(r"(?<!\\)[<&]", text) is None  # escaped: no HTML can form
    paper = render_table(runs, fmt="markdown", layout="paper")
    assert "range > r" in paper
    assert PAPER_NOTE.split(";")[0] in paper.replace("\\", "")
