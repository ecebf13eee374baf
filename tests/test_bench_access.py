"""`fsi-lab safe` and `fsi-lab identify`: the bench's instruments outside a run."""

from support import cli, cli_json


def test_identify_names_every_instrument_and_leaves_it_safe(sim_profile):
    data, proc = cli_json("identify", str(sim_profile()))
    assert proc.returncode == 0, proc.stderr
    instruments = data["instruments"]
    assert list(instruments) == ["amplifier", "source", "vibrometer", "acquisition"]
    assert all("SIM0001" in info["identity"] for info in instruments.values())
    interlocks = instruments["amplifier"]["interlocks"]
    assert "over_travel" in interlocks and not any(interlocks.values())
    assert instruments["amplifier"]["settings"]["gain"] == 2.0
    assert instruments["amplifier"]["state"]["output_enabled"] is False
    assert instruments["source"]["state"] == {"output_enabled": False, "level_v": 0.0}
    assert data["failed"] == []


def test_safe_goes_on_past_an_instrument_that_does_not_answer(sim_profile):
    # a signal generator at a port where nothing listens (port 1 on the loopback)
    dead_source = ["--set", "bench.source.plugin=keysight33500",
                   "--set", "bench.source.address=TCPIP0::127.0.0.1::1::SOCKET"]
    data, proc = cli_json("safe", str(sim_profile()), *dead_source)
    assert proc.returncode == 1
    assert data["failed"] == ["source"]
    assert "127.0.0.1::1" in data["instruments"]["source"]["error"]
    # the amplifier (first) and the others were still made safe and read back
    assert data["instruments"]["amplifier"]["state"]["output_enabled"] is False
    assert data["instruments"]["acquisition"]["state"] is not None
    text = cli("safe", str(sim_profile()), *dead_source)
    assert text.returncode == 1 and "not confirmed safe: source" in text.stderr
    assert "amplifier: safe" in text.stdout and "source: NOT confirmed safe" in text.stdout


def test_a_profile_without_instruments_is_refused(tmp_path):
    path = tmp_path / "analysis-only.toml"
    path.write_text('[analysis]\nchain = ["spectrum"]\n')
    proc = cli("safe", str(path))
    assert proc.returncode == 2 and "no instruments" in proc.stderr


def test_safe_works_when_the_rest_of_the_profile_is_wrong(sim_profile):
    # an analysis plugin and an excitation that are not installed: the bench is still reachable
    text = sim_profile().read_text().replace('plugin = "step"', 'plugin = "no-such-pulse"')
    broken = sim_profile(name="broken.toml")
    broken.write_text(text + '\n[analysis]\nchain = ["no-such-analysis"]\n')
    assert cli("run", str(broken)).returncode == 2
    data, proc = cli_json("safe", str(broken))
    assert proc.returncode == 0, proc.stderr
    assert data["instruments"]["amplifier"]["state"]["output_enabled"] is False


def test_problems_include_a_state_that_could_not_be_read():
    from fsi_lab.bench_access import problems

    report = {"amplifier": {"state": {"output_enabled": False}},
              "source": {"error": "InstrumentError: no answer"},
              "acquisition": {"state": {"error": "could not read state: no answer"}},
              "vibrometer": {"safe_state_error": "safe state failed", "state": {}}}
    assert problems(report) == {"source": "InstrumentError: no answer",
                                "acquisition": "could not read state: no answer",
                                "vibrometer": "safe state failed"}
