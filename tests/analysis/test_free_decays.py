"""Records with several free decays (impulse trains): the split, and the chain decay by decay.

Ground truth: m x'' + (c1 + c2 |x'|) x' + k x = f(t) (the system of ``quadratic_record``) and a
hardening Duffing oscillator (that of ``duffing_record``), driven by the impulse-train
excitation's half-sine impulses with its amplitude patterns, integrated exactly from rest.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from _analysis_sims import (
    decaying_tone,
    duffing_hb_backbone,
    duffing_record,
    impulse_train_response,
    modal_chirp_response,
    noisy,
    quadratic_record,
    time_axis,
)
from test_analysis_plugins import run

from fsi_lab.contract import ChannelData
from fsi_lab.dsp.decays import block_maxima, decay_segments, first_decay_peak, split_decays
from fsi_lab.dsp.hvd import hvd
from fsi_lab.dsp.instantaneous import instantaneous
from fsi_lab.dsp.integrate import lowest_mode
from fsi_lab.dsp.spectrum import free_decay_peaks, spectral_peaks
from fsi_lab.errors import AnalysisError
from fsi_lab.plugins.analysis._chain import Component, decay_labels
from fsi_lab.plugins.excitation.impulse_train import impulse_amplitudes, impulse_train

COUNT, SPACING, WIDTH, DELAY = 4, 8.0, 0.02, 0.5


def forces(order: str, fs: float, peak_response: float, w0: float) -> tuple:
    """Per-unit-mass peaks and start times of the impulses of the impulse-train excitation
    (checked against its waveform), scaled so the largest response is about ``peak_response``."""
    volts = impulse_amplitudes(1.0, 0.3, COUNT, order)
    starts = DELAY + SPACING * np.arange(COUNT)
    t = time_axis(DELAY + COUNT * SPACING, fs)
    shaped = np.zeros_like(t)
    for v, s in zip(volts, starts):
        inside = (t >= s) & (t < s + WIDTH)
        shaped[inside] = v * np.sin(math.pi * (t[inside] - s) / WIDTH)
    wave = impulse_train(1.0, 0.3, COUNT, SPACING, WIDTH, "half-sine", order, False, DELAY,
                         None, fs)
    np.testing.assert_allclose(shaped, wave, atol=1e-12)
    # A short impulse of peak F gives a velocity 2 F width / pi, an amplitude that over w0.
    return volts * peak_response * w0 * math.pi / (2 * WIDTH), starts


@functools.lru_cache(maxsize=None)
def quadratic_train(order: str) -> dict:
    q = quadratic_record()
    fs, m, c1, c2, w0 = q["fs"], q["m"], q["c1"], q["c2"], q["w0"]
    f, starts = forces(order, fs, 0.01, w0)
    t = time_axis(DELAY + COUNT * SPACING, fs)
    x, v = impulse_train_response(t, lambda x, v: -(c1 + c2 * abs(v)) * v / m - w0 * w0 * x,
                                  f, starts, WIDTH, 0.01)
    return {**q, "t": t, "x": x, "v": v, "starts": starts}


@functools.lru_cache(maxsize=None)
def duffing_train(order: str) -> dict:
    d = duffing_record()
    fs, w0, alpha = d["fs"], d["w0"], d["alpha"]
    f, starts = forces(order, fs, 1e-3, w0)
    t = time_axis(DELAY + COUNT * SPACING, fs)
    x, _ = impulse_train_response(t, lambda x, v: -2 * 0.004 * w0 * v - w0 * w0 * x
                                  - alpha * x ** 3, f, starts, WIDTH, 1e-3)
    return {**d, "t": t, "x": x, "starts": starts}


def truth_zeta(q: dict, amplitude: np.ndarray, frequency: np.ndarray) -> np.ndarray:
    """zeta = (a + b A) / (2 pi f), a = c1 / 2m, b = 4 c2 omega / (3 pi m)."""
    omega = 2 * math.pi * frequency
    return (q["c1"] / (2 * q["m"]) + 4 * q["c2"] * omega * amplitude / (3 * math.pi * q["m"])) \
        / omega


def chain(q: dict, v: np.ndarray, use_hvd: bool, method: str = "regression",
          decomposition: str = "hvd") -> tuple:
    """The chain on one channel; ``decomposition`` is hvd's method (Feldman's HVD for the
    paper's regression and envelope fits, ``bands`` for the default law fit)."""
    ch = ChannelData("tip", v, q["fs"], "velocity", "m/s")
    steps = (("hvd",) if use_hvd else ()) + ("integrate", "backbone", "damping",
                                             "equivalent-damping")
    groups, summary = run({"tip": ch}, steps, mass_per_length=q["m"],
                          params={"hvd": {"components": 1, "method": decomposition},
                                  "equivalent-damping": {"method": method}})
    assert "errors" not in summary["tip"], summary["tip"].get("errors")
    return groups, summary["tip"]["components"][0]


def check_split(entry: dict, starts: np.ndarray) -> None:
    """One free decay per impulse, each inside the spacing that follows its impulse."""
    assert entry["decays"] == COUNT
    for s, lo, hi in zip(starts, entry["decay_starts_s"], entry["decay_ends_s"]):
        assert s < lo < hi < s + SPACING


# ----------------------------------------------------------------------------- the split
def test_one_decay_gives_one_segment_from_its_largest_amplitude():
    t = np.linspace(0.0, 10.0, 400)
    a = np.minimum(t / 0.5, 1.0) * np.exp(-0.4 * t)            # build-up, then a decay
    a = a * (1 + 0.05 * np.sin(37.0 * t)) + 1e-9               # HVD-like ripple
    d = split_decays(t, a, settle=0.2, guard=0.3)
    assert d.count == 1
    assert d.peaks[0] == t[np.argmax(a)]
    assert d.starts[0] == pytest.approx(t[np.argmax(a)] + 0.2)
    assert d.ends[0] == t[-1]
    labels = d.labels(t)
    assert np.array_equal(labels >= 0, t >= d.starts[0])


@pytest.mark.parametrize("order", ["descending", "ascending", "interleaved"])
def test_a_train_of_decays_gives_one_segment_each(order):
    rng = np.random.default_rng(5)
    t = np.arange(0.0, 32.0, 0.05)
    peaks = impulse_amplitudes(1.0, 0.2, 4, order)
    starts = 0.5 + 8.0 * np.arange(4)
    a = np.full(t.size, 1e-3)
    for p, s in zip(peaks, starts):
        after = t >= s
        a[after] = np.maximum(a[after], 1e-3) * 0 + p * np.exp(-0.5 * (t[after] - s)) + 1e-3
    # Extrema alternate about a small offset, with a little noise: neither may split a decay.
    a = a * (1 + 0.1 * (-1) ** np.arange(t.size)) * (1 + 0.03 * rng.standard_normal(t.size))
    d = split_decays(t, a, settle=0.1, guard=0.2)
    assert d.count == 4
    for k, s in enumerate(starts):
        assert s <= d.peaks[k] < s + 0.2
        assert d.starts[k] == pytest.approx(d.peaks[k] + 0.1)
    assert np.all(d.bounds > starts[:-1] + 6.0) and np.all(d.bounds < starts[1:])
    assert np.all(d.ends[:-1] == pytest.approx(d.bounds - 0.2))
    labels = d.labels(t)
    for k in range(4):
        assert np.all(t[labels == k] >= d.starts[k]) and np.all(t[labels == k] <= d.ends[k])
    assert set(np.unique(labels)) == {-1, 0, 1, 2, 3}


def test_a_noise_spike_is_no_new_decay():
    t = np.arange(0.0, 10.0, 0.05)
    a = np.exp(-0.5 * t)
    a[120] *= 10.0                                        # one extremum: not sustained
    assert split_decays(t, a).count == 1


def test_split_decays_bad_input():
    assert split_decays([], []).count == 0
    with pytest.raises(AnalysisError, match="same length"):
        split_decays([0.0, 1.0], [1.0])
    with pytest.raises(AnalysisError, match="rise"):
        split_decays([0.0, 1.0], [1.0, 0.5], rise=1.0)


def test_first_decay_peak_of_a_raw_record():
    fs = 1000.0
    t = time_axis(24.0, fs)
    x = np.zeros_like(t)
    for amp, s in zip((0.2, 0.5, 1.0), (1.0, 9.0, 17.0)):      # ascending
        after = t >= s
        x[after] += decaying_tone(t[after] - s, amp, 20.0, 0.01, math.pi / 2)[0]
    x = noisy(x, 1e-4, seed=2)
    i0 = first_decay_peak(x, fs, 1 / 20.0, floor=1e-3)
    assert 1.0 <= i0 / fs < 1.05
    assert abs(x[i0]) == pytest.approx(np.max(np.abs(x[: int(9.0 * fs)])))
    # One decay: the largest sample, as before the split existed.
    one = x[int(17.0 * fs):]
    assert first_decay_peak(one, fs, 1 / 20.0, floor=1e-3) == int(np.argmax(np.abs(one)))


def test_boundary_sample_belongs_to_the_earlier_decay():
    """A clean train of decays (extrema alternating about an offset): every sample before an
    impulse - the lowest of its decay included - belongs to the earlier decay, every sample
    from the impulse on to the next."""
    t = np.arange(0.0, 24.0, 0.05)
    starts = np.array([0.52, 8.52, 16.52])                 # between two samples
    a = np.full(t.size, 1e-3)
    for p, s in zip((1.0, 0.6, 0.8), starts):
        after = t >= s
        a[after] = p * np.exp(-0.5 * (t[after] - s)) + 1e-3
    a = a * (1 + 0.1 * (-1) ** np.arange(t.size))
    d = split_decays(t, a)
    assert d.count == 3
    expected = np.searchsorted(starts, t, side="right") - 1     # the last impulse before t
    later = t >= starts[0]
    assert np.array_equal(d.regions(t)[later], expected[later])
    for k, s in enumerate(starts[1:]):
        before = np.flatnonzero(t < s)[-1]
        assert d.bounds[k] == t[before] and d.ends[k] == t[before]
        assert d.labels(t[before]) == k and d.labels(t[before + 1]) != k
    # The boundary sample is the lowest envelope between the two impulses.
    env = np.sqrt(a[:-1] * a[1:])
    for k, (s0, s1) in enumerate(zip(starts[:-1], starts[1:])):
        between = np.flatnonzero((t[1:] > s0) & (t[1:] < s1))
        assert d.regions(t[between[np.argmin(env[between])] + 1]) == k


def impulse_tones(times: tuple, fs: float = 1000.0, duration: float = 10.0,
                  freq: float = 10.0, zeta: float = 0.02) -> np.ndarray:
    """A linear mode (``freq`` Hz, ``zeta``) struck at rest by unit impulses at ``times`` (s):
    the sum of the impulse responses, exact."""
    t = time_axis(duration, fs)
    x = np.zeros_like(t)
    for s in times:
        after = t >= s
        x[after] += decaying_tone(t[after] - s, 1.0, freq, zeta, -math.pi / 2)[0]
    return x


def test_a_decay_too_short_for_its_margins_is_no_decay():
    """Impulses 1 s apart on a 10 Hz mode leave the first decay no free part once the
    integration's smear (0.4 s) after its peak and twice that before the next impulse are
    taken off: it is not counted, its points belong to no decay, and the decays left are
    numbered from 0 in time order."""
    fs, strikes = 1000.0, (0.5, 1.5, 5.0)
    x = impulse_tones(strikes, fs)
    inst = instantaneous(x, fs)
    comp = Component(0, x, "displacement", "m", fs, frequency=10.0)
    labels, decays = decay_labels(inst.peak_times, comp, 0.1, inst.peak_amplitudes)
    assert decays.count == 2
    assert np.all(decays.starts < decays.ends)
    assert set(np.unique(labels)) == {-1, 0, 1}
    for k, (lo, hi) in enumerate(((strikes[1], strikes[2]), (strikes[2], np.inf))):
        mine = inst.peak_times[labels == k]
        assert mine.size > 0 and np.all((mine > lo) & (mine < hi))
        assert np.all((mine >= decays.starts[k]) & (mine <= decays.ends[k]))
    assert not np.any((labels >= 0) & (inst.peak_times < strikes[1]))
    # The split itself: every region still separates the excitations (no averaging across).
    assert decays.bounds.size == 2 and list(decays.region) == [1, 2]


@pytest.mark.parametrize("duration, zeta", [(20.0, 0.02), (40.0, 0.01)])
def test_a_sweep_through_two_resonances_is_one_decay(duration, zeta):
    """A linear sweep 3 -> 45 Hz through a 10 Hz and a (larger) 31 Hz mode: each resonance
    passage swells about as slowly as it fades, and no impulse starts a decay - one decay,
    from the record's largest sample."""
    fs = 1000.0
    t = time_axis(duration, fs)
    x = noisy(modal_chirp_response(t, 3.0, 45.0, ((10.0, zeta, 1.0), (31.0, zeta, 20.0))),
              1e-4, seed=3)
    tb, _, mb = block_maxima(x, fs, 0.1)
    assert split_decays(tb, mb).count == 1
    assert decay_segments(x, fs, 0.1) == [(0, x.size)]
    largest = int(np.argmax(np.abs(x)))
    assert abs(largest / fs - duration * (31.0 - 3.0) / 42.0) < 0.1 * duration   # the 31 Hz mode
    assert first_decay_peak(x, fs, 0.1, floor=1e-3 * np.abs(x).max()) == largest


# ----------------------------------------------------------------------------- the chain
@pytest.mark.parametrize("order", ["descending", "ascending", "interleaved"])
def test_impulse_train_gives_c_i_c_f_and_damping_of_each_decay(order):
    """Clean record, the default chain (HVD first): C_i and C_f within 2 %, every damping
    ratio positive and on the linear + quadratic law."""
    q = quadratic_train(order)
    groups, c0 = chain(q, q["v"], use_hvd=True)
    # HVD starts at the first impulse's response (also when it is the smallest).
    assert q["starts"][0] < groups["tip/hvd"]["attrs"]["start_s"] < q["starts"][0] + 0.2
    # The default law fit, one band per mode from each decay's first free cycle: closer.
    _, law = chain(q, q["v"], use_hvd=True, method="law", decomposition="bands")
    check_split(law["equivalent_damping"], q["starts"])
    assert law["equivalent_damping"]["c_i"] == pytest.approx(q["c1"], rel=0.005)
    assert law["equivalent_damping"]["c_f"] == pytest.approx(q["c2"], rel=0.005)
    assert law["equivalent_damping"]["preferred_law"] == "quadratic"
    for key in ("backbone", "damping", "equivalent_damping"):
        check_split(c0[key], q["starts"])
    eq = c0["equivalent_damping"]
    assert eq["c_i"] == pytest.approx(q["c1"], rel=0.02)
    assert eq["c_f"] == pytest.approx(q["c2"], rel=0.02)
    assert eq["r2"] > 0.95
    z = np.array(c0["damping"]["zeta"])
    amp = np.array(c0["damping"]["amplitude"])
    f = groups["tip/damping"]["datasets"]["frequency"][0][: z.size]
    assert np.all(z > 0)
    err = z / truth_zeta(q, amp, f) - 1
    assert np.max(np.abs(err)) < 0.08 and np.median(np.abs(err)) < 0.005
    # Every decay contributes, each over a range of amplitudes.
    decay = groups["tip/damping"]["datasets"]["decay"][0][: z.size]
    assert set(decay.astype(int)) == set(range(COUNT))


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("order", ["descending", "ascending"])
def test_impulse_train_with_noise(order, seed):
    """1 % RMS noise (relative to the peak velocity): C_i and C_f within 10 % by both C_q fits
    and inside the regression's intervals, damping ratios positive."""
    q = quadratic_train(order)
    v = noisy(q["v"], 0.01, seed=seed)
    _, law = chain(q, v, use_hvd=True, method="law", decomposition="bands")
    eq = law["equivalent_damping"]
    assert eq["c_i_ci95"][0] <= q["c1"] <= eq["c_i_ci95"][1]
    assert eq["c_f_ci95"][0] <= q["c2"] <= eq["c_f_ci95"][1]
    assert eq["c_i"] == pytest.approx(q["c1"], rel=0.05)
    assert eq["c_f"] == pytest.approx(q["c2"], rel=0.05)
    for method in ("envelope", "regression"):
        groups, c0 = chain(q, v, use_hvd=True, method=method)
        check_split(c0["equivalent_damping"], q["starts"])
        eq = c0["equivalent_damping"]
        assert eq["c_i"] == pytest.approx(q["c1"], rel=0.10), method
        assert eq["c_f"] == pytest.approx(q["c2"], rel=0.10), method
    # (The envelope fit's intervals ignore the correlation HVD gives neighbouring peaks: too
    # narrow, with or without impulses.)
    assert eq["c_i_ci95"][0] <= q["c1"] <= eq["c_i_ci95"][1]
    assert eq["c_f_ci95"][0] <= q["c2"] <= eq["c_f_ci95"][1]
    z = np.array(c0["damping"]["zeta"])
    assert np.all(z > 0)


def test_impulse_train_without_hvd_is_split_too():
    """The channel analysed whole: one decay per impulse, no decrement across an impulse (all
    damping ratios positive), C_i and C_f close (the frequency-domain integration smears each
    impulse, so less close than through HVD)."""
    q = quadratic_train("interleaved")
    groups, c0 = chain(q, q["v"], use_hvd=False)
    for key in ("backbone", "damping"):
        check_split(c0[key], q["starts"])
    z = np.array(c0["damping"]["zeta"])
    assert np.all(z > 0)
    eq = c0["equivalent_damping"]
    assert eq["c_i"] == pytest.approx(q["c1"], rel=0.05)
    assert eq["c_f"] == pytest.approx(q["c2"], rel=0.10)


@pytest.mark.parametrize("use_hvd", [False, True])
def test_duffing_impulse_train_backbone_matches_harmonic_balance(use_hvd):
    d = duffing_train("interleaved")
    ch = ChannelData("tip", d["x"], d["fs"], "displacement", "m")
    steps = (("hvd",) if use_hvd else ()) + ("backbone",)
    _, summary = run({"tip": ch}, steps, params={"hvd": {"components": 1}})
    bb = summary["tip"]["components"][0]["backbone"]
    check_split(bb, d["starts"])
    a = np.array(bb["amplitude"])
    f = np.array(bb["frequency_hz"])
    kappa = 3 * d["alpha"] * a ** 2 / (4 * d["w0"] ** 2)
    assert kappa.max() > 0.25 and kappa.min() < 0.05
    assert np.max(np.abs(f / duffing_hb_backbone(a, d["w0"], d["alpha"]) - 1)) < 0.01


def test_single_decay_gives_one_segment_in_the_results():
    q = quadratic_record()
    groups, c0 = chain(q, q["v"], use_hvd=True)
    for key in ("backbone", "damping", "equivalent_damping"):
        assert c0[key]["decays"] == 1
        assert len(c0[key]["decay_starts_s"]) == 1
    attrs = groups["tip/damping"]["attrs"]
    assert attrs["component_0_decays"] == 1
    assert attrs["component_0_decay_starts_s"] == pytest.approx(c0["damping"]["decay_starts_s"])


# ----------------------------------------------------------------------------- automatic choices
#: Spacing of :func:`two_mode_train`, s: its comb lines (1 / TRAIN_SPACING apart) are 7 % of
#: the 10 Hz mode apart, too far for HVD's 5 % peak smoothing to merge them.
TRAIN_SPACING = 1.5


def two_mode_train(fs: float = 2000.0) -> tuple[np.ndarray, float, np.ndarray]:
    """Velocity-like record: COUNT decays, TRAIN_SPACING s apart, of a 10 Hz and a 31 Hz mode
    (2 % damping, descending impulse pattern, 1e-4 noise); returns the record, its rate (Hz)
    and the decay starts, s."""
    t = time_axis(DELAY + COUNT * TRAIN_SPACING, fs)
    x = np.zeros_like(t)
    starts = DELAY + TRAIN_SPACING * np.arange(COUNT)
    for amp, s in zip(impulse_amplitudes(1.0, 0.3, COUNT, "descending"), starts):
        after = t >= s
        x[after] += decaying_tone(t[after] - s, amp, 10.0, 0.02, 0.0)[0]
        x[after] += decaying_tone(t[after] - s, 0.4 * amp, 31.0, 0.02, 0.0)[0]
    return noisy(x, 1e-4, seed=4), fs, starts


def test_decay_segments_split_a_train_but_not_two_beating_modes():
    x, fs, starts = two_mode_train()
    segments = decay_segments(x, fs, 1 / 10.0)
    assert len(segments) == COUNT
    for (lo, hi), s in zip(segments, starts):
        assert s <= lo / fs < s + 0.1 and s + 0.5 * TRAIN_SPACING < hi / fs <= s + TRAIN_SPACING
    # Two modes 8 % apart of equal amplitude: the envelope swells and fades every 1.25 s,
    # symmetrically - no excitation, one segment.
    t = time_axis(10.0, fs)
    beat = decaying_tone(t, 1.0, 12.5, 0.002, 0.0)[0] + decaying_tone(t, 1.0, 13.5, 0.002, 1.0)[0]
    assert decay_segments(beat, fs, 1 / 13.0) == [(0, t.size)]
    # A 17 Hz mode that dies out fast beating with a slow 24.65 Hz one (ratio 1.45), on blocks
    # of half a period of the upper mode, as identify splits: a beat's rise spans one or two
    # blocks, as an impulse's does, but it never lifts the sum of the decays above its
    # earlier peak, so it is judged from the low itself and is no new decay.
    t = time_axis(4.0, 2000.0)
    for zeta, upper in ((0.04, 0.7), (0.02, 0.8)):
        pair = (decaying_tone(t, 1.0, 17.0, zeta, 0.0)[0]
                + decaying_tone(t, upper, 24.65, 0.005, 0.0)[0])
        assert decay_segments(noisy(pair, 1e-3, seed=1), 2000.0, 0.5 / 24.65, 1e-2,
                              confirm=2) == [(0, t.size)]


def test_a_train_shows_one_spectral_peak_per_mode_and_hvd_cutoffs_of_one_decay():
    """The whole record's spectrum is a comb (lines 1 / TRAIN_SPACING apart); the peaks used for
    HVD's automatic choices are the two modes, and the cut-offs those of a single decay: half
    of min(frequency, distance to the other mode)."""
    x, fs, starts = two_mode_train()
    comb = spectral_peaks(x, fs, window="decay", min_relative=0.01, smoothing=0.05,
                          fmin=2 * fs / x.size).frequencies
    assert comb.size > 2
    peaks = free_decay_peaks(x, fs, min_relative=0.01, smoothing=0.05).frequencies
    np.testing.assert_allclose(np.sort(peaks), [10.0, 31.0], rtol=0.01)
    res = hvd(x[int(starts[0] * fs):], fs, 2)
    np.testing.assert_allclose(res.cutoffs, [5.0, 10.5], rtol=0.02)
    # (Medians: near each impulse's onset, smeared by the filters, a component wanders.)
    median = [np.median(res.frequencies[k][~res.edge_mask[k]]) for k in range(2)]
    assert median == pytest.approx([10.0, 31.0], rel=0.01)


def test_integration_high_pass_of_a_train_is_set_by_its_lowest_mode():
    x, fs, _ = two_mode_train()
    f_lo, _ = lowest_mode(x, fs, "test")
    assert f_lo == pytest.approx(10.0, rel=0.01)
