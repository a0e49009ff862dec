"""Seeded synthetic pin-on-disc runs with known truth, and a RheoCompass export writer.

A :class:`SyntheticRun` describes a run (true μ_S, μ_K, the shape of the μ(s) curve, noise,
torque offset, ...); :func:`make_intervals` turns it into the intervals an instrument would
record (an optional normal-force set-up interval, then the friction interval) as DataFrames
with the canonical SI columns of :mod:`tribopipe.measurement`; :func:`truth` gives what a
correct reduction must find. :func:`write_rheocompass_export` writes the run the way Anton
Paar RheoCompass exports it (UTF-16 LE with BOM, TAB, CRLF, ``Project:``/``Test:``/
``Result:`` blocks, one ``Interval data:`` table per interval with a unit row).

The model (s = sliding distance at the friction radius, s_pk = static peak distance):

``overshoot``     μ rises (elastic pre-sliding, quadratic) to μ_S at s_pk, then decays to
                  μ_K with a short length λ (0.03–0.08 mm);
``no_overshoot``  μ rises monotonically to μ_K (no static peak: truth μ_S = μ_K);
``stick_slip``    as overshoot up to s_pk, then a saw-tooth of amplitude A around μ_K
                  (slow stick rise, sudden slip) with period 0.02–0.04 mm; μ_K is its mean;
                  A defaults to 0.6·(μ_S − μ_K) within 0.08–0.2;
``drift``         as overshoot, but the decay to μ_K is slow (λ = 0.2–0.3 mm): the
                  plateau is reached late;
``cliff``         μ rises linearly (stiff loading) to μ_S at s_pk, then a sudden slip
                  drops it to μ_K within λ = 0.002–0.01 mm.

s_pk is drawn in 0.05–0.25 mm unless given. The torque is
``dir·μ(s)·F_N·R + offset + noise·F_nominal·R·N(0,1)``, so ``noise`` is the per-sample
standard deviation in COF units at the nominal force; F_N carries 0.2 % noise, the
temperature 0.05 °C.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from tribopipe.measurement import ANGLE, NORMAL_FORCE, SPEED, TEMPERATURE, TIME, TORQUE
from tribopipe.physics import FOUNDING_FRICTION_RADIUS_MM, FOUNDING_SPEED_RPM

if TYPE_CHECKING:
    from collections.abc import Sequence
    from os import PathLike

    import pandas as pd

SHAPES: tuple[str, ...] = ("overshoot", "no_overshoot", "stick_slip", "drift", "cliff")


@dataclass(frozen=True)
class SyntheticRun:
    """One synthetic run and its true friction.

    ``mu_s``/``mu_k`` are the true static and kinetic COF (``mu_s`` is ignored by the
    ``no_overshoot`` shape), ``noise`` the torque noise in COF units, ``torque_offset_Nm``
    the instrument's torque zero offset [N·m], ``setup_interval`` whether a normal-force
    set-up interval (``setup_s`` long, ramp then hold, no rotation) precedes the friction
    interval of ``duration_s`` [s]. The disc rests for ``rest_s`` [s] at the start of the
    friction interval, then turns at ``speed_rpm`` in ``direction`` (+1/−1).
    ``normal_force_wobble`` is a relative slow fluctuation of F_N (0.15 = ±15 %).
    ``peak_distance_mm``, ``stick_slip_amplitude`` and ``stick_slip_period_mm`` default
    to seeded draws. ``drift_per_mm`` adds a steady linear drift of μ after the peak
    [1/mm] (a run that never reaches a steady state; μ_K is then its value at the peak).
    """

    mu_s: float = 0.8
    mu_k: float = 0.55
    shape: str = "overshoot"
    noise: float = 0.005
    torque_offset_Nm: float = 0.0
    setup_interval: bool = True
    normal_force_N: float = 3.0
    temperature_C: float = 20.0
    duration_s: float = 300.0
    sample_rate_Hz: float = 10.0
    speed_rpm: float = FOUNDING_SPEED_RPM
    friction_radius_mm: float = FOUNDING_FRICTION_RADIUS_MM
    seed: int = 0
    setup_s: float = 20.0
    rest_s: float = 2.0
    direction: int = 1
    normal_force_wobble: float = 0.0
    peak_distance_mm: float | None = None
    stick_slip_amplitude: float | None = None
    stick_slip_period_mm: float | None = None
    drift_per_mm: float = 0.0

    def __post_init__(self) -> None:
        if self.shape not in SHAPES:
            raise ValueError(f"shape must be one of {', '.join(SHAPES)}, got {self.shape!r}")
        if self.direction not in (1, -1):
            raise ValueError(f"direction must be +1 or -1, got {self.direction!r}")
        if self.duration_s <= 0 or self.sample_rate_Hz <= 0 or self.normal_force_N <= 0:
            raise ValueError("duration_s, sample_rate_Hz and normal_force_N must be > 0")

    def truth(self) -> SyntheticTruth:
        """What a correct reduction of this run must find."""
        return truth(self)


@dataclass(frozen=True)
class SyntheticTruth:
    """The known answer for a :class:`SyntheticRun`.

    ``mu_s_distance_mm`` is where the static peak sits (for ``no_overshoot``: where μ
    reaches 95 % of μ_K); ``static_distinct`` says whether a reduction should report a
    distinct μ_S; ``shape_params`` the seeded shape constants (mm, COF).
    """

    mu_s: float
    mu_k: float
    mu_s_distance_mm: float
    static_distinct: bool
    stick_slip: bool
    sliding_distance_mm: float
    shape_params: dict[str, float]


def _shape_params(run: SyntheticRun) -> dict[str, float]:
    # a separate stream so the shape does not change with the noise draws
    rng = np.random.default_rng([run.seed, 1])
    p_pk, lam_fast, lam_slow, period = rng.uniform(size=4)
    s_pk = run.peak_distance_mm if run.peak_distance_mm is not None else 0.05 + 0.2 * p_pk
    amplitude = run.stick_slip_amplitude
    if amplitude is None:
        amplitude = float(np.clip(0.6 * (run.mu_s - run.mu_k), 0.08, 0.2))
    return {
        "peak_distance_mm": float(s_pk),
        "decay_mm": 0.03 + 0.05 * float(lam_fast),
        # "cliff": the static peak ends in a sudden slip, over 0.002-0.01 mm
        "slip_decay_mm": 0.002 + 0.008 * float(lam_fast),
        "slow_decay_mm": 0.2 + 0.1 * float(lam_slow),
        "stick_slip_amplitude": float(amplitude),
        "stick_slip_period_mm": float(
            run.stick_slip_period_mm
            if run.stick_slip_period_mm is not None
            else 0.02 + 0.02 * period
        ),
    }


def mu_curve(run: SyntheticRun, s_mm: np.ndarray) -> np.ndarray:
    """The true μ at sliding distances ``s_mm`` [mm] (shape (n,)) for ``run``'s shape,
    plus the linear drift ``drift_per_mm`` after the static peak."""
    s = np.asarray(s_mm, dtype=float)
    p = _shape_params(run)
    drift = run.drift_per_mm * np.maximum(s - p["peak_distance_mm"], 0.0)
    return _shape_curve(run, s, p) + drift


def _shape_curve(run: SyntheticRun, s: np.ndarray, p: dict[str, float]) -> np.ndarray:
    s_pk = p["peak_distance_mm"]
    if run.shape == "no_overshoot":
        return run.mu_k * (1.0 - np.exp(-3.0 * s / s_pk))
    x = np.clip(s / s_pk, 0.0, 1.0)
    after = np.maximum(s - s_pk, 0.0)
    if run.shape == "cliff":  # stiff linear loading, then a sudden slip
        fall = run.mu_k + (run.mu_s - run.mu_k) * np.exp(-after / p["slip_decay_mm"])
        return np.where(s < s_pk, run.mu_s * x, fall)
    rise = run.mu_s * (1.0 - (1.0 - x) ** 2)
    if run.shape == "stick_slip":
        a, period = p["stick_slip_amplitude"], p["stick_slip_period_mm"]
        tooth = run.mu_k - a / 2 + a * np.mod(after / period, 1.0)
        return np.where(s < s_pk, rise, tooth)
    decay = p["slow_decay_mm"] if run.shape == "drift" else p["decay_mm"]
    fall = run.mu_k + (run.mu_s - run.mu_k) * np.exp(-after / decay)
    return np.where(s < s_pk, rise, fall)


def truth(run: SyntheticRun) -> SyntheticTruth:
    """The known μ_S, μ_K, peak position and expected behaviour of ``run``."""
    p = _shape_params(run)
    v = run.speed_rpm * 2 * math.pi / 60 * run.friction_radius_mm
    total = v * max(0.0, run.duration_s - run.rest_s)
    peak = run.shape != "no_overshoot"  # no_overshoot has no static peak: μ_S = μ_K
    return SyntheticTruth(
        mu_s=run.mu_s if peak else run.mu_k, mu_k=run.mu_k,
        mu_s_distance_mm=p["peak_distance_mm"], static_distinct=peak and run.mu_s > run.mu_k,
        stick_slip=run.shape == "stick_slip", sliding_distance_mm=total, shape_params=p,
    )


def make_intervals(run: SyntheticRun) -> list[pd.DataFrame]:
    """The intervals the instrument records for ``run``: [set-up,] friction.

    Each DataFrame has ``time_s`` [s, from 1/rate], ``torque_Nm``, ``normal_force_N``,
    ``angle_rad``, ``speed_rad_s``, ``temperature_C``. Same seed, same numbers.
    """
    import pandas as pd

    rng = np.random.default_rng(run.seed)
    R_m = run.friction_radius_mm * 1e-3
    omega = run.speed_rpm * 2 * math.pi / 60
    torque_noise = run.noise * run.normal_force_N * R_m
    force_noise = 0.002 * run.normal_force_N
    frames: list[pd.DataFrame] = []

    if run.setup_interval:
        n = max(2, int(round(run.setup_s * run.sample_rate_Hz)))
        t = np.arange(1, n + 1) / run.sample_rate_Hz
        ramp = np.clip(t / (0.6 * run.setup_s), 0.0, 1.0)
        force = run.normal_force_N * ramp + force_noise * rng.standard_normal(n)
        frames.append(
            pd.DataFrame(
                {
                    TIME: t,
                    TORQUE: run.torque_offset_Nm + torque_noise * rng.standard_normal(n),
                    NORMAL_FORCE: force,
                    ANGLE: np.zeros(n),
                    SPEED: np.zeros(n),
                    TEMPERATURE: run.temperature_C + 0.05 * rng.standard_normal(n),
                }
            )
        )

    n = max(2, int(round(run.duration_s * run.sample_rate_Hz)))
    t = np.arange(1, n + 1) / run.sample_rate_Hz
    moving_t = np.maximum(t - run.rest_s, 0.0)
    phi = omega * moving_t
    s = phi * run.friction_radius_mm
    speed = np.where(t > run.rest_s, omega, 0.0)
    wobble = run.normal_force_wobble * np.sin(2 * math.pi * t / 40.0 + rng.uniform(0, 2 * math.pi))
    force = run.normal_force_N * (1.0 + wobble) + force_noise * rng.standard_normal(n)
    mu = mu_curve(run, s)
    torque = (
        run.direction * mu * force * R_m
        + run.torque_offset_Nm
        + torque_noise * rng.standard_normal(n)
    )
    frames.append(
        pd.DataFrame(
            {
                TIME: t,
                TORQUE: torque,
                NORMAL_FORCE: force,
                ANGLE: run.direction * phi,
                SPEED: run.direction * speed,
                TEMPERATURE: run.temperature_C + 0.05 * rng.standard_normal(n),
            }
        )
    )
    return frames


# --------------------------------------------------------------------------- the writer

_LABELS = {
    "en": {
        "project": "Project:",
        "test": "Test:",
        "result": "Result:",
        "interval": "Interval and data points:",
        "data": "Interval data:",
        "columns": (
            "Point No.", "Time", "Torque", "Normal Force", "Deflection Angle",
            "Rotational Speed", "Temperature", "Status",
        ),
    },
    "fr": {
        "project": "Projet:",
        "test": "Test:",
        "result": "Résultat:",
        "interval": "Intervalle et points de données:",
        "data": "Interval données:",
        "columns": (
            "Point No.", "Temps", "Couple", "Force Normale", "Angle de Déflexion",
            "Vitesse de Rotation", "Température", "Etat",
        ),
    },
}
_UNITS = ("", "[s]", "[mN·m]", "[N]", "[mrad]", "[1/min]", "[°C]", "")
#: decimals written per column (time, torque mN·m, force, angle mrad, speed rpm, temperature)
_DECIMALS = (2, 5, 4, 4, 6, 2)
#: one data row: empty first cell, point number, six numbers, empty Status
_ROW = "\t%d\t" + "\t".join(f"%.{d}f" for d in _DECIMALS) + "\t"


def _data_rows(frame: pd.DataFrame, comma: bool) -> str:
    """The data rows of one interval as one CRLF-joined string.

    Numbers are converted to the export units and rounded as whole arrays (``+ 0.0``
    turns ``-0`` into ``0``); each row is then one C-level ``%`` format, which is several
    times faster than formatting and joining per cell.
    """
    columns = [
        np.asarray(frame[TIME], dtype=float),
        np.asarray(frame[TORQUE], dtype=float) * 1e3,  # N·m → mN·m
        np.asarray(frame[NORMAL_FORCE], dtype=float),
        np.asarray(frame[ANGLE], dtype=float) * 1e3,  # rad → mrad
        np.asarray(frame[SPEED], dtype=float) * 60 / (2 * math.pi),  # rad/s → 1/min
        np.asarray(frame[TEMPERATURE], dtype=float),
    ]
    rounded = [(np.round(c, d) + 0.0).tolist() for c, d in zip(columns, _DECIMALS, strict=True)]
    text = "\r\n".join(_ROW % row for row in zip(range(1, len(frame) + 1), *rounded, strict=True))
    return text.replace(".", ",") if comma else text


def _interval_block(index: int, frame: pd.DataFrame, labels: dict, comma: bool) -> list[str]:
    """The lines of one interval: count line, names, meaning row, unit row, data."""
    width = len(labels["columns"])
    return [
        f"{labels['interval']}\t{index}\t{len(frame)}",
        labels["data"] + "\t" + "\t".join(labels["columns"]),
        "\t" * width,
        "\t" + "\t".join(_UNITS),
        _data_rows(frame, comma),
    ]


@dataclass(frozen=True)
class SyntheticTest:
    """One ``Test:`` block of a RheoCompass export: its name, the sample (its result is
    ``"<sample> 1"``) and its runs, each giving ``[set-up,] friction`` intervals
    (:func:`make_intervals`) in order: one run for a plain test, several for force or
    speed steps within one test (give the later steps ``setup_interval=False`` for steps
    that follow each other without a set-up)."""

    name: str
    sample: str
    runs: tuple[SyntheticRun, ...]

    def __post_init__(self) -> None:
        if not self.runs:
            raise ValueError("a test needs at least one run")


def _test_block(test: SyntheticTest, labels: dict, comma: bool) -> list[str]:
    """The lines of one test: ``Test:``, ``Result:`` and its intervals, numbered from 1."""
    frames = [frame for run in test.runs for frame in make_intervals(run)]
    return _frames_block(test.name, test.sample, frames, labels, comma)


def _frames_block(
    name: str, sample: str, frames: list[pd.DataFrame], labels: dict, comma: bool
) -> list[str]:
    """The lines of one test named ``name`` whose result ``"<sample> 1"`` holds ``frames``
    as its intervals, numbered from 1."""
    lines = [f"{labels['test']}\t{name}", "", f"{labels['result']}\t{sample} 1", ""]
    for i, frame in enumerate(frames, start=1):
        if i > 1:
            lines.append("")
        lines.extend(_interval_block(i, frame, labels, comma))
    return lines


def rheocompass_session_text(
    tests: Sequence[SyntheticTest], *, project: str, language: str = "en"
) -> str:
    """The text (CRLF line ends, no BOM) of a RheoCompass export holding several tests,
    as RheoCompass writes a whole session into one file: one ``Project:`` line, then per
    test its ``Test:``/``Result:`` block and intervals (numbered from 1 in every result),
    tests separated by an empty line."""
    if language not in _LABELS:
        raise ValueError(f"language must be 'en' or 'fr', got {language!r}")
    if not tests:
        raise ValueError("a session needs at least one test")
    labels = _LABELS[language]
    comma = language == "fr"
    lines = [f"{labels['project']}\t{project}", ""]
    for k, test in enumerate(tests):
        if k:
            lines.append("")
        lines.extend(_test_block(test, labels, comma))
    return "\r\n".join(lines) + "\r\n"


def rheocompass_text(
    run: SyntheticRun, *, project: str, test: str, sample: str, language: str = "en"
) -> str:
    """The text (CRLF line ends, no BOM) of a RheoCompass export of ``run``.

    One project, one test, one result named ``"<sample> 1"``; the set-up interval (if
    any) is interval 1, the friction interval follows.
    """
    return rheocompass_session_text([SyntheticTest(test, sample, (run,))], project=project,
                                    language=language)


def intervals_text(
    frames: Sequence[pd.DataFrame], *, project: str, test: str, sample: str,
    language: str = "en",
) -> str:
    """The text (CRLF line ends, no BOM) of a RheoCompass export holding ``frames`` as the
    intervals of one test and result (each frame with the columns of
    :func:`make_intervals`): how any generator's intervals are written."""
    if language not in _LABELS:
        raise ValueError(f"language must be 'en' or 'fr', got {language!r}")
    labels = _LABELS[language]
    comma = language == "fr"
    lines = [f"{labels['project']}\t{project}", ""]
    lines.extend(_frames_block(test, sample, list(frames), labels, comma))
    return "\r\n".join(lines) + "\r\n"


def _write(path: str | PathLike[str], text: str, *, language: str, encoding: str,
           delimiter: str) -> Path:
    """Write an export's text (TAB-separated, CRLF) as RheoCompass saves it: UTF-16 LE
    with BOM, or UTF-8 with BOM; TAB- or comma-separated (a cell holding a comma or a
    quote then quoted, as RheoCompass' comma export does; English decimal points only)."""
    if encoding not in ("utf-16", "utf-8"):
        raise ValueError(f"encoding must be 'utf-16' or 'utf-8', got {encoding!r}")
    if delimiter not in ("\t", ","):
        raise ValueError(f"delimiter must be TAB or ',', got {delimiter!r}")
    if delimiter == "," and language != "en":
        raise ValueError("a comma-separated export needs language='en' (decimal point)")
    if delimiter == ",":
        text = "\r\n".join(",".join(_csv_cell(c) for c in line.split("\t"))
                            for line in text.split("\r\n"))
    target = Path(path)
    if encoding == "utf-16":
        target.write_bytes(b"\xff\xfe" + text.encode("utf-16-le"))
    else:
        target.write_bytes(b"\xef\xbb\xbf" + text.encode("utf-8"))
    return target


def _csv_cell(cell: str) -> str:
    """A cell of a comma-separated line: quoted (quotes doubled) when it holds a comma or
    a quote."""
    if "," in cell or '"' in cell:
        return '"' + cell.replace('"', '""') + '"'
    return cell


def write_rheocompass_export(
    path: str | PathLike[str],
    run: SyntheticRun,
    *,
    project: str,
    test: str,
    sample: str,
    language: str = "en",
    encoding: str = "utf-16",
    delimiter: str = "\t",
) -> Path:
    """Write ``run`` as a RheoCompass export and return its path.

    The default is RheoCompass' own save: UTF-16 LE with BOM, TAB, CRLF. ``language="fr"``
    writes French labels and decimal commas. ``encoding="utf-8"`` writes UTF-8 with BOM,
    and ``delimiter=","`` comma-separated cells (a cell holding a comma or a quote is
    quoted, as RheoCompass' comma export does); a comma delimiter needs the English
    decimal point.
    """
    return _write(path, rheocompass_text(run, project=project, test=test, sample=sample,
                                         language=language),
                  language=language, encoding=encoding, delimiter=delimiter)


def write_rheocompass_session(
    path: str | PathLike[str],
    tests: Sequence[SyntheticTest],
    *,
    project: str,
    language: str = "en",
    encoding: str = "utf-16",
    delimiter: str = "\t",
) -> Path:
    """Write several tests into one RheoCompass export (:func:`rheocompass_session_text`;
    encoding and delimiter as :func:`write_rheocompass_export`) and return its path."""
    return _write(path, rheocompass_session_text(tests, project=project, language=language),
                  language=language, encoding=encoding, delimiter=delimiter)


def write_intervals_export(
    path: str | PathLike[str],
    frames: Sequence[pd.DataFrame],
    *,
    project: str,
    test: str,
    sample: str,
    language: str = "en",
    encoding: str = "utf-16",
    delimiter: str = "\t",
) -> Path:
    """Write ``frames`` (intervals with the columns of :func:`make_intervals`) as one
    RheoCompass export (encoding and delimiter as :func:`write_rheocompass_export`) and
    return its path. Any generator's intervals go through the same writer as
    :class:`SyntheticRun`'s."""
    return _write(path, intervals_text(frames, project=project, test=test, sample=sample,
                                       language=language),
                  language=language, encoding=encoding, delimiter=delimiter)
