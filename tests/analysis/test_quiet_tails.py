"""Records that end in a long quiet tail (the acquisition stopped late): the padding predictor
on silent stretches, and the analysis of a long-tailed record against its short head."""

from __future__ import annotations

import numpy as np
import pytest

from fsi_lab.dsp._signal import ar_extend, predict_pad


@pytest.fixture
def numpy_strict():
    """numpy's warnings of a division by zero, an invalid value or an overflow raise."""
    with np.errstate(divide="raise", invalid="raise", over="raise"):
        yield


@pytest.mark.parametrize("name, stretch, level", [
    ("all zero", np.zeros(4000), 0.0),
    ("a constant offset (a simulated velocity after its decay)", np.full(4000, 6.4e-15), 6.4e-15),
    ("subnormal numbers (a decay gone below 1e-308)",
     1e-310 * np.cos(0.1 * np.arange(4000)), None),
])
def test_the_predictor_holds_a_silent_stretch_without_dividing_by_zero(numpy_strict, name,
                                                                      stretch, level):
    """Kumaresan-Tufts prediction (rank given) and the ridge form both: the normal matrix of
    a silent stretch has zero eigenvalues, which must not be divided by."""
    for rank in (6, None):
        ext = ar_extend(stretch, 500, 12, 10, 2000, rank=rank)
        assert ext.shape == (500,) and np.all(np.isfinite(ext)), name
        expected = float(np.mean(stretch)) if level is None else level
        np.testing.assert_allclose(ext, expected, rtol=1e-12, atol=1e-300)


def test_a_decay_that_dies_into_silence_is_padded_without_numpy_warnings(numpy_strict):
    """Two decaying tones that stop dead after 12 s of a 20 s record: the end stretch the
    predictor is fitted on is all zero; the start is padded from the decay as before."""
    fs = 2000.0
    t = np.arange(int(20 * fs)) / fs
    x = np.exp(-3 * t) * np.cos(2 * np.pi * 8 * t) + 0.3 * np.exp(-3 * t) \
        * np.cos(2 * np.pi * 27 * t + 1)
    x[t > 12] = 0.0
    padded = predict_pad(x, fs, np.array([8.0, 27.0]), 1000, 1000, rank=6)
    assert np.all(np.isfinite(padded))
    np.testing.assert_array_equal(padded[-1000:], 0.0)
    np.testing.assert_array_equal(padded[1000:-1000], x)
    # The head continues the decay backwards: larger than the first samples, and smooth.
    assert np.max(np.abs(padded[500:1000])) > np.max(np.abs(x[:200]))


# ----------------------------------------------------------------------------- the envelope
def _decay_and_noise(fs=2000.0, total=40.0, noise=1e-4, rate=2.0, seed=7):
    """A 17 Hz decay of amplitude 1 that dies into white noise of ``noise`` RMS."""
    t = np.arange(int(total * fs)) / fs
    x = np.exp(-rate * t) * np.cos(2 * np.pi * 17.0 * t)
    return t, x + noise * np.random.default_rng(seed).standard_normal(t.size)


def test_the_floor_is_the_noise_of_a_flat_tail_and_the_active_span_ends_where_it_is_reached():
    from fsi_lab.dsp.envelope import active_blocks, block_envelope, envelope_floor

    fs, noise, rate = 2000.0, 1e-4, 2.0
    t, x = _decay_and_noise(fs, noise=noise, rate=rate)
    env = block_envelope(x, 100)                      # 0.05 s blocks
    floor = envelope_floor(env)
    # The half range of 100 samples of Gaussian noise: about 2.5 sigma (median of its maximum).
    assert 2.0 * noise < floor < 3.2 * noise
    end = active_blocks(env) * 100 / fs
    # The decay e^{-2 t} crosses 3 x the floor (0.7 to 1e-3) between 3.3 and 3.6 s; a block of
    # its cycle (half range up to the amplitude) or the noise on it moves the end by a block.
    crossing = np.log(1.0 / (3.0 * floor)) / rate
    assert crossing - 0.1 <= end <= crossing + 0.15


@pytest.mark.parametrize("name, x, cut", [
    ("a decay that never reaches its noise (no tail)",
     np.exp(-0.1 * np.arange(80000) / 2000) * np.cos(2 * np.pi * 17 * np.arange(80000) / 2000)
     + 1e-4 * np.random.default_rng(1).standard_normal(80000), False),
    ("a light decay, 1/e over the record (its last quarter looks flat, but it never rises "
     "100-fold above it)",
     np.exp(-np.arange(80000) / 80000) * np.cos(0.3 * np.arange(80000)), False),
    ("a quadratic-law decay A0 / (1 + 100 t / T)",
     np.cos(0.3 * np.arange(80000)) / (1 + 100 * np.arange(80000) / 80000), False),
    ("white noise only", np.random.default_rng(2).standard_normal(80000), False),
    ("a silent channel", np.zeros(80000), False),
    ("a decay into noise", _decay_and_noise()[1], True),
])
def test_only_a_long_tail_at_the_floor_is_cut(name, x, cut):
    from fsi_lab.tails import KEEP_FACTOR, analysed_end

    tail = analysed_end([(x, 2000.0)])
    assert tail.record_s == pytest.approx(40.0)
    assert tail.cut is cut, name
    if cut:
        assert tail.analysed_s == pytest.approx(KEEP_FACTOR * tail.active_s)
        assert "quiet tail" in tail.note() and f"{tail.analysed_s:.4g} s of 40 s" in tail.note()


def test_the_envelope_of_a_run_file_dataset_read_in_chunks_is_that_of_the_array(tmp_path,
                                                                                monkeypatch):
    import h5py

    from fsi_lab.dsp import envelope

    monkeypatch.setattr(envelope, "CHUNK", 1000)      # 10 reads of 7 blocks, and a short end
    _, x = _decay_and_noise(total=5.0)
    x = x[:9999]
    with h5py.File(tmp_path / "x.h5", "w") as f:
        f.create_dataset("x", data=x, chunks=(512,))
        from_file = envelope.block_envelope(f["x"], 140)
    expected = [0.5 * (np.ptp(x[i:i + 140])) for i in range(0, x.size, 140)]
    np.testing.assert_array_equal(from_file, expected)
    assert from_file.size == 72


def test_rounding_junk_below_the_floor_starts_no_decay():
    """A decay whose end sinks into a simulation's rounding junk, with a 100-fold rise in the
    junk (1e-12 of the peak): one decay, as the record holds one excitation."""
    from fsi_lab.dsp.decays import decay_segments

    fs = 2000.0
    t = np.arange(int(20 * fs)) / fs
    x = np.exp(-3.0 * t) * np.cos(2 * np.pi * 17.0 * t)
    junk = 1e-14 * np.cos(2 * np.pi * 17.0 * t)
    junk[(t > 14) & (t < 15)] *= 100.0
    x = np.where(t > 10, junk, x)
    assert decay_segments(x, fs, 1 / 17.0) == [(0, x.size)]


# ----------------------------------------------------------------------------- the chain
@pytest.fixture(scope="module")
def long_tailed_run(tmp_path_factory):
    """The wet profile's simulated record, 60 s at 2 kHz: its decay is at rounding level after
    about 15 s (a noise-free simulation), the rest is a quiet tail."""
    return _simulated(tmp_path_factory.mktemp("tail") / "long.h5", 60.0, 2000.0)


def _simulated(out, duration, rate):
    """The registry, the wet profile and what `fsi-lab simulate` writes for it to ``out``
    (``duration`` s at ``rate`` Hz), read back."""
    from support import PROFILES

    from fsi_lab.preflight import prepare_excitation
    from fsi_lab.profile import load_profile
    from fsi_lab.registry import load_registry
    from fsi_lab.runfile import read_run
    from fsi_lab.simulation import simulate_run

    registry = load_registry()
    profile = load_profile(PROFILES / "wet-beam-sim.toml", registry)
    waveform, waveform_rate = prepare_excitation(profile, registry)
    simulate_run(profile, waveform, waveform_rate, duration, rate, out, None,
                 {"uuid": "0" * 32, "start_time": "2026-11-24T00:00:00.000000+00:00"})
    return registry, profile, read_run(out)


def _identified(registry, profile, run, seconds):
    import dataclasses
    import warnings

    from fsi_lab.chain import run_chain

    n = int(seconds * 2000)
    channels = {name: dataclasses.replace(c, data=c.data[:n]) for name, c in run.channels.items()}
    analysis = {**profile.analysis, "chain": ["hvd", "equivalent-damping"]}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        groups, summary = run_chain(channels, analysis, profile.analysis_params, registry,
                                    profile.specimen)
    assert not [str(w.message) for w in caught]      # numpy's included: none at all
    return groups, summary["tip_velocity"]


def test_a_long_quiet_tail_changes_nothing_the_analysis_identifies(long_tailed_run):
    """The whole 60 s record and its first 20 s are both analysed up to 3 x the 5.75 s over
    which the record is above 1e-7 of its peak: the same modes, C_i and C_f to the bit, with
    no warning from numpy; the truth (C_i = 0.65, C_f = 33.0) is inside the dominant mode's
    intervals (17.06 Hz, the spectrum's highest peak; C_i within 0.5 %: a noise-free record,
    whose start the component is warned moves its C_i and C_f)."""
    registry, profile, run = long_tailed_run
    groups, whole = _identified(registry, profile, run, 60.0)
    _, head = _identified(registry, profile, run, 20.0)
    assert "errors" not in whole and "errors" not in head
    assert whole["notes"][0].startswith("the record's last 42.75 s are a quiet tail")
    assert groups["tip_velocity/hvd"]["attrs"]["analysed_s"] == pytest.approx(17.25)
    assert groups["tip_velocity/hvd"]["datasets"]["components"].shape[1] == 17.25 * 2000
    assert len(whole["components"]) == len(head["components"]) == 2
    for a, b in zip(whole["components"], head["components"]):
        assert a["frequency_hz"] == b["frequency_hz"]
        assert a["equivalent_damping"] == b["equivalent_damping"]
    first = whole["components"][0]      # the mode with the spectrum's highest peak
    assert first["frequency_hz"] == pytest.approx(17.06, abs=0.01)
    ci, cf = (first["equivalent_damping"][f"{k}_ci95"] for k in ("c_i", "c_f"))
    assert first["equivalent_damping"]["c_i"] == pytest.approx(0.65, rel=5e-3)
    assert ci[0] < 0.65 < ci[1] and cf[0] < 33.0 < cf[1]


@pytest.fixture(scope="module")
def noise_free_run(tmp_path_factory):
    """What `fsi-lab simulate profiles/wet-beam-sim.toml --duration 20 --rate 10000` writes: the
    wet bench's pulse and its noise-free decay (a relative signal whose end holds the base
    integration's residue, about 4e-7 of the record's peak)."""
    return _simulated(tmp_path_factory.mktemp("noise-free") / "sim.h5", 20.0, 10000.0)


def test_a_noise_free_simulation_gives_each_beam_mode_its_c_i_and_c_f(noise_free_run):
    """Every mode found is analysed (components = "auto"): the beam's modes at 17.06, 47.8 and
    93.6 Hz each give C_i within 0.5 % and C_f within 3 % of the model's 0.65 and 33.0 (measured
    0.6500 / 33.01, 0.6500 / 32.94, 0.6501 / 32.9), their damped frequencies within 0.1 % of
    their spectral peaks. Before, the processing's own residue (the end prediction, a "decay"
    split off the relative signal's end) counted as signal: 5.7, 33.7 and 78.2 Hz with C_f
    of -420, -78 and 250. A component whose frequency leaves its spectral peak by more than 5 %
    must say so; the 2.7 Hz mode, whose band holds the base integration's residue (the
    high-passed base velocity is not the base's motion that far down), reads C_i 0.60 with an
    interval of +-54 % and must warn of it."""
    import dataclasses

    from fsi_lab.chain import run_chain

    registry, profile, run = noise_free_run
    n = int(17.25 * 10000)             # the record up to its quiet tail (3 x 5.75 s)
    channels = {name: dataclasses.replace(c, data=c.data[:n]) for name, c in run.channels.items()}
    analysis = {**profile.analysis, "chain": ["hvd", "equivalent-damping"]}
    params = {**profile.analysis_params,
              "hvd": {**profile.analysis_params.get("hvd", {}), "components": None}}
    _, summary = run_chain(channels, analysis, params, registry, profile.specimen)
    components = summary["tip_velocity"]["components"]
    beam = {}
    for c in components:
        peak = c["spectral_peak_hz"]
        if abs(c["damped_frequency_hz"] / peak - 1.0) > 0.05:
            assert any("disagrees with the spectral peak" in w for w in c["warnings"]), c
        if abs(peak / 2.67 - 1.0) < 0.02:
            assert any(w.startswith("C_i is") for w in c["warnings"]), c
        for f in (17.06, 47.8, 93.6):
            if abs(peak / f - 1.0) < 0.01:
                beam[f] = c
    assert sorted(beam) == [17.06, 47.8, 93.6]
    for f, c in beam.items():
        damping = c["equivalent_damping"]
        assert c["damped_frequency_hz"] == pytest.approx(c["spectral_peak_hz"], rel=1e-3)
        assert damping["c_i"] == pytest.approx(0.65, rel=5e-3), f
        assert damping["c_f"] == pytest.approx(33.0, rel=3e-2), f
