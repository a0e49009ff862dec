"""Plots: real PNG/SVG/PDF files of sensible size from really reduced runs and the
published map; headless; the `plot` commands end to end."""

from __future__ import annotations

import io
import struct
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner

from generators.synthetic import SyntheticRun, write_rheocompass_export
from published_map import PUBLISHED_CSV, published_runs, write_published_map
from reduced_runs import RUNS, make_processed
from tribopipe.cli import main
from tribopipe.config import load_settings
from tribopipe.errors import ExportError
from tribopipe.export.plots import plot_pair, plot_pairs, plot_runs
from tribopipe.figures.trace import plot_trace, plot_trace_row
from tribopipe.frictionmap import read_map
from tribopipe.frictionmap.schema import frame_rows
from tribopipe.labels import RunLabels
from tribopipe.layout import find_trace
from tribopipe.pipeline import reduce_file
from tribopipe.rounding import plus_minus

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def png_size(data: bytes) -> tuple[int, int]:
    """(width, height) from a PNG's IHDR chunk; asserts the signature."""
    assert data[:8] == PNG_SIGNATURE
    assert data[12:16] == b"IHDR"
    return struct.unpack(">II", data[16:24])


def assert_png(path: Path) -> None:
    data = path.read_bytes()
    width, height = png_size(data)
    assert 400 <= width <= 2000 and 250 <= height <= 1500
    assert len(data) > 10_000  # not a blank canvas
    from matplotlib.image import imread

    pixels = imread(path)
    assert pixels.shape[:2] == (height, width)
    assert pixels[..., :3].std() > 0.05  # something drawn


@pytest.fixture(scope="module")
def processed(tmp_path_factory) -> tuple[Path, Path]:
    return make_processed(tmp_path_factory.mktemp("campaign"))


@pytest.fixture(scope="module")
def published() -> pd.DataFrame:
    return published_runs(PUBLISHED_CSV)


def test_trace_plot_from_a_reduction_result(tmp_path):
    raw = tmp_path / "run.csv"
    write_rheocompass_export(raw, SyntheticRun(seed=11), project="p", test="t", sample="s")
    outcome = reduce_file(raw, load_settings(), RunLabels("Dragonskin 30", "steel", 3.0, 20.0))
    before = outcome.result.trace.copy()
    target = plot_trace(outcome.result, tmp_path / "plots" / "run.png", title="run.csv")
    assert Path(target).exists()
    assert_png(Path(target))
    pd.testing.assert_frame_equal(outcome.result.trace, before)


def test_a_boundary_reading_is_marked_on_the_trace_plot(tmp_path):
    """Issue 14: a μ_S on its search limit and a μ_K window at the trace's end are marked
    (hollow marker, dotted line, hatched window, notes); U = 2u drawn as bar and band."""
    from tribopipe.figures import TraceMarks, trace_figure
    from tribopipe.labels import flag_list

    settings = load_settings()
    raw = tmp_path / "run.csv"
    # a peak at 1 mm, the trace ending 0.65 mm after it: the plateau is cut short
    write_rheocompass_export(raw, SyntheticRun(peak_distance_mm=1.0, duration_s=238.0, seed=6),
                             project="p", test="t", sample="s")
    result = reduce_file(raw, settings, RunLabels("Dragonskin 30", "steel", 3.0, 20.0)).result
    assert "plateau_at_trace_end" in result.flags
    png = plot_trace(result, tmp_path / "boundary.png")
    assert_png(Path(png))
    figure = trace_figure()  # the figure plot_trace drew on
    assert figure.end_note.get_visible() and figure.window.get_hatch() == "//"
    assert f"{plus_minus(result.mu_k, 2 * result.u_mu_k)} (k = 2)" in figure.readings.get_text()
    assert figure.mu_k_band.get_visible()
    assert "plateau_at_trace_end" in figure.flags.get_text()

    def drawn(flags: tuple[str, ...]):
        trace = result.trace
        marks = TraceMarks(result.mu_s, result.mu_s_distance_mm, result.mu_k,
                           result.mu_k_window_mm, flags, result.u_mu_s, result.u_mu_k)
        return figure.draw(trace["sliding_distance_mm"].to_numpy(), trace["mu"].to_numpy(),
                           marks)

    drawn((*flag_list(result.flags), "peak_at_search_limit"))
    assert figure.limit_note.get_visible() and figure.limit_line.get_visible()
    assert figure.mu_s.get_markerfacecolor() == "white"
    assert figure.limit_note.get_text() == "$\\mu_S$ at search limit"
    assert figure.end_note.get_text() == "$\\mu_K$ window at trace end"
    drawn(())  # no flag, no note
    assert not figure.limit_note.get_visible() and not figure.end_note.get_visible()
    assert figure.window.get_hatch() is None


def test_trace_plot_from_parquet_and_map_row_in_every_format(processed, tmp_path):
    map_path, proc = processed
    row = frame_rows(read_map(map_path))[0]
    trace = pd.read_parquet(find_trace(proc / "traces", row.measurement_id))
    png = plot_trace_row(trace, row, tmp_path / "t.png")
    assert_png(Path(png))
    svg = Path(plot_trace_row(trace, row, tmp_path / "t.svg"))
    root = ET.parse(svg).getroot()
    assert root.tag.endswith("svg")
    # the μ_S and μ_K labels are in the legend text
    assert "0." in svg.read_text()
    pdf = Path(plot_trace_row(trace, row, tmp_path / "t", fmt="pdf"))
    assert pdf.suffix == ".pdf"
    data = pdf.read_bytes()
    assert data.startswith(b"%PDF-") and data.rstrip().endswith(b"%%EOF")


def test_plot_to_a_stream_needs_a_format(processed):
    map_path, proc = processed
    row = frame_rows(read_map(map_path))[0]
    trace = pd.read_parquet(find_trace(proc / "traces", row.measurement_id))
    buf = io.BytesIO()
    plot_trace_row(trace, row, buf, fmt="png")
    assert png_size(buf.getvalue())[0] > 400
    with pytest.raises(ExportError, match="needs a format"):
        plot_trace_row(trace, row, io.BytesIO())
    with pytest.raises(ExportError, match="png, svg, pdf"):
        plot_trace_row(trace, row, io.BytesIO(), fmt="gif")


def test_plot_runs_draws_every_run_with_a_trace(processed, published, tmp_path):
    map_path, proc = processed
    runs = pd.concat([read_map(map_path), published.iloc[:3]], ignore_index=True)
    written, missing = plot_runs(runs, proc / "traces", tmp_path / "traces")
    assert len(written) == len(RUNS)
    assert len(missing) == 3  # imported rows have no trace
    for path in written:
        assert_png(path)
        assert find_trace(proc / "traces", path.stem.rsplit("_", 1)[1]) is not None


def test_pair_plot_of_the_published_map(published, tmp_path):
    target = plot_pair(published, "Dragonskin 30", "steel", tmp_path / "ds_steel.png")
    assert_png(Path(target))
    svg = Path(plot_pair(published, "Dragonskin 30", "steel", tmp_path / "ds_steel.svg"))
    text = svg.read_text()
    # one series per temperature, each with its fitted curve in the legend
    assert "10 °C" in text and "20 °C" in text
    assert text.count("fit $\\mu_K$ = ") == 2 and text.count("(p / kPa)") == 2


def test_pair_plots_one_file_per_pair(published, tmp_path):
    written = plot_pairs(published, tmp_path / "pairs", fmt="png")
    assert len(written) == 11
    assert tmp_path / "pairs" / "pair_dragonskin-30__wood-structured.png" in written
    for path in written[:3]:
        assert_png(path)


def test_pair_plot_unknown_pair(published, tmp_path):
    with pytest.raises(ExportError, match="the map holds"):
        plot_pair(published, "Sylgard", "steel", tmp_path / "x.png")


def test_plot_commands(processed, tmp_path):
    map_path, proc = processed
    runner = CliRunner()
    result = runner.invoke(main, ["plot", "pairs", "--map", str(map_path), "-o",
                                  str(tmp_path / "pairs"), "--format", "svg"],
                           catch_exceptions=False)
    assert result.exit_code == 0
    files = sorted((tmp_path / "pairs").glob("*.svg"))
    assert [f.name for f in files] == ["pair_dragonskin-30__steel.svg",
                                       "pair_ecoflex-00-50__wood-smooth.svg"]
    result = runner.invoke(main, ["plot", "runs", "--map", str(map_path), "--processed",
                                  str(proc), "-o", str(tmp_path / "runs")],
                           catch_exceptions=False)
    assert result.exit_code == 0
    assert len(list((tmp_path / "runs").glob("*.png"))) == len(RUNS)
    result = runner.invoke(main, ["plot", "runs", "--map", str(map_path), "--processed",
                                  str(tmp_path / "nowhere")])
    assert result.exit_code == 1 and "trace folder not found" in result.output


@pytest.mark.slow
def test_plot_pairs_in_a_real_process_and_no_matplotlib_at_import(tmp_path):
    map_path = write_published_map(PUBLISHED_CSV,
                                   tmp_path / "map.parquet")
    proc = subprocess.run(
        [sys.executable, "-m", "tribopipe", "plot", "pairs", "--map", str(map_path),
         "--pin", "Ecoflex 00-50", "-o", str(tmp_path / "out"), "--format", "pdf"],
        capture_output=True, text=True, timeout=180, env={"MPLBACKEND": "TkAgg",
                                                          "PATH": "/usr/bin:/bin"},
    )
    assert proc.returncode == 0, proc.stderr
    assert len(list((tmp_path / "out").glob("*.pdf"))) == 2
    check = subprocess.run(
        [sys.executable, "-c",
         "import sys, tribopipe.export.plots, tribopipe.cli.plot; "
         "print('matplotlib' in sys.modules)"],
        capture_output=True, text=True, timeout=60,
    )
    assert check.stdout.strip() == "False"
