"""`fsi-lab safe` and `fsi-lab identify`: the bench's instruments outside a run."""

import time

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


class _Amplifier:
    """An amplifier whose first ``bad_attempts`` safe states fail (a link that hiccups) or, with
    ``stuck``, whose output never goes off."""

    def __init__(self, bad_attempts=0, stuck=False):
        self.bad_attempts, self.stuck = bad_attempts, stuck
        self.attempts, self.output, self.closed = 0, True, False

    def safe_state(self):
        self.attempts += 1
        if self.attempts <= self.bad_attempts:
            raise TimeoutError("no reply within 2 s")
        self.output = self.stuck

    def read_state(self):
        return {"output_enabled": self.output}

    def close(self):
        self.closed = True


def test_a_failed_safe_state_gets_a_second_attempt():
    from fsi_lab.bench_access import safe_and_close, unsafe_roles

    hiccup, logs = _Amplifier(bad_attempts=1), []
    states = safe_and_close({"amplifier": hiccup}, [], lambda level, text: logs.append(text))
    assert hiccup.attempts == 2 and hiccup.closed
    assert states == {"amplifier": {"output_enabled": False}} and unsafe_roles(states) == {}
    assert any("trying once more" in text for text in logs)


def test_an_output_that_stays_on_is_not_confirmed_safe():
    from fsi_lab.bench_access import safe_and_close, unsafe_roles

    for amplifier, why in ((_Amplifier(stuck=True), "still on after two attempts"),
                           (_Amplifier(bad_attempts=2), "TimeoutError: no reply")):
        states = safe_and_close({"amplifier": amplifier}, [])
        assert amplifier.attempts == 2 and amplifier.closed
        assert why in unsafe_roles(states)["amplifier"]


class _Forgetful(_Amplifier):
    """A third-party driver whose state read back forgets ``output_enabled``."""

    def read_state(self):
        return {"gain": 0.0}


def test_an_output_whose_state_does_not_say_it_is_off_is_not_confirmed_safe():
    from fsi_lab.bench_access import safe_and_close, unsafe_roles

    for role in ("amplifier", "source"):
        forgetful = _Forgetful()
        states = safe_and_close({role: forgetful}, [])
        assert forgetful.attempts == 2
        assert "does not say that the output is off" in unsafe_roles(states)[role]
    states = safe_and_close({"vibrometer": _Forgetful()}, [])  # no output to confirm
    assert unsafe_roles(states) == {}


def test_ctrl_c_waits_until_every_instrument_is_safe(sim_profile):
    import json
    import signal
    import socket
    import threading

    from support import LineReader, start_cli

    # an amplifier that accepts the connection and never answers
    mute = socket.socket()
    mute.bind(("127.0.0.1", 0))
    mute.listen()
    connections = []
    threading.Thread(target=lambda: connections.append(mute.accept()), daemon=True).start()
    address = f"TCPIP0::127.0.0.1::{mute.getsockname()[1]}::SOCKET"
    proc = start_cli("safe", str(sim_profile()), "--json",
                     "--set", "bench.amplifier.plugin=shaker-amplifier",
                     "--set", f"bench.amplifier.address={address}",
                     "--set", "bench.amplifier.timeout_s=3")
    try:
        stderr = LineReader(proc.stderr)
        deadline = time.monotonic() + 30
        while not connections and time.monotonic() < deadline:
            time.sleep(0.05)
        assert connections, "the amplifier was never opened"
        proc.send_signal(signal.SIGINT)  # while the amplifier keeps everything waiting
        assert proc.wait(timeout=60) == 130
        data = json.loads(proc.stdout.read())
    finally:
        proc.kill()
        proc.wait(timeout=10)
        mute.close()
        for connection, _ in connections:
            connection.close()
    assert data["interrupted"] is True and "amplifier" in data["failed"]
    # the instruments after the hung amplifier were still made safe
    assert data["instruments"]["source"]["state"] == {"output_enabled": False, "level_v": 0.0}
    stderr.wait_for(lambda line: "every instrument was still made safe" in line, timeout=10)
