"""User-facing errors are one line naming the file, the place and the expectation."""

from tribopipe.errors import MissingQuantityError, ReadError, TribopipeError


def test_error_names_file_line_column_and_hint() -> None:
    err = ReadError(
        "expected a number", path="run.csv", line=12, column="Torque", hint="pass --decimal ,"
    )
    assert str(err) == "run.csv:12: expected a number (column 'Torque'); hint: pass --decimal ,"


def test_error_is_always_one_line() -> None:
    err = TribopipeError("first\nsecond", path="a\nb.csv")
    assert "\n" not in str(err)


def test_subclasses_are_tribopipe_errors() -> None:
    assert issubclass(MissingQuantityError, ReadError)
    assert issubclass(ReadError, TribopipeError)

