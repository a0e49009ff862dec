"""Reader behaviour on written-out files: detection and forcing, aliases, plain CSV, and
every kind of bad input (each must give one clear line naming the file and the problem)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tribopipe.errors import ConfigError, ReadError
from tribopipe.measurement import ANGLE, NORMAL_FORCE, SPEED, TEMPERATURE, TIME, TORQUE
from tribopipe.readers import FORMATS, read_export, require_columns
from tribopipe.readers.aliases import builtin_aliases, load_aliases, name_key
from tribopipe.readers.textio import detect_decimal, detect_delimiter, to_numbers

REPO = Path(__file__).resolve().parents[1]


def rheocompass(
    labels: tuple[str, str, str, str, str] = (
        "Project:", "Test:", "Result:", "Interval and data points:", "Interval data:"),
    names: tuple[str, ...] = ("Point No.", "Time", "Torque", "Normal Force", "Status"),
    units: tuple[str, ...] = ("", "[s]", "[mN·m]", "[N]", ""),
    rows: tuple[tuple[str, ...], ...] = (
        ("1", "0.1", "2.5", "3.01", "Dy_auto"),
        ("2", "0.2", "2.6", "3.02", "Dy_auto"),
        ("3", "0.3", "2.7", "3.00", "Dy_auto"),
    ),
    declared: int | None = None,
    sep: str = "\t",
) -> str:
    """A RheoCompass table export as the software writes it (one test, one interval)."""
    project, test, result, points, data = labels
    n = len(rows) if declared is None else declared
    lines = [
        f"{project}{sep}Pin-on-disc", "", f"{test}{sep}Ecoflex on steel", "",
        f"{result}{sep}Friction 1", "", f"{points}{sep}1{sep}{n}",
        data + sep + sep.join(names),
        sep * len(names),
        sep + sep.join(units),
    ]
    lines += [sep + sep.join(r) for r in rows]
    return "\r\n".join(lines) + "\r\n"


def write(tmp_path: Path, name: str, text: str, encoding: str = "utf-16") -> Path:
    path = tmp_path / name
    path.write_bytes(text.encode(encoding))
    return path


# --- detection and forcing -------------------------------------------------------------


@pytest.mark.parametrize(
    ("encoding", "detected"),
    [("utf-16", "utf-16"), ("utf-8-sig", "utf-8-sig"), ("utf-8", "utf-8"),
     ("cp1252", "cp1252"), ("utf-16-le", "utf-16-le")],
)
def test_encoding_is_detected(tmp_path: Path, encoding: str, detected: str) -> None:
    m = read_export(write(tmp_path, "run.csv", rheocompass(), encoding))[0]
    assert m.meta.encoding == detected
    assert m.data[TORQUE].tolist() == pytest.approx([2.5e-3, 2.6e-3, 2.7e-3])


def test_forced_encoding_is_used_and_a_wrong_one_is_refused_with_a_hint(tmp_path: Path) -> None:
    path = write(tmp_path, "run.csv", rheocompass(), "utf-16")
    assert read_export(path, encoding="utf-16")[0].meta.encoding == "utf-16"
    with pytest.raises(ReadError) as exc:
        read_export(path, encoding="utf-8")
    message = str(exc.value)
    assert str(path) in message and "utf-8" in message and "--encoding utf-16" in message
    with pytest.raises(ReadError, match="binary garbage"):
        read_export(path, encoding="latin-1")
    with pytest.raises(ReadError, match="unknown encoding"):
        read_export(path, encoding="klingon")


def test_french_decimal_comma_and_labels(tmp_path: Path) -> None:
    text = rheocompass(
        labels=("Projet:", "Test:", "Résultat:", "Intervalle et points de données:",
                "Interval données:"),
        names=("Point No.", "Temps", "Intervalle Temps", "Couple", "Force Normale",
               "Température", "Angle de déflexion", "Vitesse de rotation"),
        units=("", "[s]", "[s]", "[mN·m]", "[N]", "[°C]", "[°]", "[1/min]"),
        rows=(("1", "10", "1", "2,3981", "3,05", "21,00", "90", "0,005"),
              ("2", "20", "2", "2,4", "3,10", "21,50", "180", "0,005")),
    )
    m = read_export(write(tmp_path, "fr.csv", text))[0]
    assert m.meta.decimal == ","
    assert m.data[TIME].tolist() == [10.0, 20.0]  # Temps, not Intervalle Temps
    assert m.data["interval_time_s"].tolist() == [1.0, 2.0]
    assert m.data[TORQUE].iloc[0] == pytest.approx(2.3981e-3)
    assert m.data[NORMAL_FORCE].tolist() == pytest.approx([3.05, 3.10])
    assert m.data[TEMPERATURE].tolist() == pytest.approx([21.0, 21.5])
    assert m.data[ANGLE].tolist() == pytest.approx([math.pi / 2, math.pi])
    assert m.data[SPEED].iloc[0] == pytest.approx(0.005 * 2 * math.pi / 60)


def test_german_labels_and_column_names(tmp_path: Path) -> None:
    text = rheocompass(
        labels=("Projekt:", "Test:", "Ergebnis:", "Intervall und Datenpunkte:",
                "Intervalldaten:"),
        names=("Messpunkt", "Zeit", "Drehmoment", "Normalkraft", "Auslenkwinkel",
               "Drehzahl", "Temperatur"),
        units=("", "[s]", "[µN·m]", "[N]", "[mrad]", "[1/min]", "[°C]"),
        rows=(("1", "0,1", "2398,1", "3,0", "1,5", "0,005", "20,0"),),
    )
    m = read_export(write(tmp_path, "de.csv", text))[0]
    assert m.meta.project == "Pin-on-disc" and m.meta.result == "Friction 1"
    assert m.data[TORQUE].iloc[0] == pytest.approx(2.3981e-3)
    assert m.data[ANGLE].iloc[0] == pytest.approx(1.5e-3)
    assert set(m.data.columns) >= {TIME, TORQUE, NORMAL_FORCE, ANGLE, SPEED, TEMPERATURE}


def test_forced_decimal_and_delimiter(tmp_path: Path) -> None:
    text = "Time [s];Torque [mN·m];Normal Force [N]\n0,5;1,25;3\n1,0;1,5;3\n"
    path = write(tmp_path, "plain.csv", text, "utf-8")
    m = read_export(path)[0]
    assert (m.meta.delimiter, m.meta.decimal) == (";", ",")
    assert m.data[TORQUE].tolist() == pytest.approx([1.25e-3, 1.5e-3])
    forced = read_export(path, delimiter=";", decimal=",")[0]
    assert forced.data[TIME].tolist() == [0.5, 1.0]
    with pytest.raises(ReadError, match="expected a number"):
        read_export(path, decimal=".")
    with pytest.raises(ReadError, match="decimal mark"):
        read_export(path, decimal=";")


def test_tab_delimiter_can_be_named(tmp_path: Path) -> None:
    path = write(tmp_path, "run.csv", rheocompass(), "utf-16")
    assert read_export(path, delimiter="tab")[0].meta.delimiter == "\t"
    with pytest.raises(ReadError):
        read_export(path, delimiter=",")


def test_english_thousands_separators_are_not_decimal_commas(tmp_path: Path) -> None:
    text = (
        "Data Series Information\nName:\t\t\ts1\nInterval:\t\t\t1\n"
        "Number of Data Points:\t\t\t2\n\n"
        "Meas. Pts.\tTime\tTorque\tDeflection Angle\tStatus\n"
        "\t[s]\t[µNm]\t[mrad]\t[]\n"
        "1\t0.5\t1,460\t9,945.692\tDy_auto\n"
        "2\t1.0\t1,470.5\t******\tDy_auto\n"
    )
    m = read_export(write(tmp_path, "rp.txt", text, "utf-8"))[0]
    assert m.meta.file_format == "rheoplus" and m.meta.decimal == "."
    assert m.data[TORQUE].tolist() == pytest.approx([1460e-6, 1470.5e-6])
    assert m.data[ANGLE].iloc[0] == pytest.approx(9.945692)
    assert np.isnan(m.data[ANGLE].iloc[1])


@pytest.mark.parametrize(
    ("cells", "decimal"),
    [(["2,3981", "0,05"], ","), (["1,460", "0.5"], "."), (["9,945.692"], "."),
     (["1.234,5"], ","), (["2,21E+04"], ","), (["0.100", "3"], ".")],
)
def test_decimal_mark_detection(cells: list[str], decimal: str) -> None:
    assert detect_decimal(cells) == decimal


def test_ambiguous_thousands_keep_the_default() -> None:
    assert detect_decimal(["1,460"], default=".") == "."
    assert detect_decimal(["1,460"], default=",") == ","


def test_bulk_number_conversion_reports_the_bad_cell() -> None:
    values, bad = to_numbers(["1.5", "", "******", "2"], ".")
    assert bad is None and values[0] == 1.5 and np.isnan(values[1:3]).all()
    _, bad = to_numbers(["1.5", "x", "2"], ".")
    assert bad == 1


def test_delimiter_detection_prefers_tab() -> None:
    assert detect_delimiter(["a\tb,c", "1,5\t2,5"]) == "\t"
    assert detect_delimiter(["a;b", "1,5;2"]) == ";"
    assert detect_delimiter(["a,b", "1,2"]) == ","
    assert detect_delimiter(["just words", "more words"]) is None


def test_unknown_format_name_is_refused(tmp_path: Path) -> None:
    path = write(tmp_path, "run.csv", rheocompass())
    with pytest.raises(ReadError, match="unknown format"):
        read_export(path, fmt="tribo-x")
    assert read_export(path, fmt="rheocompass")[0].meta.file_format == "rheocompass"
    assert set(FORMATS) == {"rheocompass", "rheocompass-xlsx", "rheoplus", "csv"}


# --- plain CSV and aliases -------------------------------------------------------------


@pytest.mark.parametrize(
    "header",
    ["Time [s],Torque [mN·m],Normal Force [N],Angle [°]",
     "time (s),torque (mNm),normal force (N),deflection angle (deg)",
     "time_s,torque_mNm,normal_force_N,angle_deg"],
)
def test_plain_csv_with_units_in_the_header(tmp_path: Path, header: str) -> None:
    text = header + "\n0.0,1.5,3.0,0\n0.1,1.6,3.1,90\n"
    m = read_export(write(tmp_path, "plain.csv", text, "utf-8"))[0]
    assert m.meta.file_format == "csv" and m.meta.interval == 1
    assert m.data[TORQUE].tolist() == pytest.approx([1.5e-3, 1.6e-3])
    assert m.data[NORMAL_FORCE].tolist() == [3.0, 3.1]
    assert m.data[ANGLE].iloc[1] == pytest.approx(math.pi / 2)
    require_columns(m, TORQUE, NORMAL_FORCE)


def test_plain_csv_with_a_unit_row(tmp_path: Path) -> None:
    text = "Time,Speed,Torque,Normal Force\n[s],[rpm],[µN·m],[mN]\n0,0.005,2000,3000\n"
    m = read_export(write(tmp_path, "plain.csv", text, "utf-8"))[0]
    assert m.data[SPEED].iloc[0] == pytest.approx(0.005 * 2 * math.pi / 60)
    assert m.data[TORQUE].iloc[0] == pytest.approx(2e-3)
    assert m.data[NORMAL_FORCE].iloc[0] == pytest.approx(3.0)


def test_names_match_ignoring_case_accents_spaces() -> None:
    table = builtin_aliases()
    for name in ("TEMPERATURE", "Temperature", "température", " Temp érature "):
        assert table.quantity(name) == "temperature", name
    assert table.quantity("Intervalle Temps") is None
    assert table.quantity("Temps") == "time"
    assert name_key("Force  Normale") == name_key("force normale") == "forcenormale"


def test_builtin_aliases_cover_english_french_german() -> None:
    table = builtin_aliases()
    expected = {
        "torque": ["Torque", "Couple", "Drehmoment"],
        "normal_force": ["Normal Force", "Force Normale", "Normalkraft"],
        "angle": ["Deflection Angle", "Angle de déflexion", "Auslenkwinkel"],
        "speed": ["Rotational Speed", "Speed", "Vitesse de rotation", "Drehzahl"],
        "temperature": ["Temperature", "Température", "Temperatur"],
        "time": ["Time", "Temps", "Zeit"],
    }
    for quantity, names in expected.items():
        for name in names:
            assert table.quantity(name) == quantity, name


def test_user_alias_file_extends_the_builtin_table(tmp_path: Path) -> None:
    user = tmp_path / "aliases.toml"
    user.write_text('[canonical.torque]\nnames = ["Par"]\n'
                    '[canonical.normal_force]\nnames = ["Fuerza Normal"]\n', encoding="utf-8")
    text = "Tiempo [s];Par [mN·m];Fuerza Normal [N]\n0,5;1,25;3\n"
    path = write(tmp_path, "es.csv", text, "utf-8")
    m = read_export(path, aliases=user)[0]
    assert m.data[TORQUE].iloc[0] == pytest.approx(1.25e-3)
    assert m.data[NORMAL_FORCE].iloc[0] == 3.0
    assert "tiempo_s" in m.data.columns  # not in this user file: kept by its own name
    assert load_aliases(user).quantity("Couple") == "torque"  # built-ins still there


def test_an_edited_alias_file_is_read_again(tmp_path: Path) -> None:
    user = tmp_path / "aliases.toml"
    user.write_text('[canonical.torque]\nnames = ["Par"]\n', encoding="utf-8")
    assert load_aliases(user) is load_aliases(user)  # one parse for a batch of files
    user.write_text('[canonical.torque]\nnames = ["Drehmo"]\n', encoding="utf-8")
    assert load_aliases(user).quantity("Drehmo") == "torque"
    assert load_aliases(user).quantity("Par") is None


def test_project_example_alias_file_is_valid() -> None:
    table = load_aliases(REPO / "configs" / "aliases.toml")
    assert table.quantity("Par") == "torque"
    assert table.quantity("Fuerza normal") == "normal_force"


@pytest.mark.parametrize(
    ("content", "problem"),
    [('[canonical.torq]\nnames = ["x"]\n', "unknown canonical quantity"),
     ("[canonical.torque]\nnames = 3\n", "needs names"),
     ("[other]\n", "unknown table"),
     ("not toml = = \n", "cannot read alias file")],
)
def test_a_bad_alias_file_is_a_config_error(tmp_path: Path, content: str, problem: str) -> None:
    user = tmp_path / "aliases.toml"
    user.write_text(content, encoding="utf-8")
    with pytest.raises(ConfigError, match=problem):
        load_aliases(user)


# --- bad input: one clear line naming the file ---------------------------------------


def assert_one_line_error(path: Path, pattern: str, **kwargs: object) -> str:
    with pytest.raises(ReadError) as exc:
        read_export(path, **kwargs)
    message = str(exc.value)
    assert "\n" not in message and str(path) in message, message
    assert pattern in message, message
    return message


def test_missing_file(tmp_path: Path) -> None:
    assert_one_line_error(tmp_path / "nope.csv", "file not found")


@pytest.mark.parametrize("content", [b"", b"   \r\n\r\n", "\ufeff".encode("utf-8")])
def test_empty_file(tmp_path: Path, content: bytes) -> None:
    path = tmp_path / "empty.csv"
    path.write_bytes(content)
    with pytest.raises(ReadError, match="empty file"):
        read_export(path)


def test_binary_file(tmp_path: Path) -> None:
    path = tmp_path / "image.csv"
    path.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + bytes(range(256)) * 4)
    assert_one_line_error(path, "is a PNG image")


def test_truncated_file_names_the_interval(tmp_path: Path) -> None:
    text = rheocompass(declared=10)  # the file stops after 3 of 10 declared points
    message = assert_one_line_error(write(tmp_path, "cut.csv", text), "truncated")
    assert "interval 1 declares 10 points but holds 3" in message


def test_utf16_file_cut_in_the_middle_of_a_character(tmp_path: Path) -> None:
    raw = rheocompass(declared=3).encode("utf-16")
    path = tmp_path / "cut.csv"
    path.write_bytes(raw[: len(raw) - 31])  # odd length: half a UTF-16 code unit
    assert_one_line_error(path, "truncated")


def test_header_without_data(tmp_path: Path) -> None:
    text = rheocompass(rows=(), declared=0)
    assert_one_line_error(write(tmp_path, "hdr.csv", text), "header without data")
    only_header = "Project:\tX\r\n\r\nTest:\tY\r\n"
    assert_one_line_error(write(tmp_path, "hdr2.csv", only_header), "no 'Interval data:'")


def test_header_without_unit_row(tmp_path: Path) -> None:
    text = "Project:\tX\r\nInterval and data points:\t1\t1\r\nInterval data:\tPoint No.\tTime\r\n"
    assert_one_line_error(write(tmp_path, "u.csv", text), "unit row")


def test_missing_torque_column_is_reported_by_require_columns(tmp_path: Path) -> None:
    text = rheocompass(names=("Point No.", "Time", "Normal Force", "Status"),
                       units=("", "[s]", "[N]", ""),
                       rows=(("1", "0.1", "3.0", ""),))
    m = read_export(write(tmp_path, "noM.csv", text))[0]
    with pytest.raises(ReadError) as exc:
        require_columns(m, TORQUE, NORMAL_FORCE)
    message = str(exc.value)
    assert "noM.csv" in message and "interval 1" in message and "torque_Nm" in message
    assert "Normal Force → normal_force_N" in message


def test_torque_in_an_unknown_unit_is_refused(tmp_path: Path) -> None:
    text = rheocompass(units=("", "[s]", "[ozf·in]", "[N]", ""))
    message = assert_one_line_error(write(tmp_path, "u.csv", text), "unknown unit")
    assert "'Torque'" in message and "ozf·in" in message


def test_a_word_in_a_number_column_names_line_and_column(tmp_path: Path) -> None:
    rows = (("1", "0.1", "2.5", "3.0", ""), ("2", "0.2", "oops", "3.0", ""))
    message = assert_one_line_error(write(tmp_path, "w.csv", rheocompass(rows=rows)),
                                    "expected a number")
    assert "w.csv:12" in message and "'Torque'" in message and "oops" in message


def test_a_csv_that_is_not_an_export(tmp_path: Path) -> None:
    path = write(tmp_path, "prices.csv", "item,price\napple,1.20\npear,0.90\n", "utf-8")
    assert_one_line_error(path, "not a recognised export")


def test_a_csv_with_no_known_quantity_when_forced(tmp_path: Path) -> None:
    path = write(tmp_path, "prices.csv", "item,price\napple,1.20\n", "utf-8")
    message = assert_one_line_error(path, "not an export", fmt="csv")
    assert "item, price" in message


def test_a_legacy_xls_workbook(tmp_path: Path) -> None:
    path = tmp_path / "old.xls"
    path.write_bytes(b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1" + b"\x00" * 600)
    assert_one_line_error(path, "legacy Excel")


def test_a_broken_xlsx(tmp_path: Path) -> None:
    path = tmp_path / "broken.xlsx"
    path.write_bytes(b"PK\x03\x04" + b"garbage" * 50)
    assert_one_line_error(path, "not a readable Excel workbook")


def test_reading_does_not_depend_on_row_content_order_of_columns(tmp_path: Path) -> None:
    """Columns are matched by name, not position: swapping two columns changes nothing."""
    a = rheocompass()
    b = rheocompass(names=("Point No.", "Normal Force", "Time", "Torque", "Status"),
                    units=("", "[N]", "[s]", "[mN·m]", ""),
                    rows=(("1", "3.01", "0.1", "2.5", "Dy_auto"),
                          ("2", "3.02", "0.2", "2.6", "Dy_auto"),
                          ("3", "3.00", "0.3", "2.7", "Dy_auto")))
    ma = read_export(write(tmp_path, "a.csv", a))[0].data
    mb = read_export(write(tmp_path, "b.csv", b))[0].data
    for col in (TIME, TORQUE, NORMAL_FORCE):
        assert ma[col].tolist() == mb[col].tolist()


# --- properties ------------------------------------------------------------------------

_VALUES = st.lists(
    st.floats(min_value=-1e4, max_value=1e4, allow_nan=False).map(lambda v: round(v, 6)),
    min_size=1,
    max_size=30,
)


@settings(max_examples=40, deadline=None)
@given(
    torque_mNm=_VALUES,
    decimal=st.sampled_from([".", ","]),
    encoding=st.sampled_from(["utf-16", "utf-8-sig", "cp1252"]),
)
def test_written_values_read_back_in_si(
    torque_mNm: list[float], decimal: str, encoding: str
) -> None:
    """Whatever the values, decimal mark and encoding: torque in mN·m reads back ×1e-3,
    in file order, with one row per point."""
    import tempfile

    def fmt(v: float) -> str:
        return repr(v).replace(".", decimal)

    rows = tuple(
        (str(k + 1), fmt(0.1 * k), fmt(v), fmt(3.0), "Dy_auto")
        for k, v in enumerate(torque_mNm)
    )
    text = rheocompass(rows=rows)
    with tempfile.TemporaryDirectory() as tmp:
        m = read_export(
            write(Path(tmp), "p.csv", text, encoding), decimal=None if len(rows) > 3 else decimal
        )[0]
    assert m.data["point_no"].tolist() == list(range(1, len(rows) + 1))
    assert m.data[TORQUE].to_numpy() == pytest.approx(np.array(torque_mNm) * 1e-3, rel=1e-12)


def test_three_decimals_after_a_point_are_not_thousands() -> None:
    assert detect_decimal(["2.398", "12"], default=",") == "."
    assert detect_decimal(["0,005"], default=".") == ","  # a leading zero never groups


def test_an_absurd_point_number_is_refused_not_overflowed(tmp_path: Path) -> None:
    text = "Time [s],Torque [mNm],Point No.\n1,2,99999999999999999999999\n"
    message = assert_one_line_error(write(tmp_path, "big.csv", text, "utf-8"),
                                    "expected a point number")
    assert "big.csv:2" in message


def test_a_new_format_is_one_reader_entry(tmp_path, monkeypatch):
    """Detection, ``fmt=`` and the refusal hint read :data:`readers.READERS` only: a toy
    text format registered there is detected and read, and named where nothing matches."""
    from tribopipe import readers
    from tribopipe.readers import plaincsv
    from tribopipe.readers.spec import Reader

    toy = Reader(
        name="toy",
        suffixes=(".toy",),
        expects="a toy export ('TOY')",
        parse=lambda rows, path, aliases: plaincsv.parse_intervals(rows[1:], path, aliases),
        looks_like=lambda rows, aliases: bool(rows) and rows[0][1][:1] == ["TOY"],
        data_line=plaincsv.data_line,
    )
    monkeypatch.setattr(readers, "READERS", (toy, *readers.READERS))
    path = tmp_path / "run.toy"
    path.write_text("TOY;\ntime [s];torque [mNm];normal force [N]\n0;1,5;2\n1;1,6;2\n",
                    encoding="utf-8")
    (m,) = readers.read_export(path)
    assert m.meta.file_format == "toy"
    assert m.data["torque_Nm"].tolist() == pytest.approx([1.5e-3, 1.6e-3])
    bad = tmp_path / "bad.txt"
    bad.write_text("item;price\napple;1\n", encoding="utf-8")
    with pytest.raises(ReadError, match="not a recognised export") as err:
        readers.read_export(bad)
    assert "a toy export ('TOY')" in str(err.value)
