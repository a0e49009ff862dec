"""The friction interval of an export: the one that rotates, with its set-up's torque offset.

Seeded synthetic exports (a normal-force set-up interval, then the friction interval) and
real rheometer files that hold no pin-on-disc run at all.
"""

from __future__ import annotations

import pytest

from conftest import shared_file
from tribopipe.config import InstrumentConfig, ReductionParams
from tribopipe.errors import MissingQuantityError, ReductionError
from tribopipe.intervals import robust_mean, select_friction_interval
from tribopipe.measurement import Measurement, MeasurementMeta
from tribopipe.reduce import reduce_measurement
from tribopipe.synthetic import SyntheticRun, make_intervals

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
    with pytest.raises(MissingQuantityError) as err:
        select_friction_interval(readers.read_export(small))
    assert str(small) in str(err.value) and "missing: normal_force_N" in str(err.value)
    laos = shared_file("real-exports", "rheocompass_fr_utf16_laos.csv")
    with pytest.raises(ReductionError) as err:
        picked = select_friction_interval(readers.read_export(laos))
        reduce_measurement(picked, INSTRUMENT, PARAMS)
    message = str(err.value)
    assert message.startswith(str(laos)) and "contact threshold" in message
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


def test_the_old_import_place_still_works() -> None:
    from tribopipe import reduce

    assert reduce.select_friction_interval is select_friction_interval
