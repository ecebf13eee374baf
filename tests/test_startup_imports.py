"""The everyday commands load only what they use (issue 14, "start-up in a blink").

``fsi-lab --help``, ``profile check``, ``plugins`` and ``safe`` must not load the analysis
(scipy), the compiled integrator (numba), the run-file library (h5py) or the GUI (Qt,
pyqtgraph); ``safe`` talks to its instruments through pyvisa and pyserial, ``show`` reads its
file with h5py, and neither needs more. Each of those libraries takes a good part of a second
to import, so a command that loads one no longer starts in a blink.

Not a timing test: each command runs in a fresh interpreter which, once the command is done,
writes down which of those libraries it imported.
"""

import json
import math
import subprocess
import sys

import pytest
from support import GOOD_PROFILE, ROOT, cli

#: Libraries that are slow to import, by top-level module name.
HEAVY = ("scipy", "numba", "h5py", "PySide6", "pyqtgraph", "pyvisa", "pyvisa_py", "serial")

#: Runs ``fsi_lab.cli.main(ARGS)`` and writes the HEAVY modules then loaded to the file OUT:
#: ``python -c PROBE OUT ARGS...``.
PROBE = """
import json, sys
from fsi_lab.cli import main
try:
    code = main(sys.argv[2:])
except SystemExit as exc:  # --help
    code = exc.code
heavy = json.loads({heavy!r})
loaded = sorted({{name.split(".")[0] for name in sys.modules}} & set(heavy))
with open(sys.argv[1], "w") as out:
    json.dump({{"code": code, "loaded": loaded}}, out)
""".format(heavy=json.dumps(HEAVY))


def loaded_by(tmp_path, *args: str) -> tuple[int, set[str]]:
    """Exit code of ``fsi-lab ARGS`` and the HEAVY libraries it imported."""
    out = tmp_path / "loaded.json"
    proc = subprocess.run([sys.executable, "-c", PROBE, str(out), *args], capture_output=True,
                          text=True, timeout=240, cwd=ROOT)
    assert out.exists(), proc.stderr
    found = json.loads(out.read_text())
    return found["code"], set(found["loaded"])


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    """A small run file, made by ``fsi-lab import``."""
    folder = tmp_path_factory.mktemp("startup")
    csv_path = folder / "decay.csv"
    rows = [f"{0.01 * math.exp(-k / 400) * math.sin(k / 5):.6g}" for k in range(4000)]
    csv_path.write_text("tip_velocity [m/s]\n" + "\n".join(rows) + "\n")
    out = folder / "decay.h5"
    proc = cli("import", str(csv_path), "--rate", "1000", "-o", str(out))
    assert proc.returncode == 0, proc.stderr
    return out


@pytest.mark.parametrize("args, allowed", [
    (("--help",), set()),
    (("profile", "check", str(GOOD_PROFILE)), set()),
    (("profile", "check", str(GOOD_PROFILE), "--json"), set()),
    (("plugins", "--json"), set()),
    (("safe", str(GOOD_PROFILE)), {"pyvisa", "pyvisa_py", "serial"}),
], ids=["help", "profile-check", "profile-check-json", "plugins", "safe"])
def test_a_command_loads_only_what_it_uses(tmp_path, args, allowed):
    code, loaded = loaded_by(tmp_path, *args)
    assert code == 0
    assert loaded <= allowed, f"fsi-lab {' '.join(args)} imported {sorted(loaded - allowed)}"


def test_show_reads_its_file_with_h5py_alone(tmp_path, run_file):
    code, loaded = loaded_by(tmp_path, "show", str(run_file))
    assert code == 0
    assert loaded == {"h5py"}


def test_the_probe_sees_what_a_command_loads(tmp_path, run_file):
    """The analysis does load scipy: were the probe blind, the tests above would pass for
    nothing."""
    _, loaded = loaded_by(tmp_path, "analyze", str(run_file), "--mass-per-length", "0.02")
    assert {"scipy", "h5py"} <= loaded


def test_simulate_loads_the_integrator_and_h5py_but_no_signal_processing(tmp_path):
    """``simulate`` needs numba (the integrator and the shaker's filters), h5py (the run file)
    and numpy; not scipy.signal (a second or more to import), the analysis or the instruments
    (scipy.linalg comes with numba)."""
    probe = ("import json, sys\n"
             "from fsi_lab.cli import main\n"
             "code = main(sys.argv[2:])\n"
             "json.dump({'code': code, 'modules': sorted(sys.modules)}, open(sys.argv[1], 'w'))\n")
    out = tmp_path / "modules.json"
    proc = subprocess.run([sys.executable, "-c", probe, str(out), "simulate", str(GOOD_PROFILE),
                           "--duration", "2", "--rate", "5000", "-o", str(tmp_path / "s.h5"),
                           "--quiet"], capture_output=True, text=True, timeout=240, cwd=ROOT)
    assert out.exists(), proc.stderr
    found = json.loads(out.read_text())
    assert found["code"] == 0
    modules = set(found["modules"])
    assert {"numba", "h5py", "fsi_lab.modal_integrator", "fsi_lab.biquad"} <= modules
    unwanted = ("scipy.signal", "scipy.stats", "scipy.integrate", "scipy.interpolate",
                "fsi_lab.dsp.identify", "pyvisa", "serial", "PySide6")
    assert not [m for m in modules if m.startswith(unwanted)]
