"""The master curve over speed and temperature: shift laws recovered from data made with
them, the refusals, the model-based prediction inside the covered range only, the CLI."""

from __future__ import annotations

import dataclasses
import json
import math

import pytest
from click.testing import CliRunner

from test_frictionmap import run_record
from tribopipe import frictionmap as fm
from tribopipe.cli import main
from tribopipe.errors import ExportError
from tribopipe.mastercurve import master_curve, predict, shift_law
from tribopipe.query import groups_of

SPEEDS = (0.007, 0.021, 0.07, 0.21)
TEMPS = (10.0, 25.0, 40.0)
FORCES = (1.0, 9.0)


def _records(law: dict, shift: str, curve, *, temps=TEMPS, speeds=SPEEDS, forces=FORCES):
    """Two repeats per condition of μ_K = curve(x, force) at x = log10(a_T·v), a_T by
    ``shift`` about 25 °C; the repeats ±0.001 apart."""
    out = []
    i = 0
    for force in forces:
        for t in temps:
            for v in speeds:
                x = math.log10(v) + shift_law(shift, law, 25.0, t)
                for repeat, delta in ((1, -0.001), (2, 0.001)):
                    i += 1
                    rec = dataclasses.replace(
                        run_record(0, force_N=force, temperature_C=t, repeat=repeat),
                        measurement_id=f"m{i:04d}", nominal_speed_mm_s=v,
                        mu_k=curve(x, force) + delta, flags="")
                    out.append(rec)
    return out


def _quadratic(x: float, force: float) -> float:
    return (0.9 if force < 5 else 0.6) + 0.08 * x - 0.01 * x * x


def _groups(records):
    return groups_of(fm.records_frame(records), "map")


def test_arrhenius_shift_and_curves_are_recovered_from_data_made_with_them():
    mc = master_curve(_groups(_records({"Ea_kJ_mol": 55.0}, "arrhenius", _quadratic)),
                      "Ecoflex 00-50", "steel")
    assert mc.shift == "arrhenius" and mc.reference_temperature_C == 25.0
    assert mc.parameters["Ea_kJ_mol"] == pytest.approx(55.0, rel=1e-6)
    assert mc.uncertainties["Ea_kJ_mol"] < 0.01
    assert mc.log10_aT[25.0] == 0.0 and mc.log10_aT[10.0] > 0 > mc.log10_aT[40.0]
    assert mc.residual_sd < 1e-8
    low = next(c for c in mc.curves if c.pressure_kPa < 50)
    high = next(c for c in mc.curves if c.pressure_kPa > 50)
    assert low.coefficients == pytest.approx((0.9, 0.08, -0.01), abs=1e-6)
    assert high.coefficients == pytest.approx((0.6, 0.08, -0.01), abs=1e-6)
    data = mc.to_dict()
    assert {"shift", "Ea_kJ_mol", "u_Ea_kJ_mol", "reference_temperature_C", "log10_aT",
            "curve", "residual_sd"} <= set(data)


def test_wlf_constants_are_recovered():
    records = _records({"C1": 6.0, "C2_K": 140.0}, "wlf", _quadratic)
    mc = master_curve(_groups(records), "Ecoflex 00-50", "steel", shift="wlf")
    # three temperatures fix two constants exactly here (no noise in the means)
    assert mc.parameters["C1"] == pytest.approx(6.0, rel=1e-3)
    assert mc.parameters["C2_K"] == pytest.approx(140.0, rel=1e-3)
    assert {"C1", "C2"} <= set(mc.to_dict())


def test_prediction_inside_the_covered_range_and_refused_outside():
    law = {"Ea_kJ_mol": 55.0}
    groups = _groups(_records(law, "arrhenius", _quadratic))
    mc = master_curve(groups, "Ecoflex 00-50", "steel")
    p = min(c.pressure_kPa for c in mc.curves)
    t, v = 32.0, 0.03
    got = predict(mc, p, t, v)
    truth = _quadratic(math.log10(v) + shift_law("arrhenius", law, 25.0, t), 1.0)
    assert got.mu_k == pytest.approx(truth, abs=1e-6) and got.model_based
    assert got.to_dict()["mu_k"]["value"] == got.mu_k
    with pytest.raises(ExportError, match="outside the range the master curve covers"):
        predict(mc, p, 40.0, 10.0)


def test_refusals_in_one_line():
    one_t = _groups(_records({"Ea_kJ_mol": 55.0}, "arrhenius", _quadratic, temps=(25.0,)))
    with pytest.raises(ExportError, match="at least 2 temperatures"):
        master_curve(one_t, "Ecoflex 00-50", "steel")
    one_v = _groups(_records({"Ea_kJ_mol": 55.0}, "arrhenius", _quadratic, speeds=(0.007,)))
    with pytest.raises(ExportError, match="at least 2 sliding speeds"):
        master_curve(one_v, "Ecoflex 00-50", "steel")
    # a steep shift: each temperature's half decade lands 2 decades from the next
    steep = _groups(_records({"Ea_kJ_mol": 400.0}, "arrhenius",
                             lambda x, f: 0.5 + 0.05 * x, speeds=(0.007, 0.021)))
    with pytest.raises(ExportError, match="overlaps no other") as info:
        master_curve(steep, "Ecoflex 00-50", "steel")
    assert "\n" not in str(info.value)
    with pytest.raises(ExportError, match="unknown shift"):
        master_curve(one_t, "Ecoflex 00-50", "steel", shift="magic")


def test_cli_master_curve_json_plot_and_model_based_query(tmp_path):
    map_path = tmp_path / "map.parquet"
    fm.append_records(map_path, _records({"Ea_kJ_mol": 55.0}, "arrhenius", _quadratic))
    plot = tmp_path / "mc.png"
    out = CliRunner().invoke(main, ["map", "master-curve", "--pin", "Ecoflex 00-50", "--disc",
                                    "steel", "--json", "--output", str(plot), "--map",
                                    str(map_path)])
    assert out.exit_code == 0, out.output
    data = json.loads(out.stdout)
    assert data["Ea_kJ_mol"] == pytest.approx(55.0, rel=1e-6)
    assert [a["temperature_C"] for a in data["log10_aT"]] == list(TEMPS)
    assert plot.read_bytes()[:4] == b"\x89PNG"
    text = CliRunner().invoke(main, ["map", "master-curve", "--pin", "Ecoflex 00-50",
                                     "--disc", "steel", "--map", str(map_path)])
    assert text.exit_code == 0 and "Ea = 55.0 kJ/mol" in text.output
    q = CliRunner().invoke(main, ["query", "--pin", "Ecoflex 00-50", "--disc", "steel",
                                  "--force", "1", "--temperature", "32", "--speed", "0.03",
                                  "--master-curve", "--json", "--map", str(map_path)])
    assert q.exit_code == 0, q.output
    answer = json.loads(q.stdout)
    assert answer["model_based"] is True and set(answer["mu_k"]) >= {"value"}
    refused = CliRunner().invoke(main, ["query", "--pin", "Ecoflex 00-50", "--disc", "steel",
                                        "--force", "1", "--temperature", "32", "--speed",
                                        "100", "--master-curve", "--map", str(map_path)])
    assert refused.exit_code != 0 and "refused" in refused.output
    assert refused.output.strip().count("\n") == 0
