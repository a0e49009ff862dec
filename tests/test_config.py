"""Instrument configs: the founding defaults, the shipped TOML, and refusal of bad keys."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from tribopipe.config import InstrumentConfig, load_settings, settings_from_dict
from tribopipe.errors import ConfigError

REPO = Path(__file__).resolve().parents[1]


def test_founding_friction_radius_follows_from_paper_speed() -> None:
    # 0.005 rpm must give 0.007 mm/s at the friction radius (the paper's statement).
    inst = InstrumentConfig()
    assert inst.friction_radius_mm == pytest.approx(13.37, abs=0.005)
    assert inst.nominal_sliding_speed_mm_s == pytest.approx(0.007, abs=5e-6)


def test_pin_area_is_28_27_mm2() -> None:
    assert InstrumentConfig().pin_area_mm2 == pytest.approx(28.27, abs=0.005)


def test_shipped_tpid44_config_equals_defaults() -> None:
    shipped = load_settings(REPO / "configs" / "instruments" / "t-pid44.toml")
    assert shipped.instrument == InstrumentConfig()
    assert shipped.config_hash == load_settings(None).config_hash


def test_config_hash_changes_with_geometry() -> None:
    a = settings_from_dict({})
    b = settings_from_dict({"instrument": {"friction_radius_mm": 15.0}})
    assert a.config_hash != b.config_hash
    assert b.instrument.friction_radius_mm == 15.0


def test_unknown_key_is_refused_with_file_and_key(tmp_path: Path) -> None:
    cfg = tmp_path / "cell.toml"
    cfg.write_text("[instrument]\npin_radius_m = 0.003\n", encoding="utf-8")
    with pytest.raises(ConfigError) as err:
        load_settings(cfg)
    text = str(err.value)
    assert str(cfg) in text and "pin_radius_m" in text and "pin_radius_mm" in text


@pytest.mark.parametrize("value", ["0", "-3.0", "nan"])
def test_non_positive_radius_is_refused(tmp_path: Path, value: str) -> None:
    cfg = tmp_path / "cell.toml"
    cfg.write_text(f"[instrument]\npin_radius_mm = {value}\n", encoding="utf-8")
    with pytest.raises(ConfigError, match="pin_radius_mm"):
        load_settings(cfg)


def test_broken_toml_names_the_file(tmp_path: Path) -> None:
    cfg = tmp_path / "broken.toml"
    cfg.write_text("[instrument\n", encoding="utf-8")
    with pytest.raises(ConfigError, match="broken.toml.*not valid TOML"):
        load_settings(cfg)


def test_missing_config_file_is_a_config_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="not found"):
        load_settings(tmp_path / "nope.toml")


def test_other_pin_count_changes_area_not_radius() -> None:
    inst = InstrumentConfig(n_pins=1, pin_radius_mm=2.0)
    assert inst.pin_area_mm2 == pytest.approx(math.pi * 4.0)


def test_config_hash_is_computed_once_and_stays_stable() -> None:
    settings = settings_from_dict({"reduction": {"run_in_mm": 0.3}})
    first = settings.config_hash
    assert settings.config_hash is first  # cached on the object
    assert settings_from_dict({"reduction": {"run_in_mm": 0.3}}).config_hash == first


def test_the_one_merge_overrides_key_by_key_and_copies() -> None:
    from tribopipe.config import merge_tables, settings_tables

    base = settings_tables({"instrument": {"pin_radius_mm": 4.0},
                            "reduction": {"median_window": 9, "run_in_mm": 0.5}}, "inst.toml")
    ours = settings_tables({"campaign": {}, "reduction": {"median_window": 5}}, "c.toml")
    merged = merge_tables(base, ours)
    assert merged == {"instrument": {"pin_radius_mm": 4.0},
                      "reduction": {"median_window": 5, "run_in_mm": 0.5}}
    assert base["reduction"]["median_window"] == 9  # inputs untouched
    settings = settings_from_dict(merged)
    assert (settings.reduction.median_window, settings.reduction.run_in_mm) == (5, 0.5)
    with pytest.raises(ConfigError, match=r"c\.toml: \[reduction\] must be a table"):
        settings_tables({"reduction": 3}, "c.toml")


def test_reduction_params_live_in_config_and_import_from_reduce_too() -> None:
    from tribopipe.config import ReductionParams
    from tribopipe.config import ReductionParams as from_reduce

    assert from_reduce is ReductionParams
    assert load_settings().reduction == ReductionParams()
