"""The written simulator input, loaded in the free engines themselves.

MuJoCo compiles our MJCF (through ``<include>``, as a user would) and reports the pair's
friction in the model and in a live contact; PyElastica runs our Python file, builds
``RodPlaneContactWithAnisotropicFriction`` from it and applies it to a rod lying on a
plane: the friction force it computes is μ_K × load when sliding and at most μ_S × load
when stuck. Each test skips with a reason where its engine is not installed
(``pip install -e '.[test,engines]'``; ``.ci/run`` installs both).
"""

from __future__ import annotations

import math
import runpy

import pandas as pd
import pytest

from published_map import PUBLISHED_CSV, group_table, published_runs
from sim_files import pyelastica_values
from tribopipe.export.simulators import write_mujoco, write_pyelastica
from tribopipe.query import query

PIN, DISC = "Dragonskin 30", "steel"
HOSTILE = "Evil\n*HEADING\r\n'\"</pair><!-- -->--$ import os\x1b\u2028end"


@pytest.fixture(scope="module")
def groups() -> pd.DataFrame:
    """The published groups with a μ_S 1.4 × μ_K, and one pin renamed to a hostile name."""
    g = group_table(published_runs(PUBLISHED_CSV))
    g["mu_s_n"] = g["mu_k_n"]
    g["mu_s_mean"] = g["mu_k_mean"] * 1.4
    g["mu_s_ci95_low"] = g["mu_s_mean"] - 0.02
    g["mu_s_ci95_high"] = g["mu_s_mean"] + 0.02
    hostile = g[(g.pin == PIN) & (g.disc == DISC)].copy()
    hostile["pin"] = HOSTILE
    return pd.concat([g, hostile], ignore_index=True)


@pytest.fixture(scope="module")
def mujoco():
    return pytest.importorskip("mujoco", reason="mujoco not installed: pip install -e '.[test]'")


@pytest.fixture(scope="module")
def elastica():
    return pytest.importorskip(
        "elastica", reason="pyelastica not installed: pip install -e '.[engines]'"
    )


MODEL = """<mujoco>
  <worldbody>
    <geom name="table" type="plane" size="1 1 0.1" friction="0.9 0.005 0.0001"/>
    <body pos="0 0 0.0095">
      <freejoint/>
      <geom name="finger" type="sphere" size="0.01" friction="0.1 0.005 0.0001"/>
    </body>
  </worldbody>
  <include file="contact.xml"/>
</mujoco>
"""


@pytest.mark.parametrize("pin,coefficient", [(PIN, "mu_k"), (PIN, "mu_s"), (HOSTILE, "mu_k")])
def test_mujoco_compiles_the_file_and_reports_the_coefficient(
    mujoco, groups, tmp_path, pin, coefficient
):
    (tmp_path / "contact.xml").write_text(
        write_mujoco(groups, pin=pin, disc=DISC, pressure_kPa=47.16, temperature_C=20.0,
                     coefficient=coefficient, geom1="finger", geom2="table"),
        encoding="utf-8",
    )
    (tmp_path / "model.xml").write_text(MODEL, encoding="utf-8")
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "model.xml"))
    res = query(groups, pin, DISC, 47.16, 20.0)
    mu = res.mu_s.value if coefficient == "mu_s" else res.mu_k.value
    w = math.log(47.16 / 35.37) / math.log(58.95 / 35.37)  # log p - log mu between groups
    mid = 0.45 ** (1 - w) * 0.36 ** w
    assert mu == pytest.approx(mid * (1.4 if coefficient == "mu_s" else 1.0))
    assert model.npair == 1
    finger = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "finger")
    table = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "table")
    # (MuJoCo stores a pair's geoms in its own order)
    assert {int(model.pair_geom1[0]), int(model.pair_geom2[0])} == {finger, table}
    assert list(model.pair_friction[0]) == pytest.approx([mu, mu, 0.005, 0.0001, 0.0001],
                                                         rel=1e-9)
    # a live contact: the pair's value, not the geoms' maximum (0.9)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    assert data.ncon == 1
    assert list(data.contact[0].friction[:2]) == pytest.approx([mu, mu], rel=1e-9)


def _rod_on_plane(elastica, namespace: dict, tmp_path):
    """A 4-element rod lying on a plane, in contact through the arrays of ``namespace``."""
    import numpy as np

    class Simulator(elastica.BaseSystemCollection, elastica.Contact):
        pass

    sim = Simulator()
    radius = 0.005
    rod = elastica.CosseratRod.straight_rod(
        n_elements=4, start=np.array([0.0, 0.0, 0.9 * radius]),
        direction=np.array([1.0, 0.0, 0.0]), normal=np.array([0.0, 0.0, 1.0]),
        base_length=0.1, base_radius=radius, density=1000.0, youngs_modulus=1e6,
    )
    plane = elastica.Plane(plane_origin=np.zeros(3), plane_normal=np.array([0.0, 0.0, 1.0]))
    sim.append(rod)
    sim.append(plane)
    handle = sim.detect_contact_between(rod, plane)
    handle.using(
        elastica.RodPlaneContactWithAnisotropicFriction, k=1e2, nu=0.0, slip_velocity_tol=1e-6,
        static_mu_array=namespace["static_mu_array"],
        kinetic_mu_array=namespace["kinetic_mu_array"],
    )
    sim.finalize()  # checks the rod/plane pairing as a run would
    return rod, plane, handle.instantiate()


def _friction_x(contact, rod, plane, *, speed: float, push_per_node: float) -> float:
    """Total axial friction force [N] on the rod under 0.2 N per node of load."""
    rod.velocity_collection[:] = 0.0
    rod.velocity_collection[0, :] = speed
    rod.external_forces[:] = 0.0
    rod.external_forces[2, :] = -0.2
    rod.external_forces[0, :] = push_per_node
    contact.apply_contact(rod, plane)
    return float(rod.external_forces[0].sum() - push_per_node * rod.external_forces.shape[1])


@pytest.mark.slow
def test_pyelastica_runs_the_file_and_applies_its_coefficients(elastica, groups, tmp_path):
    path = tmp_path / "friction.py"
    path.write_text(
        write_pyelastica(groups, pin=HOSTILE, disc=DISC, pressure_kPa=35.37, temperature_C=20.0,
                         coefficient="mu_s"),
        encoding="utf-8",
    )
    values = pyelastica_values(path.read_text(encoding="utf-8"))  # nothing else in the file
    assert values["PAIR"] == (HOSTILE, DISC)
    namespace = runpy.run_path(str(path))  # the file runs as written
    rod, plane, contact = _rod_on_plane(elastica, namespace, tmp_path)
    mu_s, mu_k = 0.45 * 1.4, 0.45
    assert (contact.static_mu_forward, contact.static_mu_backward,
            contact.static_mu_sideways) == pytest.approx((mu_s,) * 3)
    assert (contact.kinetic_mu_forward, contact.kinetic_mu_backward,
            contact.kinetic_mu_sideways) == pytest.approx((mu_k,) * 3)
    load = 0.2 * rod.external_forces.shape[1]
    # sliding along the rod: kinetic friction mu_k x load against the motion
    assert _friction_x(contact, rod, plane, speed=1e-3, push_per_node=0.0) == pytest.approx(
        -mu_k * load, rel=1e-9)
    # at rest, pushed with more than mu_s x load: static friction holds mu_s x load
    assert _friction_x(contact, rod, plane, speed=0.0, push_per_node=0.4) == pytest.approx(
        -mu_s * load, rel=1e-9)
