"""Analysis that streams (issue 16, item 1; docs/streaming-analysis.md): channels read from the
run file when used, a chunk at a time where a step needs one pass, and the same numbers as the
analysis of the channels held in memory."""

from __future__ import annotations

import json
import shutil
import tracemalloc

import numpy as np
import pytest


@pytest.fixture(scope="module")
def wet_run(tmp_path_factory):
    """The wet profile's simulated record, 8 s at 2 kHz (drive, base acceleration, tip
    velocity; the chain analyses the tip velocity against the base acceleration)."""
    from support import PROFILES

    from fsi_lab.preflight import prepare_excitation
    from fsi_lab.profile import load_profile
    from fsi_lab.registry import load_registry
    from fsi_lab.simulation import simulate_run

    registry = load_registry()
    profile = load_profile(PROFILES / "wet-beam-sim.toml", registry)
    waveform, rate = prepare_excitation(profile, registry)
    out = tmp_path_factory.mktemp("stream") / "wet.h5"
    simulate_run(profile, waveform, rate, 8.0, 2000.0, out, None,
                 {"uuid": "0" * 32, "start_time": "2026-11-25T00:00:00.000000+00:00",
                  "profile": profile.text, "profile_path": str(profile.path), "overrides": []})
    return registry, out


def _as_json(value):
    return json.loads(json.dumps(value, default=str))


def test_a_run_file_read_lazily_gives_the_numbers_of_its_channels_in_memory(wet_run, tmp_path):
    """``fsi-lab analyze``'s path (channels read from the file when first used) against the
    chain on the channels loaded whole: the same summary to the bit, and only the channels the
    chain uses are read, each once."""
    from fsi_lab import sources
    from fsi_lab.batch import AnalyseTask, analyse_file, analysis_profile
    from fsi_lab.chain import run_chain
    from fsi_lab.runfile import read_run

    registry, path = wet_run
    copy = tmp_path / "wet.h5"
    shutil.copy(path, copy)
    loaded = read_run(path)
    assert not any(isinstance(c, sources.LazyChannelData) for c in loaded.channels.values())
    profile = analysis_profile(loaded, registry)
    _, in_memory = run_chain(loaded.channels, profile.analysis, profile.analysis_params,
                             registry, profile.specimen)
    before = len(sources.whole_reads())
    streamed = analyse_file(AnalyseTask(str(copy)), registry)["summary"]["channels"]
    reads = sources.whole_reads()[before:]
    assert sorted(reads) == [("base_acceleration", 16000), ("tip_velocity", 16000)]
    assert "errors" not in streamed["tip_velocity"]
    assert _as_json(streamed) == _as_json(in_memory)


def _long_run(path, samples, channels=4):
    """A run file of ``channels`` channels of ``samples`` samples: a 50 Hz decay every 2 s in
    noise (the first channel a velocity, the rest accelerations), at 10 kHz."""
    from fsi_lab.runfile import RunFileWriter

    rate = 10_000.0
    t = np.arange(samples) / rate
    phase = t % 2.0
    signal = np.exp(-3.0 * phase) * np.sin(2 * np.pi * 50.0 * phase)
    rng = np.random.default_rng(5)
    writer = RunFileWriter(path, {"kind": "imported", "profile": "", "overrides": []})
    for k in range(channels):
        name = f"ch{k}"
        writer.create_channel(name, {"units": "m/s" if k == 0 else "m/s^2",
                                     "quantity": "velocity" if k == 0 else "acceleration",
                                     "sample_rate": rate, "t0": 0.0})
        for start in range(0, samples, 1 << 16):
            part = signal[start:start + (1 << 16)]
            writer.append(name, part + 1e-4 * rng.standard_normal(part.size))
    writer.set_attrs({"exit_status": "completed"})
    writer.close()
    return path


def test_checking_a_run_and_cutting_its_quiet_tail_hold_no_whole_channel(tmp_path, monkeypatch):
    """``read_run`` (lazily), ``require_analysable`` and ``cut_quiet_tail`` on a run of 4
    channels of 400 000 samples (3.2 MB each), read 32 768 samples at a time: no whole-record
    read (refused beyond 0 samples), and a traced peak of less than one channel's size
    (held whole, the 4 channels take 12.8 MB)."""
    from fsi_lab import sources
    from fsi_lab.chain import cut_quiet_tail
    from fsi_lab.dsp import envelope
    from fsi_lab.runfile import read_run, require_analysable

    path = _long_run(tmp_path / "long.h5", 400_000)
    monkeypatch.setattr(sources, "CHUNK", 1 << 15)
    monkeypatch.setattr(envelope, "CHUNK", 1 << 15)
    run = read_run(path, load_data=False, lazy=True)
    tracemalloc.start()
    try:
        with sources.whole_read_limit(0):
            require_analysable(run)
            channels, tail = cut_quiet_tail(run.channels, list(run.channels))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert not tail.cut
    assert all(not c.loaded for c in channels.values())
    assert peak < 0.5 * 400_000 * 8, peak
    # The guard refuses a whole read, naming the channel.
    with sources.whole_read_limit(1000), pytest.raises(Exception, match="'ch0'.*400000"):
        channels["ch0"].data
    # Without it, the channel is read once, as float64, equal to the file's.
    first = channels["ch0"].data
    assert first is channels["ch0"].data and first.dtype == np.float64
    np.testing.assert_array_equal(first, read_run(path).channels["ch0"].data)


def test_a_nan_in_a_lazily_read_channel_is_refused_with_its_first_index(tmp_path):
    import h5py

    from fsi_lab.errors import InputFileError
    from fsi_lab.runfile import read_run, require_analysable

    path = _long_run(tmp_path / "nan.h5", 100_000, channels=2)
    with h5py.File(path, "r+") as handle:
        data = handle["channels/ch1"]
        data[70_000] = np.nan
        data[90_001] = np.inf
    run = read_run(path, load_data=False, lazy=True)
    with pytest.raises(InputFileError, match=r"ch1 holds 2 NaN or infinite samples \(the "
                                             r"first at index 70000\)"):
        require_analysable(run)


# ----------------------------------------------------------------------------- components
def _two_mode_decay(fs=2000.0, seconds=30.0, seed=3):
    t = np.arange(int(seconds * fs)) / fs
    x = np.exp(-1.5 * t) * np.sin(2 * np.pi * 21.0 * t) \
        + 0.4 * np.exp(-2.5 * t) * np.sin(2 * np.pi * 67.0 * t + 0.3)
    return x + 1e-4 * np.random.default_rng(seed).standard_normal(t.size)


def test_components_row_by_row_equal_the_rows_transformed_together():
    """Envelopes and frequencies from each band's analytic signal on its own equal, to the bit,
    those of every band transformed at once (the in-memory formula)."""
    import math

    import scipy.fft as sfft

    from fsi_lab.dsp.components import _envelopes_and_frequencies

    fs = 2000.0
    rng = np.random.default_rng(1)
    rows = np.cumsum(rng.standard_normal((3, 20_011)), axis=1)
    n = rows.shape[1]
    m = sfft.next_fast_len(2 * n)
    h = np.zeros(m)
    h[0] = 1.0
    h[1:(m + 1) // 2] = 2.0
    z = sfft.ifft(sfft.fft(rows, n=m, axis=1) * h, axis=1)[:, :n]
    env, freq = _envelopes_and_frequencies(rows, fs)
    np.testing.assert_array_equal(env, np.abs(z))
    np.testing.assert_array_equal(
        freq, np.gradient(np.unwrap(np.angle(z), axis=1), axis=1) * (fs / (2.0 * math.pi)))


def test_band_components_hold_one_band_transform_at_a_time():
    """The components of a 30 s two-mode decay at 2 kHz (60 000 samples): beyond what they
    keep (components, envelopes, frequencies, the mask, the residual and the record), the
    traced peak stays under 90 bytes per sample (the whole-record band split and one band's
    analytic signal; transforming the bands together took about 200)."""
    from fsi_lab.dsp.components import band_components
    from fsi_lab.dsp.identify import identify

    fs = 2000.0
    x = _two_mode_decay(fs)
    ident = identify(x, fs)
    assert len(ident.modes) == 2
    tracemalloc.start()
    try:
        res = band_components(x, fs, ident)
        current, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    kept = sum(a.nbytes for a in (res.components, res.envelopes, res.frequencies,
                                  res.edge_mask, res.residual, res.record))
    assert current >= kept
    assert (peak - kept) / x.size < 90.0, (peak - kept) / x.size


# ----------------------------------------------------------------------------- integration
def test_integration_by_blocks_of_bins_equals_the_whole_spectrum_at_once(monkeypatch):
    """The integrating high-pass applied 1000 bins at a time gives, to the bit, what it gives
    applied to the whole spectrum at once; and integrating a 60 s record at 2 kHz holds less
    than 53 bytes per sample beyond its result (with the whole spectrum's factor: 57)."""
    from fsi_lab.dsp import integrate as module

    x = _two_mode_decay(seconds=60.0)
    whole = {order: module.integrate(x, 2000.0, order=order) for order in (1, 2)}
    monkeypatch.setattr(module, "FACTOR_BLOCK", 1000)
    for order in (1, 2):
        np.testing.assert_array_equal(module.integrate(x, 2000.0, order=order), whole[order])
    tracemalloc.start()
    try:
        out = module.integrate(x, 2000.0, order=1)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert (peak - out.nbytes) / x.size < 53.0, (peak - out.nbytes) / x.size


# ----------------------------------------------------------------------------- identify
def _all_noisy_splits_first(modes, w, window, model, bands, fs, integrate, noise, rng):
    """The correction's noisy model records as the in-memory path measured them: every
    realisation's bands split and held first, the errors and crossings taken after."""
    from fsi_lab.dsp import identify as module

    noisy = []
    for _ in range(module.NOISE_REALIZATIONS // 2 if noise > 0 else 0):
        extra = rng.normal(0.0, noise, model.size)
        noisy += [module.split(model + extra, fs, bands, integrate=integrate),
                  module.split(model - extra, fs, bands, integrate=integrate)]
    errors, crossings = {}, {}
    for mode in modes:
        cycles = [module.half_cycles(parts[mode.band], fs, mode.frequency) for parts in noisy]
        if cycles:
            crossings[mode.band] = [hc.crossings for hc in cycles]
        fit = module._preferred(mode)
        for j, d in enumerate(mode.decays):
            if d["w"] == w and cycles:
                errors[id(mode), j] = [module._errors(hc, window[0] / fs, d["times"],
                                                      fit.model[j]) for hc in cycles]
    return errors, crossings


def _numbers(ident):
    return [(m.frequency_hz, m.frequency_ci, m.quadratic.params.tolist(),
             m.quadratic.se.tolist(), [d.amplitude.tolist() for d in m.decays],
             [None if d.scale is None else d.scale.tolist() for d in m.decays],
             m.start_drift) for m in ident.modes]


def test_the_noisy_correction_measures_one_realisation_at_a_time(monkeypatch):
    """identify's last correction pass takes the errors of each noisy model record as it is
    made: the same numbers, to the bit, as with every record's bands held first; and the
    traced peak of identify on a 30 s two-mode decay at 2 kHz stays under 500 bytes per sample
    (with the 16 noisy records' bands held together: about 670)."""
    from fsi_lab.dsp import identify as module

    x = _two_mode_decay(seconds=30.0)
    tracemalloc.start()
    try:
        streamed = module.identify(x, 2000.0)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak / x.size < 500.0, peak / x.size
    monkeypatch.setattr(module, "_noisy_errors", _all_noisy_splits_first)
    held = module.identify(x, 2000.0)
    assert len(streamed.modes) == 2
    assert _numbers(streamed) == _numbers(held)


# ----------------------------------------------------------------------------- spectra
@pytest.mark.parametrize("window", ["decay", "hann"])
def test_a_long_records_spectrum_leaves_no_record_long_window_behind(window):
    """The spectrum of 600 000 samples holds nothing after it returns but its two arrays (its
    window and detrending ramp were cached for the process: 16 bytes per sample); the windows
    of short records are still cached, and both give the same numbers."""
    from fsi_lab.dsp import spectrum as module

    x = np.random.default_rng(4).standard_normal(600_000)
    module.amplitude_spectrum(x[:1000], 1000.0, window=window)   # imports and small caches
    tracemalloc.start()
    try:
        f, a = module.amplitude_spectrum(x, 1000.0, window=window)
        current = tracemalloc.get_traced_memory()[0]
    finally:
        tracemalloc.stop()
    assert current < f.nbytes + a.nbytes + (1 << 16), current - f.nbytes - a.nbytes
    assert module._window(window, 1000) is module._window(window, 1000)
    np.testing.assert_array_equal(module._window(window, 1000),
                                  module._make_window(window, 1000))


# ----------------------------------------------------------------------------- FRF
def _random_run(path, samples, rate=2000.0, clip=None):
    """A run file of a 20 Hz mode (1 % damping) driven through its base by white noise:
    ``base`` (m/s^2) and ``tip`` (m/s)."""
    import scipy.signal as ssig

    from fsi_lab.runfile import RunFileWriter

    wn = 2 * np.pi * 20.0
    mode = ssig.cont2discrete(([1.0, 0.0], [1.0, 2 * 0.01 * wn, wn ** 2]), 1 / rate)
    x = np.random.default_rng(6).standard_normal(samples)
    y = ssig.lfilter(mode[0].ravel(), mode[1], x)
    if clip is not None:
        x = np.clip(x, -clip, clip)
    writer = RunFileWriter(path, {"kind": "imported", "profile": "", "overrides": []})
    for name, data, quantity, unit in (("base", x, "acceleration", "m/s^2"),
                                       ("tip", y, "velocity", "m/s")):
        writer.create_channel(name, {"units": unit, "quantity": quantity, "sample_rate": rate,
                                     "t0": 0.0})
        writer.append(name, data)
    writer.set_attrs({"exit_status": "completed"})
    writer.close()
    return path


def test_the_frf_of_a_run_files_channels_read_a_chunk_at_a_time_is_the_in_memory_one(
        tmp_path, monkeypatch):
    """H1, H2, coherence and the modal fits of channels of 1 000 000 samples read from the run
    file 20 000 samples (and 4 segments) at a time equal, to the bit, those of the channels in
    memory; no whole channel is read, and the traced peak stays under a quarter of one
    channel's size (8 MB)."""
    from fsi_lab import sources
    from fsi_lab.dsp import spectrum
    from fsi_lab.dsp.frf import frf
    from fsi_lab.runfile import read_run

    path = _random_run(tmp_path / "random.h5", 1_000_000)
    monkeypatch.setattr(sources, "CHUNK", 20_000)
    monkeypatch.setattr(spectrum, "_CHUNK_SAMPLES", 1 << 14)  # (both paths sum alike)
    loaded = read_run(path).channels
    held = frf(loaded["base"].data, loaded["tip"].data, 2000.0, segment=4096)
    lazy = read_run(path, load_data=False, lazy=True).channels
    tracemalloc.start()
    try:
        with sources.whole_read_limit(0):
            streamed = frf(sources.samples_of(lazy["base"]), sources.samples_of(lazy["tip"]),
                           2000.0, segment=4096)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 0.25 * 1_000_000 * 8, peak
    for name in ("frequency", "h1", "h2", "coherence", "natural_frequencies",
                 "damping_ratios", "damping_ratio_ci95", "half_power_damping_ratios"):
        np.testing.assert_array_equal(getattr(streamed, name), getattr(held, name), name)
    assert streamed.warnings == held.warnings
    assert held.natural_frequencies.size >= 1


@pytest.mark.parametrize("case", ["clipped", "nan", "constant", "fine"])
def test_a_source_is_refused_as_its_samples_in_memory_are(tmp_path, monkeypatch, case):
    """The checks of a record read a chunk at a time (chunks of 1000 samples, so that flat
    tops straddle them) give the in-memory checks' verdicts and messages."""
    import h5py

    from fsi_lab import sources
    from fsi_lab.dsp._signal import as_record
    from fsi_lab.errors import AnalysisError
    from fsi_lab.runfile import read_run

    path = _random_run(tmp_path / "r.h5", 20_000, clip=1.0 if case == "clipped" else None)
    with h5py.File(path, "r+") as handle:
        if case == "nan":
            handle["channels/base"][12_345] = np.nan
        if case == "constant":
            handle["channels/base"][:] = 0.25
    monkeypatch.setattr(sources, "CHUNK", 1000)
    source = read_run(path, load_data=False, lazy=True).channels["base"].samples()
    data = read_run(path).channels["base"].data
    messages = []
    for check in (lambda: as_record(data, "frf", min_samples=64, name="reference record"),
                  lambda: sources.check_source(source, "frf", min_samples=64,
                                               name="reference record")):
        try:
            check()
            messages.append(None)
        except AnalysisError as exc:
            messages.append(str(exc))
    assert messages[0] == messages[1]
    assert (messages[0] is None) == (case == "fine")
