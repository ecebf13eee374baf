"""Files named on the command line that are not what they claim: each is refused with one
message naming the file and what is accepted (exit 2), without hanging or a traceback."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from support import GOOD_PROFILE, run_main


def _refused(code, out, err, *fragments):
    assert code == 2, (code, out, err)
    assert "Traceback" not in err and err.count("fsi-lab: error:") == 1, err
    for fragment in fragments:
        assert fragment in err, err


@pytest.mark.parametrize("encode, fragment", [
    (lambda text: text.encode("utf-16"),
     "UTF-16 text (a spreadsheet's 'Unicode text' export?); expected"),
    (lambda text: text.replace("# ", "# caf\u00e9 ", 1).encode("latin-1"),
     "not UTF-8 text (byte 0xe9 at offset"),

])
def test_a_profile_that_is_not_utf8_is_refused(tmp_path, encode, fragment):
    path = tmp_path / "p.toml"
    path.write_bytes(encode(GOOD_PROFILE.read_text()))
    _refused(*run_main("profile", "check", str(path)), f"{path}: {fragment}",
             "expected a profile (TOML text) saved as UTF-8")


def test_a_run_file_given_for_a_profile_is_refused_as_what_it_is(tmp_path):
    path = tmp_path / "p.toml"
    path.write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(64))
    _refused(*run_main("profile", "check", str(path)),
             f"{path}: is an HDF5 file (a MATLAB v7.3 MAT-file, or a run file?), not text; "
             "expected a profile (TOML text)")


def test_a_profile_with_a_utf8_byte_order_mark_is_read(tmp_path):
    path = tmp_path / "p.toml"
    path.write_bytes(b"\xef\xbb\xbf" + GOOD_PROFILE.read_bytes())
    code, out, err = run_main("profile", "check", str(path))
    assert code == 0, err


@pytest.mark.parametrize("text, where", [
    ("x = " + "[" * 5000 + "]" * 5000 + "\n", "the profile"),  # RecursionError in tomllib
    ('[run]\nname = ' + "{a = " * 40 + "1" + "}" * 40 + "\n", "run.name.a"),
])
def test_a_deeply_nested_profile_is_refused(tmp_path, text, where):
    path = tmp_path / "deep.toml"
    path.write_text(text)
    _refused(*run_main("profile", "check", str(path)),
             f"{path}: {where}: tables or arrays nested more than 8 levels deep")


# A FIFO would block its reader forever and /dev/zero never ends: they are tried in a child
# process (with a time limit), all in one, so that a regression cannot hang the test session.
UNENDING = r"""
import json, sys
sys.path.insert(0, sys.argv[1])
from support import run_main
print(json.dumps([run_main(*args) for args in json.loads(sys.argv[2])]))
"""


def test_a_fifo_or_a_device_is_refused_without_reading_it(tmp_path):
    fifo = tmp_path / "profile.toml"
    os.mkfifo(fifo)
    out = tmp_path / "x.h5"
    commands = [["profile", "check", str(fifo)], ["profile", "check", "/dev/zero"],
                ["import", "/dev/zero", "--rate", "10", "-o", str(out)], ["show", "/dev/zero"],
                ["analyze", "/dev/zero"], ["import", str(fifo), "--rate", "10", "-o", str(out)]]
    proc = subprocess.run([sys.executable, "-c", UNENDING, str(Path(__file__).parent),
                           json.dumps(commands)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    for command, (code, out_text, err) in zip(commands, json.loads(proc.stdout)):
        name = command[2] if command[0] == "profile" else command[1]
        kind = "a FIFO (named pipe)" if name == str(fifo) else "a character device"
        _refused(code, out_text, err, f"{name}: is {kind}, not a regular file; expected")
    assert not out.exists()


def test_a_directory_is_refused(tmp_path):
    _refused(*run_main("profile", "check", str(tmp_path)), f"{tmp_path}: is a directory")


def test_a_csv_field_over_the_csv_module_limit_is_refused(tmp_path):
    path = tmp_path / "big.csv"
    path.write_text("tip [m/s]\n" + "1" * 140000 + "\n2\n")
    out = tmp_path / "out.h5"
    _refused(*run_main("import", str(path), "--rate", "10", "-o", str(out)),
             f"{path}: line 2: field larger than field limit (131072)",
             "expected a CSV file (UTF-8, or Windows-1252)")
    assert not out.exists()
