"""`fsi-lab import`: CSV files recorded elsewhere become run files."""

import json
import re

import h5py
import numpy as np
import pytest
from support import cli_here, cli_json_here, run_main

from fsi_lab.runfile import read_run
from fsi_lab.units import STANDARD_GRAVITY


def _write(path, header, rows):
    path.write_text(",".join(header) + "\n" + "\n".join(",".join(map(str, r)) for r in rows) + "\n")
    return path


def test_import_with_rate(tmp_path):
    t = np.arange(500) / 1000.0
    v = 0.01 * np.sin(2 * np.pi * 17 * t)
    a = 0.5 * np.cos(2 * np.pi * 17 * t)
    csv_path = _write(tmp_path / "rec.csv", ["tip [m/s]", "base [g]", "drive [V]"],
                      zip(v, a, np.ones_like(t)))
    out = tmp_path / "rec.h5"
    data, proc = cli_json_here("import", str(csv_path), "--rate", "1000", "-o", str(out))
    assert proc.returncode == 0, proc.stderr
    # (the column in volts without a sensitivity is said to stay so)
    assert data == {"run": str(out), "notes": [
        f"{csv_path}: drive is in volts without --sensitivity: kept in volts (a drive signal "
        "stays so; a sensor's gives frequencies, but not the motion it measures: C_i, C_f, "
        "backbones); a column imported in volts becomes the motion it measures with its "
        "sensor's sensitivity: fsi-lab import ... --sensitivity NAME=200mV/(mm/s)"]}
    run = read_run(out)
    assert run.attrs["kind"] == "imported" and run.attrs["exit_status"] == "completed"
    tip = run.channels["tip"]
    assert (tip.quantity, tip.unit, tip.sample_rate) == ("velocity", "m/s", 1000.0)
    np.testing.assert_allclose(tip.data, v, rtol=1e-12)
    base = run.channels["base"]
    assert (base.quantity, base.unit) == ("acceleration", "m/s^2")
    np.testing.assert_allclose(base.data, a * STANDARD_GRAVITY, rtol=1e-12)
    assert run.channel_attrs["base"]["original_units"] == "g"
    assert run.channels["drive"].quantity == "voltage"


def test_time_column_replaces_rate(tmp_path):
    t = 2.0 + np.arange(100) / 250.0
    csv_path = _write(tmp_path / "t.csv", ["time [s]", "x [m]"], zip(t, np.sin(t)))
    out = tmp_path / "t.h5"
    assert cli_here("import", str(csv_path), "-o", str(out)).returncode == 0
    run = read_run(out)
    assert run.channels["x"].sample_rate == pytest.approx(250.0)
    assert run.channels["x"].t0 == pytest.approx(2.0)
    assert run.channels["x"].quantity == "displacement"
    assert "time" not in run.channels


@pytest.mark.parametrize("header, rows, args, fragment", [
    (["tip [in/s]"], [[1], [2]], ["--rate", "10"],
     "header column 1 (tip): unit 'in/s' is not accepted; expected m, m/s, m/s^2, g or V, "
     "with a prefix m, u (µ) or n"),
    (["time [min]", "tip [m/s]"], [[0, 1], [1, 2]], [],
     "header column 1 (time): unit 'min' is not accepted; expected m, m/s"),
    (["tip"], [[1], [2]], ["--rate", "10"], "header column 1 is 'tip'; expected 'name [unit]'"),
    (["tip [m/s]", "tip [m]"], [[1, 2], [2, 3]], ["--rate", "10"],
     "column name 'tip' appears twice"),
    (["tip [m/s]"], [[1], ["x"]], ["--rate", "10"], "line 3, column 1 (tip): 'x' is not a number"),
    (["tip [m/s]", "b [V]"], [[1, 2], [2]], ["--rate", "10"],
     "line 3 has 1 value; the header has 2 columns"),
    (["tip [m/s]"], [[1], [2]], [], "no 'time [s]' column; give the sample rate with --rate HZ"),
    (["tip [m/s]"], [[1], [2]], ["--rate", "-5"],
     "--rate -5: a sample rate of -5 Hz; expected 0.001 to 1e+09 Hz"),
    (["time [s]", "tip [m/s]"], [[0, 1], [0.1, 2], [0.25, 3]], [],
     "the time column is not uniformly sampled"),
    (["tip [m/s]"], [[1], ["nan"]], ["--rate", "10"], "line 3, column 1 (tip) holds 'nan': a "
     "missing sample (the recorder lost it, or the export left it out); expected a finite "
     "number in every cell"),
    (["tip [m/s]", "base [m/s^2]"], [[1, 2], [3, "#NV"], [2, 2]], ["--rate", "10"],
     "line 3, column 2 (base) holds '#NV': a missing sample"),
    (["tip [m/s]", "base [m/s^2]"], [[1, 2], ["", 3], [2, 2]], ["--rate", "10"],
     "line 3, column 1 (tip) is empty: a missing sample"),
    (["tip [m/s]"], [[1], ["inf"]], ["--rate", "10"], "'inf' (an overflow of the recorder?); "
     "expected a finite number"),
    (["time [s]", "tip [m/s]", "index"], [[0, 1, 0], [0.1, 2, 1]], [],
     "header column 3 is 'index' (a sample number or index column? leave it out with --skip "
     "3, or export without it)"),
    (["time [s]", "tip [m/s]", "hammer [N]"], [[0, 1, 0], [0.1, 2, 1]], [],
     "unit 'N' is not accepted; expected m, m/s, m/s^2, g or V, with a prefix m, u (µ) or n "
     "on m, m/s, m/s^2 and V (mm/s, um, mV), or s or ms for the time column (a column of "
     "another quantity, such as a hammer's force, is not read: leave it out with --skip 3)"),
    (["3rd tip [m/s]"], [[1], [2]], ["--rate", "10"],
     "header column 1: name '3rd tip' is not accepted; expected a letter followed by "
     "letters, digits, '_', '-' or spaces"),
    (["tip velocity [m/s]", "tip_velocity [m/s]"], [[1, 2], [2, 3]], ["--rate", "10"],
     "column name 'tip_velocity' appears twice"),
    # time steps of 5e-324 s would store sample_rate = inf
    (["time [s]", "tip [m/s]"], [[0, 1], ["5e-324", 2], ["1e-323", 3]], [],
     "the time column (steps of 4.94066e-324 s) gives: a sample rate of inf Hz; expected "
     "0.001 to 1e+09 Hz"),
    (["tip [m/s]"], [[1], [2]], ["--rate", "1e-300"],
     "--rate 1e-300: a sample rate of 1e-300 Hz; expected 0.001 to 1e+09 Hz"),
    (["time [s]"], [[0], [1], [2]], [],
     "only a time column; expected data columns 'name [unit]' beside it"),
    (["time [s]", "Time [s]", "tip [m/s]"], [[0, 0, 1], [1, 1, 2]], [],
     "header columns 1 and 2 are both time columns; expected at most one 'time [s]' column"),
    (["time [s]", "tip [m/s]"], [["1e300", 1], ["1.0000000001e300", 2]], [],
     "the time column (steps of"),
    (["time [s]", "tip [m/s]"], [[2e9, 1], [2e9 + 0.001, 2]], [],
     "line 2: the time column starts at 2e+09 s; expected a start within 1e+09 s of 0"),
    (["tip [g]"], [["1e308"], [1]], ["--rate", "10"],
     "line 2, column 1 (tip): too large to convert from g to m/s^2; expected a finite value"),
])
def test_bad_csv_is_refused_with_file_and_place(tmp_path, header, rows, args, fragment):
    csv_path = _write(tmp_path / "bad.csv", header, rows)
    out = tmp_path / "bad.h5"
    proc = cli_here("import", str(csv_path), "-o", str(out), *args)
    assert proc.returncode == 2
    assert fragment in proc.stderr
    assert not out.exists()


def _imported(csv_path, *args):
    out = csv_path.with_suffix(".h5")
    proc = cli_here("import", str(csv_path), "-o", str(out), *args)
    assert proc.returncode == 0, proc.stderr
    return read_run(out)


def test_an_export_with_decimal_commas_reads_as_the_same_record(tmp_path):
    """A signal analyser's export where the decimal mark is a comma: a preamble of comments,
    semicolon-separated 'name (unit)' columns in ms, mm/s and m/s², a trailing semicolon on
    every line. It gives the same channels, in SI, as the comma-separated file of the values."""
    rng = np.random.default_rng(5)
    t = 0.25 + np.arange(300) / 2000.0
    v = 0.02 * np.exp(-2.0 * t) * np.sin(2 * np.pi * 17 * t) + 1e-5 * rng.standard_normal(t.size)
    a = 3.0 * rng.standard_normal(t.size)
    plain = _write(tmp_path / "plain.csv", ["time [s]", "tip_velocity [m/s]", "base [m/s^2]"],
                   zip(t.tolist(), v.tolist(), a.tolist()))

    def comma(x):
        return repr(float(x)).replace(".", ",")

    lines = ["# Exported by the signal analyser", "# Sample rate: 2000 Hz",
             "Time (ms);tip velocity (mm/s);base (m/s²);"]
    lines += [f"{comma(1e3 * ti)};{comma(1e3 * vi)};{comma(ai)};" for ti, vi, ai in zip(t, v, a)]
    local = tmp_path / "local.csv"
    local.write_text("\r\n".join(lines) + "\r\n", encoding="utf-8-sig")
    expected, found = _imported(plain), _imported(local)
    assert found.channels["tip_velocity"].sample_rate == pytest.approx(2000.0, rel=1e-9)
    assert found.channels["tip_velocity"].t0 == pytest.approx(0.25, rel=1e-12)
    np.testing.assert_allclose(found.channels["tip_velocity"].data,
                               expected.channels["tip_velocity"].data, rtol=1e-12)
    np.testing.assert_allclose(found.channels["base"].data, expected.channels["base"].data,
                               rtol=1e-15)
    assert found.channels["tip_velocity"].unit == "m/s"
    attrs = found.channel_attrs["tip_velocity"]
    assert (attrs["original_units"], attrs["original_name"]) == ("mm/s", "tip velocity")
    assert "original_name" not in found.channel_attrs["base"]


@pytest.mark.parametrize("unit, value, si_unit, si_value", [
    ("mm", "2.5", "m", 2.5e-3), ("um", "4", "m", 4e-6), ("µm/s", "7", "m/s", 7e-6),
    ("mm/s^2", "3", "m/s^2", 3e-3), ("m/s2", "3", "m/s^2", 3.0), ("mV", "12", "V", 0.012),
    ("g", "1", "m/s^2", STANDARD_GRAVITY), ("nm", "5", "m", 5e-9),
])
def test_units_with_a_prefix_are_converted_to_si(tmp_path, unit, value, si_unit, si_value):
    run = _imported(_write(tmp_path / "u.csv", [f"x [{unit}]"], [[value], [value]]),
                    "--rate", "100")
    assert run.channels["x"].unit == si_unit
    np.testing.assert_allclose(run.channels["x"].data, [si_value, si_value], rtol=1e-15)


def test_tab_separated_values_with_a_decimal_point(tmp_path):
    path = tmp_path / "tabs.tsv"
    path.write_text("tip [m/s]\tbase [g]\n0.5\t-1.25e-3\n1.5\t2\n")
    run = _imported(path, "--rate", "10")
    np.testing.assert_array_equal(run.channels["tip"].data, [0.5, 1.5])
    np.testing.assert_allclose(run.channels["base"].data,
                               np.array([-1.25e-3, 2.0]) * STANDARD_GRAVITY, rtol=1e-15)


@pytest.mark.parametrize("rate, style", [(2560, "%.6f"), (25600, "%.6f"), (8192, "%.6g"),
                                         (6000, "%.5f"), (3333.25, "%.7f")])
def test_a_time_column_printed_to_a_few_digits_gives_the_rate_it_was_written_at(tmp_path, rate,
                                                                              style):
    """A signal analyser prints its time column rounded (2560 Hz to 6 decimals: steps of
    0.000390 and 0.000391 s). The steps are uniform within that rounding, and the rate is the
    whole number of Hz the rounding allows (a rate that is no whole number is kept to the
    column's precision)."""
    t = np.arange(4000) / rate
    path = tmp_path / "rounded.csv"
    path.write_text("time [s],x [m/s]\n" + "".join(f"{style % ti},{k % 7}\n"
                                                   for k, ti in enumerate(t)))
    found = _imported(path).channels["x"].sample_rate
    assert found == pytest.approx(rate, rel=1e-6)
    if float(rate).is_integer():
        assert found == rate
    # --rate beside the column: taken as given when the column agrees
    assert _imported(path.rename(tmp_path / "given.csv"), "--rate", str(rate)
                     ).channels["x"].sample_rate == rate


def test_a_rate_the_time_column_contradicts_is_refused(tmp_path):
    path = _write(tmp_path / "t.csv", ["time [s]", "x [m]"],
                  [[f"{k / 5000:.6f}", k] for k in range(50)])
    proc = cli_here("import", str(path), "-o", str(tmp_path / "t.h5"), "--rate", "1000")
    assert proc.returncode == 2
    assert f"--rate 1000: the time column of {path} gives 5000 Hz; leave out --rate" \
        in proc.stderr


@pytest.mark.parametrize("text, values", [
    ("x [m/s]\n0,0125\n-1,5E-03\n", [0.0125, -1.5e-3]),          # one column, decimal comma
    ("time [s],x [m]\n0,1,\n0.1,2,\n", [1.0, 2.0]),                 # separator ending the rows
    ("x [m]\ty [m]\n1\t2\n3\t4\n", [1.0, 3.0]),
    ("x [m];y [m];\n1,5;2;\n2,5;3;\n;;\n;;\n", [1.5, 2.5]),    # a sheet's empty rows at its end
])
def test_exports_from_other_tools_read_as_written(tmp_path, text, values):
    path = tmp_path / "other.csv"
    path.write_text(text)
    np.testing.assert_allclose(_imported(path, "--rate", "10").channels["x"].data, values,
                               rtol=1e-15)


def test_a_utf16_export_with_its_byte_order_mark_is_read(tmp_path):
    """A spreadsheet's "Unicode text" export: UTF-16 with a byte-order mark, tabs."""
    path = tmp_path / "unicode.txt"
    path.write_bytes("v [µm/s]\tbase [m/s²]\r\n1,5\t2\r\n2,5\t3\r\n".encode("utf-16"))
    run = _imported(path, "--rate", "100")
    np.testing.assert_allclose(run.channels["v"].data, [1.5e-6, 2.5e-6], rtol=1e-15)


@pytest.mark.parametrize("text, fragment", [
    # a point among decimal commas, a comma among points: thousands separators, never read
    # a thousand times off
    ("time [s];v [um/s]\n0;0\n0,0002;1.234\n0,0004;150.000\n",
     "line 3 has '0,0002' (a decimal comma) and line 3 '1.234' (a point: a thousands "
     "separator?); expected one decimal mark"),
    ("time [s]\tv [um/s]\n0\t0\n0.0002\t1,234\n",
     "line 3 has '1,234' (a decimal comma) and line 3 '0.0002' (a point"),
    ("x [m],y [m]\n\"1,5\",2\n1,2\n", "'1,5' is not a number (a decimal comma in a "
     "comma-separated file? separate the columns with semicolons)"),
    ("x [m];y [m]\n1.234,5;2\n1;2\n", "'1.234,5' is not a number (its digits are grouped by "
     "thousands with '.': export the numbers without thousands separators, e.g. '1234,5')\n"),
    ("v [m/s];Kraft [N]\n0;1\n1;2\n",
     "unit 'N' is not accepted; expected m, m/s, m/s^2, g or V, with a prefix m, u (µ) or n on "
     "m, m/s, m/s^2 and V (mm/s, um, mV), or s or ms for the time column"),
    (",x [m]\n0,1\n1,2\n", "line 1, header column 1 is empty (a table's index column? "
     "export without it, e.g. pandas' to_csv(index=False))"),
    ("Sample rate: 5000\nx [m]\n1\n2\n", "line 1, header column 1 is 'Sample rate: 5000'; "
     "expected 'name [unit]'"),
    ("Sample rate: 5000\nx [m]\n1\n2\n", "The first line that is not a '#' comment is the "
     "header row: begin any lines above it with '#'; line 2 ('x [m]') is one: begin line 1 "
     "with '#'"),
    # an analyser's export: lines about itself, a blank one, then its header (refused as a
    # header, not as a sample missing at the blank line, and the header it holds is named)
    ("Polytec export\nDate;29.11.2026\n\nTime [s];v [m/s]\n0;1\n0,1;2\n",
     "line 1, header column 1 is 'Polytec export'; expected 'name [unit]'"),
    ("Polytec export\nDate;29.11.2026\n\nTime [s];v [m/s]\n0;1\n0,1;2\n",
     "; line 4 ('Time [s];v [m/s]') is one: begin lines 1 to 3 with '#'"),
    ("x [m]\n\"1\n2\"\n3\n", "line 2: a quoted value spans several lines"),
    ("x [m],y [m]\n0.1,\"2\n", "line 2: unexpected end of data"),
    ("# a preamble\n# and nothing else\n", "only comments; expected a header row"),
    # the line numbers are the file's, comments counted
    ("# preamble\ntime [s];x [m]\n0;1\n0,1;2\n0,2;3\n# note\n0,35;4\n",
     "step 0.15 s at line 7 against a mean of 0.116667 s"),
    ("x [m];y [m]\n1,5;2\n1,5\n", "line 3 has 1 value; the header has 2 columns (separated by "
     "semicolons)"),
    ("x [m];y [m]\n1.000,5;2\n1;2\n", "line 2, column 1 (x): '1.000,5' is not a number"),
    ("# only a comment\n", "only comments; expected a header row"),
    # a missing sample in a column printed to a step's resolution (whole ms at 1 kHz)
    ("time [ms];x [m]\n" + "".join(f"{k};1\n" for k in range(40) if k != 20),
     "step 0.002 s at line 22 against a mean of"),
])
def test_an_export_read_wrong_is_refused_naming_why(tmp_path, text, fragment):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    proc = cli_here("import", str(path), "-o", str(tmp_path / "bad.h5"), "--rate", "10")
    assert proc.returncode == 2
    assert fragment in proc.stderr
    assert not (tmp_path / "bad.h5").exists()


# A record with no time column: the rows are the samples, one sample period apart.
SAMPLES = [f"{0.01 * np.sin(2 * np.pi * 17 * k / 1000):.7f}" for k in range(60)]


@pytest.mark.parametrize("end", ["\n", "\r\n"])
@pytest.mark.parametrize("header, sep, blank, after, fragment", [
    # one column (the tester's files: 4000 samples read as 3999, each later one a period
    # early); the line empty, spaces or tabs, or separators alone
    ("tip [m/s]", "", "", 30, "is blank"),
    ("tip [m/s]", "", " ", 30, "is blank"),
    ("tip [m/s]", "", " \t ", 30, "is blank"),
    ("tip [m/s]", "", ";", 30, "has no values (separators alone)"),
    ("tip [m/s]", "", ",", 30, "has no values (separators alone)"),
    ("tip [m/s]", "", '""', 30, "has no values (separators alone)"),
    ("tip [m/s]", "", "", 58, "is blank"),        # before the last row
    # two columns: a blank line, and a sheet's empty row among the rows
    ("tip [m/s],base [g]", ",", "", 30, "is blank"),
    ("tip [m/s],base [g]", ",", ",,", 30, "has no values (separators alone)"),
    ("tip [m/s];base [g];", ";", ";;", 30, "has no values (separators alone)"),
    ("tip [m/s]\tbase [g]", "\t", "\t", 30, "has no values (separators alone)"),
])
def test_a_blank_line_among_the_rows_is_refused_as_a_missing_sample(tmp_path, header, sep,
                                                                      blank, after, fragment,
                                                                      end):
    """Skipped, a blank line among the rows of a file without a time column would move every
    later sample one sample period early (the frequencies read 0.5 to 2.4 % high): it is
    refused like an empty cell, naming its line (the header is line 1)."""
    trailing = sep if sep and header.endswith(sep) else ""
    rows = [sep.join([value] * header.count("[")) + trailing for value in SAMPLES]
    path = tmp_path / "gap.csv"
    path.write_bytes(end.join([header, *rows[:after], blank, *rows[after:], ""]).encode())
    out = tmp_path / "gap.h5"
    proc = cli_here("import", str(path), "-o", str(out), "--rate", "1000")
    assert proc.returncode == 2, proc.stderr
    assert f"{path}: line {after + 2} {fragment}: a sample is missing there" in proc.stderr
    assert ("expected a row of values on every line from the first row to the last: blank "
            "lines only above the first row or after the last") in proc.stderr
    assert not out.exists()


def test_a_blank_line_in_a_time_column_names_its_line(tmp_path):
    """With a time column the blank line shows as a step twice the others; it is named."""
    lines = ["time [s],tip [m/s]"] + [f"{k / 1000:.3f},{v}" for k, v in enumerate(SAMPLES)]
    path = tmp_path / "timed.csv"
    path.write_text("\n".join([*lines[:21], "", *lines[22:]]) + "\n")
    proc = cli_here("import", str(path), "-o", str(tmp_path / "timed.h5"))
    assert proc.returncode == 2
    assert f"{path}: line 22 is blank: a sample is missing there" in proc.stderr
    assert not (tmp_path / "timed.h5").exists()


@pytest.mark.parametrize("end", ["\n", "\r\n"])
@pytest.mark.parametrize("blank", ["", "  ", "\t", " \t", ";", ",", ";;"])
def test_blank_lines_above_the_first_row_and_after_the_last_are_accepted(tmp_path, blank, end):
    """Blank lines around the table (between the header and the first row too) hide no
    sample: every row is read, none shifted; comment lines stay accepted anywhere, after the
    last row too."""
    lines = [blank, "# exported", blank, "tip [m/s]", blank, *SAMPLES[:30], "# a note",
             *SAMPLES[30:], blank, "# end", blank, blank]
    path = tmp_path / "around.csv"
    path.write_bytes((end.join(lines) + end).encode())
    run = _imported(path, "--rate", "1000")
    np.testing.assert_array_equal(run.channels["tip"].data, np.array(SAMPLES, dtype=float))
    # without the final newline, and with only a trailing newline
    for name, text in (("bare.csv", end.join(["tip [m/s]", *SAMPLES])),
                       ("one.csv", end.join(["tip [m/s]", *SAMPLES]) + end)):
        (tmp_path / name).write_bytes(text.encode())
        np.testing.assert_array_equal(_imported(tmp_path / name, "--rate", "1000")
                                      .channels["tip"].data, np.array(SAMPLES, dtype=float))


def test_utf16_without_its_byte_order_mark_is_refused_naming_it(tmp_path):
    path = tmp_path / "u16.csv"
    path.write_bytes("x [m]\n1\n2\n".encode("utf-16-le"))
    proc = cli_here("import", str(path), "-o", str(tmp_path / "u16.h5"), "--rate", "10")
    assert proc.returncode == 2
    assert "holds NUL characters (UTF-16 text without its byte-order mark?)" in proc.stderr


@pytest.mark.parametrize("cells, group", [(["164,807", "-1.292,940"], "'.'"),
                                          (["164.807", "-1 292.940"], "' '")])
def test_digits_grouped_by_thousands_are_refused_naming_the_separator(tmp_path, cells, group):
    """A spreadsheet's display format exported as is: the samples below 1000 read, the first
    one above is refused, and the message says why and what to export instead."""
    path = tmp_path / "grouped.csv"
    path.write_text("tip velocity [um/s]\n" + "\n".join(cells) + "\n")
    proc = cli_here("import", str(path), "-o", str(tmp_path / "grouped.h5"), "--rate", "5000")
    assert proc.returncode == 2
    expected = cells[1].replace(group.strip("'"), "")
    assert (f"line 3, column 1 (tip velocity): {cells[1]!r} is not a number (its digits are "
            f"grouped by thousands with {group}: export the numbers without thousands "
            f"separators, e.g. {expected!r})") in proc.stderr
    assert not (tmp_path / "grouped.h5").exists()


def test_an_acceleration_column_beside_the_velocity_is_said_to_be_left_out(tmp_path):
    """Picked by quantity, the velocity is analysed and the acceleration beside it is not: a
    note on the analysed channel says so and how to have it analysed; none once it is the
    reference."""
    t = np.arange(2000) / 1000.0
    v = 0.01 * np.exp(-t) * np.sin(2 * np.pi * 17 * t)
    path = _write(tmp_path / "both.csv", ["tip [m/s]", "tip_acc [m/s^2]"],
                  zip(v, np.gradient(v, t)))
    run = tmp_path / "both.h5"
    assert cli_here("import", str(path), "--rate", "1000", "-o", str(run)).returncode == 0
    data, proc = cli_json_here("analyze", str(run), "--set", "analysis.chain=spectrum")
    assert proc.returncode == 0, proc.stderr
    assert list(data["channels"]) == ["tip"]
    assert data["channels"]["tip"]["notes"] == [
        "tip_acc (acceleration): not analysed; with no channel named only the velocity and "
        "displacement channels are; an acceleration channel is analysed (integrated to "
        "velocity) when named, --set analysis.channels=tip_acc, or is the base's motion as "
        "the reference, --set analysis.reference=tip_acc"]
    data, proc = cli_json_here("analyze", str(run), "--set", "analysis.chain=spectrum",
                               "--set", "analysis.reference=tip_acc")
    assert proc.returncode == 0, proc.stderr
    assert "notes" not in data["channels"]["tip"]


def test_a_time_column_refused_is_left_out_with_ignore_time(tmp_path):
    # a scope's time stamps printed to whole ms at 2 kHz: refused, and read at the given rate
    path = tmp_path / "scope.csv"
    path.write_text("time [s],v [m/s]\n" + "".join(f"{i / 2000:.3f},{i}\n" for i in range(8)))
    out = tmp_path / "scope.h5"
    proc = cli_here("import", str(path), "-o", str(out), "--rate", "2000")
    assert proc.returncode == 2 and "--rate HZ --ignore-time" in proc.stderr
    proc = cli_here("import", str(path), "-o", str(out), "--ignore-time")
    assert proc.returncode == 2
    assert "--ignore-time: the sample rate is then --rate's; expected --rate HZ" in proc.stderr
    assert not out.exists()
    proc = cli_here("import", str(path), "-o", str(out), "--rate", "2000", "--ignore-time")
    assert proc.returncode == 0, proc.stderr
    assert "time column left out" not in proc.stderr      # (within its printed digits)
    run = read_run(out)
    assert list(run.channels) == ["v"]
    assert (run.channels["v"].sample_rate, run.channels["v"].t0) == (2000.0, 0.0)
    np.testing.assert_array_equal(run.channels["v"].data, np.arange(8.0))


def test_a_time_column_left_out_that_disagrees_with_the_rate_given_is_named(tmp_path):
    """Stamps of an analyser at 2048 Hz (to 0.1 ms, with jitter) imported at --rate 2000 with
    --ignore-time: the record is read at 2000 Hz, as asked, and a note says the column ran at
    2048 Hz and by how much every frequency would be off (it was imported without a word,
    and a 17 Hz mode read 16.6 Hz)."""
    rng = np.random.default_rng(1)
    t = np.arange(400) / 2048 + 2e-5 * rng.standard_normal(400)
    path = tmp_path / "jitter.csv"
    path.write_text("time [s],v [m/s]\n" + "".join(f"{ti:.4f},{i}\n" for i, ti in enumerate(t)))
    out = tmp_path / "jitter.h5"
    proc = cli_here("import", str(path), "-o", str(out), "--rate", "2000", "--ignore-time")
    assert proc.returncode == 0, proc.stderr
    said = re.search(r"the time column left out \(--ignore-time\) runs at (\S+) Hz on average, "
                     r"not the 2000 Hz given with --rate, which is used: were the rate wrong, "
                     r"every frequency read from the record would be (\S+) times the true one",
                     proc.stderr)
    assert said, proc.stderr
    assert float(said[1]) == pytest.approx(2048.0, rel=2e-4)
    assert float(said[2]) == pytest.approx(2000.0 / 2048.0, rel=2e-4)
    assert read_run(out).channels["v"].sample_rate == 2000.0


def test_a_windows_1252_export_is_read_and_says_so(tmp_path):
    # German Excel's "CSV (Trennzeichen-getrennt)": µ and ² a byte each, semicolons, commas
    path = tmp_path / "excel.csv"
    text = ("Zeit [s];Geschwindigkeit [µm/s];Fußpunkt [m/s²]\r\n"
            + "".join(f"{i / 1000:.3f};{1.5 * i:.1f};{0.25 * i:.2f}\r\n".replace(".", ",")
                      for i in range(6)))
    path.write_bytes(text.encode("cp1252"))
    out = tmp_path / "excel.h5"
    data, proc = cli_json_here("import", str(path), "-o", str(out))
    assert proc.returncode == 0, proc.stderr
    note = (f"{path}: not UTF-8; read as Windows-1252 (the text of Excel and analysers on "
            "Western European Windows), which gives the header 'Geschwindigkeit [µm/s]', "
            "'Fußpunkt [m/s²]'; if that reads wrong, save the file as UTF-8")
    assert data == {"run": str(out), "notes": [note]}
    assert f"[note] {note}" in proc.stderr
    run = read_run(out)
    assert run.attrs["source_encoding"] == "cp1252"
    assert run.channels["Geschwindigkeit"].sample_rate == pytest.approx(1000.0)
    np.testing.assert_allclose(run.channels["Geschwindigkeit"].data, 1.5e-6 * np.arange(6))
    np.testing.assert_allclose(run.channels["Fusspunkt"].data, 0.25 * np.arange(6))
    assert run.channel_attrs["Fusspunkt"]["original_name"] == "Fußpunkt"


@pytest.mark.parametrize("content, fragment", [
    # not UTF-8 and a byte Windows-1252 leaves undefined
    (b"v [m/s]\n1\n\x81\n", "not UTF-8 text (byte 0x81 at offset 10, nor Windows-1252 text)"),
    # UTF-8 (a µ in two bytes) and then a byte that is not: damaged, not another encoding
    ("v [µm/s]\n1\n".encode() + b"\xb5\n",
     "not UTF-8 text (byte 0xb5 at offset 12 after UTF-8 characters: damaged UTF-8?)"),
    (b"PK\x03\x04\x14\x00\x06\x00", "is a zip archive (a spreadsheet workbook such as .xlsx "
     "or .ods?), not text; expected a CSV file"),
    (b"MATLAB 5.0 MAT-file, Platform: GLNXA64", "is a MATLAB MAT-file, not text"),
    (b"TDSm\x0e\x00\x00\x00", "is a TDMS file (LabVIEW, DIAdem), not text"),
    (b"    -1\n    58\nTip velocity\n", "is a universal file (UFF, dataset 58), not a CSV file"),
])
def test_files_that_are_not_csv_text_are_refused_as_what_they_are(tmp_path, content, fragment):
    path = tmp_path / "export.csv"
    path.write_bytes(content)
    out = tmp_path / "export.h5"
    proc = cli_here("import", str(path), "-o", str(out), "--rate", "10")
    assert proc.returncode == 2
    assert f"fsi-lab: error: {path}: " in proc.stderr and fragment in proc.stderr
    assert not out.exists()


def test_a_column_of_numbers_under_minus_one_is_not_taken_for_a_universal_file(tmp_path):
    path = tmp_path / "numbers.csv"
    path.write_text("-1\n2\n3\n")
    proc = cli_here("import", str(path), "-o", str(tmp_path / "n.h5"), "--rate", "10")
    assert proc.returncode == 2 and "line 1 holds numbers, not a header row" in proc.stderr


def test_existing_output_is_never_overwritten(tmp_path):
    csv_path = _write(tmp_path / "a.csv", ["x [m]"], [[1], [2]])
    out = tmp_path / "a.h5"
    out.write_bytes(b"precious")
    proc = cli_here("import", str(csv_path), "--rate", "10", "-o", str(out))
    assert proc.returncode == 2 and "already exists" in proc.stderr
    assert out.read_bytes() == b"precious"


def test_a_record_with_nothing_to_identify_exits_2_and_keeps_its_analysis(tmp_path):
    """White noise holds no free decay: every channel's identification is refused, so
    `fsi-lab analyze` says so and exits 2 (one file and in a batch, next to a good file), and
    what it could compute (the spectrum) is still stored in the file."""
    rng = np.random.default_rng(3)
    noise = _write(tmp_path / "noise.csv", ["tip [m/s]"], zip(1e-3 * rng.standard_normal(4000)))
    t = np.arange(4000) / 1000.0
    decay = _write(tmp_path / "decay.csv", ["tip [m/s]"],
                   zip(0.01 * np.exp(-1.5 * t) * np.sin(2 * np.pi * 17 * t)
                       + 1e-5 * rng.standard_normal(t.size)))
    runs = []
    for csv_path in (noise, decay):
        out = csv_path.with_suffix(".h5")
        assert cli_here("import", str(csv_path), "--rate", "1000", "-o", str(out)).returncode == 0
        runs.append(out)
    proc = cli_here("analyze", str(runs[0]), "--mass-per-length", "0.1")
    assert proc.returncode == 2, proc.stderr
    assert f"{runs[0]}: nothing was identified: channel tip: " in proc.stderr
    with h5py.File(runs[0], "r") as stored:
        assert stored["analysis/tip/spectrum/peak_frequencies"].size > 0
    data, proc = cli_json_here("analyze", str(runs[0]), str(runs[1]), "--mass-per-length", "0.1")
    assert proc.returncode == 2 and data["exit_code"] == 2
    bad, good = data["files"]
    assert (bad["exit_code"], good["exit_code"]) == (2, 0)
    assert bad["error"].startswith("nothing was identified: channel tip: ")
    assert good["analysis"]["channels"]["tip"]["components"]


@pytest.mark.parametrize("unit, step", [("S", 0.001), ("MS", 1.0), ("Ms", 1.0)])
def test_a_time_column_s_unit_is_read_in_any_case(tmp_path, unit, step):
    """An analyser that writes `Time [S]` (or `[MS]`) was refused: in a time column the
    unit can only be seconds or milliseconds."""
    path = tmp_path / "caps.csv"
    path.write_text(f"Time [{unit}],tip [m/s]\n"
                    + "".join(f"{k * step:g},{v}\n" for k, v in enumerate(SAMPLES)))
    run = _imported(path)
    assert run.channels["tip"].sample_rate == pytest.approx(1000.0)
    np.testing.assert_array_equal(run.channels["tip"].data, np.array(SAMPLES, dtype=float))


def test_columns_left_out_with_skip_are_not_read_and_later_columns_keep_their_numbers(
        tmp_path):
    """A sample index and a hammer's force beside the motion: ``--skip`` leaves them out (the
    run file names them), the other columns are read as without them, and a refusal names a
    column by its number in the file. A number outside the header, or one that leaves nothing,
    is refused before anything is written."""
    t = np.arange(300) / 1000.0
    v = 0.01 * np.sin(2 * np.pi * 17 * t)
    path = _write(tmp_path / "hammer.csv", ["index", "time [s]", "force [N]", "tip [mm/s]"],
                  zip(range(t.size), t, 5.0 + 0 * t, 1e3 * v))
    run = _imported(path, "--skip", "3", "--skip", "1")
    assert list(run.channels) == ["tip"] and list(run.attrs["skipped_columns"]) == [1, 3]
    assert run.channels["tip"].sample_rate == pytest.approx(1000.0)
    np.testing.assert_allclose(run.channels["tip"].data, v, rtol=1e-12, atol=1e-15)
    # the same rows with a value that is not a number in the 4th column: named as the 4th
    bad = path.read_text().splitlines()
    bad[5] = ",".join(bad[5].split(",")[:3] + ["x"])
    path.write_text("\n".join(bad) + "\n")
    for args, fragment in (
            (["--skip", "1", "--skip", "3"], "line 6, column 4 (tip): 'x' is not a number"),
            (["--skip", "5"], "--skip 5: " + str(path) + " has 4 columns (header row, line 1); "
                              "expected a column number from 1 to 4"),
            (["--skip", "1", "--skip", "2", "--skip", "3", "--skip", "4"],
             "--skip leaves none of the 4 columns"),
            (["--skip", "0"], "'0': expected a column number")):
        out = tmp_path / "refused.h5"
        code, _, err = run_main("import", str(path), "-o", str(out), *args)
        assert code == 2 and fragment in err, err
        assert not out.exists()
    # an analyser's names over their units: the force is refused by its name and number, and
    # left out the same way
    two_rows = tmp_path / "names_units.csv"
    two_rows.write_text("Time;Force;Velocity\ns;N;mm/s\n"
                        + "".join(f"{k / 1000:g};5;{1e3 * x:g}\n".replace(".", ",")
                                  for k, x in enumerate(v)))
    code, _, err = run_main("import", str(two_rows), "-o", str(tmp_path / "refused.h5"))
    assert code == 2 and "header column 2 (Force): unit 'N' is not accepted" in err \
        and "leave it out with --skip 2" in err, err
    run = _imported(two_rows, "--skip", "2")
    assert list(run.channels) == ["Velocity"]
    np.testing.assert_allclose(run.channels["Velocity"].data, v, rtol=1e-5, atol=1e-9)


def test_a_column_in_volts_is_calibrated_with_its_sensor_s_sensitivity(tmp_path):
    """A vibrometer's decoder output in mV and an accelerometer's in V, each with its
    sensitivity as a data sheet gives it: stored as velocity and acceleration in SI, with the
    sensitivity in volts per SI unit, as a run stores a channel; the calibrated base is
    accepted as the reference (in volts it is not an acceleration)."""
    t = np.arange(400) / 1000.0
    millivolts = 50.0 * np.sin(2 * np.pi * 17 * t)
    volts = 0.3 * np.cos(2 * np.pi * 17 * t)
    path = _write(tmp_path / "volts.csv", ["tip velocity [mV]", "base [V]"],
                  zip(millivolts, volts))
    out = tmp_path / "volts.h5"
    proc = cli_here("import", str(path), "--rate", "1000", "-o", str(out), "--reference", "base",
               "--sensitivity", "tip_velocity=200mV/(mm/s)", "--sensitivity", "base=100 mV/g")
    assert proc.returncode == 0, proc.stderr
    run = read_run(out)
    tip, base = run.channels["tip_velocity"], run.channels["base"]
    assert (tip.quantity, tip.unit, base.quantity, base.unit) == (
        "velocity", "m/s", "acceleration", "m/s^2")
    # 50 mV at 200 mV per mm/s is 0.25 mm/s; 0.3 V at 100 mV per g is 3 g
    np.testing.assert_allclose(tip.data, millivolts / 200.0 * 1e-3, rtol=1e-12)
    np.testing.assert_allclose(base.data, volts / 0.1 * STANDARD_GRAVITY, rtol=1e-12)
    attrs = run.channel_attrs
    assert attrs["tip_velocity"]["sensitivity"] == pytest.approx(200.0, rel=1e-12)
    assert attrs["tip_velocity"]["sensitivity_units"] == "V/(m/s)"
    assert attrs["base"]["sensitivity"] == pytest.approx(0.1 / STANDARD_GRAVITY, rel=1e-12)
    assert attrs["base"]["sensitivity_units"] == "V/(m/s^2)"
    assert attrs["tip_velocity"]["original_units"] == "mV"
    assert run.attrs["reference"] == "base"


@pytest.mark.parametrize("written", ["200mV/(mm/s)", "5mm/s/V", "5 mm/s / V", "0.2 V/(mm/s)"])
def test_a_decoder_s_scale_factor_and_its_sensitivity_calibrate_alike(tmp_path, written):
    # a vibrometer decoder's range is given as a scale factor (Polytec: 5 mm/s/V)
    millivolts = [10.0, -20.0, 5.0]
    path = _write(tmp_path / "decoder.csv", ["tip [mV]"], [(v,) for v in millivolts])
    out = tmp_path / "decoder.h5"
    proc = cli_here("import", str(path), "--rate", "100", "-o", str(out),
               "--sensitivity", f"tip={written}")
    assert proc.returncode == 0, proc.stderr
    run = read_run(out)
    # 10 mV at 5 mm/s per V is 0.05 mm/s
    np.testing.assert_allclose(run.channels["tip"].data, np.array(millivolts) * 5e-6,
                               rtol=1e-12)
    assert run.channel_attrs["tip"]["sensitivity"] == pytest.approx(200.0, rel=1e-12)


@pytest.mark.parametrize("given, fragment", [
    ("speed=200mV/(mm/s)", "--sensitivity speed=200mV/(mm/s): 'speed' is not a data column"),
    ("base=200mV/(mm/s)", "--sensitivity base=200mV/(mm/s): the column is written in g, "
     "already calibrated; expected a column in V or mV"),
    ("tip=5 mm/s", "--sensitivity tip=5 mm/s: not understood; expected a number, volts "
     "(V or mV) and the unit per which, e.g. 200mV/(mm/s)"),
    ("tip=0 mm/s/V", "--sensitivity tip=0 mm/s/V: not understood"),
    ("tip=0 mV/g", "--sensitivity tip=0 mV/g: not understood"),
    ("tip=100mV/V", "--sensitivity tip=100mV/V: not understood"),
    ("tip", "--sensitivity tip: expected NAME=SENSITIVITY, e.g. tip_velocity=200mV/(mm/s)"),
])
def test_a_sensitivity_that_cannot_calibrate_its_column_is_refused(tmp_path, given, fragment):
    path = _write(tmp_path / "rec.csv", ["tip [mV]", "base [g]"], [(1, 2), (2, 3), (3, 4)])
    out = tmp_path / "rec.h5"
    proc = cli_here("import", str(path), "--rate", "100", "-o", str(out), "--sensitivity", given)
    assert proc.returncode == 2
    assert fragment in proc.stderr
    assert not out.exists()


def test_a_record_in_volts_alone_is_refused_saying_how_to_calibrate_it(tmp_path):
    """Nothing in a record of volts is a motion: the refusal names the import option that
    makes one."""
    t = np.arange(2000) / 1000.0
    path = _write(tmp_path / "volts.csv", ["tip [V]"],
                  [(v,) for v in np.exp(-t) * np.sin(2 * np.pi * 17 * t)])
    run = tmp_path / "volts.h5"
    assert cli_here("import", str(path), "--rate", "1000", "-o", str(run)).returncode == 0
    proc = cli_here("analyze", str(run))
    assert proc.returncode == 2
    assert "nothing to analyse" in proc.stderr
    assert "--sensitivity NAME=200mV/(mm/s)" in proc.stderr
    # named, it gives its spectrum and frequencies (stored); C_i and C_f are refused with the
    # same advice, and the exit code says the input was not what they need
    proc = cli_here("analyze", str(run), "--set", "analysis.channels=tip",
               "--mass-per-length", "0.1346")
    refused = [line for line in proc.stdout.splitlines() if "failed equivalent-damping" in line]
    assert refused and "--sensitivity NAME=200mV/(mm/s)" in refused[0], proc.stdout
    assert proc.returncode == 2, proc.stderr
    assert "channel tip holds volts, not the motion its sensor measures: its frequencies are " \
        "stored, but integrate, backbone, damping, equivalent-damping need that motion" \
        in proc.stderr and "--sensitivity NAME=200mV/(mm/s)" in proc.stderr, proc.stderr
    with h5py.File(run, "r") as handle:
        summary = json.loads(handle["analysis"].attrs["summary"])
    stored = summary["channels"]["tip"]["components"]
    assert stored and abs(stored[0]["frequency_hz"] - 17.0) < 0.05
    # the same record calibrated is analysed (exit 0 or 3 with --strict, not 2)
    calibrated = tmp_path / "calibrated.h5"
    assert cli_here("import", str(path), "--rate", "1000", "-o", str(calibrated),
               "--sensitivity", "tip=200mV/(mm/s)").returncode == 0
    proc = cli_here("analyze", str(calibrated), "--mass-per-length", "0.1346")
    assert proc.returncode == 0 and "holds volts" not in proc.stderr, proc.stderr


def test_the_units_examples_run_as_written():
    """parse_unit's and parse_sensitivity's Examples sections (the import's unit reading)."""
    import doctest

    import fsi_lab.units

    result = doctest.testmod(fsi_lab.units, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted >= 6 and result.failed == 0, result


@pytest.mark.parametrize("text, fragment", [
    # grouped in thousands with the only mark in the file: never read 1000 times off
    ("Abstand [um];Basis [m/s^2]\n25.300;0\n25.301;0\n-25.299;0\n",
     "every value with a '.' has one '.' and three digits after it, and none lies between -1 "
     "and 1 (line 2: '25.300'): a thousands separator (25.300 read as 25300) cannot be told "
     "from a decimal mark; expected --decimal-mark '.' if it is the decimal mark"),
    ("v [um/s]\n21,357\n567\n-1,234\n", "every value with a ',' has one ','"),
    # a spreadsheet's error value in a row's first cell is no comment
    ("v [mm/s];b [m/s^2]\n1,0;0,1\n#NV;0,2\n3,0;0,3\n",
     "line 3 begins with '#NV' (a spreadsheet's error value in a row of samples, not a "
     "comment): a sample is missing there"),
    ("v [mm/s]\n1\n#DIV/0!\n3\n", "line 3 begins with '#DIV/0!'"),
    # the first row of samples too
    ("a [m/s],b [m/s]\n#N/A,1\n2,3\n4,5\n", "line 2 begins with '#N/A'"),
    # and below a header numpy wrote as a comment
    ("# a [m/s];b [m/s]\n#NV;1,5\n2;3\n4;5\n", "line 2 begins with '#NV'"),
    # names that meet once written as channel names
    ("v+ [m/s],v [m/s]\n1,2\n3,4\n", "column name 'v' appears twice in the header (written "
     "'v+' and 'v'); expected a name to each column"),
    ("v [m/s],b [m/s]\n1,2\n3,4\n", "separates its columns with commas; expected a decimal "
     "comma only in a file separated by semicolons or tabs"),
    # no header row: say so, with one for the columns found
    ("0,1.5,2\n0.001,1.6,2\n", "line 1 holds numbers, not a header row: the file has none; "
     "expected a first row naming its 3 columns 'name [unit]', e.g. 'time [s],tip velocity "
     "[m/s],base acceleration [m/s^2]'"),
    # time columns refused name the way out
    ("time [s],v [m/s]\n0.000,1\n0.000,2\n0.001,3\n", "the time column does not increase "
     "(line 3: printed with too few digits for its step?); if the samples were taken at a "
     "steady rate, give the rate with --rate HZ --ignore-time (the time column is then left "
     "out)"),
    # rows out of order are not a rounding: --ignore-time would keep them so
    ("time [s],v [m/s]\n0.000,1\n0.002,2\n0.001,3\n0.003,4\n", "the time column goes back "
     "from 0.002 s to 0.001 s at line 4: its rows are out of order (or records were joined); "
     "expected times that increase row by row. Sort the rows by time"),
])
def test_an_export_that_would_be_read_wrong_is_refused_saying_what_to_change(tmp_path, text,
                                                                             fragment):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    args = ["--decimal-mark", ","] if "decimal comma only" in fragment else []
    proc = cli_here("import", str(path), "-o", str(tmp_path / "bad.h5"), "--rate", "1000", *args)
    assert proc.returncode == 2
    assert fragment in proc.stderr
    assert not (tmp_path / "bad.h5").exists()


@pytest.mark.parametrize("text, args, values", [
    # --decimal-mark settles the grouped-looking file: a decimal point
    ("Abstand [mm];Basis [m/s^2]\n25.300;0\n25.301;0\n", ["--decimal-mark", "."],
     [0.0253, 0.025301]),
    # a value below 1 shows the mark is decimal: read as found
    ("x [mm];y [m]\n25.300;0\n0.125;0\n", [], [0.0253, 0.000125]),
    # numpy's savetxt writes the header row as a comment
    ("# x [mm],y [m]\n1.5,0\n2.5,0\n", [], [0.0015, 0.0025]),
    # a CSV writer that doubles the carriage return (Windows, a file opened without newline='')
    ("x [mm],y [m]\r\r\n1.5,0\r\r\n2.5,0\r\r\n", [], [0.0015, 0.0025]),
    # comments among the rows stay comments, numbers and separators in them too
    ("x [mm];y [m]\n1,5;0\n# the shaker stopped here\n2,5;0\n", [], [0.0015, 0.0025]),
    ("x [mm],y [m]\n1.5,0\n# gain changed, 10\n2.5,0\n", [], [0.0015, 0.0025]),
    # a blank line between an analyser's units row and its first row of samples
    ("x;y\nmm;m\n\n1.5;0\n2.5;0\n", [], [0.0015, 0.0025]),
])
def test_exports_read_as_meant(tmp_path, text, args, values):
    path = tmp_path / "good.csv"
    path.write_text(text, newline="")
    out = tmp_path / "good.h5"
    proc = cli_here("import", str(path), "-o", str(out), "--rate", "1000", *args)
    assert proc.returncode == 0, proc.stderr
    channels = read_run(out).channels
    np.testing.assert_allclose(channels["x" if "x" in channels else "Abstand"].data, values,
                               rtol=1e-12)


def test_a_time_column_in_double_precision_keeps_its_tolerance(tmp_path):
    """The single-precision allowance is for single-precision columns: times printed to 9
    decimals (double precision) with a step 2 % long late in the record are refused."""
    t = np.arange(200000) / 10000.0
    t[150000:] += 4e-6
    path = tmp_path / "double.csv"
    path.write_text("time [s],v [m/s]\n" + "".join(f"{v:.9f},1\n" for v in t))
    proc = cli_here("import", str(path), "-o", str(tmp_path / "double.h5"))
    assert proc.returncode == 2
    assert "the time column is not uniformly sampled" in proc.stderr


def test_a_time_column_with_samples_missing_is_refused_as_a_gap_not_as_jitter(tmp_path):
    """A DAQ that dropped a block: 100 samples' time missing 1.2 s into a 2 kHz record. The
    refusal names the gap (where, how many samples) and says why --ignore-time would not do:
    it would join the two sides (the frequency read 0.44 % off that way). No run file."""
    t = np.arange(6000) / 2000.0
    t = np.concatenate((t[:2400], t[2500:]))
    path = tmp_path / "gap.csv"
    path.write_text("time [s],v [m/s]\n" + "".join(f"{v:.6f},{np.sin(v)}\n" for v in t))
    out = tmp_path / "gap.h5"
    proc = cli_here("import", str(path), "-o", str(out))
    assert proc.returncode == 2
    assert ("the time column jumps from 1.19950 s to 1.25000 s at line 2402, where its steps are "
            "0.0005 s: about 100 samples are missing there") in proc.stderr
    assert "--ignore-time would join the two sides" in proc.stderr
    assert not out.exists()


def test_the_sensitivity_the_delay_and_the_reference_take_the_names_as_written(tmp_path):
    """A column named outside the channel-name rule is given to the options as the header
    wrote it (or as its channel is named); one sensitivity per column."""
    path = _write(tmp_path / "rec.csv", ["Fußpunkt [mV]", "tip velocity [m/s]"],
                  [(100, 1), (200, 2), (300, 3)])
    out = tmp_path / "rec.h5"
    proc = cli_here("import", str(path), "--rate", "100", "-o", str(out), "--sensitivity",
               "Fußpunkt=100mV/g", "--reference", "Fußpunkt", "--delay", "tip velocity=0.001")
    assert proc.returncode == 0, proc.stderr
    run = read_run(out)
    assert run.attrs["reference"] == "Fusspunkt"
    np.testing.assert_allclose(run.channels["Fusspunkt"].data,
                               [STANDARD_GRAVITY, 2 * STANDARD_GRAVITY, 3 * STANDARD_GRAVITY])
    assert run.channel_attrs["tip_velocity"]["sensor_delay_s"] == 0.001
    proc = cli_here("import", str(path), "--rate", "100", "-o", str(tmp_path / "twice.h5"),
               "--sensitivity", "Fusspunkt=100mV/g", "--sensitivity", "Fusspunkt=10mV/g")
    assert proc.returncode == 2
    assert "'Fusspunkt' is given twice; expected one sensitivity per column" in proc.stderr


def test_a_time_column_kept_in_single_precision_is_read(tmp_path):
    """LabVIEW's SGL and float32 arrays print times that miss the clock by their last place
    (2.4e-7 s at 4 s): a column of 20 000 such times at 5 kHz is uniform sampling."""
    t = (np.arange(20000) / 5000.0).astype(np.float32)
    path = tmp_path / "single.csv"
    path.write_text("time [s],v [m/s]\n" + "".join(f"{float(v):.9g},1\n" for v in t))
    proc = cli_here("import", str(path), "-o", str(tmp_path / "single.h5"))
    assert proc.returncode == 0, proc.stderr
    # (the rate from the column's ends, to single precision)
    assert read_run(tmp_path / "single.h5").channels["v"].sample_rate == pytest.approx(
        5000.0, rel=1e-7)


def test_an_analyser_s_names_and_units_read_as_its_header(tmp_path):
    """Names on one row and units on the next (LMS, DIAdem, dSPACE, oscilloscopes), a time
    column in s under any name, and names with signs and letters outside ASCII: read as
    channels named in ASCII, with the names written kept."""
    path = tmp_path / "analyser.txt"
    path.write_text("Zeit\tPoint1:+Z\tFußpunkt\n[s]\t[mm/s]\t[g]\n"
                    "0\t1,5\t0\n0,0002\t2,5\t1\n0,0004\t2\t0\n", encoding="utf-8")
    run = _imported(path)
    tip, base = run.channels["Point1_Z"], run.channels["Fusspunkt"]
    assert (tip.unit, tip.sample_rate, base.unit) == ("m/s", 5000.0, "m/s^2")
    np.testing.assert_allclose(tip.data, [0.0015, 0.0025, 0.002], rtol=1e-12)
    np.testing.assert_allclose(base.data, [0.0, STANDARD_GRAVITY, 0.0], rtol=1e-12)
    assert run.channel_attrs["Point1_Z"]["original_name"] == "Point1:+Z"


@pytest.mark.parametrize("between", ["", "\n"])
def test_lines_about_an_export_above_its_names_and_units_are_named(tmp_path, between):
    # (the names row and the units row may stand a blank line apart)
    path = tmp_path / "lms.txt"
    path.write_text(f"Section\tSection1\nSampling frequency\t5120\n\nTime\tv\n{between}s\tm/s\n"
                    "0\t1\n0.0001953125\t2\n")
    proc = cli_here("import", str(path), "-o", str(tmp_path / "lms.h5"))
    assert proc.returncode == 2
    assert "line 4 ('Time\\tv') is one: begin lines 1 to 3 with '#'" in proc.stderr
    # the way out it names: the names and units rows read once their line is given
    proc = cli_here("import", str(path), "-o", str(tmp_path / "lms.h5"), "--header-line", "4")
    assert proc.returncode == 0, proc.stderr
    tip = read_run(tmp_path / "lms.h5").channels["v"]
    assert (tip.unit, tip.sample_rate) == ("m/s", 5120.0)
    np.testing.assert_allclose(tip.data, [1.0, 2.0])


@pytest.mark.parametrize("line, fragment", [
    ("3", "--header-line 3: line 3 of {path} is blank; expected the line that holds its header "
          "row"),
    ("5", "--header-line 5: line 5 of {path} holds numbers, not a header row"),
    ("9", "--header-line 9: {path} has 6 lines; expected the number of the line"),
    ("0", "argument --header-line: '0'"),
])
def test_a_header_line_that_holds_no_header_row_is_refused(tmp_path, line, fragment):
    path = tmp_path / "export.csv"
    path.write_text("Analyzer export\nDate,2026-11-30\n\ntime [s],tip [mm/s]\n0,1\n0.001,2\n")
    proc = cli_here("import", str(path), "-o", str(tmp_path / "out.h5"), "--header-line", line)
    assert proc.returncode == 2
    assert fragment.format(path=path) in proc.stderr, proc.stderr
    assert not (tmp_path / "out.h5").exists()
