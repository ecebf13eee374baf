"""Files named on the command line that are not what they claim: each is refused with one
message naming the file and what is accepted (exit 2), without hanging or a traceback."""

import os

import pytest

from support import GOOD_PROFILE, cli, run_main


def _refused(code, out, err, *fragments):
    assert code == 2, (code, out, err)
    assert "Traceback" not in err and err.count("fsi-lab: error:") == 1, err
    for fragment in fragments:
        assert fragment in err, err


@pytest.mark.parametrize("encode, fragment", [
    (lambda text: text.encode("utf-16"), "not UTF-8 text (byte 0xff at offset 0)"),
    (lambda text: text.replace("# ", "# caf\u00e9 ", 1).encode("latin-1"),
     "not UTF-8 text (byte 0xe9 at offset"),
])
def test_a_profile_that_is_not_utf8_is_refused(tmp_path, encode, fragment):
    path = tmp_path / "p.toml"
    path.write_bytes(encode(GOOD_PROFILE.read_text()))
    _refused(*run_main("profile", "check", str(path)), f"{path}: {fragment}",
             "expected a profile (TOML text) saved as UTF-8")


def test_a_profile_with_a_utf8_byte_order_mark_is_read(tmp_path):
    path = tmp_path / "p.toml"
    path.write_bytes(b"\xef\xbb\xbf" + GOOD_PROFILE.read_bytes())
    code, out, err = run_main("profile", "check", str(path))
    assert code == 0, err


@pytest.mark.parametrize("text, where", [
    ("x = " + "[" * 5000 + "]" * 5000 + "\n", "the file"),  # RecursionError in tomllib
    ('[run]\nname = ' + "{a = " * 40 + "1" + "}" * 40 + "\n", "run.name.a"),
])
def test_a_deeply_nested_profile_is_refused(tmp_path, text, where):
    path = tmp_path / "deep.toml"
    path.write_text(text)
    _refused(*run_main("profile", "check", str(path)),
             f"{path}: {where}: tables or arrays nested more than 8 levels deep")


def test_a_fifo_as_the_profile_is_refused_without_waiting(tmp_path):
    fifo = tmp_path / "profile.toml"
    os.mkfifo(fifo)
    proc = cli("profile", "check", str(fifo), timeout=60)
    _refused(proc.returncode, proc.stdout, proc.stderr,
             f"{fifo}: is a FIFO (named pipe), not a regular file; expected a profile")


@pytest.mark.parametrize("command", [("profile", "check"), ("import", "--rate", "10", "-o", "x.h5"),
                                     ("show",), ("analyze",)])
def test_a_device_is_refused_without_reading_it(tmp_path, command):
    head, rest = command[0], command[1:]
    args = [head, *rest[:1], "/dev/zero", *rest[1:]] if head == "profile" else [head, "/dev/zero",
                                                                               *rest]
    proc = cli(*args, timeout=60, cwd=tmp_path)
    _refused(proc.returncode, proc.stdout, proc.stderr,
             "/dev/zero: is a character device, not a regular file; expected")
    assert not (tmp_path / "x.h5").exists()


def test_a_directory_is_refused(tmp_path):
    _refused(*run_main("profile", "check", str(tmp_path)), f"{tmp_path}: is a directory")


def test_a_csv_field_over_the_csv_module_limit_is_refused(tmp_path):
    path = tmp_path / "big.csv"
    path.write_text("tip [m/s]\n" + "1" * 140000 + "\n2\n")
    out = tmp_path / "out.h5"
    _refused(*run_main("import", str(path), "--rate", "10", "-o", str(out)),
             f"{path}: line 2: field larger than field limit (131072)",
             "expected a UTF-8 CSV file")
    assert not out.exists()
