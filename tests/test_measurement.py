"""The measurement's metadata labels say where a number came from."""


def test_interval_label_leaves_out_what_is_unknown() -> None:
    from tribopipe.measurement import MeasurementMeta, interval_label

    assert interval_label("T", "R", 2) == "T / R / interval 2"
    assert interval_label(None, None, 1) == "interval 1"
    assert interval_label(None, None, None) == ""
    assert MeasurementMeta("a.csv", "csv").label == "a.csv"
    assert MeasurementMeta("a.csv", "csv", test="T", interval=3).label == "a.csv [T / interval 3]"
