"""Session exports for the tests: several tests in one RheoCompass file, as a lab exports
a whole session, written by the synthetic export writer with known truth.

``SESSION`` holds three tests of one pin, disc and temperature at three forces: the first
and the last with a normal-force set-up interval (each with its own torque offset, so a
borrowed offset would show), the middle one without. ``STEPS`` is one test whose method
holds two force steps (3 N, then 5 N without a new set-up). :func:`write_xlsx_twin` writes a
text export's cells into an Excel sheet laid out as RheoCompass's own .xlsx export is
(labels in column A, numbers as numbers, empty cells empty).
"""

from __future__ import annotations

from pathlib import Path

from generators.synthetic import SyntheticRun, SyntheticTest, write_rheocompass_session

#: the Test names follow this pattern (the README's example)
TEST_PATTERN = "{pin} on {disc}, {force} N, {temperature} °C, #{repeat}"
DURATION_S = 120.0


def run(mu_s: float, mu_k: float, force_N: float, seed: int, **kw: object) -> SyntheticRun:
    """A short run at 20 °C with little noise."""
    return SyntheticRun(mu_s=mu_s, mu_k=mu_k, normal_force_N=force_N, temperature_C=20.0,
                        duration_s=DURATION_S, noise=0.004, seed=seed, **kw)


#: Test name -> (true mu_s, true mu_k, force [N], torque offset [N·m], set-up interval)
SESSION_TRUTH = {
    "DS30 on steel, 1 N, 20 °C, #1": (0.80, 0.62, 1.0, 3e-4, True),
    "DS30 on steel, 3 N, 20 °C, #1": (0.60, 0.47, 3.0, 0.0, False),
    "DS30 on steel, 5 N, 20 °C, #1": (0.47, 0.36, 5.0, -2e-4, True),
}


def session_tests(seed: int = 0, repeat: int = 1) -> list[SyntheticTest]:
    """The three tests of ``SESSION_TRUTH`` (seeds from ``seed``; Test names ending in
    ``#<repeat>``)."""
    return [
        SyntheticTest(name.replace("#1", f"#{repeat}"), "DS30",
                      (run(mu_s, mu_k, force, seed + k, torque_offset_Nm=offset,
                           setup_interval=setup),))
        for k, (name, (mu_s, mu_k, force, offset, setup)) in enumerate(SESSION_TRUTH.items())
    ]


def write_session(path: Path, *, language: str = "en", seed: int = 0, repeat: int = 1,
                  tests: list[SyntheticTest] | None = None) -> Path:
    """``SESSION`` (or ``tests``) as one RheoCompass export."""
    return write_rheocompass_session(path, tests or session_tests(seed, repeat),
                                     project="session", language=language)


def steps_test(seed: int = 20) -> SyntheticTest:
    """One test with two force steps: a set-up, 3 N (μ_K 0.47), then 5 N (μ_K 0.36)."""
    return SyntheticTest("DS30 on steel, steps, 20 °C", "DS30", (
        run(0.60, 0.47, 3.0, seed, torque_offset_Nm=2.5e-4),
        run(0.47, 0.36, 5.0, seed + 1, torque_offset_Nm=2.5e-4, setup_interval=False),
    ))


def write_xlsx_twin(text_export: Path, target: Path) -> Path:
    """The cells of a UTF-16 TAB text export written into the first sheet of a workbook,
    as RheoCompass's Excel export lays them out: labels and names as text, numbers as
    numbers (a decimal comma read as a point), empty cells left empty."""
    import openpyxl

    text = text_export.read_bytes().decode("utf-16")
    workbook = openpyxl.Workbook()
    sheet = workbook.active
    sheet.title = "session"
    for line in text.splitlines():
        sheet.append([_cell(c) for c in line.split("\t")])
    workbook.save(target)
    return target


def _cell(text: str) -> object:
    if not text:
        return None
    try:
        number = float(text.replace(",", "."))
    except ValueError:
        return text
    return int(number) if number.is_integer() and "." not in text and "," not in text \
        else number
