"""The per-run trace plot (issue 10's speed, issue 11's normal-force panel and header).

What a reader of a trace plot relies on, checked on real PNG/SVG files and on the figure's
artists: min–max decimation keeps every pixel column's extremes (spikes included) and the
look of the line; the reused figure carries nothing over from an earlier run; the PNG drawn
from the kept background matches matplotlib's own full drawing; the header names the file,
the conditions, the readings and every flag, literally (names are never mathtext); the
force panel shows the measured and the nominal force.
"""

from __future__ import annotations

import io
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from matplotlib.image import imread
from PIL import Image

from generators.synthetic import SyntheticRun, write_rheocompass_export
from tribopipe.config import load_settings
from tribopipe.figures import (
    TraceConditions,
    TraceFigure,
    TraceMarks,
    minmax_decimate,
    plot_trace,
    plot_trace_row,
    save_figure,
    trace_figure,
)
from tribopipe.frictionmap.schema import MapRow
from tribopipe.labels import RunLabels
from tribopipe.pipeline import plot_run, reduce_file
from tribopipe.pipeline.run_outputs import run_conditions


def column_extremes(x, y, x_range, columns):
    """{column: (min, max)} of the finite y of the samples with a finite x, as the
    decimation defines columns."""
    x0, x1 = x_range
    out: dict[int, tuple[float, float]] = {}
    for xi, yi in zip(x, y, strict=True):
        if not (math.isfinite(xi) and math.isfinite(yi)):
            continue
        col = min(max(int(math.floor((xi - x0) * columns / (x1 - x0))), 0), columns - 1)
        lo, hi = out.get(col, (yi, yi))
        out[col] = (min(lo, yi), max(hi, yi))
    return out


# ---------------------------------------------------------------------------- decimation

finite = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)
value = st.one_of(finite, finite, finite, st.just(math.nan), st.just(math.inf))


def samples(x, y) -> set[tuple[float, float]]:
    """The (x, y) pairs of a line, NaN and ±inf y as one marker (all mean "no value")."""
    return {(float(a), float(b) if math.isfinite(b) else math.inf) for a, b in zip(x, y,
                                                                                 strict=True)}


@settings(max_examples=300, deadline=None)
@given(points=st.lists(st.tuples(st.floats(0.0, 5.0), value), min_size=1, max_size=400),
       columns=st.integers(1, 60))
def test_decimation_keeps_every_columns_min_and_max(points, columns):
    """For a never-decreasing x (a sliding distance): every column keeps its min and max,
    the kept samples are original samples in their order, at most two per column."""
    x = np.cumsum([step for step, _ in points])
    y = np.asarray([v for _, v in points])
    x_before, y_before = x.copy(), y.copy()
    x_range = (float(x[0]), float(x[-1]) + 1e-9)
    xd, yd = minmax_decimate(x, y, x_range, columns)
    np.testing.assert_array_equal(x, x_before)  # inputs untouched
    np.testing.assert_array_equal(y, y_before)
    assert column_extremes(xd, yd, x_range, columns) == column_extremes(x, y, x_range, columns)
    assert samples(xd, yd) <= samples(x, y)
    assert (np.diff(xd) >= 0).all()
    if x.size > 2 * columns:
        assert xd.size <= 2 * columns
    else:
        np.testing.assert_array_equal(xd, x)


@settings(max_examples=200, deadline=None)
@given(points=st.lists(st.tuples(finite, finite), min_size=2, max_size=300),
       columns=st.integers(1, 20))
def test_decimation_of_any_x_keeps_every_columns_min_and_max(points, columns):
    """x that goes back and forth (a jittering angle) still keeps every column's extremes."""
    x = np.asarray([a for a, _ in points])
    y = np.asarray([b for _, b in points])
    x_range = (float(x.min()), float(x.max()) + 1.0)
    xd, yd = minmax_decimate(x, y, x_range, columns)
    assert column_extremes(xd, yd, x_range, columns) == column_extremes(x, y, x_range, columns)
    assert samples(xd, yd) <= samples(x, y)


def test_a_one_sample_spike_survives_decimation():
    rng = np.random.default_rng(4)
    s = np.arange(15_000) * 0.0007
    mu = 0.6 + 0.01 * rng.standard_normal(s.size)
    mu[7123] = 1.1
    mu[9000] = -0.3
    xd, yd = minmax_decimate(s, mu, (s[0], s[-1]), 732)
    assert xd.size <= 2 * 732
    assert 1.1 in yd and s[7123] in xd
    assert -0.3 in yd and s[9000] in xd


def test_a_gap_in_the_data_stays_a_gap():
    s = np.arange(10_000) * 0.001
    mu = np.full(s.size, 0.5)
    mu[4000:4300] = np.nan  # 0.3 mm without data: about 30 of 100 columns
    xd, yd = minmax_decimate(s, mu, (0.0, 10.0), 100)
    gap = (xd > 4.01) & (xd < 4.29)
    assert gap.any() and np.isnan(yd[gap]).all()
    assert np.isfinite(yd[(xd < 3.99) | (xd > 4.31)]).all()


def render_line(x, y, x_range):
    """A black 0.8-pt line on a 840 × 360 px Agg canvas (no axes): the red channel."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 3), dpi=120)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_axis_off()
    ax.set_xlim(*x_range)
    ax.set_ylim(0.0, 1.2)
    ax.plot(x, y, color="k", lw=0.8)
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[..., 0].astype(int)


def test_a_decimated_line_looks_like_the_full_one():
    """15,000 noisy samples with a rise and a spike, drawn whole and decimated to the
    canvas' 840 columns: the same pixels are inked (anti-aliasing aside)."""
    rng = np.random.default_rng(1)
    s = np.arange(15_000) * 0.0007
    mu = 0.6 + 0.01 * rng.standard_normal(s.size) + 0.05 * np.sin(3 * s)
    mu[:200] = np.linspace(0.0, 0.9, 200)
    mu[7123] = 1.1
    x_range = (float(s[0]), float(s[-1]))
    full = render_line(s, mu, x_range)
    xd, yd = minmax_decimate(s, mu, x_range, 840)
    assert xd.size <= 1680
    thin = render_line(xd, yd, x_range)
    ink_full, ink_thin = full < 128, thin < 128
    overlap = (ink_full & ink_thin).sum()
    assert overlap >= 0.95 * ink_full.sum() and overlap >= 0.95 * ink_thin.sum()
    assert (np.abs(full - thin) > 64).mean() < 0.005
    # the spike's column is inked up to the spike's height in both
    col = int(s[7123] / x_range[1] * 840)
    spike_row = int(round((1.2 - 1.1) / 1.2 * 360))
    assert full[spike_row - 2 : spike_row + 3, col - 2 : col + 3].min() < 128
    assert thin[spike_row - 2 : spike_row + 3, col - 2 : col + 3].min() < 128


# ---------------------------------------------------------------------------- runs


@pytest.fixture(scope="module")
def outcomes(tmp_path_factory):
    """Two reduced runs of different length, force and shape (one with stick-slip and a
    wobbling normal force)."""
    folder = tmp_path_factory.mktemp("runs")
    settings_ = load_settings()
    out = []
    for name, run, labels in (
        ("DS30_steel_3N_20C_r1.csv", SyntheticRun(duration_s=900.0, seed=5),
         RunLabels("Dragonskin 30", "steel", 3.0, 20.0, 1)),
        ("EF50_acrylic_9N_10C_r2.csv",
         SyntheticRun(shape="stick_slip", normal_force_N=9.0, normal_force_wobble=0.15,
                      duration_s=600.0, seed=6),
         RunLabels("Ecoflex 00-50", "acrylic", 9.0, 10.0, 2)),
    ):
        raw = write_rheocompass_export(folder / name, run, project="p", test="t", sample="s")
        out.append(reduce_file(raw, settings_, labels))
    return out


def pixels(target) -> np.ndarray:
    """RGB pixels (0..1) of a PNG file or bytes."""
    data = target.getvalue() if isinstance(target, io.BytesIO) else Path(target).read_bytes()
    return imread(io.BytesIO(data))[..., :3]


def marks_of(outcome, flags=None) -> TraceMarks:
    r = outcome.result
    return TraceMarks(mu_s=r.mu_s, mu_s_distance_mm=r.mu_s_distance_mm, mu_k=r.mu_k,
                      mu_k_window_mm=r.mu_k_window_mm,
                      flags=tuple(r.flags) if flags is None else flags)


def draw(figure: TraceFigure, outcome, *, force=True, nominal=True, flags=None, source=None):
    trace = outcome.result.trace
    conditions = run_conditions(outcome)
    if not nominal:
        conditions = TraceConditions(source=conditions.source, pin=conditions.pin)
    if source is not None:
        conditions = TraceConditions(source, *list(vars(conditions).values())[1:])
    return figure.draw(trace["sliding_distance_mm"], trace["mu"], marks_of(outcome, flags),
                       mu_smooth=trace["mu_smooth"],
                       normal_force_N=trace["normal_force_N"] if force else None,
                       conditions=conditions)


def png_of(figure: TraceFigure) -> np.ndarray:
    buf = io.BytesIO()
    figure.save(buf, "png")
    return pixels(buf)


def test_the_reused_figure_keeps_nothing_of_an_earlier_run(outcomes):
    """A run drawn after others (with a nominal force or without, a force trace or none,
    other limits, flags and header, on a kept background) gives the same picture as that
    run drawn on a new figure."""
    a, b = outcomes
    reused = TraceFigure()
    for outcome in (a, b, a):
        png_of(draw(reused, outcome))
    # b's legend rows again (its kept background), another header
    fresh = png_of(draw(TraceFigure(), b, source="other.csv"))
    np.testing.assert_array_equal(png_of(draw(reused, b, source="other.csv")), fresh)
    # other legend rows (a new background), after a run with a force panel
    fresh = png_of(draw(TraceFigure(), b, force=False, nominal=False, flags=("x_flag",)))
    again = png_of(draw(reused, b, force=False, nominal=False, flags=("x_flag",)))
    np.testing.assert_array_equal(again, fresh)


def test_the_png_matches_matplotlibs_own_drawing(outcomes):
    """The PNG (kept background, grid and ticks as line collections, text typeset by
    Pillow) against the same figure drawn whole by matplotlib with its own ticks."""
    figure = draw(TraceFigure(), outcomes[1])
    fast = png_of(figure)
    figure._vector_axes(True)
    buf = io.BytesIO()
    try:
        save_figure(figure.figure, buf, "png", figure.dpi)
    finally:
        figure._vector_axes(False)
    whole = pixels(buf)
    assert fast.shape == whole.shape
    differ = np.abs(fast - whole).max(axis=2)
    assert (differ > 0.1).mean() < 0.03  # text anti-aliasing and 256 colours aside
    assert (differ > 0.5).mean() < 0.01


def test_the_figures_palette_keeps_every_runs_colours(outcomes, tmp_path):
    """PNGs are written in one palette per figure, learned from a calibration plot:
    across runs of other shapes (stick-slip, no distinct peak, a sudden slip, noisy),
    with and without a force panel, nearly every pixel is as close to the exact picture
    as with the picture's own palette, and none is far off."""
    from tribopipe.figures import png_palette

    figure = TraceFigure()
    settings_ = load_settings()
    runs = list(outcomes)
    for i, kw in enumerate([{"shape": "no_overshoot"}, {"shape": "cliff"},
                            {"noise": 0.03, "normal_force_N": 1.0}]):
        raw = write_rheocompass_export(tmp_path / f"p{i}.csv",
                                       SyntheticRun(duration_s=500.0, seed=40 + i, **kw),
                                       project="p", test="t", sample="s")
        force_N = float(kw.get("normal_force_N", SyntheticRun().normal_force_N))
        runs.append(reduce_file(raw, settings_, RunLabels("a", "b", force_N, None, None)))
    for outcome in runs:
        for force in (True, False):
            exact = draw(figure, outcome, force=force).render()
            truth = np.asarray(exact).astype(int)
            mapped = exact.quantize(palette=figure.palette(), dither=Image.Dither.NONE)
            error = np.abs(np.asarray(mapped.convert("RGB")).astype(int) - truth).max(axis=2)
            own = np.abs(np.asarray(png_palette(exact).convert("RGB")).astype(int)
                         - truth).max(axis=2)
            assert np.percentile(error, 99.9) <= max(np.percentile(own, 99.9), 12) + 4
            assert (error > 32).sum() <= 10 and error.max() <= 96


def test_tick_labels_are_matplotlibs(outcomes):
    """The labels typeset on the PNG are those matplotlib draws for the same limits."""
    figure = draw(TraceFigure(), outcomes[0])
    typeset = [text for text, *_ in figure._tick_labels]
    figure._vector_axes(True)
    try:
        figure.figure.canvas.draw()
        own = []
        for axis, (lo, hi) in ((figure.mu_ax.yaxis, figure.mu_ax.get_ylim()),
                               (figure.force_ax.yaxis, figure.force_ax.get_ylim()),
                               (figure.force_ax.xaxis, figure.force_ax.get_xlim())):
            own += [label.get_text() for loc, label in
                    zip(axis.get_majorticklocs(), axis.get_majorticklabels(), strict=True)
                    if lo <= loc <= hi]
    finally:
        figure._vector_axes(False)
    assert sorted(typeset) == sorted(own)
    assert len(typeset) >= 8


def test_header_names_file_conditions_readings_and_flags(outcomes):
    outcome = outcomes[1]
    figure = draw(TraceFigure(), outcome)
    r = outcome.result
    assert figure.title.get_text() == "EF50_acrylic_9N_10C_r2.csv"
    pressure = outcome.record.pressure_kPa
    assert figure.conditions.get_text() == (
        f"Ecoflex 00-50 on acrylic · F 9 N ({pressure:.4g} kPa per pin) · 10 °C · repeat 2")
    assert figure.readings.get_text() == (
        f"μ_S = {r.mu_s:.3f} at {r.mu_s_distance_mm:.3g} mm · μ_K = {r.mu_k:.3f} over "
        f"{r.mu_k_window_mm[0]:.3g}–{r.mu_k_window_mm[1]:.3g} mm")
    assert "stick_slip" in r.flags
    assert figure.flags.get_text() == "flags: " + ", ".join(r.flags)


def test_any_flag_list_is_in_the_header_in_red():
    figure = TraceFigure()
    s = np.linspace(0.0, 5.0, 3000)
    flags = ("peak_at_search_limit", "plateau_at_trace_end", "a_flag_added_next_year")
    figure.draw(s, np.full(s.size, 0.5), TraceMarks(None, None, 0.5, None, flags))
    assert figure.flags.get_text() == ("flags: peak_at_search_limit, plateau_at_trace_end, "
                                       "a_flag_added_next_year")
    assert figure.flags.get_color() == "tab:red"
    figure.draw(s, np.full(s.size, 0.5), TraceMarks(None, None, 0.5, None, ()))
    assert figure.flags.get_text() == "flags: none"
    assert figure.readings.get_text() == "μ_S not found · μ_K = 0.500"
    assert not figure.mu_s.get_visible() and not figure.window.get_visible()
    assert figure.mu_k.get_linestyle() == "--"  # no window: dashed over the whole run


def test_boundary_flags_and_uncertainties_are_marked():
    """Issue 14's boundary flags (whatever raises them): μ_S on its search limit is a
    hollow marker on a dotted line with a note; a μ_K window that ends with the trace is
    hatched, with a dashed line at its end and a note. U = 2u is a bar on μ_S, a band on
    μ_K, and ± U in the readings. A run without them after one with them shows none."""
    figure = TraceFigure()
    s = np.linspace(0.0, 2.0, 4000)
    mu = np.where(s < 1.2, 0.7 * s / 1.2, 0.5)
    flags = ("peak_at_search_limit", "plateau_at_trace_end")
    figure.draw(s, mu, TraceMarks(0.62, 1.06, 0.5, (1.3, 2.0), flags, 0.01, 0.002))
    assert figure.limit_line.get_visible() and list(figure.limit_line.get_xdata()) == [1.06] * 2
    assert figure.mu_s.get_markerfacecolor() == "white"
    assert figure.limit_note.get_visible() and figure.limit_note.xy == (1.06, 0.62)
    assert figure.window.get_hatch() == "//" and figure.force_window.get_hatch() is None
    assert figure.end_line.get_visible() and list(figure.end_line.get_xdata()) == [2.0] * 2
    assert figure.end_note.get_visible()
    assert figure.mu_s_bar.get_visible() and list(figure.mu_s_bar.get_ydata()) == \
        pytest.approx([0.60, 0.64])
    band = figure.mu_k_band
    assert band.get_visible() and (band.get_x(), band.get_y()) == pytest.approx((1.3, 0.496))
    assert band.get_height() == pytest.approx(0.008)
    assert figure.readings.get_text() == ("μ_S = 0.620 ± 0.020 (k = 2) at 1.06 mm · "
                                          "μ_K = 0.5000 ± 0.0040 (k = 2) over 1.3–2 mm")
    buf = io.BytesIO()
    figure.save(buf, "png")
    assert pixels(buf).std() > 0.05
    figure.draw(s, mu, TraceMarks(0.62, 1.06, 0.5, (1.3, 1.9)))
    hidden = (figure.limit_line, figure.limit_note, figure.end_line, figure.end_note,
              figure.mu_s_bar, figure.mu_k_band)
    assert not any(a.get_visible() for a in hidden)
    assert figure.window.get_hatch() is None and figure.mu_s.get_markerfacecolor() == "tab:red"


def test_conditions_line():
    assert TraceConditions().line() == "conditions unknown"
    assert TraceConditions(pin="DS30", normal_force_N=5.0).line() == "DS30 on disc ? · F 5 N"
    full = TraceConditions("f.csv", "DS30", "steel", 1.0, 11.79, 20.0, 3)
    assert full.line() == "DS30 on steel · F 1 N (11.79 kPa per pin) · 20 °C · repeat 3"
    row = MapRow(measurement_id="x", source="reduced", source_file="f.csv", pin="DS30",
                 disc="steel", normal_force_N=1.0, pressure_kPa=11.79, temperature_C=20.0,
                 repeat=3, mu_k=0.5)
    assert TraceConditions.from_row(row) == full
    unknown = replace(row, source_file=None, pin="", disc="", normal_force_N=math.nan,
                      pressure_kPa=math.nan, temperature_C=None, repeat=None)
    assert TraceConditions.from_row(unknown).line() == "conditions unknown"


def test_hostile_names_are_printed_not_parsed(outcomes, tmp_path):
    """A name with TeX-like text would break (or execute) matplotlib's mathtext: it is
    shown literally, in every format."""
    outcome = outcomes[0]
    evil = TraceConditions(source="a$b$c \\frac{ <script>.csv", pin="$\\alpha$",
                           disc="{\\bf x}$", normal_force_N=3.0)
    for fmt in ("png", "svg", "pdf"):
        target = plot_trace(outcome.result, tmp_path / f"evil.{fmt}", conditions=evil)
        assert Path(target).stat().st_size > 5_000
    figure = trace_figure()
    assert figure.title.get_text() == "a$b$c \\frac{ <script>.csv"
    assert figure.conditions.get_text().startswith("$\\alpha$ on {\\bf x}$ · F 3 N")
    assert "<script>" not in (tmp_path / "evil.svg").read_text()  # text drawn as paths


def test_a_long_file_name_is_cut_in_the_middle():
    figure = TraceFigure()
    s = np.linspace(0.0, 1.0, 100)
    name = "run_" + "x" * 300 + "_end.csv"
    figure.draw(s, s, TraceMarks(None, None, None, None), conditions=TraceConditions(name))
    title = figure.title.get_text()
    assert len(title) == 110 and title.startswith("run_x") and title.endswith("_end.csv")
    assert "…" in title


def test_force_panel_shows_measured_and_nominal_force(outcomes):
    outcome = outcomes[1]  # 9 N nominal, ±15 % wobble
    figure = draw(TraceFigure(), outcome)
    fx, fy = figure.force.get_data()
    assert figure.force.get_visible() and len(fy) <= 2 * figure.columns
    force = outcome.result.trace["normal_force_N"].to_numpy()
    assert max(fy) == force.max() and min(fy) == force.min()  # extremes kept
    assert figure.nominal.get_visible() and set(figure.nominal.get_ydata()) == {9.0}
    lo, hi = figure.force_ax.get_ylim()
    assert lo <= 0.75 * 9.0 and hi >= 1.25 * 9.0  # the ±25 % band around nominal
    assert lo <= force.min() and hi >= force.max()
    # the μ_K window is shaded on both panels
    assert figure.force_window.get_visible()
    assert figure.force_window.get_x() == pytest.approx(outcome.result.mu_k_window_mm[0])


def test_a_trace_without_normal_force_says_so(outcomes, tmp_path):
    outcome = outcomes[0]
    trace = outcome.result.trace.drop(columns=["normal_force_N", "mu_smooth"])
    row = replace(outcome.record, mu_k_window_start_mm=math.nan, mu_k_window_end_mm=math.nan,
                  flags=None, source_file=None, pin="", disc="", normal_force_N=math.nan,
                  pressure_kPa=math.nan, temperature_C=None, repeat=None)
    target = plot_trace_row(trace, row, tmp_path / "no_force.png")
    figure = trace_figure()
    assert figure.no_force.get_visible()
    assert not figure.force.get_visible() and not figure.nominal.get_visible()
    assert not figure.smooth.get_visible()
    assert figure.conditions.get_text() == "conditions unknown"
    assert pixels(target).std() > 0.05


def test_plot_run_writes_a_small_palette_png(outcomes, tmp_path):
    path = plot_run(tmp_path, outcomes[0])
    assert path.parent == tmp_path / "plots" / "traces"
    with Image.open(path) as image:
        assert image.mode == "P" and image.size == (700, 530)
        assert image.info.get("Software") == "tribopipe"
        assert len(image.getcolors(256) or []) > 20  # anti-aliased, not posterised
    assert 15_000 < path.stat().st_size < 100_000
    assert trace_figure().title.get_text() == "DS30_steel_3N_20C_r1.csv"


def test_plot_trace_row_draws_a_stored_trace(outcomes, tmp_path):
    """The report's path: a Parquet trace and a map row (with its conditions)."""
    outcome = outcomes[1]
    stored = tmp_path / "t.parquet"
    outcome.result.trace.to_parquet(stored)
    row = outcome.record
    png = plot_trace_row(pd.read_parquet(stored), row, io.BytesIO(), fmt="png", dpi=80)
    with Image.open(io.BytesIO(png.getvalue())) as image:
        assert image.size == (560, 424)
    figure = trace_figure(80)
    assert figure.title.get_text() == "EF50_acrylic_9N_10C_r2.csv"
    assert figure.conditions.get_text().startswith("Ecoflex 00-50 on acrylic · F 9 N")
    assert figure.flags.get_text() == "flags: " + str(row.flags).replace(";", ", ")
