"""Re-analysing a run file: ``/analysis`` is replaced by rewriting the file, so the file keeps
its size over any number of analyses (also one grown by older versions, which modified it in
place), everything else is carried over exactly, and a failure or a ``kill -9`` at any moment of
the rewrite leaves the run file as it was, readable by h5py and h5dump."""

import os
import shutil
import signal
import subprocess
import sys

import h5py
import numpy as np
import pytest
from support import GOOD_PROFILE, ROOT, run_main

from fsi_lab.errors import AnalysisError
from fsi_lab.runfile import RunFileWriter, read_analysis_summary, read_run, write_analysis

#: The file may differ from its size after the first analysis by this fraction at most.
TOLERANCE = 0.05


@pytest.fixture(scope="module")
def analysed(tmp_path_factory):
    """A 2 s simulated record of the wet beam (the demo profile), analysed once: the file and
    its size after that first analysis, bytes."""
    path = tmp_path_factory.mktemp("reanalysis") / "sim.h5"
    code, _, err = run_main("simulate", str(GOOD_PROFILE), "--duration", "2", "--rate", "5000",
                            "-o", str(path))
    assert code == 0, err
    code, _, err = run_main("analyze", str(path), "--quiet")
    assert code == 0, err
    return path, path.stat().st_size


def _content(path):
    """Everything of a run file but ``/analysis``, as comparable values: every node's kind and
    attributes (value and encoded HDF5 type), and each dataset's type, layout and data."""
    def attributes(node):
        return {name: (repr(node.attrs[name]),
                       h5py.h5a.open(node.id, name.encode()).get_type().encode())
                for name in node.attrs}

    content = {}
    with h5py.File(path, "r") as handle:
        content["/"] = attributes(handle)

        def visit(name, node):
            if name == "analysis" or name.startswith("analysis/"):
                return
            entry = {"attrs": attributes(node), "kind": type(node).__name__}
            if isinstance(node, h5py.Dataset):
                entry.update(dtype=node.dtype.str, chunks=node.chunks, maxshape=node.maxshape,
                             compression=node.compression, data=node[()].tobytes())
            content[name] = entry

        handle.visititems(visit)
    return content


def _h5dump(path):
    h5dump = shutil.which("h5dump")
    assert h5dump, "h5dump (hdf5-tools) is needed; `make test` installs it"
    return subprocess.run([h5dump, "-A", str(path)], capture_output=True, text=True, check=False,
                          timeout=60)


def _rewrites(path):
    """What rewrites of ``path`` left in its folder."""
    return sorted(path.parent.glob(f".{path.name}.*.rewrite"))


def _reanalyse_in_place(path):
    """What fsi-lab did before it rewrote files: the new ``/analysis`` written beside the old
    in the same file, the old deleted, the new renamed (HDF5 does not reuse the freed space)."""
    with h5py.File(path, "r+") as handle:
        handle.copy(handle["analysis"], "analysis.new")
        del handle["analysis"]
        handle.move("analysis.new", "analysis")


def test_repeated_analyses_keep_the_file_size_and_the_record(analysed, tmp_path):
    """Five analyses of the 2 s record: modified in place, each added its results' size to
    the file (measured: 1.7, 2.4, 3.1 and 3.8 times the size after the first)."""
    original, first = analysed  # analysed once
    path = tmp_path / "run.h5"
    shutil.copy(original, path)
    before = _content(path)
    sizes = []
    for _ in range(4):
        code, _, err = run_main("analyze", str(path), "--quiet")
        assert code == 0, err
        sizes.append(path.stat().st_size)
    assert all(abs(size / first - 1) <= TOLERANCE for size in sizes), (first, sizes)
    assert _content(path) == before  # the record, the profile and the model, exactly
    assert read_analysis_summary(path)["channels"]["tip_velocity"]["components"]
    assert _rewrites(path) == []
    dump = _h5dump(path)
    assert dump.returncode == 0, dump.stderr
    assert '"completed"' in dump.stdout and "tip_velocity" in dump.stdout


def test_a_file_grown_by_in_place_analyses_shrinks_back(analysed, tmp_path):
    original, first = analysed
    path = tmp_path / "old.h5"
    shutil.copy(original, path)
    for _ in range(3):
        _reanalyse_in_place(path)
    with h5py.File(path, "r+") as handle:  # and an older version killed while writing
        handle.copy(handle["analysis"], "analysis.new")
    assert path.stat().st_size > 2 * first  # what the issue was about
    before = _content(path)
    code, _, err = run_main("analyze", str(path), "--quiet")
    assert code == 0, err
    assert abs(path.stat().st_size / first - 1) <= TOLERANCE, (first, path.stat().st_size)
    with h5py.File(path, "r") as handle:
        assert "analysis.new" not in handle
    assert {k: v for k, v in _content(path).items() if not k.startswith("analysis.new")} == {
        k: v for k, v in before.items() if not k.startswith("analysis.new")}


def test_a_failure_while_writing_the_results_leaves_the_file_as_it_was(analysed, tmp_path):
    original, _ = analysed
    path = tmp_path / "run.h5"
    shutil.copy(original, path)
    data = path.read_bytes()
    groups = {"tip_velocity/spectrum": {"datasets": {"frequency": np.arange(1e5)}},
              "tip_velocity/bad": {"datasets": {"x": np.array([object()])}}}
    with pytest.raises(AnalysisError, match=r"/analysis/tip_velocity/bad/x: the analysis "
                                            r"result cannot be stored \(TypeError.*previous"):
        write_analysis(path, groups, {"channels": {}})
    assert path.read_bytes() == data
    assert _rewrites(path) == []


KILLED = r"""
import os, signal, sys
import numpy as np
from fsi_lab import runfile

path, moment = sys.argv[1], sys.argv[2]


def die(*args, **kwargs):
    os.kill(os.getpid(), signal.SIGKILL)


class Dies:
    def __array__(self, dtype=None, copy=None):
        die()


groups = {"tip_velocity/spectrum": {"datasets": {"frequency": np.arange(1e5)}}}
if moment == "results":  # with the record copied and part of the results written
    groups["tip_velocity/x"] = {"datasets": {"x": Dies()}}
else:  # the rewrite complete and synced, not yet renamed
    runfile.os.replace = die
runfile.write_analysis(path, groups, {"channels": {}})
"""


@pytest.mark.parametrize("moment", ["results", "rename"])
def test_kill_9_during_the_rewrite_leaves_the_file_as_it_was(analysed, tmp_path, moment):
    original, _ = analysed
    path = tmp_path / "run.h5"
    shutil.copy(original, path)
    data = path.read_bytes()
    proc = subprocess.Popen([sys.executable, "-c", KILLED, str(path), moment], cwd=ROOT,
                            stderr=subprocess.PIPE, text=True)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == -signal.SIGKILL, err
    assert path.read_bytes() == data
    dump = _h5dump(path)
    assert dump.returncode == 0, dump.stderr
    assert read_analysis_summary(path)["channels"]["tip_velocity"]["components"]
    left = _rewrites(path)
    assert len(left) == 1 and str(proc.pid) in left[0].name  # what the killed process left
    write_analysis(path, {"tip_velocity/spectrum": {"datasets": {"frequency": np.arange(3.0)}}},
                   {"channels": {"tip_velocity": {"f": 1.0}}})
    assert _rewrites(path) == []  # removed by the next analysis, its process being gone
    assert read_analysis_summary(path)["channels"]["tip_velocity"] == {"f": 1.0}
    np.testing.assert_array_equal(read_run(path).channels["tip_velocity"].data,
                                  read_run(original).channels["tip_velocity"].data)


@pytest.fixture
def small_run(tmp_path):
    path = tmp_path / "small.h5"
    writer = RunFileWriter(path, {"uuid": "0" * 32, "kind": "measured", "profile": "[run]\n",
                                  "stopped_early": False})
    writer.create_channel("v", {"units": "m/s", "quantity": "velocity", "sample_rate": 100.0})
    writer.append("v", np.arange(1000.0))
    writer.set_attrs({"exit_status": "completed"})
    writer.close()
    return path


def test_the_rewrite_keeps_permissions_links_and_foreign_nodes(small_run, tmp_path):
    with h5py.File(small_run, "r+") as handle:  # what a user may have added
        handle.create_group("notes").attrs["operator"] = "A. N."
        handle["notes"]["alias"] = h5py.SoftLink("/channels/v")
    os.chmod(small_run, 0o640)
    link = tmp_path / "link.h5"
    link.symlink_to(small_run.name)
    before = _content(small_run)
    write_analysis(link, {"v/a": {"datasets": {"x": np.arange(3.0)}}}, {"channels": {}})
    assert link.is_symlink() and os.readlink(link) == small_run.name
    assert small_run.stat().st_mode & 0o777 == 0o640
    assert _content(small_run) == before
    with h5py.File(small_run, "r") as handle:
        assert handle["notes"].get("alias", getlink=True).path == "/channels/v"
        assert handle.attrs["stopped_early"].dtype == np.bool_  # HDF5's enum, kept as such
        np.testing.assert_array_equal(handle["analysis/v/a/x"][()], np.arange(3.0))
