"""Rows of the simulated wet bench: profiles/wet-beam-sim.toml with each excitation plugin.

The record is the bench's own physics (:class:`fsi_lab.modelling.BenchPhysics`: source volts,
amplifier, shaker, base acceleration, the four-mode beam in water with the paper's C_i = 0.65
and C_f = 33.0 on every element), simulated once per case; each trial adds white noise to the
tip velocity and the base acceleration (``Case.noise`` of each one's largest value). It is
analysed as ``fsi-lab run`` analyses it: the profile's hvd (method ``bands``, here with
``components = "auto"`` so that mode 2 is always among them) and equivalent-damping (method
``law``, the modal conversion from the specimen) with the base acceleration as the reference.
The mode validated is mode 2 (the paper's 17 Hz wet mode): its C_i and C_f should be the
bench's, or carry a warning, or be refused. Random excitation that fills the whole record leaves
no free decay: there the right answer is a refusal.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np

from validation.cases import WET_C_F, WET_C_I, Case, Mode

PROFILE = Path(__file__).resolve().parent.parent / "profiles" / "wet-beam-sim.toml"
#: The mode validated (1-based, the paper's wet mode 2).
MODE = 2
#: Noise of each channel, a share of its largest value.
NOISE = 0.005


@functools.lru_cache(maxsize=1)
def _registry():
    from fsi_lab.registry import load_registry

    return load_registry()


def _profile(overrides: tuple[str, ...]):
    from fsi_lab.profile import load_profile

    return load_profile(PROFILE, _registry(), list(overrides))


def bench_case(name: str, overrides: tuple[str, ...], expect: str = "number") -> Case:
    """A row of the wet bench with the profile's ``overrides`` (``--set`` strings)."""
    from fsi_lab.modelling import beam_model

    profile = _profile(overrides)
    frequency = float(beam_model(profile.specimen, profile.model, None)
                      .natural_frequencies_hz[MODE - 1])
    return Case(f"wet bench, {name}", (Mode(frequency, c_i=WET_C_I, c_f=WET_C_F),),
                fs=float(profile.run["sample_rate"]), duration=float(profile.run["duration"]),
                noise=NOISE, bench=overrides, expect=expect)


def bench_cases() -> list[Case]:
    """The bench with each excitation plugin at two heights (random: the profile's second of
    noise, then a free decay; and noise filling the whole record)."""
    return [
        bench_case("ramp derivative 0.01 V s", ("excitation.height=0.01",)),
        bench_case("ramp derivative 0.02 V s", ("excitation.height=0.02",)),
        bench_case("step 0.5 V", ("excitation.plugin=step",)),
        bench_case("step 1 V", ("excitation.plugin=step", "excitation.amplitude=1.0")),
        bench_case("impulse train 1 V", ("excitation.plugin=impulse-train",)),
        bench_case("impulse train 0.5 V", ("excitation.plugin=impulse-train",
                                           "excitation.max_amplitude=0.5",
                                           "excitation.min_amplitude=0.05")),
        bench_case("random 0.1 V for 1 s", ("excitation.plugin=random",)),
        bench_case("random 0.1 V for the whole record", ("excitation.plugin=random",
                                                         "excitation.duration=10"),
                   expect="refusal"),
    ]


def bench_record(case: Case) -> np.ndarray:
    """Tip velocity (m/s) and base acceleration (m/s^2) of the case, rows 0 and 1."""
    from fsi_lab.modelling import BenchPhysics, beam_model
    from fsi_lab.preflight import prepare_excitation

    profile = _profile(case.bench)
    waveform, rate = prepare_excitation(profile, _registry())
    physics = BenchPhysics(beam_model(profile.specimen, profile.model, None), profile.shaker,
                           case.fs, profile.specimen.measurement_point)
    gain = float(profile.roles["amplifier"].settings.get("gain", 1.0))
    n = int(round(case.duration * case.fs))
    t = np.arange(n) / case.fs
    drive = np.interp(t, np.arange(waveform.size) / rate, waveform, right=0.0)
    block = int(case.fs)
    parts = [physics.advance(drive[s:s + block] * gain) for s in range(0, n, block)]
    return np.stack([np.concatenate([p["tip_velocity"] for p in parts]),
                     np.concatenate([p["base_acceleration"] for p in parts])])


def bench_estimate(case: Case, x: np.ndarray):
    """fsi-lab's C_i and C_f of mode 2 in the noisy record ``x`` (:func:`bench_record`'s rows),
    through the analysis chain as ``fsi-lab run`` runs it."""
    from fsi_lab.chain import run_chain
    from fsi_lab.contract import ChannelData
    from fsi_lab.params import validate
    from validation.run import Estimate

    profile = _profile(case.bench)
    registry = _registry()
    chain = ["hvd", "equivalent-damping"]
    given = {"hvd": {**profile.analysis_params.get("hvd", {}), "components": None},
             "equivalent-damping": profile.analysis_params.get("equivalent-damping", {})}
    params = {name: validate(registry.get("analysis", name).params, given[name],
                             f"analysis.{name}") for name in chain}
    channels = {"tip_velocity": ChannelData("tip_velocity", x[0], case.fs, "velocity", "m/s"),
                "base_acceleration": ChannelData("base_acceleration", x[1], case.fs,
                                                 "acceleration", "m/s^2")}
    _, summary = run_chain(channels, {"chain": chain, "channels": ["tip_velocity"],
                                      "reference": "base_acceleration"},
                           params, registry, specimen=profile.specimen)
    found = summary["tip_velocity"]
    comps = [c for c in found.get("components", []) if "frequency_hz" in c]
    if not comps:
        errors = "; ".join(e.get("message", "") for e in found.get("errors", []))
        return Estimate(refused=errors or "no component")
    truth = case.truth.frequency
    comp = min(comps, key=lambda c: abs(math.log(c["frequency_hz"] / truth)))
    if abs(comp["frequency_hz"] / truth - 1.0) > 0.2:
        return Estimate(refused=f"no component near {truth:.4g} Hz")
    eq = comp.get("equivalent_damping")
    if not eq or "c_i" not in eq:
        return Estimate(refused=(eq or {}).get("error", "no C_i or C_f for the component"))
    return Estimate(c_i=eq["c_i"], c_i_ci=tuple(eq["c_i_ci95"]), c_f=eq["c_f"],
                    c_f_ci=tuple(eq["c_f_ci95"]), frequency=comp["frequency_hz"],
                    frequency_ci=tuple(comp.get("frequency_ci95_hz", (math.nan, math.nan))),
                    law=eq.get("preferred_law", ""), warned=bool(comp.get("warnings")))
