"""A seeded mutation fuzzer over real and synthetic exports, through the real CLI.

Every case is a real export (``tests/data``, and ``../shared/real-exports`` where present)
or a synthetic one (RheoCompass UTF-16 in English and French, a plain CSV) damaged by one
or two seeded mutations: truncation, bit flips, deleted or duplicated lines, swapped
delimiters, unknown units, text in numeric cells, NaN/inf, huge values (cells or a whole
column), zero or constant torque, constant time, shuffled rows, another encoding, NUL
bytes, an empty file.

Cases run in groups: each group's files go through one ``tribopipe reduce`` (in-process
with ``click.testing``; one group per run as a real subprocess) together with a good
export. The rule checked for every case: no traceback; every stderr line is one problem
(``error:``) naming exactly one file, or a duplicate; no file is silent (it has a
summary per reduced run, or its problems, one line each: a file of several tests has
one per failing test or run); every summary is strict JSON with physical numbers (a
zero-torque case is flagged ``no_friction_signal``); the good neighbour always lands; no
numeric warning reaches the user. A campaign of mutated files
goes through ``tribopipe batch`` with worker processes: one ``failed:`` line and one
``failures.csv`` row per bad file, the good runs in the map.

The default run checks :data:`FAST_GROUPS` groups (~200 cases); ``pytest -m fuzz`` runs
:data:`FULL_GROUPS` more (≥ 2,000 cases; ``.ci/run`` does). A failing case names its
group, case and mutations; ``TRIBOPIPE_FUZZ_SEED`` shifts every seed.
"""

from __future__ import annotations

import json
import os
import random
import re
import subprocess
import sys
import warnings
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import pandas as pd
import pytest

from conftest import SHARED
from generators.synthetic import SyntheticRun, make_intervals, rheocompass_text
from hostile import GOOD_RUN, good_export, invoke
from tribopipe.frictionmap import read_map

DATA = Path(__file__).resolve().parent / "data"
SEED = int(os.environ.get("TRIBOPIPE_FUZZ_SEED", "20240521"))
CASES_PER_GROUP = 20
FAST_GROUPS = 10
FULL_GROUPS = 100

Mutation = Callable[[bytes, random.Random], bytes]


# ------------------------------------------------------------------ the seeds


@dataclass(frozen=True)
class Seed:
    """One export to mutate: its bytes, its suffix and whether it is a synthetic run
    (which reduces when undamaged)."""

    name: str
    raw: bytes
    suffix: str
    synthetic: bool


def _plain_csv(run: SyntheticRun) -> bytes:
    frame = make_intervals(run)[-1]
    return frame.to_csv(index=False, lineterminator="\n").encode("utf-8")


def _rheocompass(run: SyntheticRun, language: str) -> bytes:
    text = rheocompass_text(run, project="fuzz", test="t", sample="S", language=language)
    return b"\xff\xfe" + text.encode("utf-16-le")


def seeds() -> list[Seed]:
    """The real exports (tests/data, and ../shared/real-exports where present) and five
    synthetic runs (short, so a group reduces quickly)."""
    out: list[Seed] = []
    real = {p.name: p for p in sorted(DATA.iterdir()) if p.suffix in (".csv", ".txt", ".xlsx")}
    shared = SHARED / "real-exports"
    if shared.is_dir():
        real.update({p.name: p for p in sorted(shared.iterdir())
                     if p.suffix in (".csv", ".txt", ".xlsx")})
    for name, path in sorted(real.items()):
        out.append(Seed(name, path.read_bytes(), path.suffix, synthetic=False))
    runs = [
        replace(GOOD_RUN, duration_s=60.0, seed=1),
        replace(GOOD_RUN, duration_s=60.0, shape="stick_slip", seed=2),
        replace(GOOD_RUN, duration_s=60.0, setup_interval=False, torque_offset_Nm=2e-4,
                seed=3),
    ]
    out.append(Seed("synthetic_en", _rheocompass(runs[0], "en"), ".csv", synthetic=True))
    out.append(Seed("synthetic_stick_slip", _rheocompass(runs[1], "en"), ".txt",
                    synthetic=True))
    out.append(Seed("synthetic_fr", _rheocompass(runs[2], "fr"), ".csv", synthetic=True))
    out.append(Seed("synthetic_plain", _plain_csv(runs[0]), ".csv", synthetic=True))
    out.append(Seed("synthetic_plain_noangle",
                    _plain_csv(runs[2]).replace(b"angle_rad", b"unused_x"), ".csv",
                    synthetic=True))
    return out


SEEDS = seeds()


# ------------------------------------------------------------------ the mutations


def _codec(raw: bytes) -> tuple[str, bytes]:
    if raw.startswith(b"\xff\xfe"):
        return "utf-16-le", b"\xff\xfe"
    if raw.startswith(b"\xef\xbb\xbf"):
        return "utf-8", b"\xef\xbb\xbf"
    return "latin-1", b""          # byte for byte, whatever the file's real encoding


def on_text(change: Callable[[str, random.Random], str]) -> Mutation:
    """A mutation of the decoded text, encoded back the way the file was."""
    def mutate(raw: bytes, rng: random.Random) -> bytes:
        codec, bom = _codec(raw)
        body = raw[len(bom):]
        if codec == "utf-16-le" and len(body) % 2:
            body = body[:-1]
        text = body.decode(codec, errors="replace")
        return bom + change(text, rng).encode(codec, errors="replace")
    return mutate


def truncate(raw: bytes, rng: random.Random) -> bytes:
    return raw[: rng.randrange(len(raw) + 1)]


def bit_flips(raw: bytes, rng: random.Random) -> bytes:
    data = bytearray(raw)
    for _ in range(rng.randint(1, 8)):
        if data:
            data[rng.randrange(len(data))] ^= 1 << rng.randrange(8)
    return bytes(data)


def nul_bytes(raw: bytes, rng: random.Random) -> bytes:
    k = rng.randrange(len(raw) + 1)
    return raw[:k] + b"\x00" * rng.randint(1, 64) + raw[k:]


def empty(raw: bytes, rng: random.Random) -> bytes:
    return rng.choice([b"", b"\n", b"\xff\xfe", b" \r\n\t"])


def reencode(raw: bytes, rng: random.Random) -> bytes:
    codec, bom = _codec(raw)
    text = raw[len(bom):].decode(codec, errors="replace")
    target = rng.choice(["utf-8", "utf-16-le", "utf-16-be", "cp1252", "utf-8-sig"])
    return text.encode(target, errors="replace")


def _lines(text: str) -> list[str]:
    return text.splitlines(keepends=True)


def delete_lines(text: str, rng: random.Random) -> str:
    lines = _lines(text)
    for _ in range(rng.randint(1, 5)):
        if lines:
            del lines[rng.randrange(len(lines))]
    return "".join(lines)


def duplicate_lines(text: str, rng: random.Random) -> str:
    lines = _lines(text)
    if not lines:
        return text
    k = rng.randrange(len(lines))
    block = lines[k: k + rng.randint(1, 20)]
    return "".join(lines[:k] + block + lines[k:])


def shuffle_rows(text: str, rng: random.Random) -> str:
    lines = _lines(text)
    if len(lines) < 4:
        return text
    k = rng.randrange(len(lines) // 2, len(lines) - 1)
    block = lines[k: k + rng.randint(2, 40)]
    rng.shuffle(block)
    return "".join(lines[:k] + block + lines[k + len(block):])


def swap_delimiters(text: str, rng: random.Random) -> str:
    old, new = rng.choice([("\t", ";"), ("\t", ","), ("\t", " "), (",", "\t"), (",", ";"),
                           (";", ","), ("\t", "|")])
    if rng.random() < 0.5:
        return text.replace(old, new)
    lines = _lines(text)
    for _ in range(rng.randint(1, 10)):
        if lines:
            k = rng.randrange(len(lines))
            lines[k] = lines[k].replace(old, new)
    return "".join(lines)


UNIT = re.compile(r"\[[^\[\]\r\n]{0,12}\]")


def unknown_units(text: str, rng: random.Random) -> str:
    units = list(UNIT.finditer(text))
    if not units:
        return text
    chosen = rng.sample(units, k=min(len(units), rng.randint(1, 3)))
    for m in sorted(chosen, key=lambda m: -m.start()):
        odd = rng.choice(["[furlong]", "[mN·m·s]", "[]", "[µ]", "[N/m²²]", "[??]", "[kN]",
                          "[rad/s²]", "[%]", "[1/min]", "[mrad]", "[K]"])
        text = text[: m.start()] + odd + text[m.end():]
    return text


NUMBER = re.compile(r"(?<![\w.,])[-+]?\d+(?:[.,]\d+)?(?:[eE][-+]?\d+)?(?![\w.,])")


def replace_numbers(choices: list[str], share: tuple[float, float]) -> Callable:
    def change(text: str, rng: random.Random) -> str:
        p = rng.uniform(*share)
        return NUMBER.sub(lambda m: rng.choice(choices) if rng.random() < p else m.group(0),
                          text)
    return change


text_in_numbers = replace_numbers(["abc", "1,2,3", "--", "#NAME?", "0x1F", "1.2.3", "١٢",
                                   "1e", "e5", "N/A", "*5"], (0.0005, 0.01))
nan_inf = replace_numbers(["nan", "NaN", "inf", "-inf", "Infinity", "******"], (0.001, 0.3))
huge = replace_numbers(["1e308", "-1e308", "9e999", "1" + "0" * 400, "1e-320", "4e300"],
                       (0.0005, 0.2))


def _column_values(name_pattern: str, value: Callable[[str, int], str]) -> Callable:
    """Set every data cell of the column whose header matches ``name_pattern``."""
    header = re.compile(name_pattern, re.IGNORECASE)

    def change(text: str, rng: random.Random) -> str:
        out = []
        column = None
        delimiter = "\t" if "\t" in text[:2000] else ","
        for i, line in enumerate(_lines(text)):
            cells = line.rstrip("\r\n").split(delimiter)
            hits = [j for j, c in enumerate(cells) if header.fullmatch(c.strip())]
            if hits:
                column = hits[0]
            elif column is not None and column < len(cells) and NUMBER.fullmatch(
                    cells[column].strip()):
                cells[column] = value(cells[column], i)
                line = delimiter.join(cells) + line[len(line.rstrip("\r\n")):]
            out.append(line)
        return "".join(out)
    return change


zero_torque = _column_values(r"torque(_nm)?|couple", lambda cell, i: "0")
constant_torque = _column_values(r"torque(_nm)?|couple", lambda cell, i: "0.123")
constant_time = _column_values(r"time(_s)?|temps", lambda cell, i: "5")
HUGE_COLUMNS = (r"time(_s)?|temps", r"torque(_nm)?|couple", r"normal.?force(_n)?|force normale",
                r"(deflection.?)?angle(_rad)?|angle de d.flexion", r"temp.rature(_c)?")


def huge_column(text: str, rng: random.Random) -> str:
    """One whole column (time, torque, force, angle or temperature) scaled far beyond
    any measurement, or set to the largest doubles."""
    value = rng.choice(["1e300", "-1e308", "1.7976931348623157e308", "3e38", "1e12"])
    return _column_values(rng.choice(HUGE_COLUMNS), lambda cell, i: value)(text, rng)

MUTATIONS: dict[str, Mutation] = {
    "truncate": truncate,
    "bit_flips": bit_flips,
    "nul_bytes": nul_bytes,
    "empty": empty,
    "reencode": reencode,
    "delete_lines": on_text(delete_lines),
    "duplicate_lines": on_text(duplicate_lines),
    "shuffle_rows": on_text(shuffle_rows),
    "swap_delimiters": on_text(swap_delimiters),
    "unknown_units": on_text(unknown_units),
    "text_in_numbers": on_text(text_in_numbers),
    "nan_inf": on_text(nan_inf),
    "huge": on_text(huge),
    "zero_torque": on_text(zero_torque),
    "constant_torque": on_text(constant_torque),
    "constant_time": on_text(constant_time),
    "huge_column": on_text(huge_column),
}
#: how often each mutation is drawn (the text-level ones find the deeper paths)
WEIGHTS = {"empty": 1, "nul_bytes": 2, "reencode": 2}
#: a workbook is bytes in a zip: only byte-level mutations make sense
BYTE_LEVEL = ("truncate", "bit_flips", "nul_bytes", "empty")


@dataclass(frozen=True)
class Case:
    """One mutated export: where it came from and what was done to it."""

    number: int
    seed: Seed
    mutations: tuple[str, ...]
    raw: bytes

    @property
    def file_name(self) -> str:
        return f"c{self.number:05d}_{'+'.join(self.mutations)}{self.seed.suffix}"

    @property
    def zero_torque_only(self) -> bool:
        return self.seed.synthetic and self.mutations in (("zero_torque",),
                                                          ("constant_torque",))


def make_case(number: int) -> Case:
    """Case ``number`` (same number, same bytes): a seed and one or two mutations."""
    rng = random.Random(f"{SEED}-{number}")
    # half synthetic runs (undamaged, they reduce: mutations reach the reduction), half real
    synthetic = rng.random() < 0.5
    seed = rng.choice([s for s in SEEDS if s.synthetic == synthetic])
    names = list(BYTE_LEVEL if seed.suffix == ".xlsx" else MUTATIONS)
    weights = [WEIGHTS.get(n, 4) for n in names]
    chosen = tuple(rng.choices(names, weights, k=1 if rng.random() < 0.7 else 2))
    raw = seed.raw
    for name in chosen:
        raw = MUTATIONS[name](raw, rng)
    return Case(number, seed, chosen, raw)


# ------------------------------------------------------------------ one group


def _refuse_constant(name: str) -> None:
    raise AssertionError(f"JSON holds {name}: not strict JSON")


def check_group(group: int, tmp_path: Path, *, subprocess_run: bool = False) -> None:
    """Reduce one group of cases with a good neighbour and check the rule for each."""
    folder = tmp_path / f"group{group}"
    folder.mkdir()
    cases = [make_case(group * CASES_PER_GROUP + k) for k in range(CASES_PER_GROUP)]
    paths = []
    for case in cases:
        path = folder / case.file_name
        path.write_bytes(case.raw)
        paths.append(path)
    good = good_export(folder / "good_neighbour.csv")
    out = tmp_path / f"out{group}"
    args = ["reduce", *map(str, paths), str(good), "--no-map", "--output", str(out)]
    if subprocess_run:
        done = subprocess.run([sys.executable, "-m", "tribopipe", *args], capture_output=True,
                              timeout=600, check=False)
        stderr = done.stderr.decode("utf-8")
        output, code = done.stdout.decode("utf-8") + stderr, done.returncode
    else:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", RuntimeWarning)
            result = invoke(*args)
        assert result.exception is None or isinstance(result.exception, SystemExit), \
            f"group {group}: uncaught {type(result.exception).__name__}: {result.exception}"
        numeric = [f"{w.filename}:{w.lineno}: {w.message}" for w in caught
                   if issubclass(w.category, RuntimeWarning)]
        assert not numeric, f"group {group}: numeric warnings reach the user: {numeric[:3]}"
        stderr, output, code = result.stderr, result.output, result.exit_code
    where = f"group {group} (TRIBOPIPE_FUZZ_SEED={SEED})"
    assert "Traceback" not in output, f"{where}:\n{output}"
    summaries = {p.name: p for p in (out / "summaries").glob("*.json")} \
        if (out / "summaries").is_dir() else {}
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    for line in lines:
        assert re.match(r"(error: |duplicate: |\d+ error\(s\) in \d+ of \d+ file\(s\)\.$)",
                        line), f"{where}: a line that is not one problem of one file: {line!r}"
        if line.startswith("error: "):   # names exactly one of the files
            assert sum(c.file_name in line for c in cases) + ("good_neighbour" in line) == 1, \
                f"{where}: {line!r}"
    failed = 0
    for case in cases:
        stem = case.file_name.rsplit(".", 1)[0]
        errors = [ln for ln in lines if ln.startswith("error: ") and case.file_name in ln]
        duplicate = [ln for ln in lines if ln.startswith(f"duplicate: {folder / case.file_name}")]
        written = [p for name, p in summaries.items() if name.startswith(stem + "_")]
        what = f"{where}, case {case.number} ({case.seed.name}: {', '.join(case.mutations)})"
        # every file is accounted for: its runs' summaries, its problems, or a duplicate
        assert errors or written or duplicate, f"{what}: neither reduced nor reported"
        if case.seed.synthetic and not duplicate:   # one test, one friction interval
            assert len(errors) + len(written) >= 1, what
        failed += bool(errors)
        for path in written:
            summary = json.loads(path.read_text(encoding="utf-8"),
                                 parse_constant=_refuse_constant)
            assert 0 <= summary["mu_k"] <= 10 and summary["mu_s"] >= summary["mu_k"], what
            assert summary["normal_force_N"] > 0 and summary["pressure_kPa"] > 0, what
            if case.zero_torque_only:
                assert "no_friction_signal" in summary["flags"], f"{what}: {summary['flags']}"
    assert [n for n in summaries if n.startswith("good_neighbour_")], f"{where}: lost the good"
    assert code == (1 if failed else 0), f"{where}: exit code {code}\n{output}"


@pytest.mark.parametrize("group", range(FAST_GROUPS))
def test_mutated_exports_fail_alone_in_one_line(group: int, tmp_path: Path) -> None:
    check_group(group, tmp_path)


@pytest.mark.slow
def test_a_group_in_a_real_process(tmp_path: Path) -> None:
    check_group(FAST_GROUPS + FULL_GROUPS, tmp_path, subprocess_run=True)


@pytest.mark.fuzz
@pytest.mark.parametrize("group", range(FAST_GROUPS, FAST_GROUPS + FULL_GROUPS))
def test_more_mutated_exports_fail_alone_in_one_line(group: int, tmp_path: Path) -> None:
    check_group(group, tmp_path, subprocess_run=group % 25 == 0)


# ------------------------------------------------------------------ a campaign


def check_campaign(first_case: int, n_cases: int, tmp_path: Path) -> None:
    """A campaign folder of ``n_cases`` mutated synthetic exports and three good ones,
    through ``tribopipe batch`` with two worker processes."""
    raw = tmp_path / "raw"
    raw.mkdir()
    synthetic = [s for s in SEEDS if s.synthetic and s.suffix == ".csv"]
    names = {}
    for k in range(n_cases):
        rng = random.Random(f"{SEED}-campaign-{first_case + k}")
        seed = rng.choice(synthetic)
        chosen = tuple(rng.choices(list(MUTATIONS), k=1))
        data = MUTATIONS[chosen[0]](seed.raw, rng)
        name = f"DS30_steel_3N_20C_r{100 + k}_{chosen[0]}.csv"
        (raw / name).write_bytes(data)
        names[name] = chosen[0]
    for repeat in (1, 2, 3):
        good_export(raw / f"DS30_steel_3N_20C_r{repeat}_good.csv",
                    replace(GOOD_RUN, seed=500 + repeat))
    cfg = tmp_path / "c.toml"
    cfg.write_text('[campaign]\nname = "fuzz"\nraw_dir = "raw"\noutput_dir = "out"\n'
                   'filename_pattern = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}_{x}"\n'
                   "plots = false\n", encoding="utf-8")
    result = invoke("batch", str(cfg), "--jobs", "2")
    assert result.exception is None or isinstance(result.exception, SystemExit), result.output
    assert "Traceback" not in result.output, result.output
    failures = pd.read_csv(tmp_path / "out" / "failures.csv", dtype=str)
    failed_lines = [ln for ln in result.stderr.splitlines() if ln.startswith("failed: ")]
    # files that failed alike are said once, with their count
    alike = [re.match(r"failed: (\d+) files alike, e\.g\. ", ln) for ln in failed_lines]
    assert sum(int(m.group(1)) if m else 1 for m in alike) == len(failures), result.stderr
    for name in failures["file"]:
        assert sum(ln.startswith((f"failed: {name}", "failed: ")) and name in ln
                   for ln in failed_lines) <= 1, (name, result.stderr)
        assert name.split(" ")[0].rstrip(":") in names, name
    table = pd.read_csv(tmp_path / "out" / "runs.csv", dtype=str, keep_default_na=False)
    # what is no export (an emptied file, NUL bytes) is set aside and said, never a failure
    set_aside = {m.group(1) for ln in result.stderr.splitlines()
                 if (m := re.match(r"note: not an export: skipped: (\S+) \(", ln))}
    assert not set_aside & set(table["file"])
    assert set(table["file"]) | set_aside == set(names) | {
        f"DS30_steel_3N_20C_r{r}_good.csv" for r in (1, 2, 3)}   # no file is silent
    good = table[table["file"].str.endswith("_good.csv")]
    assert (good["status"] == "reduced").all() and len(good) == 3
    runs = read_map(tmp_path / "out" / "friction_map.parquet")
    reduced_ids = set(table.loc[table["status"] == "reduced", "measurement_id"])
    assert reduced_ids <= set(runs["measurement_id"])      # every reduced run landed
    assert result.exit_code == (1 if len(failures) else 0)


def test_a_campaign_of_mutated_exports(tmp_path: Path) -> None:
    check_campaign(0, 30, tmp_path)


@pytest.mark.fuzz
@pytest.mark.parametrize("part", range(4))
def test_more_campaigns_of_mutated_exports(part: int, tmp_path: Path) -> None:
    check_campaign(1000 + 50 * part, 50, tmp_path)
