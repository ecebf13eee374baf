"""Long records analysed in segments (issue 16; docs/streaming-analysis.md, fsi_lab.segmented):
a record above the analysis's budget is cut between its free decays, each segment analysed by
the chain, its per-sample results written at its offset, the identification pooled."""

from __future__ import annotations

import dataclasses
import shutil
import tracemalloc

import h5py
import numpy as np
import pytest

RATE = 2000.0
#: The period of the train (s): the wet profile's pulse and its free decay, which reaches the
#: noise after about 2.5 s.
PERIOD_S = 4.0
USED = ("tip_velocity", "base_acceleration")


@pytest.fixture(scope="module")
def period(tmp_path_factory):
    """One period of the wet profile's simulated record at 2 kHz (noise-free), its channels."""
    from support import PROFILES

    from fsi_lab.preflight import prepare_excitation
    from fsi_lab.profile import load_profile
    from fsi_lab.registry import load_registry
    from fsi_lab.runfile import read_run
    from fsi_lab.simulation import simulate_run

    registry = load_registry()
    profile = load_profile(PROFILES / "wet-beam-sim.toml", registry)
    waveform, rate = prepare_excitation(profile, registry)
    out = tmp_path_factory.mktemp("segmented") / "one.h5"
    simulate_run(profile, waveform, rate, PERIOD_S, RATE, out, None,
                 {"uuid": "0" * 32, "start_time": "2026-11-25T00:00:00.000000+00:00",
                  "profile": profile.text, "profile_path": str(profile.path), "overrides": []})
    return registry, profile, read_run(out)


def _train(path, period, repeats, seed=4):
    """A run file of ``repeats`` periods of the pulse and its decay, with white noise of 1e-4
    of each channel's peak (the profile's chain analyses the tip velocity)."""
    from fsi_lab.runfile import RunFileWriter

    _, profile, run = period
    rng = np.random.default_rng(seed)
    writer = RunFileWriter(path, {"kind": "simulated", "profile": profile.text,
                                  "profile_path": str(profile.path), "overrides": [],
                                  "uuid": "1" * 32,
                                  "start_time": "2026-11-25T00:00:00.000000+00:00"})
    for name, channel in run.channels.items():
        writer.create_channel(name, {"units": channel.unit, "quantity": channel.quantity,
                                     "sample_rate": channel.sample_rate, "t0": 0.0})
        x = np.tile(channel.data, repeats)
        writer.append(name, x + 1e-4 * np.abs(channel.data).max() * rng.standard_normal(x.size))
    writer.set_attrs({"exit_status": "completed"})
    writer.close()
    return path


def _analyse(path, registry, *sets):
    from fsi_lab.batch import AnalyseTask, analyse_file

    return analyse_file(AnalyseTask(str(path), tuple(sets)), registry)["summary"]


CHAIN = "analysis.chain=hvd,equivalent-damping"
#: 3 periods of 2 used channels: 48 000 samples; this budget holds one period and a half.
BUDGET = "analysis.segment_samples=24000"


@pytest.fixture(scope="module")
def analysed(period, tmp_path_factory):
    """The same 3-period record analysed in memory and in segments."""
    registry = period[0]
    folder = tmp_path_factory.mktemp("train")
    source = _train(folder / "train.h5", period, 3)
    memory, segmented = folder / "memory.h5", folder / "segmented.h5"
    shutil.copy(source, memory)
    shutil.copy(source, segmented)
    return (source, memory, _analyse(memory, registry, CHAIN),
            segmented, _analyse(segmented, registry, CHAIN, BUDGET))


def _coefficients(component, key):
    """Value and standard error (from the 95 % interval) of C_i or C_f."""
    value, (lo, hi) = component[key], component[f"{key}_ci95"]
    return value, (hi - lo) / (2 * 1.96)


def test_below_the_budget_the_record_is_analysed_in_memory_as_before(analysed):
    _, _, memory, _, _ = analysed
    info = memory["channels"]["tip_velocity"]
    assert "segmented" not in info and "errors" not in info
    assert len(info["components"]) == 2


def test_pooled_segments_give_the_in_memory_c_i_and_c_f(period, analysed):
    """Three free decays, one per segment; the law fitted to the union of the segments' decays
    against the in-memory analysis of the whole record (its identification takes the three
    decays together): per mode, both frequencies within 0.05 % of the simulated beam's natural
    frequency (measured: 17.0626 Hz both, against 17.0634), C_i and C_f within two standard
    errors of their difference (the two take their noise and band estimates from different
    records; measured: 17 Hz C_i 0.6525 vs 0.6522, C_f 31.45 vs 31.47; 48 Hz C_i 0.650 vs
    0.654, C_f 33 vs 26, whose standard errors of 34 and 62 say it is not resolved on this
    mode, the smaller of the two; the 94 Hz mode came second when modes were ranked by the
    sum of their squared extrema); and the truth of the simulation (C_i = 0.65, C_f = 33) inside
    the pooled intervals and the in-memory ones (C_i's within 0.3 %, the filter correction's
    own bias on a record this clean; C_f's within 1 %, the band fits' own bias on this
    multi-mode record, 17 Hz C_f within 5 %). The in-memory 94 Hz C_i (then reported) read 0.671
    (95 %: 0.647 to 0.695) when the whole record's noise was measured on one spectrum: the
    second and third pulses' broadband content (the base's motion taken off) counted as
    noise, 2.8 times it."""
    from fsi_lab.modelling import beam_model

    profile = period[1]
    natural = beam_model(profile.specimen, profile.model).natural_frequencies_hz
    _, _, memory, _, segmented = analysed
    info = segmented["channels"]["tip_velocity"]
    assert "errors" not in info
    seg = info["segmented"]
    assert seg["segments"] == 3 and seg["free_decays"] == 3 and seg["cut"] == "quiet"
    assert [row["free_decays"] for row in seg["table"]] == [1, 1, 1]
    assert info["notes"][0].startswith("the record (12 s) is longer than the analysis budget")
    pooled = {round(c["frequency_hz"]): c for c in info["components"]}
    whole = {round(c["frequency_hz"]): c for c in memory["channels"]["tip_velocity"]
             ["components"]}
    assert sorted(pooled) == sorted(whole) == [17, 48]
    for f, component in pooled.items():
        other = whole[f]
        assert component["segments"] == 3 and component["decays"] == 3
        truth = natural[int(np.argmin(np.abs(natural - f)))]
        assert component["frequency_hz"] == pytest.approx(truth, rel=5e-4)
        assert other["frequency_hz"] == pytest.approx(truth, rel=5e-4)
        own = other["equivalent_damping"]
        for key in ("c_i", "c_f"):
            (a, sa), (b, sb) = _coefficients(component, key), _coefficients(own, key)
            assert abs(a - b) <= 2 * np.hypot(sa, sb)
        # C_i: inside its interval, give or take the 0.3 % the filter correction leaves on a
        # record this clean (its interval is then narrower than that; test_quiet_tails too).
        # C_f: inside its interval give or take 1 %, and on the 17 Hz mode within the issue's
        # 5 % of the bench's 33.0: what is left on this multi-mode record read almost without
        # noise is the band fits' own bias (31.47, 95 %: 30.09 to 32.84, in memory; 31.45
        # pooled).
        for entry in (own, component):
            lo, hi = entry["c_i_ci95"]
            assert lo - 0.003 * 0.65 < 0.65 < hi + 0.003 * 0.65
            if f == 17:
                assert abs(entry["c_f"] / 33.0 - 1.0) < 0.05
            lo, hi = entry["c_f_ci95"]
            assert lo - 0.01 * 33.0 < 33.0 < hi + 0.01 * 33.0
    mode = seg["modes"][0]
    assert [row["segment"] for row in mode["per_segment"]] == [1, 2, 3]
    assert all(row["c_i_ci95"][0] < row["c_i"] < row["c_i_ci95"][1]
               for row in mode["per_segment"])
    # the union's intervals hold the method's accuracy (fsi_lab.accuracy), and say so
    for component, pooled in zip(info["components"], seg["modes"]):
        factors = pooled["widened"]["accuracy"]
        assert min(factors.values()) >= 1.0
        assert ("the method's accuracy" in component["pooled"]) == (max(factors.values())
                                                                   > 1.05)
        lo, hi = component["c_i_ci95"]
        assert (hi - lo) / 2 >= 0.003 * component["c_i"]


def test_no_free_decay_is_cut(period, analysed):
    """Every cut lies where both used channels rest at their floor, and each segment holds its
    period's whole burst (from the pulse at 0.1 s to where the decay reaches the noise)."""
    from fsi_lab.dsp.envelope import ABOVE, block_envelope
    from fsi_lab.runfile import read_run
    from fsi_lab.segments import noise_floor, plan_segments
    from fsi_lab.sources import samples_of
    from fsi_lab.tails import BLOCK_S

    source = analysed[0]
    run = read_run(source, load_data=False, lazy=True)
    channels = [(samples_of(run.channels[n]), RATE) for n in USED]
    plan = plan_segments(channels, 24000)
    block = int(BLOCK_S * RATE)
    for data, _ in channels:
        envelope = block_envelope(data, block)
        quiet = envelope <= ABOVE * noise_floor(envelope)
        active = np.flatnonzero(~quiet)
        for k, segment in enumerate(plan.segments):
            for edge in (segment.start_s, segment.stop_s):
                at = int(edge / BLOCK_S)
                if 0 < at < envelope.size:  # not the record's own ends
                    assert quiet[at - 1:at + 1].all()
            inside = active[(active * BLOCK_S >= k * PERIOD_S)
                            & (active * BLOCK_S < (k + 1) * PERIOD_S)]
            assert segment.start_s <= inside[0] * BLOCK_S
            assert (inside[-1] + 1) * BLOCK_S <= segment.stop_s
            assert (segment.stop_s - segment.start_s) * 2 * RATE <= 24000


def test_per_sample_results_are_written_at_each_segments_offset(period, analysed):
    """The segmented file's per-sample datasets span the whole record; over each segment they
    hold what the chain gives on that segment as a record of its own (to the bit), and NaN
    between segments; the rest of each segment's results is in its own group."""
    from fsi_lab.chain import run_chain
    from fsi_lab.runfile import read_run

    registry, profile, _ = period
    source, _, _, path, summary = analysed
    run = read_run(source)
    table = summary["channels"]["tip_velocity"]["segmented"]["table"]
    analysis = {**profile.analysis, "chain": ["hvd", "equivalent-damping"]}
    n = run.channels["tip_velocity"].data.size
    with h5py.File(path, "r") as handle:
        group = handle["analysis/tip_velocity/hvd"]
        components = group["components"][()]
        assert components.shape == (2, n) and group["edge_mask"].shape == (2, n)
        assert group.attrs["segments"] == 3
        starts = handle["analysis/tip_velocity/segments/start_sample"][()]
        covered = np.zeros(n, bool)
        for k, row in enumerate(table):
            a, b = int(round(row["start_s"] * RATE)), int(round(row["stop_s"] * RATE))
            assert starts[k] == a
            part = {name: dataclasses.replace(c, data=c.data[a:b])
                    for name, c in run.channels.items()}
            groups, _ = run_chain(part, analysis, profile.analysis_params, registry,
                                  profile.specimen)
            own = groups["tip_velocity/hvd"]["datasets"]["components"]
            np.testing.assert_array_equal(components[:own.shape[0], a:a + own.shape[1]], own)
            covered[a:a + own.shape[1]] = True
            assert f"segment_{k:04d}" in group and "cutoffs" in group[f"segment_{k:04d}"]
        assert np.isnan(components[:, ~covered]).all() and (~covered).any()


def test_a_decay_longer_than_the_budget_is_refused_naming_both(period, tmp_path):
    from fsi_lab.errors import AnalysisError

    registry = period[0]
    path = _train(tmp_path / "train.h5", period, 2)
    with pytest.raises(AnalysisError, match=r"a free decay .* from 0\.\d+ s lasts [\d.]+ s, "
                                            r"longer than the analysis budget of 6000 samples "
                                            r"of the used channels \(1\.5 s\)"):
        _analyse(path, registry, CHAIN, "analysis.segment_samples=6000")


def test_a_record_without_quiet_stretches_is_cut_at_fixed_lengths():
    from fsi_lab.segments import plan_segments

    rng = np.random.default_rng(1)
    x = rng.standard_normal(50_000)
    plan = plan_segments([(x, 1000.0), (rng.standard_normal(50_000), 1000.0)], 20_000)
    assert plan.fixed and len(plan.segments) == 5
    assert [s.stop_s - s.start_s for s in plan.segments] == pytest.approx([10.0] * 5)
    assert "no quiet stretch" in plan.note() and "fixed lengths of 10 s" in plan.note()


def test_peak_memory_does_not_grow_with_the_record(period, tmp_path, monkeypatch):
    """The segmented analysis of 1 and of 2 periods (a budget of 12 000 samples of the two used
    channels: 3 s; the longer record is 2.7 times it), the reads' chunks and the spectra's
    caches made small: the traced peak of the longer is within 25 % of the shorter's (a peak
    that grew with the record would double), and no step reads more than a segment's samples
    of a channel at once (the guard refuses it)."""
    from fsi_lab import segmented, sources
    from fsi_lab.dsp import envelope, spectrum

    registry = period[0]
    monkeypatch.setattr(sources, "CHUNK", 1 << 12)
    monkeypatch.setattr(envelope, "CHUNK", 1 << 12)
    monkeypatch.setattr(spectrum, "_CHUNK_SAMPLES", 1 << 12)
    monkeypatch.setattr(spectrum, "CACHED_SAMPLES", 1 << 8)
    monkeypatch.setattr(segmented, "WELCH_S", 0.5)
    peaks = {}
    for repeats in (1, 2):
        path = _train(tmp_path / f"train{repeats}.h5", period, repeats)
        tracemalloc.start()
        try:
            with sources.whole_read_limit(6000):
                summary = _analyse(path, registry, "analysis.chain=hvd",
                                   "analysis.segment_samples=12000")
            peaks[repeats] = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        info = summary["channels"]["tip_velocity"]
        assert "errors" not in info
        assert info["segmented"]["segments"] == repeats
    assert peaks[2] <= 1.25 * peaks[1], peaks


def test_per_sample_results_are_stored_every_stride_th_sample(period, analysed, tmp_path,
                                                               monkeypatch):
    """With ``segment_stride = 4`` a per-sample dataset holds every 4th sample of the record's
    (sample j of it is the record's sample 4 j: the same numbers as the full one there,
    NaN between segments as well); the views read such a dataset every so many samples when
    it is longer than they draw, and put each point at its time on the record."""
    from fsi_lab.gui import results as gui_results
    from fsi_lab.gui.analysis.datasets import time_axis

    registry = period[0]
    source, _, _, full_path, _ = analysed
    path = tmp_path / "strided.h5"
    shutil.copy(source, path)
    summary = _analyse(path, registry, CHAIN, BUDGET, "analysis.segment_stride=4")
    assert summary["channels"]["tip_velocity"]["segmented"]["segments"] == 3
    with h5py.File(full_path, "r") as full, h5py.File(path, "r") as strided:
        for name in ("components", "envelopes", "frequencies", "edge_mask", "residual"):
            every, kept = full["analysis/tip_velocity/hvd"][name][()], \
                strided["analysis/tip_velocity/hvd"][name][()]
            assert kept.shape[-1] == -(-every.shape[-1] // 4), name
            np.testing.assert_array_equal(kept, every[..., ::4], err_msg=name)
            assert strided["analysis/tip_velocity/hvd"][name].attrs["sample_stride"] == 4
        assert strided["analysis/tip_velocity/hvd"].attrs["sample_stride"] == 4
        n = full["analysis/tip_velocity/hvd/components"].shape[-1]
    monkeypatch.setattr(gui_results, "DISPLAY_SAMPLES", n // 4 // 3 + 1)
    shown = gui_results.load_results(path)
    hvd = shown.result("tip_velocity", "hvd")
    step = -(-(-(-n // 4)) // (n // 4 // 3 + 1))
    assert step >= 3 and hvd.stride == 4 * step
    with h5py.File(full_path, "r") as full:
        every = full["analysis/tip_velocity/hvd/components"][()]
    np.testing.assert_array_equal(hvd.datasets["components"], every[..., ::4 * step])
    t = time_axis(shown, "tip_velocity", hvd, hvd.datasets["components"].shape[-1])
    assert t[1] - t[0] == pytest.approx(4 * step / RATE, rel=1e-12)
    assert t[-1] == pytest.approx((t.size - 1) * 4 * step / RATE, rel=1e-12)


def test_the_stride_keeps_forty_samples_per_cycle_at_the_highest_band_edge():
    from types import SimpleNamespace

    from fsi_lab.segmented import STORED_PER_CYCLE, stride_of

    ident = SimpleNamespace(modes=[SimpleNamespace(band_hz=(11.8, 21.0)),
                                   SimpleNamespace(band_hz=(81.8, 224.6))])
    assert stride_of({}, 204_800.0, ident) == int(204_800.0 // (STORED_PER_CYCLE * 224.6)) == 22
    assert stride_of({}, 10_000.0, ident) == 1
    assert stride_of({}, 204_800.0, SimpleNamespace(modes=[])) == 1
    assert stride_of({}, 204_800.0, None) == 1
    assert stride_of({"segment_stride": 7}, 204_800.0, ident) == 7


@pytest.fixture(scope="module")
def whole_chain(period, tmp_path_factory):
    """The 3-period record analysed in segments by the profile's whole chain."""
    registry = period[0]
    path = tmp_path_factory.mktemp("whole") / "train.h5"
    _train(path, period, 3)
    return path, _analyse(path, registry, BUDGET)


def test_the_segments_curves_are_gathered_per_pooled_mode(whole_chain):
    """Backbones, damping curves and C_q points of the segments are at the top of their groups,
    one row per pooled mode (the summary's component), made of the rows of the segments'
    components that went into it, times on the record's clock, decays counted on."""
    path, summary = whole_chain
    info = summary["channels"]["tip_velocity"]
    modes = info["segmented"]["modes"]
    starts = [row["start_s"] for row in info["segmented"]["table"]]
    assert len(modes) >= 1 and all(len(m["per_segment"]) == 3 for m in modes[:1])
    with h5py.File(path, "r") as handle:
        for plugin, name in (("backbone", "frequency"), ("backbone", "time"),
                             ("damping", "zeta"), ("backbone", "decay"),
                             ("equivalent-damping", "c_q")):
            group = handle[f"analysis/tip_velocity/{plugin}"]
            merged = group[name][()]
            assert merged.shape[0] == len(modes), (plugin, name)
            for m, mode in enumerate(modes):
                parts, counted = [], 0.0
                for member in mode["per_segment"]:
                    k, index = member["component"], member["segment"] - 1
                    row = group[f"segment_{index:04d}/{name}"][k]
                    if name == "time":
                        row = row + starts[index]
                    if name == "decay":
                        row = row + counted
                        counted = np.nanmax(row) + 1
                    parts.append(row)
                whole = np.concatenate(parts)
                np.testing.assert_array_equal(merged[m, :whole.size], whole)
                assert np.isnan(merged[m, whole.size:]).all()
        times = handle["analysis/tip_velocity/backbone/time"][0]
        finite = times[np.isfinite(times)]
        assert finite.min() < PERIOD_S and finite.max() > 2 * PERIOD_S  # every segment's decay
        assert "bands" not in handle["analysis/tip_velocity/hvd"]  # not a curve: left in place


def test_the_gui_draws_a_segmented_records_curves(whole_chain, qtbot):
    from fsi_lab.gui.results import load_results
    from fsi_lab.plugins.analysis.views.amplitude_views import BackboneView, DampingView
    from fsi_lab.plugins.analysis.views.equivalent_damping_view import EquivalentDampingView

    path, summary = whole_chain
    results = load_results(path)
    pooled = summary["channels"]["tip_velocity"]["components"][0]
    for kind in (BackboneView, DampingView, EquivalentDampingView):
        view = kind()
        qtbot.addWidget(view)
        view.show_results(results, "tip_velocity")
        assert view.filled, (kind.__name__, view.note.text())
    text = view.values.text()  # the C_q view gives the pooled C_i and C_f
    assert f"{pooled['c_i']:.4g}" in text and f"{pooled['c_f']:.4g}" in text
