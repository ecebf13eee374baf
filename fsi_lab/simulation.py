"""``fsi-lab simulate``: a run file of the profile's beam model driven by its excitation."""

from __future__ import annotations

import traceback
from pathlib import Path
from typing import Any, Callable

import numpy as np

from fsi_lab.errors import RunAborted
from fsi_lab.modelling import BenchPhysics, beam_model, model_summary
from fsi_lab.runfile import INTERRUPTED, RunFileWriter, utc_now, write_attrs

#: Name of the simulated channels and what they hold.
SIMULATED_CHANNELS = {
    "drive": ("voltage", "V"),
    "base_acceleration": ("acceleration", "m/s^2"),
    "tip_velocity": ("velocity", "m/s"),
}


#: Samples simulated and written at a time (2 MB per channel): few large writes, and progress,
#: Ctrl+C and SIGTERM seen every few hundredths of a second.
BLOCK_SAMPLES = 1 << 18


def drive_block(waveform: np.ndarray, waveform_rate: float, start: int, stop: int,
                sample_rate: float) -> np.ndarray:
    """Samples ``start`` to ``stop`` (exclusive) at ``sample_rate`` Hz of the source waveform
    sampled at ``waveform_rate`` Hz, linear between its samples and 0 V after its last (the
    values of ``numpy.interp`` on the whole record, read from the stretch of the waveform the
    block needs)."""
    t = np.arange(start, stop) / sample_rate
    first = max(0, int(np.floor(t[0] * waveform_rate)) - 1) if t.size else 0
    last = min(waveform.size, int(np.ceil(t[-1] * waveform_rate)) + 2) if t.size else 0
    if first >= waveform.size or t.size == 0:
        return np.zeros(t.size)
    return np.interp(t, np.arange(first, last) / waveform_rate, waveform[first:last],
                     right=0.0)


def simulate_run(profile: Any, waveform: np.ndarray, waveform_rate: float, duration: float,
                 sample_rate: float, out: Path, modes: int | None, attrs: dict[str, Any],
                 progress: Callable[[float], None] = lambda fraction: None) -> Path:
    """Write a run file of the model driven by the profile's excitation.

    The excitation (source volts) passes through the amplifier gain and the ``[shaker]`` model
    to give the base acceleration that drives the beam. Records longer than the excitation are
    padded with zeros. Channels: ``drive`` (V), ``base_acceleration`` (m/s^2) and
    ``tip_velocity`` (absolute velocity at ``specimen.measurement_point``, m/s), the layout of a
    measured run. The record is simulated and written :data:`BLOCK_SAMPLES` at a time, straight
    from the integrator's output, so memory does not grow with its length.
    """
    model = beam_model(profile.specimen, profile.model, modes)
    physics = BenchPhysics(model, profile.shaker, sample_rate, profile.specimen.measurement_point)
    gain = float(profile.roles["amplifier"].settings.get("gain", 1.0)) if profile.roles else 1.0
    total = int(round(duration * sample_rate))
    waveform = np.asarray(waveform, dtype=float)
    writer = RunFileWriter(out, {**attrs, "kind": "simulated"})
    ending = {"exit_status": "failed", "error": "", "traceback": ""}
    try:
        writer.write_excitation(waveform, waveform_rate,
                                {"plugin": profile.excitation_plugin, "amplifier_gain": gain},
                                profile.excitation)
        for name, (quantity, unit) in SIMULATED_CHANNELS.items():
            writer.create_channel(name, {"units": unit, "quantity": quantity,
                                         "sample_rate": sample_rate, "t0": 0.0,
                                         "sensitivity": 1.0, "source_instrument": "model"})
        for start in range(0, total, BLOCK_SAMPLES):
            stop = min(total, start + BLOCK_SAMPLES)
            chunk = drive_block(waveform, waveform_rate, start, stop, sample_rate)
            motion = physics.advance(chunk * gain)
            writer.append("drive", chunk)
            writer.append("base_acceleration", motion["base_acceleration"])
            writer.append("tip_velocity", motion["tip_velocity"])
            progress(stop / total)
        write_attrs(writer.file.create_group("model"), model_summary(model))
        ending["exit_status"] = "completed"
    except (KeyboardInterrupt, RunAborted) as exc:  # recorded as the runner records an abort
        ending.update(exit_status="aborted", error=str(exc) or INTERRUPTED)
        raise
    except BaseException as exc:
        ending.update(error=f"{type(exc).__name__}: {exc}", traceback=traceback.format_exc())
        raise
    finally:
        writer.set_attrs({**ending, "stop_time": utc_now()})
        writer.close()
    return out
