"""One option vocabulary for every command, and one rule for the map a command reads.

-o/--output for what a command writes, --map for the map it reads, --plots/--no-plots,
--instrument for the instrument file and CAMPAIGN for the campaign file. The old spellings
still work, each with one note naming the new one. Without --map a command reads the map
the last ``batch`` run in its folder recorded in ``.tribopipe-map`` (else
processed/friction_map.parquet) and says which.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import click
import pytest
from click.testing import CliRunner

from generators.synthetic import SyntheticRun, write_rheocompass_export
from tribopipe.cli import main
from tribopipe.project import DEFAULT_MAP, PROJECT_FILE

PATTERN = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"
RUN = SyntheticRun(mu_s=0.8, mu_k=0.55, normal_force_N=3.0, temperature_C=20.0,
                   duration_s=150.0, noise=0.004, seed=3)


def _commands() -> Iterator[tuple[str, click.Command]]:
    """Every leaf command with its full name."""
    def walk(cmd: click.Command, path: list[str]) -> Iterator[tuple[str, click.Command]]:
        ctx = click.Context(cmd, info_name=path[-1])
        if isinstance(cmd, click.Group):
            for name in cmd.list_commands(ctx):
                sub = cmd.get_command(ctx, name)
                assert sub is not None
                yield from walk(sub, [*path, name])
        else:
            yield " ".join(path[1:]), cmd
    yield from walk(main, ["tribopipe"])


def _visible(cmd: click.Command) -> dict[str, click.Option]:
    return {o: p for p in cmd.params if isinstance(p, click.Option) and not p.hidden
            for o in p.opts}


@pytest.fixture()
def workdir(tmp_path: Path) -> Iterator[Path]:
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        yield tmp_path
    finally:
        os.chdir(cwd)


def _raw(folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    for repeat in (1, 2):
        run = replace(RUN, seed=RUN.seed + repeat)
        write_rheocompass_export(folder / f"DS30_steel_3N_20C_r{repeat}.csv", run,
                                 project="p", test="t", sample="DS30")
    return folder


def test_every_command_speaks_one_vocabulary() -> None:
    seen_output = 0
    for name, cmd in _commands():
        opts = _visible(cmd)
        # what a command writes is -o/--output; the old names are hidden
        for old in ("--out", "--plot", "--config"):
            assert old not in opts, f"{name}: {old} is visible"
        if "--output" in opts:
            seen_output += 1
            assert "-o" in opts["--output"].opts, name
        # every option that names a map is --map (map validate too)
        for opt in opts.values():
            if "map" in opt.name and opt.name != "map_path":
                assert opt.is_flag, f"{name}: {opt.opts} names a map without --map"
        if "--plots" in opts:
            assert opts["--plots"].secondary_opts == ["--no-plots"], name
        # a default --help states is the default the option has
        for opt in opts.values():
            if opt.show_default and opt.default is not None and not opt.is_flag:
                assert opt.help is not None, name
    assert seen_output >= 20  # every command that writes something
    assert "--map" in _visible(dict(_commands())["map validate"])
    assert "--instrument" in _visible(dict(_commands())["query"])


@pytest.mark.parametrize(("args", "old", "new"), [
    (["reduce", "{export}", "--no-map", "--out", "{tmp}/o"], "--out", "-o/--output"),
    (["reduce", "{export}", "--no-map", "--plot", "-o", "{tmp}/o"], "--plot", "--plots"),
    (["reduce", "{export}", "--no-map", "--config", "{instrument}"], "--config",
     "--instrument"),
    (["batch", "{raw}", "--pattern", PATTERN, "--out", "{tmp}/o", "--no-plots"], "--out",
     "-o/--output"),
])
def test_an_old_spelling_still_works_with_one_note(tmp_path: Path, args: list[str], old: str,
                                                   new: str) -> None:
    raw = _raw(tmp_path / "raw")
    instrument = Path(__file__).resolve().parents[1] / "configs" / "instruments" / "t-pid44.toml"
    values = {"export": str(raw / "DS30_steel_3N_20C_r1.csv"), "tmp": str(tmp_path),
              "raw": str(raw), "instrument": str(instrument)}
    result = CliRunner().invoke(main, [a.format(**values) if a != PATTERN else a
                                       for a in args])
    assert result.exit_code == 0, result.output
    notes = [line for line in result.stderr.splitlines() if line.startswith(f"note: {old} ")]
    assert notes == [f"note: {old} is now {new} (the old spelling works until the next "
                     "release)"]
    if old == "--plot":
        assert list((tmp_path / "o" / "plots" / "traces").glob("*.png"))
    if old == "--out":
        assert list((tmp_path / "o" / "traces").glob("*.parquet"))


def test_old_and_new_spelling_together_are_refused(tmp_path: Path) -> None:
    raw = _raw(tmp_path / "raw")
    result = CliRunner().invoke(main, ["reduce", str(raw / "DS30_steel_3N_20C_r1.csv"),
                                       "--no-map", "--out", "a", "-o", "b"])
    assert result.exit_code == 2
    assert "--out is the old spelling of -o/--output: give one" in result.stderr


def test_batch_names_the_map_and_later_commands_read_it(workdir: Path) -> None:
    _raw(workdir / "raw")
    runner = CliRunner()
    done = runner.invoke(main, ["batch", "raw", "--pattern", PATTERN, "-o", "out/demo",
                                "--no-plots"])
    assert done.exit_code == 0, done.output
    assert (workdir / PROJECT_FILE).read_text() == "out/demo/friction_map.parquet\n"
    assert "commands run here without --map now read out/demo/friction_map.parquet" \
        in done.stderr
    for args in (["map", "show"], ["map", "validate"],
                 ["query", "--pin", "DS30", "--disc", "steel", "--pressure", "35"],
                 ["map", "table", "--format", "markdown"]):
        result = runner.invoke(main, args)
        assert result.exit_code == 0, (args, result.output)
        assert result.stderr.splitlines()[0] == (
            f"map: out/demo/friction_map.parquet (from ./{PROJECT_FILE}, written by the "
            "last `tribopipe batch` here)"), args
    shown = runner.invoke(main, ["map", "show"])
    assert "2 run" in shown.stdout
    # --map always wins, and is not announced
    other = runner.invoke(main, ["map", "show", "--map", "elsewhere.parquet"])
    assert "map: " not in other.stderr


def test_without_a_project_file_the_default_is_said(workdir: Path) -> None:
    result = CliRunner().invoke(main, ["map", "show"])
    assert result.stderr.splitlines()[0].startswith(f"map: {DEFAULT_MAP} (the default; ")


@pytest.mark.parametrize("content", [b"a.parquet\nb.parquet\n", b"\xff\xfe", b"notes.txt\n",
                                     b"a\x1b[31m.parquet\n"])
def test_a_bad_project_file_is_one_line(workdir: Path, content: bytes) -> None:
    (workdir / PROJECT_FILE).write_bytes(content)
    result = CliRunner().invoke(main, ["map", "show"])
    assert result.exit_code == 1
    assert len(result.stderr.splitlines()) == 1
    assert PROJECT_FILE in result.stderr and "delete it" in result.stderr
    assert "\x1b" not in result.stderr


def test_reduce_no_map_writes_nothing(workdir: Path) -> None:
    raw = _raw(workdir / "raw")
    before = sorted(workdir.rglob("*"))
    result = CliRunner().invoke(main, ["reduce", str(raw / "DS30_steel_3N_20C_r1.csv"),
                                       "--pin", "DS30", "--disc", "steel", "--no-map"])
    assert result.exit_code == 0, result.output
    assert "0.5" in result.stdout  # it printed μ
    assert sorted(workdir.rglob("*")) == before
    # with -o it writes there, and only there
    done = CliRunner().invoke(main, ["reduce", str(raw / "DS30_steel_3N_20C_r1.csv"),
                                     "--no-map", "-o", "kept"])
    assert done.exit_code == 0
    assert {p.parent.name for p in (workdir / "kept").rglob("*") if p.is_file()} == {
        "traces", "summaries"}
    assert not (workdir / "processed").exists()


def test_publish_takes_output_and_the_old_positional_folder(workdir: Path) -> None:
    _raw(workdir / "raw")
    runner = CliRunner()
    runner.invoke(main, ["batch", "raw", "--pattern", PATTERN, "--no-plots"])
    new = runner.invoke(main, ["map", "publish", "-o", "pkg", "--lab", "L",
                               "--allow-synthetic"])
    old = runner.invoke(main, ["map", "publish", "pkg2", "--lab", "L", "--allow-synthetic"])
    assert new.exit_code == 0 and old.exit_code == 0, (new.output, old.output)
    assert (workdir / "pkg" / "datapackage.json").is_file()
    assert (workdir / "pkg2" / "datapackage.json").is_file()
    assert "note: the positional FOLDER is now -o/--output FOLDER" in old.stderr
