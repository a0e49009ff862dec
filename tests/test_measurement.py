"""The measurement's metadata labels say where a number came from."""


def test_interval_label_leaves_out_what_is_unknown() -> None:
    from tribopipe.measurement import MeasurementMeta, interval_label

    assert interval_label("T", "R", 2) == "T / R / interval 2"
    assert interval_label(None, None, 1) == "interval 1"
    assert interval_label(None, None, None) == ""
    assert MeasurementMeta("a.csv", "csv").label == "a.csv"
    assert MeasurementMeta("a.csv", "csv", test="T", interval=3).label == "a.csv [T / interval 3]"


def test_require_columns_names_file_interval_and_what_was_found() -> None:
    import pandas as pd
    import pytest

    from tribopipe.errors import MissingQuantityError
    from tribopipe.measurement import Measurement, MeasurementMeta, require_columns
    from tribopipe.readers import require_columns as from_readers

    assert from_readers is require_columns
    meta = MeasurementMeta("run.csv", "csv", interval=2, header_line=7,
                           column_map=(("Time [s]", "time_s"), ("F [N]", "normal_force_N")))
    m = Measurement(pd.DataFrame({"time_s": [0.0, 1.0], "normal_force_N": [1.0, float("nan")]}),
                    meta)
    require_columns(m, "time_s", "normal_force_N")  # one finite value is enough
    with pytest.raises(MissingQuantityError,
                       match=r"run\.csv:7: interval 2 has no torque_Nm values "
                             r"\(columns found: Time \[s\] → time_s, F \[N\] → normal_force_N\)"):
        require_columns(m, "torque_Nm")


def test_the_set_up_torque_offset_is_a_typed_field() -> None:
    from tribopipe.measurement import MeasurementMeta, TorqueOffset

    meta = MeasurementMeta("a.csv", "csv")
    assert meta.torque_offset is None and meta.extra == ()
    offset = TorqueOffset(torque_Nm=3e-4, source="set-up interval 1")
    assert MeasurementMeta("a.csv", "csv", torque_offset=offset).torque_offset.torque_Nm == 3e-4


def test_a_run_is_named_one_way() -> None:
    """``measurement.run_name`` is the one name of a run: messages, the reduce table,
    the map's account and the trace plot all read it."""
    from tribopipe.measurement import interval_label, run_name

    assert run_name("a.csv") == "a.csv"
    assert run_name("a.csv", "friction", None, 3) == "a.csv [friction / interval 3]"
    assert run_name("a.csv", "friction", "r1", 3, 2) == "a.csv [friction / r1 / interval 3 #2]"
    assert run_name("a.csv", occurrence=2) == "a.csv [#2]"
    assert interval_label(None, None, None) == ""
