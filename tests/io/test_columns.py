"""Column maps: an instrument's table export read as a Waveform, every bad map or file one
message naming the item, column or line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from msens.cli import main
from msens.errors import InputError
from msens.io.columns import ColumnMap, ColumnSource, column_map, load_column_map, parse_column_map
from msens.io.mapped import MappedFile, apply_column_map, mapped, read_mapped
from msens.io.read import read_waveform
from msens.io.text_table import parse_table
from msens.io.waveform import Channel

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "data"
SCOPE = EXAMPLES / "scope-mss.csv"
MAP = "time=Time:ms,mss@13=CH1:mV,mss@18=CH2:mV"

EXPORT = """Model,DSO-X 2CH
Record Length,4

Time,CH1,CH2,Extra
s,V,V,
-1.000000e-06,1.5,-2.0,x
0.000000e+00,2.5,-3.0,y
1.000000e-06,3.5,-4.0,z
2.000000e-06,4.5,-5.0,
"""


def test_parse_inline_map_units_and_numbers():
    m = parse_column_map("time=Time:us, bead@13=CH1:0.5,rod@18#2=CH2:mV ,mss@13=CH3")
    assert m.time == ColumnSource("Time", 1e-6)
    assert m.channels == (
        (Channel("bead", 13), ColumnSource("CH1", 0.5)),
        (Channel("rod", 18, 2), ColumnSource("CH2", 1e-3)),
        (Channel("mss", 13), ColumnSource("CH3", 1.0)),
    )
    assert m.columns == {"Time": "time", "CH1": "bead@13", "CH2": "rod@18#2", "CH3": "mss@13"}
    assert parse_column_map(m.text()) == m  # the canonical text reads back


def test_toml_map_equals_inline_map():
    m = load_column_map(EXAMPLES / "scope-columns.toml")
    assert m == parse_column_map(MAP, source=m.source)
    assert column_map(str(EXAMPLES / "scope-columns.toml")) == m  # a .toml string is a file
    assert column_map(MAP) == parse_column_map(MAP)


def test_toml_table_form(tmp_path):
    p = tmp_path / "m.toml"
    p.write_text('schema = "msens.columns/1"\n[columns]\ntime = { column = "T:x", scale = "ms" }'
                 '\n"bead@13" = { column = "a=b", scale = -2.0 }\n')
    m = load_column_map(p)
    assert m.time == ColumnSource("T:x", 1e-3)
    assert m.channels == ((Channel("bead", 13), ColumnSource("a=b", -2.0)),)


def test_read_export_skips_settings_and_units_rows(tmp_path):
    p = tmp_path / "scope.csv"
    p.write_bytes(EXPORT.replace("\n", "\r\n").encode())
    w = read_mapped(p, "time=Time:s,bead@13=CH1:mV,bead@18=CH2")
    np.testing.assert_allclose(w.time, [-1e-6, 0.0, 1e-6, 2e-6])
    np.testing.assert_allclose(w.channel("bead@13"), [1.5e-3, 2.5e-3, 3.5e-3, 4.5e-3],
                               rtol=1e-15)
    np.testing.assert_array_equal(w.channel("bead@18"), [-2.0, -3.0, -4.0, -5.0])
    assert dict(w.metadata) == {"source_file": "scope.csv", "units": "V",
                                "columns": "time=Time,bead@13=CH1:0.001,bead@18=CH2"}
    # the same through read_waveform: a keyword, or a MappedFile that passes as a path
    assert read_waveform(p, columns="time=Time:s,bead@13=CH1:mV,bead@18=CH2") == w
    assert read_waveform(mapped(p, "time=Time:s,bead@13=CH1:mV,bead@18=CH2")) == w


@pytest.mark.parametrize("delimiter", [";", "\t"])
def test_semicolon_and_tab_exports_with_quoted_names(delimiter):
    text = delimiter.join(['"Time"', '"CH1"']) + "\n" + "\n".join(
        delimiter.join([f"{k * 1e-6!r}", f"{k}.0"]) for k in range(5))
    table = parse_table(text, {"Time": "time", "CH1": "bead@13"}, "t.txt")
    np.testing.assert_array_equal(table.columns["CH1"], [0.0, 1.0, 2.0, 3.0, 4.0])
    assert table.lines == (2, 3, 4, 5, 6)


def test_example_scope_export_matches_its_source_rounding():
    w = read_waveform(SCOPE, columns=MAP)
    assert w.names == ("mss@13", "mss@18")
    assert w.time.size == 2435
    assert w.dt == pytest.approx(4e-7, rel=1e-12)
    assert w.time[0] == pytest.approx(-2e-5, abs=1e-15)
    assert np.abs(w.data).max() < 1.0  # volts, not millivolts


def test_fixed_format_times_get_their_rounding_undone():
    # 10 MHz printed in ms with 6 significant digits: a deviation of up to 0.05 dt
    rows = "\n".join(f"{t * 1e3:.5e},1.0" for t in 1.23456789e-3 + 1e-7 * np.arange(50))
    table = parse_table("Time,CH1\n" + rows, {"Time": "time", "CH1": "bead@2"}, "x")
    assert table.resolution["Time"] == pytest.approx(5e-6)  # ms, as printed
    w = apply_column_map(table.columns, parse_column_map("time=Time:ms,bead@2=CH1"), "x",
                         resolution=table.resolution)
    np.testing.assert_allclose(np.diff(w.time), 1e-7, rtol=1e-9)


def test_apply_column_map_to_a_dict_of_columns():
    m = parse_column_map("time=t:ms,bead@5=v")
    w = apply_column_map({"t": [0, 1, 2], "v": [1, 2, 3], "other": "ignored"}, m, "mem")
    np.testing.assert_array_equal(w.time, [0.0, 1e-3, 2e-3])
    with pytest.raises(InputError, match=r"mem: column 'v' \(for bead@5\) not found; "
                                         r"columns present: 't'"):
        apply_column_map({"t": [0, 1, 2]}, m, "mem")
    with pytest.raises(InputError, match=r"mem: column 'v' has 2 values but the time column "
                                         r"'t' has 3"):
        apply_column_map({"t": [0, 1, 2], "v": [1, 2]}, m, "mem")
    with pytest.raises(InputError, match=r"mem: sample 2: channel bead@5 \(column 'v'\) value "
                                         r"nan is not finite"):
        apply_column_map({"t": [0, 1, 2], "v": [1, 2, np.nan]}, m, "mem")


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("time=Time,bead@13=CH1,bead@13=CH2", r"--columns: target bead@13 given twice"),
        ("time=Time,bead@13=CH1,bead@13#1=CH2", r"target bead@13 given twice"),
        ("time=T,time=U,bead@13=CH1", r"target 'time' given twice"),
        ("time=Time,bead@13=CH1,bead@18=CH1", r"column 'CH1' is mapped twice \(bead@13 and "
                                              r"bead@18\)"),
        ("time=Time,bead@13=Time", r"column 'Time' is mapped twice \(time and bead@13\)"),
        ("time=Time,bead@13=CH1:abc", r"'bead@13=CH1:abc': scale 'abc' is not a number or a "
                                      r"unit \(V, mV"),
        ("time=Time:mV,bead@13=CH1", r"scale 'mV' is not a number or a unit \(s, ms"),
        ("time=Time,bead@13=CH1:0", r"scale of bead@13 must be a finite nonzero number, got 0"),
        ("time=Time,bead@13=CH1:nan", r"scale of bead@13 must be a finite nonzero number"),
        ("time=Time:-1e-3,bead@13=CH1", r"scale of time must be a finite number > 0"),
        ("bead@13=CH1", r"no 'time=COLUMN' item"),
        ("time=Time", r"names no channel"),
        ("time=Time,coil@13=CH1", r"target 'coil@13': unknown channel name"),
        ("time=Time,bead@13", r"item 'bead@13' has no '='"),
        ("time=Time,,bead@13=CH1", r"empty item"),
        ("time=Time,bead@13=", r"target 'bead@13' has an empty column name"),
    ],
)
def test_bad_inline_maps(text, message):
    with pytest.raises(InputError, match=message):
        parse_column_map(text)


@pytest.mark.parametrize(
    ("body", "message"),
    [
        ('[columns]\ntime = "T"\n"bead@3" = 5\n', r"'columns.bead@3' must be \"COLUMN"),
        ('[columns]\ntime = "T"\n"bead@3" = { column = "A", scale = 0 }\n',
         r"'columns.bead@3': scale of bead@3 must be a finite nonzero"),
        ('[columns]\ntime = "T"\n"bead@3" = { column = "A", gain = 2 }\n',
         r"unknown key 'columns.bead@3.gain'"),
        ('[columns]\ntime = "T"\n"bead@3" = "A:volts"\n', r"scale 'volts' is not a number"),
        ('time = "T"\n', r"'columns' is missing"),
        ('[columns]\ntime = "T"\n"bead@3" = "A"\n[extra]\n', r"unknown key 'extra'"),
    ],
)
def test_bad_toml_maps(tmp_path, body, message):
    p = tmp_path / "m.toml"
    p.write_text('schema = "msens.columns/1"\n' + body)
    with pytest.raises(InputError, match=message):
        load_column_map(p)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("Time,CH1\n0,1\n1,2\n", r"f\.csv:1: column 'CH2' \(for bead@18\) not in the header; "
                                 r"columns present: 'Time', 'CH1'"),
        ("a,b\n0,1\n", r"f\.csv: no header line names the time column 'Time'; the first line "
                       r"is 'a,b'"),
        ("Time,CH1,CH2,CH1\n0,1,2,3\n", r"f\.csv:1: column 'CH1' appears twice in the header"),
        ("Time,CH1,CH2\n", r"f\.csv: no data rows after the header \(line 1\)"),
        ("Time,CH1,CH2\n0,1,2\n1,x,2\n", r"f\.csv:3: column 'CH1' \(for bead@13\): "
                                         r"non-numeric cell 'x'"),
        ("Time,CH1,CH2\n0,1,2\n1,2\n", r"f\.csv:3: 2 cells, but column 'CH2' is column 3"),
        ("Time;CH1;CH2\n0;1,5;2\n1;2,5;3\n" + "2;3,5;4\n" * 5,
         r"f\.csv:2: column 'CH1' \(for bead@13\): non-numeric cell '1,5' \(decimal commas "
         r"are not read"),
        ("Time,CH1,CH2\ns,V,\n0,1,\n1,2,3\n", r"f\.csv:3: column 'CH2' \(for bead@18\): "
                                              r"non-numeric cell ''"),
        ("Time,CH1,CH2\n0,1,2\n1,2,3\n3,3,4\n", r"f\.csv:3: time_s is not uniformly sampled"),
        ("Time,CH1,CH2\n0,1,2\n1,inf,3\n", r"f\.csv:3: channel bead@13 \(column 'CH1'\) value "
                                           r"inf is not finite"),
    ],
)
def test_bad_exports_name_line_and_column(tmp_path, text, message):
    p = tmp_path / "f.csv"
    p.write_text(text)
    with pytest.raises(InputError, match=message):
        read_mapped(p, "time=Time,bead@13=CH1,bead@18=CH2")


def test_only_text_exports_take_a_map(tmp_path):
    with pytest.raises(InputError, match=r"column maps read text exports"):
        read_mapped(tmp_path / "x.npz", MAP)


def test_map_objects_are_checked_when_built():
    with pytest.raises(InputError, match=r"no channel"):
        ColumnMap(time=ColumnSource("T"), channels=())
    assert str(MappedFile(SCOPE, parse_column_map(MAP))) == str(SCOPE)


# --------------------------------------------------------------------------- command line


def test_cli_check_waveform_and_convert_with_a_map(tmp_path, capsys):
    assert main(["check-waveform", str(SCOPE), "--columns", MAP]) == 0
    assert "ok, 2435 samples, dt = 4e-07 s" in capsys.readouterr().out
    assert main(["check-waveform", str(SCOPE)]) == 2  # unmapped: a pointer to --columns
    assert "--columns" in capsys.readouterr().err
    target = tmp_path / "scope.npz"
    toml = str(EXAMPLES / "scope-columns.toml")
    assert main(["convert", str(SCOPE), str(target), "--columns", toml]) == 0
    assert read_waveform(target) == read_waveform(SCOPE, columns=MAP)


BAD_MAPS = [
    ("time=Time:ms,mss@13=CH1:mV,mss@18=CH3", "column 'CH3' (for mss@18) not in the header"),
    ("time=Time:ms,mss@13=CH1,mss@13=CH2", "target mss@13 given twice"),
    ("time=Time:ms,mss@13=CH1:x1e-3,mss@18=CH2", "scale 'x1e-3' is not a number or a unit"),
]


@pytest.mark.parametrize(("columns", "fragment"), BAD_MAPS)
@pytest.mark.parametrize("command", ["check-waveform", "convert", "compare", "diagnose"])
def test_cli_bad_maps_exit_2_with_one_message(tmp_path, capsys, monkeypatch, command,
                                              columns, fragment):
    import msens.pipeline

    def no_run(*args, **kwargs):  # a bad map must fail before anything is simulated
        raise AssertionError("ran the study")

    monkeypatch.setattr(msens.pipeline, "run_study", no_run)
    monkeypatch.setattr("msens.workflows.compare.run_study", no_run)
    argv = {
        "check-waveform": ["check-waveform", str(SCOPE)],
        "convert": ["convert", str(SCOPE), str(tmp_path / "x.npz")],
        "compare": ["compare", "studies/paper-mss.toml", str(SCOPE), "--out",
                    str(tmp_path / "o")],
        "diagnose": ["diagnose", str(SCOPE), "--study", "studies/paper-mss.toml", "--out",
                     str(tmp_path / "o")],
    }[command]
    monkeypatch.chdir(Path(__file__).resolve().parents[2])
    assert main([*argv, "--columns", columns]) == 2
    err = capsys.readouterr().err
    assert err.splitlines()[-1].startswith("msens: error: ") and fragment in err
    assert err.count("msens: error") == 1 and "Traceback" not in err
    assert not (tmp_path / "x.npz").exists()


def test_cli_diagnose_columns_need_data(tmp_path, capsys):
    assert main(["diagnose", "--reference", "bead", "--out", str(tmp_path / "o"),
                 "--columns", MAP]) == 2
    assert "--columns maps the columns of DATA" in capsys.readouterr().err
