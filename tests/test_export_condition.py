"""A single-condition export asks once: one message names every choice still missing with
the values the map holds, and a choice the map holds one value for is taken and said."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from published_map import PUBLISHED_CSV, write_published_map
from tribopipe.cli import main
from tribopipe.errors import ExportError
from tribopipe.export.simulators import one_condition

PIN, DISC = "Dragonskin 30", "steel"


@pytest.fixture(scope="module")
def map_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_published_map(PUBLISHED_CSV,
                               tmp_path_factory.mktemp("map") / "friction_map.parquet")


def _messages(args: list[str]) -> tuple[int, list[str]]:
    result = CliRunner().invoke(main, args)
    return result.exit_code, [line for line in result.stderr.splitlines()
                              if not line.startswith("map: ")]


def test_every_missing_choice_is_named_once_with_the_values_held(map_path: Path,
                                                                  groups) -> None:
    code, lines = _messages(["export", "mujoco", "--map", str(map_path)])
    assert code == 1
    assert len(lines) == 1
    line = lines[0]
    pins = sorted({str(p) for p in groups["pin"]})
    discs = sorted({str(d) for d in groups["disc"]})
    temps = sorted({float(t) for t in groups["temperature_C"]})
    assert f"--pin ({', '.join(pins)})" in line
    assert f"--disc ({', '.join(discs)})" in line
    assert "--pressure (" in line and " kPa)" in line
    assert "--temperature (" + ", ".join(f"{t:g}" for t in temps) + " °C)" in line


def test_one_more_command_is_enough(map_path: Path, groups) -> None:
    """Give what the one message asked for (a value it listed for each) and it writes."""
    code, lines = _messages(["export", "mujoco", "--map", str(map_path), "--pin", PIN])
    assert code == 1 and len(lines) == 1
    asked = lines[0]
    assert "--pin" not in asked.split("give ", 1)[1]
    pair = groups[(groups["pin"] == PIN) & (groups["disc"] == DISC)]
    pressure = f"{sorted(set(pair['pressure_kPa']))[1]:.4g}"
    temperature = f"{sorted(set(pair['temperature_C']))[0]:g}"
    assert pressure in asked and temperature in asked
    done = CliRunner().invoke(main, ["export", "mujoco", "--map", str(map_path), "--pin", PIN,
                                     "--disc", DISC, "--pressure", pressure,
                                     "--temperature", temperature])
    assert done.exit_code == 0, done.output
    assert "<mujoco" in done.stdout


def test_a_value_the_map_holds_alone_is_taken_and_said(groups) -> None:
    one_temp = groups[groups["temperature_C"] == groups["temperature_C"].min()]
    notes: list[str] = []
    pin, disc, p, t, v = one_condition(one_temp, "mujoco", PIN, DISC, 35.37, None, None,
                                       notes.append)
    assert t == float(one_temp["temperature_C"].iloc[0])
    assert notes == [f"--temperature {t:g} °C: the only value the map holds here; taken"]
    only = one_temp[(one_temp["pin"] == PIN) & (one_temp["disc"] == DISC)]
    notes.clear()
    pin, disc, p, t, v = one_condition(only.iloc[:1], "mujoco", None, None, None, None, None,
                                       notes.append)
    assert (pin, disc) == (PIN, DISC)
    assert p == float(only["pressure_kPa"].iloc[0])  # the exact value, not the shown one
    assert [n.split(" ")[0] for n in notes] == ["--pin", "--disc", "--pressure",
                                                "--temperature"]


def test_an_unknown_name_is_asked_with_the_rest(groups) -> None:
    with pytest.raises(ExportError) as err:
        one_condition(groups, "mujoco", "Dragonskin30", DISC, None, None, None)
    text = str(err.value)
    assert "'Dragonskin30' is not one" in text and "--pressure (" in text


def test_help_states_the_defaults_truthfully() -> None:
    text = " ".join(CliRunner().invoke(main, ["export", "mujoco", "--help"]).output.split())
    assert "default: every pin" not in text.casefold().replace("default: every pin for a", "")
    assert "for one condition, the map's only pin (else required)" in text
    assert "the pair's only measured pressure (else required)" in text
