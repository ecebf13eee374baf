"""A high-pass in the measuring chain, read off a release at the start of a velocity record.

An AC-coupled channel (a digitiser's AC coupling, a sensor's or decoder's high-pass of corner
f_c) passes a mode of frequency f with the gain ``1 / sqrt(1 + (f_c / f)^2)`` (first order):
every amplitude of the mode reads low by that factor, the decay's shape is kept, and C_f (a
damping per unit amplitude) comes out high by its inverse: +20 % for a 3 Hz mode behind a
2 Hz coupling. Nothing in the mode's own band shows it.

A release shows it at low frequencies. Let go from a held displacement ``x0``, a structure
oscillates about its rest position: the integral of a DC-coupled velocity record (the
displacement, less where it started) oscillates about ``-x0`` and stays there. A high-pass
passes no step: the integral of its output returns to where it started, as
``exp(-2 pi f_c t)``. :func:`release_shift` measures that return: the mean of the integrated
velocity over the periods after a release, against the displacement the release let go.

The test needs a record that starts at a release (the velocity rising from zero, its first
extremum a quarter period later or a little less, the first swing starting at one of its ends: a
pulse from rest starts it at its middle, and moves the mean by nothing on any channel) and a
velocity offset that can be measured where the record is still (before the release) or quiet
(after the decay). Behind a high-pass whose corner is close to the mode's frequency (time
constant under a fifth of a period) a release's first swing starts near its middle too: that
release cannot be told from a pulse, and is not flagged. An excitation that leaves no net
impulse can look like a release behind a high-pass; the warning built on it says so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fsi_lab.dsp._signal import as_record, check_rate, fail

#: Periods after the release over which the mean displacement is measured (from, to).
SHIFT_PERIODS = (2.0, 6.0)
#: A start is a release when the velocity's first extremum comes at least this share of a
#: period after it (an impact's comes at once).
RELEASE_RISE = 0.125
#: ... and at most this share (a release's comes a quarter period after it, less the phase its
#: damping and a high-pass lead it by; a pulse as long as half a period and more, which drives
#: the motion through its first swing, puts it later).
RELEASE_PEAK = 0.28
#: ... and identify's first free decay starts within this many periods of it (a burst of
#: forcing that starts like a release is still forced much later).
RELEASE_FORCED = 3.0
#: ... and the velocity where the motion starts is below this share of that extremum.
RELEASE_START = 0.25
#: ... and the integrated velocity's mean over the first period lies at least this share of
#: its swing off where it started (a pulse from rest starts the swing at its middle: 0 to
#: 0.12 for half-sine pulses up to 0.4 period long; a release behind a first-order high-pass
#: of time constant tau keeps about tau / T of it, 0.2 for a corner at 0.8 times the mode's
#: frequency).
RELEASE_SIDE = 0.2
#: Below this ``ratio`` the time constant is read from the first period instead (the noise
#: in the shift's measure then weighs more than the relaxation left in it).
RATIO_RESOLVED = 0.05
#: Share of the record at its end whose mean (over whole periods) gives the velocity offset,
#: when it is quiet.
TAIL_SHARE = 0.1
#: A tail is quiet when its standard deviation is below this share of the first extremum (a
#: decay's remainder of amplitude A, averaged over N whole periods, moves the offset by about
#: A / (pi N) at most).
QUIET_TAIL = 0.1
#: The mean displacement after :data:`SHIFT_PERIODS` is measured over spans of this many
#: periods (at most :data:`LEVEL_SPANS` of them); a release is no measure when their means
#: spread over more than :data:`LEVEL_WANDER` of its swing.
SPAN_PERIODS = 4
LEVEL_SPANS = 10
LEVEL_WANDER = 0.3
#: Noise multiples above which the motion is taken to have started.
START_LEVEL = 5.0
#: A record's first period is still when its standard deviation is under this many times
#: the noise.
STILL_LEVEL = 2.0


@dataclass(frozen=True)
class ReleaseShift:
    """How far the mean displacement stays from where a release started.

    Attributes
    ----------
    start
        Sample index of the release.
    displacement
        The displacement the release let go: half the range of the integrated velocity over
        the first period (the record's unit times s).
    shift
        Mean of the integrated velocity over :data:`SHIFT_PERIODS` periods after the release,
        less its value at the release (same unit): about ``-displacement`` on a DC-coupled
        channel.
    ratio
        ``|shift| / displacement``: about 1 on a DC-coupled channel, near 0 behind a high-pass
        whose corner is a sizeable share of the mode's frequency.
    first_share
        The integrated velocity's mean over the first period, less its value at the release,
        over ``displacement`` (absolute): about 1 on a DC-coupled channel; behind a high-pass
        of time constant tau (periods) about ``tau (1 - exp(-1 / tau))``, which still measures
        a time constant under a period, whose relaxation is over before ``ratio`` is measured.
    corner_hz
        The first-order high-pass corner (Hz) that would give ``ratio`` (from ``first_share``
        where ``ratio`` is under :data:`RATIO_RESOLVED`), or 0 for shares of 1 or more.
    """

    start: int
    displacement: float
    shift: float
    ratio: float
    first_share: float
    corner_hz: float

    def gain(self, frequency_hz: float) -> float:
        """The gain at ``frequency_hz`` (Hz) of a first-order high-pass at :attr:`corner_hz`."""
        return 1.0 / math.sqrt(1.0 + (self.corner_hz / frequency_hz) ** 2)


def _held_share(tau_periods: float, span: tuple[float, float]) -> float:
    """The mean of ``exp(-t / tau)`` over ``span`` (t and tau in periods)."""
    a, b = span
    return tau_periods / (b - a) * (math.exp(-a / tau_periods) - math.exp(-b / tau_periods))


def _corner(share: float, span: tuple[float, float], frequency: float) -> float:
    """The first-order corner (Hz) whose release relaxation keeps ``share`` of the shift, on
    average over ``span`` (periods of ``frequency`` after the release), by bisection on the
    time constant; 0 for a share of 1 or more."""
    if share >= _held_share(1e6, span):
        return 0.0
    low, high = 1e-3, 1e6                  # time constants, periods
    for _ in range(100):
        mid = math.sqrt(low * high)
        if _held_share(mid, span) > share:
            high = mid
        else:
            low = mid
    return frequency / (2.0 * math.pi * math.sqrt(low * high))


def release_shift(v: np.ndarray, fs: float, frequency: float, noise: float,
                  free: int | None = None) -> ReleaseShift | None:
    """Measure how far a velocity record's mean displacement stays from a release at its start.

    Parameters
    ----------
    v
        Velocity samples, U/s (any consistent unit), starting still or at the release.
    fs
        Sample rate, Hz.
    frequency
        The lowest mode's frequency, Hz: the period the release is judged on.
    noise
        The record's white noise RMS, U/s: the level above which the motion has started.
    free
        Sample index where the record's first free decay starts (as
        :func:`fsi_lab.dsp.identify.identify` finds it), or None: a motion still forced more
        than :data:`RELEASE_FORCED` periods after it started is no release.

    Returns
    -------
    ReleaseShift or None
        None when the record does not start with a release followed by
        :data:`SHIFT_PERIODS` periods, its velocity offset cannot be measured (no still
        period before the release, no quiet tail), or its mean displacement wanders after the
        release (a drift, not a step that relaxes).

    Raises
    ------
    AnalysisError
        A record that cannot be read, a rate, frequency or noise that is not a positive
        number.

    Examples
    --------
    A 5 Hz decay released at the record's start, as recorded and through a 1 Hz first-order
    high-pass (an AC coupling that reads its amplitudes 2 % low):

    >>> import numpy as np, scipy.signal
    >>> from fsi_lab.dsp.coupling import release_shift
    >>> from fsi_lab.dsp.laws import simulate_decay
    >>> fs, w0 = 2000.0, 2 * np.pi * 5.0
    >>> t = np.arange(int(20 * fs)) / fs
    >>> v = simulate_decay("quadratic", [0.3, 50.0], w0, 1e-3, 0.0, t,
    ...                    quantity="displacement", output="velocity")
    >>> print(round(release_shift(v, fs, 5.0, 1e-7).ratio, 2))
    1.05
    >>> b, a = scipy.signal.butter(1, 1.0, "highpass", fs=fs)
    >>> found = release_shift(scipy.signal.lfilter(b, a, v), fs, 5.0, 1e-7)
    >>> print(f"{found.ratio:.2f}, corner {found.corner_hz:.2f} Hz, gain {found.gain(5.0):.3f}")
    0.02, corner 1.03 Hz, gain 0.979
    """
    func = "release_shift"
    fs = check_rate(fs, func)
    v = as_record(v, func, min_samples=16, check_clipping=False)
    for name, value in (("frequency", frequency), ("noise", noise)):
        if not (isinstance(value, (int, float, np.number)) and math.isfinite(value)
                and value > 0):
            raise fail(func, f"{name} = {value!r}; expected a positive number")
    period = int(round(fs / frequency))
    if period < 4 or v.size < 2 * period:
        return None
    # Still from the first sample (within the noise of its own mean, the velocity offset) up
    # to the release, or moving from it: then the offset comes from a quiet tail.
    still = float(np.std(v[:period])) < STILL_LEVEL * noise
    level = float(np.mean(v[:period])) if still else 0.0
    moving = np.flatnonzero(np.abs(v - level) > START_LEVEL * noise)
    if not moving.size:
        return None
    start = int(moving[0]) if still else 0
    end = start + int(math.ceil(SHIFT_PERIODS[1] * period))
    if end > v.size:
        return None
    first = v[start:start + period // 2] - level
    peak = int(np.argmax(np.abs(first)))
    top = float(abs(first[peak]))
    if not RELEASE_RISE * period <= peak <= RELEASE_PEAK * period \
            or abs(float(first[0])) > RELEASE_START * top \
            or (free is not None and free - start > RELEASE_FORCED * period):
        return None
    if still:
        offset = float(np.mean(v[:start]))
    else:
        # (whole periods of the lowest mode: what is left of the decay there averages out)
        tail = v[-max(1, int(TAIL_SHARE * v.size) // period) * period:]
        if tail.size + end > v.size or float(np.std(tail)) > QUIET_TAIL * top:
            return None
        offset = float(np.mean(tail))
    # The integral from the release on, over the shift's periods and the spans after them.
    a, b = (int(round(p * period)) for p in SHIFT_PERIODS)
    span = SPAN_PERIODS * period
    integral = np.cumsum(v[start:start + b + LEVEL_SPANS * span] - offset) / fs
    moved = np.concatenate(([0.0], integral[:end - start - 1]))
    swing = 0.5 * float(np.ptp(moved[:period]))
    if swing <= 0.0:
        return None
    # A release starts at one end of its first swing, so the first period's mean lies off
    # where it started (by the whole swing on a DC-coupled channel, by the share a high-pass
    # has not yet taken back behind one); a pulse from rest starts the swing at its middle.
    first_share = abs(float(np.mean(moved[:period]))) / swing
    if first_share < RELEASE_SIDE:
        return None
    shift = float(np.mean(moved[a:b]))
    ratio = abs(shift) / swing
    # After the release has relaxed (DC-coupled: at once; behind a high-pass that matters,
    # within a few periods) the mean stays put; a mean that wanders, as under a drift of
    # the velocity's offset, measures nothing.
    later = integral[b:]
    if later.size >= 2 * span:
        means = later[:later.size // span * span].reshape(-1, span).mean(axis=1)
        if float(np.ptp(means)) > LEVEL_WANDER * swing:
            return None
    corner = _corner(ratio, SHIFT_PERIODS, frequency) if ratio >= RATIO_RESOLVED \
        else _corner(first_share, (0.0, 1.0), frequency)
    return ReleaseShift(start=start, displacement=swing, shift=shift, ratio=ratio,
                        first_share=first_share, corner_hz=corner)
