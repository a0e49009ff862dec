"""The written simulator input, loaded in the free engines themselves.

MuJoCo compiles our MJCF (through ``<include>``, as a user would) and reports the pair's
friction in the model and in a live contact; PyElastica runs our Python file, builds
``RodPlaneContactWithAnisotropicFriction`` from it and applies it to a rod lying on a
plane: the friction force it computes is μ_K × load when sliding and at most μ_S × load
when stuck. USD (pxr with the PhysX schemas) reads back the material's authored static
and dynamic friction, its combine mode and both bindings; PyBullet loads both URDFs, reads
each link's lateral friction and measures the friction of a box sliding on the disc;
Drake parses the SDFormat file, finalizes the plant and combines the two geometries'
CoulombFriction by its own rule. Each test skips with a reason where its engine is not
installed (``pip install -e '.[test,engines]'``; ``.ci/run`` installs them); Drake's sit
behind the ``drake`` marker (``pytest -m drake``, run by ``.ci/run``).
"""

from __future__ import annotations

import functools
import math
import runpy

import pandas as pd
import pytest

from helpers import with_mu_s
from sim_files import pyelastica_values
from tribopipe.export.simulators import export_simulator_input
from tribopipe.query import query

PIN, DISC = "Dragonskin 30", "steel"
write_mujoco = functools.partial(export_simulator_input, fmt="mujoco")
write_pyelastica = functools.partial(export_simulator_input, fmt="pyelastica")
HOSTILE = "Evil\n*HEADING\r\n'\"</pair><!-- -->--$ import os\x1b\u2028end"


@pytest.fixture(scope="module")
def groups(published_groups: pd.DataFrame) -> pd.DataFrame:
    """The published groups with a μ_S 1.4 × μ_K, and one pin renamed to a hostile name."""
    g = with_mu_s(published_groups)
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


# ---------------------------------------------------------------------------- OpenUSD


@pytest.fixture(scope="module")
def pxr_usd():
    """pxr's Usd and UsdShade with the PhysX schemas registered (physx-usd-schemas)."""
    pxr = pytest.importorskip("pxr", reason="usd-core not installed: pip install -e '.[engines]'")
    pytest.importorskip("physx_usd_schemas",
                        reason="physx-usd-schemas not installed: pip install -e '.[engines]'")
    from pxr import Usd, UsdPhysics, UsdShade

    return pxr, Usd, UsdPhysics, UsdShade


@pytest.mark.parametrize("pin,with_mu_s", [(PIN, True), (HOSTILE, True), (PIN, False)])
def test_usd_opens_and_both_bodies_carry_the_pair_values(
    pxr_usd, groups, tmp_path, pin, with_mu_s
):
    _, Usd, UsdPhysics, UsdShade = pxr_usd
    table = groups if with_mu_s else groups.drop(
        columns=[c for c in groups.columns if c.startswith("mu_s")])
    path = tmp_path / "friction.usda"
    path.write_text(export_simulator_input(table, "usd", pin=pin, disc=DISC,
                                           pressure_kPa=47.16, temperature_C=20.0),
                    encoding="utf-8")
    res = query(table, pin, DISC, 47.16, 20.0)
    stage = Usd.Stage.Open(str(path))
    material = stage.GetPrimAtPath("/TribopipeFriction/PinOnDisc")
    assert material.HasAPI(UsdPhysics.MaterialAPI)
    assert "PhysxMaterialAPI" in material.GetAppliedSchemas()
    physics = UsdPhysics.MaterialAPI(material)
    # authored, never the schema's fallback (0.0 for staticFriction)
    assert physics.GetStaticFrictionAttr().HasAuthoredValue()
    assert physics.GetDynamicFrictionAttr().HasAuthoredValue()
    static = physics.GetStaticFrictionAttr().Get()
    dynamic = physics.GetDynamicFrictionAttr().Get()
    expected_static = res.mu_s.value if with_mu_s else res.mu_k.value
    assert dynamic == pytest.approx(res.mu_k.value, rel=1e-6)  # USD floats are 32-bit
    assert static == pytest.approx(expected_static, rel=1e-6)
    mode = material.GetAttribute("physxMaterial:frictionCombineMode")
    assert mode.HasAuthoredValue() and mode.Get() == "average"
    assert "multiply" in mode.GetMetadata("allowedTokens")  # the schema knows the attribute
    for body in ("Pin", "Disc"):
        prim = stage.GetPrimAtPath(f"/TribopipeFriction/{body}")
        bound, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial("physics")
        assert bound.GetPath() == material.GetPath(), body
    # PhysX's rule on two bodies bound to the same material: the higher-priority mode of the
    # two (both "average"), static and dynamic separately: the pair's values come back
    assert (static + static) / 2 == static and (dynamic + dynamic) / 2 == dynamic


# ---------------------------------------------------------------------------- PyBullet


@pytest.fixture()
def bullet():
    """A pybullet client without a window; disconnected after the test."""
    pb = pytest.importorskip("pybullet",
                             reason="pybullet not installed: pip install -e '.[engines]'")
    client = pb.connect(pb.DIRECT)
    yield pb, client
    pb.disconnect(client)


def _sliding_friction(pb, client, pin_body: int, disc_body: int) -> tuple[float, float]:
    """(friction/normal force ratio, pin speed [m/s]) of the pin pushed along the disc by
    a lateral force of twice its weight: the ratio comes from the contact points'
    lateral friction and normal forces after the pin is sliding."""
    pb.setGravity(0, 0, -9.81, physicsClientId=client)
    mass = pb.getDynamicsInfo(pin_body, -1, physicsClientId=client)[0]
    for _ in range(120):  # settle
        pb.stepSimulation(physicsClientId=client)
    ratios = []
    for _ in range(40):
        position = pb.getBasePositionAndOrientation(pin_body, physicsClientId=client)[0]
        pb.applyExternalForce(pin_body, -1, [2.0 * mass * 9.81, 0, 0], position,
                              pb.WORLD_FRAME, physicsClientId=client)
        pb.stepSimulation(physicsClientId=client)
        points = pb.getContactPoints(pin_body, disc_body, physicsClientId=client)
        normal = sum(p[9] for p in points)
        lateral = sum(p[10] * p[11][0] + p[12] * p[13][0] for p in points)
        if normal > 0:
            ratios.append(abs(lateral) / normal)
    speed = pb.getBaseVelocity(pin_body, physicsClientId=client)[0][0]
    return sum(ratios[-10:]) / 10, speed


@pytest.mark.parametrize("pin,coefficient", [(PIN, "mu_k"), (PIN, "mu_s"), (HOSTILE, "mu_k")])
def test_pybullet_loads_both_links_and_a_sliding_contact_has_the_pair_mu(
    bullet, groups, tmp_path, pin, coefficient
):
    pb, client = bullet
    cond = {"pin": pin, "disc": DISC, "pressure_kPa": 47.16, "temperature_C": 20.0,
            "coefficient": coefficient}
    res = query(groups, pin, DISC, 47.16, 20.0)
    mu = res.mu_k.value if coefficient == "mu_k" else res.mu_s.value
    for body in ("pin", "disc"):
        (tmp_path / f"{body}.urdf").write_text(
            export_simulator_input(groups, "pybullet", body=body, **cond), encoding="utf-8")
    disc = pb.loadURDF(str(tmp_path / "disc.urdf"), [0, 0, 0], useFixedBase=True,
                       physicsClientId=client)
    pin_body = pb.loadURDF(str(tmp_path / "pin.urdf"), [0, 0, 0.0201],
                           physicsClientId=client)
    assert pb.getDynamicsInfo(pin_body, -1, physicsClientId=client)[1] == pytest.approx(mu)
    assert pb.getDynamicsInfo(disc, -1, physicsClientId=client)[1] == 1.0
    ratio, speed = _sliding_friction(pb, client, pin_body, disc)
    assert speed > 0.05  # sliding, so the contact is at its friction limit
    assert ratio == pytest.approx(mu, rel=1e-3)  # Bullet's product: mu x 1.0


def test_pybullet_equal_values_on_both_links_would_give_mu_squared(bullet, groups, tmp_path):
    """Why the disc carries 1.0: the pin's file loaded as both bodies gives mu²."""
    pb, client = bullet
    res = query(groups, PIN, DISC, 47.16, 20.0)
    text = export_simulator_input(groups, "pybullet", pin=PIN, disc=DISC, pressure_kPa=47.16,
                                  temperature_C=20.0)
    (tmp_path / "pin.urdf").write_text(text, encoding="utf-8")
    (tmp_path / "plate.urdf").write_text(
        text.replace('size="0.02 0.02 0.02"', 'size="0.4 0.4 0.02"'), encoding="utf-8")
    plate = pb.loadURDF(str(tmp_path / "plate.urdf"), [0, 0, 0], useFixedBase=True,
                        physicsClientId=client)
    pin_body = pb.loadURDF(str(tmp_path / "pin.urdf"), [0, 0, 0.0201], physicsClientId=client)
    ratio, _ = _sliding_friction(pb, client, pin_body, plate)
    assert ratio == pytest.approx(res.mu_k.value ** 2, rel=1e-3)


# ---------------------------------------------------------------------------- Drake


@pytest.fixture(scope="module")
def pydrake():
    return pytest.importorskip("pydrake", reason="drake not installed: pip install -e '.[engines]'")


def _drake_friction(path) -> list:
    """Each collision geometry's CoulombFriction in a finalized plant of the file."""
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
    from pydrake.systems.framework import DiagramBuilder

    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, 0.0)
    Parser(plant).AddModels(str(path))
    plant.Finalize()
    inspector = scene_graph.model_inspector()
    found = []
    for geometry in inspector.GetAllGeometryIds():
        props = inspector.GetProximityProperties(geometry)
        if props is not None:
            found.append(props.GetProperty("material", "coulomb_friction"))
    return found


@pytest.mark.drake
@pytest.mark.parametrize("pin,mu_s", [(PIN, "measured"), (HOSTILE, "measured"),
                                       (PIN, "unknown"), (PIN, "below mu_k")])
def test_drake_parses_the_file_and_combines_to_the_pair_values(
    pydrake, groups, tmp_path, pin, mu_s
):
    from pydrake.multibody.plant import CalcContactFrictionFromSurfaceProperties

    table = groups.copy()
    if mu_s == "unknown":
        table = table.drop(columns=[c for c in table.columns if c.startswith("mu_s")])
    elif mu_s == "below mu_k":
        table["mu_s_mean"] = table["mu_k_mean"] * 0.9
    path = tmp_path / "friction.sdf"
    path.write_text(export_simulator_input(table, "drake", pin=pin, disc=DISC,
                                           pressure_kPa=47.16, temperature_C=20.0),
                    encoding="utf-8")
    res = query(table, pin, DISC, 47.16, 20.0)
    static = res.mu_s.value if mu_s == "measured" else res.mu_k.value
    pin_friction, disc_friction = _drake_friction(path)
    combined = CalcContactFrictionFromSurfaceProperties(pin_friction, disc_friction)
    # the file holds 10 significant digits (unit_systems.num): the engine's value is the pair's
    # to half a unit of the 10th
    assert combined.dynamic_friction() == pytest.approx(res.mu_k.value, rel=1e-9)
    assert combined.static_friction() == pytest.approx(static, rel=1e-9)
    assert combined.static_friction() >= combined.dynamic_friction()
