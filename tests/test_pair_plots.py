"""Pair plots for a paper: μ_S beside μ_K where measured, the fit's legend says p is in
kPa, and `plot pairs --dpi` sets the resolution of the PNG."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner
from PIL import Image

from published_map import PUBLISHED_CSV, published_runs
from reduced_runs import SPREAD_RUNS, make_processed
from tribopipe.cli import main
from tribopipe.export.plots import draw_pair, fit_label
from tribopipe.figures import new_figure
from tribopipe.fit import fit_power_law
from tribopipe.frictionmap import read_map


@pytest.fixture(scope="module")
def reduced(tmp_path_factory: pytest.TempPathFactory) -> Path:
    map_path, _ = make_processed(tmp_path_factory.mktemp("pairs"), SPREAD_RUNS)
    return map_path


def _labels(runs, with_s: bool) -> tuple[list[str], str]:
    ax = new_figure(6.4, 5.2).add_subplot()
    fits_s = fit_power_law(runs, quantity="mu_s") if with_s else None
    draw_pair(ax, runs, fit_power_law(runs), fits_s)
    return ax.get_legend_handles_labels()[1], ax.get_ylabel()


def test_mu_s_is_drawn_beside_mu_k(reduced: Path) -> None:
    runs = read_map(reduced)
    runs = runs[(runs["disc"] == "steel") & ~runs["excluded"].astype(bool)]
    labels, ylabel = _labels(runs, with_s=True)
    assert any("$\\mu_S$: mean ± SD" in t for t in labels)
    assert any("$\\mu_K$: mean ± SD" in t for t in labels)
    assert any(t.startswith("20 °C fit $\\mu_S$ = ") for t in labels)
    assert "$\\mu_S$" in ylabel and "$\\mu_K$" in ylabel


def test_a_map_without_mu_s_draws_mu_k_alone() -> None:
    runs = published_runs(PUBLISHED_CSV)
    runs = runs[(runs["pin"] == "Dragonskin 30") & (runs["disc"] == "steel")]
    labels, ylabel = _labels(runs, with_s=False)
    assert labels and not any("mu_S" in t for t in labels)
    assert ylabel == "kinetic coefficient of friction $\\mu_K$"


def test_the_fit_legend_says_p_is_in_kpa() -> None:
    text = fit_label("$\\mu_K$", 3.451, -0.5443, 0.9971)
    assert text == "fit $\\mu_K$ = 3.45·(p / kPa)$^{-0.544}$, R² = 0.997"


def test_dpi_sets_the_png_resolution(reduced: Path, tmp_path: Path) -> None:
    sizes = {}
    for dpi in (60, 120):
        out = tmp_path / f"d{dpi}"
        done = CliRunner().invoke(main, ["plot", "pairs", "--map", str(reduced), "--dpi",
                                         str(dpi), "-o", str(out)])
        assert done.exit_code == 0, done.output
        (png,) = sorted(out.glob("pair_dragonskin-30__steel.png"))
        with Image.open(png) as image:
            sizes[dpi] = image.size
    assert sizes[120][0] == pytest.approx(2 * sizes[60][0], abs=2)
    assert sizes[120][0] == pytest.approx(6.4 * 120, abs=2)
    refused = CliRunner().invoke(main, ["plot", "pairs", "--map", str(reduced), "--dpi", "5"])
    assert refused.exit_code == 2


def test_the_dpi_default_in_help_is_the_figures_default() -> None:
    from tribopipe.figures import DPI

    text = " ".join(CliRunner().invoke(main, ["plot", "pairs", "--help"]).output.split())
    assert f"Default: {DPI}." in text
