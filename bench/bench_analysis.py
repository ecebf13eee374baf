"""Speed and accuracy of the analysis chain (issue: HVD <= 0.5 s for 3 components on 1e6
samples and >= 5x faster than pysdkit's HVD at equal or better accuracy; the whole chain on a
10 s record at 10 kHz in <= 0.5 s).

Both HVDs decompose the same signal, three decaying tones whose components are known exactly;
accuracy is the relative RMS error of each component over the middle 90 % of the record.
pysdkit is imported inside :func:`rows` (it is installed in the benchmark environment only).

Every time is measured :data:`~bench.table.REPEAT` times, ours and each reference's alike, and
given as median (min-max). Warm: in this process, after one untimed call (numba compiled, FFT
plans made). Cold: the first call in a fresh process with an empty numba cache, its imports
timed apart. pysdkit's HVD spends about 40 % of its time in a Python loop (``differ``, a
central difference sample by sample); the "vectorised" peer is pysdkit with that loop replaced
by ``numpy.gradient`` (the same numbers to the bit), as a user would write it. The floor of an
HVD is one FFT of the record's length (numpy's ``rfft`` of 1e6 samples), the whole chain's one
FFT of its 10 s record (1e5 samples), warm and cold alike. The last rows time
``fsi-lab analyze RUN.h5`` as a user runs it, the whole process, on a 10 s simulated record.
"""

from __future__ import annotations

import math

import numpy as np

from bench.table import Row, cache_times, cold_times, figure, median, process_times, times

FS = 10_000.0
N = 1_000_000
FREQS = (7.3, 23.1, 61.7)
AMPS = (1.0, 0.4, 0.15)
ZETAS = (0.002, 0.001, 0.0008)


def _signal() -> tuple[np.ndarray, list[np.ndarray]]:
    t = np.arange(N) / FS
    parts = [a * np.exp(-z * 2 * math.pi * f * t) * np.cos(2 * math.pi * f * t + 0.4 * i)
             for i, (f, a, z) in enumerate(zip(FREQS, AMPS, ZETAS))]
    return sum(parts), parts


def _errors(components: np.ndarray, parts: list[np.ndarray]) -> list[float]:
    cut = N // 20
    mid = slice(cut, N - cut)
    out = []
    for k, truth in enumerate(parts):
        # Match each true component with the extracted one closest to it.
        errs = [float(np.sqrt(np.mean((c[mid] - truth[mid]) ** 2) / np.mean(truth[mid] ** 2)))
                for c in components]
        out.append(min(errs))
    return out


def _fmt(errors: list[float]) -> str:
    return " / ".join(f"{e:.1e}" for e in errors)


def _registry():
    import importlib

    from fsi_lab.registry import Registry, add_plugin

    registry = Registry()
    for module in ("spectrum", "hvd", "integrate", "instantaneous", "backbone", "damping",
                   "equivalent_damping"):
        add_plugin(registry, importlib.import_module(f"fsi_lab.plugins.analysis.{module}"),
                   module)
    return registry


#: The whole chain's record: a 10 s two-mode free decay at 10 kHz with 0.5 % noise.
CHAIN_FS = 10_000.0
CHAIN_SECONDS = 10.0


def chain_record(fs: float = CHAIN_FS, seconds: float = CHAIN_SECONDS) -> np.ndarray:
    """The whole chain's tip velocity record, m/s: two decaying modes (5 and 32 Hz) and noise."""
    t = np.arange(int(seconds * fs)) / fs
    v = (0.06 * np.exp(-0.02 * 2 * math.pi * 5 * t) * np.cos(2 * math.pi * 5 * t)
         + 0.02 * np.exp(-0.005 * 2 * math.pi * 32 * t) * np.cos(2 * math.pi * 32 * t + 0.3))
    return v + 0.005 * 0.06 * np.random.default_rng(0).standard_normal(t.size)


def chain_inputs(fs: float = CHAIN_FS, seconds: float = CHAIN_SECONDS) -> dict:
    """The keyword arguments of :func:`fsi_lab.chain.run_chain` for the whole default chain
    on :func:`chain_record`."""
    from fsi_lab.chain import default_chain
    from fsi_lab.contract import ChannelData
    from fsi_lab.params import validate

    channels = {"tip": ChannelData("tip", chain_record(fs, seconds), fs, "velocity", "m/s")}
    registry = _registry()
    chain = default_chain(registry)
    params = {name: validate(registry.get("analysis", name).params, {}, name)
              for name in chain}
    return {"channels": channels, "analysis": {"chain": chain}, "params": params,
            "registry": registry, "mass_per_length": 0.13}


_CHAIN = "from bench.bench_analysis import chain_inputs\ninputs = chain_inputs()"


def _chain_rows() -> list[Row]:
    """The default chain in this process on a 10 s record at 10 kHz: warm (after one untimed
    call) and cold (the first call in a fresh process with an empty numba cache, the plugins'
    work modules imported by it as a user's first analysis does; the chain's imports apart),
    next to its floor, one numpy rfft of the record (warm, and the first in a fresh process)."""
    from fsi_lab.chain import run_chain

    inputs = chain_inputs()
    run_chain(**inputs)
    elapsed = times(lambda: run_chain(**inputs))
    errors = run_chain(**inputs)[1]["tip"].get("errors")
    record = inputs["channels"]["tip"].data
    floor = times(lambda: np.fft.rfft(record))
    imports, cold = cold_times("from fsi_lab.chain import run_chain", "run_chain(**inputs)",
                               prepare=_CHAIN)
    floor_imports, floor_cold = cold_times(
        "import numpy", "numpy.fft.rfft(x)",
        prepare="from bench.bench_analysis import chain_record\nx = chain_record()")
    name = (f"analysis: whole chain ({' > '.join(inputs['analysis']['chain'])}), "
            f"{CHAIN_SECONDS:g} s at "
            f"{CHAIN_FS / 1000:g} kHz, in-process")
    return [
        Row(f"{name}, warm", figure(elapsed) + (" (with errors)" if errors else ""),
            f"floor: one numpy rfft of the record {figure(floor, 'ms', 1e3, 2)}", "<= 0.5 s",
            median(elapsed) <= 0.5 and not errors),
        Row(f"{name}, cold: first call, fresh process, empty numba cache",
            f"{figure(cold, digits=2)}; imports {figure(imports, digits=2)}",
            f"floor: first rfft of the record in a fresh process "
            f"{figure(floor_cold, 'ms', 1e3, 2)}; import numpy {figure(floor_imports, digits=2)}",
            "-", None),
    ]


def _vectorised_differ(y, delta, dtype=np.float64):
    """pysdkit's ``differ`` (central differences, one-sided at the ends) without its loop."""
    return np.gradient(np.asarray(y, dtype=dtype), delta)


_SIGNAL = "from bench.bench_analysis import FS, _signal\nx, _ = _signal()"


def _hvd_rows() -> list[Row]:
    from fsi_lab.dsp.hvd import hvd

    x, parts = _signal()
    ours = hvd(x, FS, 3)                                     # warm-up (numba, FFT plans)
    t_ours = times(lambda: hvd(x, FS, 3))
    err_ours = _errors(ours.components, parts)
    fc = float(np.min(ours.cutoffs))
    floor = times(lambda: np.fft.rfft(x))
    imports_ours, cold_ours = cold_times("from fsi_lab.dsp.hvd import hvd", "hvd(x, FS, 3)",
                                         prepare=_SIGNAL)
    name = "analysis: HVD 3 components, 1e6 samples"
    try:
        import pysdkit._tid.hvd as pysdkit_hvd
        from pysdkit import HVD
    except ImportError:
        missing = "pysdkit not installed (pip install pysdkit)"
        return [Row(f"{name}, warm", figure(t_ours), missing, "<= 0.5 s, >= 5x faster", False),
                Row(f"{name}, cold", figure(cold_ours), missing, "-", None)]
    # Same cut-off as our slowest filter, in pysdkit's unit (FFT bins of the 2N-long mirrored
    # record); one constant carrier per component.
    fpar = max(1, int(round(fc * 2 * N / FS)))
    model = HVD(K=3, fpar=fpar, mirror=True)
    imfs = model.fit_transform(x)
    t_ref = times(lambda: model.fit_transform(x))
    err_ref = _errors(imfs, parts)
    looped = pysdkit_hvd.differ
    pysdkit_hvd.differ = _vectorised_differ
    try:
        same = np.array_equal(model.fit_transform(x), imfs)
        t_vec = times(lambda: model.fit_transform(x))
    finally:
        pysdkit_hvd.differ = looped
    imports_ref, cold_ref = cold_times(
        "from pysdkit import HVD", "model.fit_transform(x)",
        prepare=f"{_SIGNAL}\nmodel = HVD(K=3, fpar={fpar}, mirror=True)")
    ratio, ratio_vec = median(t_ref) / median(t_ours), median(t_vec) / median(t_ours)
    return [
        Row(f"{name}, warm", figure(t_ours),
            f"pysdkit {figure(t_ref, digits=2)}; vectorised {figure(t_vec, digits=2)} (fpar="
            f"{fpar}{'' if same else ', NOT the same result'})",
            "<= 0.5 s, >= 5x faster", median(t_ours) <= 0.5 and ratio_vec >= 5.0 and same),
        Row(f"{name}, cold: first call, fresh process, empty numba cache",
            f"{figure(cold_ours, digits=2)}; imports {figure(imports_ours, digits=2)}",
            f"pysdkit {figure(cold_ref, digits=2)}; imports {figure(imports_ref, digits=2)}",
            "-", None),
        Row(f"{name}, floor: one numpy rfft of the record", figure(floor, digits=4), "-", "-",
            None),
        Row("analysis: HVD accuracy (rel. RMS per component, middle 90 %)",
            _fmt(err_ours), "pysdkit " + _fmt(err_ref), "equal or better, dominant <= 1 %",
            all(a <= b for a, b in zip(err_ours, err_ref)) and err_ours[0] <= 0.01),
        Row("analysis: HVD speed-up (ratio of medians)",
            f"warm {ratio:.1f}x over pysdkit, {ratio_vec:.1f}x over vectorised; cold "
            f"{median(cold_ref) / median(cold_ours):.2f}x over pysdkit", "1x", ">= 5x warm",
            ratio_vec >= 5.0),
    ]


def _analyze_rows() -> list[Row]:
    """``fsi-lab analyze RUN.h5`` (the wet profile's chain, modal model included) on a 10 s
    simulated record at 10 kHz, whole process: cold (empty numba cache) and with the numba
    cache filled by an untimed run; the floor is a process that imports numpy and h5py and
    reads the record."""
    import sys
    import tempfile
    from pathlib import Path

    command = [sys.executable, "-m", "fsi_lab.cli"]
    profile = Path(__file__).resolve().parents[1] / "profiles" / "wet-beam-sim.toml"
    with tempfile.TemporaryDirectory() as folder:
        run = Path(folder) / "sim.h5"
        process_times([*command, "simulate", str(profile), "--duration", "10", "--rate",
                       "10000", "-o", str(run), "--quiet"], repeat=1)
        analyze = [*command, "analyze", str(run), "--quiet"]
        cold, cached = cache_times(analyze, Path(folder))
        read = ("import h5py, numpy; f = h5py.File(__import__('sys').argv[1], 'r'); "
                "[numpy.asarray(d[()]) for d in f['channels'].values()]")
        floor = process_times([sys.executable, "-c", read, str(run)])
    name = "fsi-lab analyze RUN.h5, 10 s wet record at 10 kHz, whole process"
    reference = f"import numpy, h5py and read the record: {figure(floor, digits=2)}"
    return [Row(f"{name}, cold (empty numba cache)", figure(cold, digits=2), reference, "-",
                None),
            Row(f"{name}, numba cache filled", figure(cached, digits=2), reference, "-", None)]


def rows() -> list[Row]:
    return [*_hvd_rows(), *_chain_rows(), *_analyze_rows()]
