"""Run files really damaged: by h5py edits (nodes deleted, replaced or linked away, attributes
changed to other types and values) and by their bytes (bits flipped, cut short, zeroed), given
to ``fsi-lab show`` and ``fsi-lab analyze``: exit 0, or exit 2 with one message naming the
file and nothing written to it; never a traceback, a crash or a hang."""

import shutil

import h5py
import numpy as np
import pytest
from fuzzkit import EDGE_FLOATS, EDGE_INTS, FUZZ, check_command, tally, texts
from hypothesis import given, settings
from hypothesis import strategies as st
from support import SIM_PROFILE, run_main

EDIT_CASES = 120
BYTE_CASES = 80


@pytest.fixture(scope="module")
def originals(tmp_path_factory, loaded_once):
    """A measured run (in-process bench, analysed) and imported data, to damage."""
    folder = tmp_path_factory.mktemp("originals")
    profile = folder / "sim.toml"
    profile.write_text(SIM_PROFILE.format(
        duration=0.5, realtime="false", amplitude=0.5, amplifier_extra="", acquisition_extra="",
        analysis='[analysis]\nchain = ["spectrum"]\nchannels = ["tip_velocity"]\n'))
    code, _, err = run_main("run", str(profile), "--out", str(folder / "runs"))
    assert code == 0, err
    csv = folder / "rec.csv"
    t = np.arange(400) / 200.0
    csv.write_text("time [s],tip [m/s],base [g]\n" + "\n".join(
        f"{a},{b},{c}" for a, b, c in zip(t, np.sin(9 * t), np.cos(3 * t))))
    code, _, err = run_main("import", str(csv), "-o", str(folder / "imported.h5"),
                            "--reference", "base")
    assert code == 0, err
    return [next((folder / "runs").glob("*.h5")), folder / "imported.h5"]


def _nodes(handle):
    names = []
    handle.visit(names.append)
    return ["/"] + ["/" + name for name in names]


attribute_values = st.one_of(
    texts.map(lambda text: text.replace("\x00", "")),  # (HDF5 strings cannot hold NUL)
    st.sampled_from(EDGE_FLOATS), st.sampled_from([i for i in EDGE_INTS if abs(i) < 2**63]),
    st.sampled_from(['{"a": 1', "[1, 2]", '{"channels": 5}', "null", "[" * 40 + "]" * 40,
                     "fsi-lab run", "velocity", "m/s"]),
    st.binary(max_size=8).map(np.void), st.booleans(),
    st.sampled_from([np.zeros(3), np.array([b"a", b"b"]), h5py.Empty("f8"), np.ones((2, 2))]))
datasets = st.sampled_from([np.zeros((4, 2)), np.array([b"x", b"y"]), np.ones(50, complex),
                            np.zeros(0), np.float64(3.0), np.arange(10), np.ones(5, bool),
                            np.full(20, np.nan)])


def _edit(draw, handle):
    """One damage done with h5py to a random node (or nothing, when HDF5 itself refuses to do
    it, e.g. a link whose name is taken)."""
    nodes = _nodes(handle)
    path = draw(st.sampled_from(nodes))
    node = handle[path]
    operation = draw(st.sampled_from(["attr", "attr", "attr", "del_attr", "delete", "replace",
                                      "link", "move"]))
    try:
        if operation == "attr":
            keys = list(node.attrs) + ["sample_rate", "t0", "quantity", "units", "summary",
                                       "profile", "overrides", "reference", "format"]
            node.attrs[draw(st.sampled_from(keys))] = draw(attribute_values)
        elif operation == "del_attr" and len(node.attrs):
            del node.attrs[draw(st.sampled_from(sorted(node.attrs)))]
        elif operation == "delete" and path != "/":
            del handle[path]
        elif operation == "replace" and path != "/":
            del handle[path]
            if draw(st.booleans()):
                handle.create_group(path)
            else:
                handle.create_dataset(path, data=draw(datasets))
        elif operation == "link":
            group = node if isinstance(node, h5py.Group) else node.parent
            target = draw(st.sampled_from(nodes + ["/nowhere"]))
            group[draw(st.sampled_from(["ghost", "x"]))] = \
                h5py.ExternalLink("/etc/hostname", "/x") if draw(st.booleans()) \
                else h5py.SoftLink(target)
        elif operation == "move" and path != "/":
            handle.move(path, path + "_moved")
    except (KeyError, OSError, RuntimeError, TypeError, ValueError):
        pass  # HDF5 would not make this damage


def _commands(draw, path):
    commands = [["show", str(path)] + draw(st.sampled_from([[], ["--json"]]))]
    if draw(st.integers(0, 2)) == 2:
        commands.append(["analyze", str(path), "--set", "analysis.chain=spectrum"]
                        + draw(st.sampled_from([[], ["--json"]])))
    return commands


def _check(path, commands):
    for args in commands:
        if args[0] == "show":  # show never writes
            check_command(args, named=[str(path)], inputs=[path])
        else:  # analyze writes its results into the file, only when it accepts the file
            before = path.read_bytes()
            code = check_command(args, named=[str(path)])
            assert code == 0 or path.read_bytes() == before, args


def test_run_files_damaged_by_edits_are_read_or_refused(tmp_path, originals):
    count = [0]

    @settings(FUZZ, max_examples=EDIT_CASES)
    @given(st.data())
    def case(data):
        path = tmp_path / "damaged.h5"
        shutil.copy(data.draw(st.sampled_from(originals)), path)
        with h5py.File(path, "r+") as handle:
            for _ in range(data.draw(st.integers(1, 3))):
                _edit(data.draw, handle)
        _check(path, _commands(data.draw, path))
        count[0] += 1  # (a case whose draws ran out of data is abandoned before this line)

    case()
    tally("run files (h5py edits)", count[0], EDIT_CASES)


def test_run_files_damaged_in_their_bytes_are_read_or_refused(tmp_path, originals):
    count = [0]

    @settings(FUZZ, max_examples=BYTE_CASES)
    @given(st.data())
    def case(data):
        raw = bytearray(data.draw(st.sampled_from(originals)).read_bytes())
        operation = data.draw(st.sampled_from(["flip", "flip", "cut", "zero"]))
        if operation == "flip":  # mostly in the metadata at the start of the file
            for _ in range(data.draw(st.integers(1, 8))):
                end = 8192 if data.draw(st.booleans()) else len(raw)
                raw[data.draw(st.integers(0, end - 1))] ^= 1 << data.draw(st.integers(0, 7))
        elif operation == "cut":
            raw = raw[:data.draw(st.integers(0, len(raw) - 1))]
        else:
            start = data.draw(st.integers(0, len(raw) - 1))
            raw[start:start + 64] = bytes(len(raw[start:start + 64]))
        path = tmp_path / "damaged.h5"
        path.write_bytes(bytes(raw))
        _check(path, _commands(data.draw, path))
        count[0] += 1

    case()
    tally("run files (bytes)", count[0], BYTE_CASES)
