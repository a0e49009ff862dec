"""The friction interval of an export: the one that rotates, with its set-up's torque offset.

Seeded synthetic exports (a normal-force set-up interval, then the friction interval) and
real rheometer files that hold no pin-on-disc run at all.
"""

from __future__ import annotations

import pytest

from conftest import shared_file
from generators.synthetic import SyntheticRun, make_intervals
from tribopipe.config import InstrumentConfig, ReductionParams
from tribopipe.errors import MissingQuantityError, NotFrictionTestError, ReductionError
from tribopipe.measurement import Measurement, MeasurementMeta
from tribopipe.reduction.intervals import robust_mean, select_friction_interval

INSTRUMENT = InstrumentConfig()
PARAMS = ReductionParams()


def measurements(run: SyntheticRun, name: str = "run.csv") -> list[Measurement]:
    """The run's intervals as the readers would hand them over."""
    return [
        Measurement(
            frame,
            MeasurementMeta(source_file=name, file_format="synthetic", test="Friction",
                            result="Friction 1", interval=i),
        )
        for i, frame in enumerate(make_intervals(run), start=1)
    ]


def test_the_rotating_interval_is_chosen_and_the_set_up_gives_the_offset() -> None:
    items = measurements(SyntheticRun(torque_offset_Nm=3e-4, seed=41))
    before = [m.meta for m in items]
    picked = select_friction_interval(items)
    assert picked.meta.interval == 2
    assert picked.data is items[1].data
    # 200 set-up samples with 0.2 mN·m noise: the median is good to ~0.02 mN·m
    offset = picked.meta.torque_offset
    assert offset is not None and offset.torque_Nm == pytest.approx(3e-4, abs=5e-5)
    assert offset.source == "set-up interval 1"
    assert [m.meta for m in items] == before  # inputs untouched
    assert items[1].meta.torque_offset is None


def test_without_angle_or_speed_the_interval_with_torque_is_chosen() -> None:
    frames = make_intervals(SyntheticRun(seed=42))
    items = [
        Measurement(f.drop(columns=["angle_rad", "speed_rad_s"]),
                    MeasurementMeta("plain.csv", "synthetic", interval=i))
        for i, f in enumerate(frames, start=1)
    ]
    picked = select_friction_interval(items)
    assert picked.meta.interval == 2
    assert picked.meta.torque_offset is None  # rest of the set-up is not verified


def test_intervals_without_torque_are_a_missing_quantity() -> None:
    frames = make_intervals(SyntheticRun(seed=43))
    items = [Measurement(f.drop(columns=["torque_Nm"]),
                         MeasurementMeta("nt.csv", "synthetic", interval=i))
             for i, f in enumerate(frames, start=1)]
    with pytest.raises(MissingQuantityError, match="nt.csv: no interval has time, torque"):
        select_friction_interval(items)


def test_real_rheometer_files_that_are_not_friction_runs_are_refused_in_one_line() -> None:
    """Real RheoCompass exports (shear and LAOS tests, no pin-on-disc run) must be
    refused with the file and the reason, not reduced to a number."""
    readers = pytest.importorskip("tribopipe.readers")
    small = shared_file("real-exports", "rheocompass_en_utf16_small.txt")
    with pytest.raises(NotFrictionTestError) as err:
        select_friction_interval(readers.read_export(small))
    assert str(small) in str(err.value) and "flow curve" in str(err.value)
    laos = shared_file("real-exports", "rheocompass_fr_utf16_laos.csv")
    # an oscillation is refused before any reduction, whatever the contact threshold
    with pytest.raises(NotFrictionTestError) as err:
        select_friction_interval(readers.read_export(laos))
    message = str(err.value)
    assert message.startswith(str(laos)) and "not a pin-on-disc friction test" in message
    assert "oscillation" in message
    assert "\n" not in message


def test_the_robust_mean_ignores_spikes_but_not_noise() -> None:
    import numpy as np

    rng = np.random.default_rng(1)
    torque = 3e-4 + rng.normal(0, 2e-5, 400)
    spiked = torque.copy()
    spiked[::50] = 5e-3  # 8 spikes, each 25 SDs away
    assert robust_mean(torque) == pytest.approx(float(np.mean(torque)), abs=2e-6)
    assert robust_mean(spiked) == pytest.approx(robust_mean(torque), abs=3e-6)
    assert robust_mean([2.0, 2.0, 2.0]) == 2.0


# --------------------------------------------------------------------------- several tests


def session(*runs_per_test: tuple[SyntheticRun, ...]) -> list[Measurement]:
    """The intervals of several tests, numbered from 1 in each, as a session export reads."""
    items = []
    for k, runs in enumerate(runs_per_test, start=1):
        frames = [f for run in runs for f in make_intervals(run)]
        items += [Measurement(frame, MeasurementMeta("s.csv", "synthetic", test=f"T{k}",
                                                     result=f"T{k} 1", interval=i))
                  for i, frame in enumerate(frames, start=1)]
    return items


def test_every_test_gets_its_friction_interval_and_its_own_set_up_offset() -> None:
    from tribopipe.reduction.intervals import friction_intervals

    items = session(
        (SyntheticRun(torque_offset_Nm=3e-4, seed=51),),
        (SyntheticRun(torque_offset_Nm=-2e-4, setup_interval=False, seed=52),),
        (SyntheticRun(torque_offset_Nm=-2e-4, seed=53),),
    )
    found = friction_intervals(items)
    assert [(r.test, r.result) for r in found] == [("T1", "T1 1"), ("T2", "T2 1"),
                                                  ("T3", "T3 1")]
    assert all(r.problem is None and len(r.friction) == 1 for r in found)
    one, two, three = (r.friction[0] for r in found)
    assert (one.meta.interval, two.meta.interval, three.meta.interval) == (2, 1, 2)
    assert one.meta.torque_offset.torque_Nm == pytest.approx(3e-4, abs=5e-5)
    # T2 has no set-up of its own and never borrows T1's (another test, another zero)
    assert two.meta.torque_offset is None
    assert three.meta.torque_offset.torque_Nm == pytest.approx(-2e-4, abs=5e-5)
    assert three.meta.torque_offset.source == "set-up interval 1"


def test_force_steps_in_one_test_are_one_friction_interval_each() -> None:
    """A set-up, then 3 N and 5 N steps without a new set-up: both steps are friction
    intervals; the nearest at-rest interval before each (the set-up) zeroes both."""
    from tribopipe.reduction.intervals import friction_intervals

    items = session((SyntheticRun(normal_force_N=3.0, torque_offset_Nm=2e-4, seed=54),
                     SyntheticRun(normal_force_N=5.0, torque_offset_Nm=2e-4,
                                  setup_interval=False, duration_s=200.0, seed=55)))
    (found,) = friction_intervals(items)
    assert [m.meta.interval for m in found.friction] == [2, 3]
    for m in found.friction:
        assert m.meta.torque_offset.source == "set-up interval 1"
        assert m.meta.torque_offset.torque_Nm == pytest.approx(2e-4, abs=5e-5)
    # the single choice is still one interval: the one travelling farthest
    assert select_friction_interval(items).meta.interval == 2


def test_a_test_without_rotation_is_its_own_problem_naming_it() -> None:
    from tribopipe.reduction.intervals import friction_intervals

    still = make_intervals(SyntheticRun(seed=56))[0]  # a set-up alone: the disc never turns
    items = session((SyntheticRun(seed=57),)) + [
        Measurement(still, MeasurementMeta("s.csv", "synthetic", test="Hold", result="Hold 1",
                                           interval=1))]
    good, bad = friction_intervals(items)
    assert len(good.friction) == 1 and good.problem is None
    assert bad.friction == () and isinstance(bad.problem, ReductionError)
    message = str(bad.problem)
    assert message.startswith("s.csv: Hold / Hold 1: no friction interval: no rotation")
    # a one-test export keeps the message it always had
    with pytest.raises(ReductionError, match=r"^s\.csv: no rotation in any of the 1 interval"):
        select_friction_interval(items[-1:])


def test_the_real_two_test_relaxation_export_has_no_friction_interval_in_either_test(
    data_dir,
) -> None:
    """A real session export of two stress-relaxation tests: torque but no normal force
    and no rotation. Each test is refused on its own, by name."""
    from tribopipe.readers import read_export
    from tribopipe.reduction.intervals import friction_intervals

    path = data_dir / "rheocompass_en_utf16_two_tests.csv"
    found = friction_intervals(read_export(path))
    assert [r.test for r in found] == ["Stress Relaxation 1", "Stress Relaxation"]
    for r in found:
        assert r.friction == ()
        assert isinstance(r.problem, NotFrictionTestError)
        assert str(r.problem).startswith(
            f"{path}: {r.test} / Step strain 1: no friction interval: not a pin-on-disc "
            "friction test: it looks like a stress relaxation test")
        assert r.problem.looks_like.startswith("a stress relaxation test")  # a field
