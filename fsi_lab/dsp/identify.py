"""Identification of a record's modes from its free decays: backbones and damping laws.

:func:`identify` takes one channel (a velocity, displacement or acceleration) and returns, for
each mode with significant free-decay content, its small-amplitude natural frequency with an
interval, its backbone (frequency against amplitude), the fits of the candidate damping laws
(:mod:`.laws`) with the one the record prefers, and sentences saying how far to trust each
number. The steps:

0. **Dropouts and spikes.** Runs of samples a vibrometer held or zeroed while it had no
   signal (:func:`.spikes.find_dropouts`) are filled by linear prediction, and isolated
   samples far off the oscillation their neighbours trace (:func:`.spikes.find_spikes`) are
   replaced, in the record and in the reference; a note names them.
1. **Free decays.** The record is split into its free decays (:func:`.decays.decay_segments`
   on half-period maxima of the record low-passed at :data:`SPLIT_BAND` times its dominant
   frequency: a step or ramp derivative gives one, an impulse train one per impulse); each is
   analysed on its own window, from its largest sample (a quarter period later when an
   excitation inside the record precedes it; from the end of a steady forced response that
   holds the largest sample, as a sine dwell switched off inside the record: :func:`_plateau_end`;
   later still when the caller knows the excitation ends later) to just before the next
   build-up. Decays whose base (the reference) still moves
   are left out, and a record with none is refused (random excitation through the record), as
   is one excited too often to split (its spectrum a comb of harmonic lines: :data:`COMB_LINES`),
   with the impulse spacing it would need. A release split at its modes' beating nodes,
   whose first short window's spectrum merges them into a hump that stands out of nothing,
   is read as one decay (:func:`_beat_split`).
2. **Modes.** The peaks of the decays' averaged spectrum (:func:`.spectrum.averaged_spectrum`)
   of at least :data:`MODE_THRESHOLD` of the largest are candidate modes; those the sampling
   cannot resolve (fewer than :data:`MIN_SAMPLES_PER_CYCLE` samples per cycle) or the windows
   cannot hold (fewer than :data:`MIN_CYCLES` cycles), and steady lines (mains hum: a peak
   that keeps :data:`STEADY_SHARE` of its amplitude from the decays' first third to their
   last and is there before the excitation), are left out with a note, each keeping a band
   of its own. Heavily damped modes under those peaks' threshold or the whole decays' noise
   are noted, with the band that identifies them (:func:`_broad_small_peaks`,
   :func:`_early_peaks`: the spectra of the decays' first parts). A candidate
   becomes a mode when one of its decays keeps :data:`MIN_CYCLES` cycles above the noise floor:
   a spectral bump without a free decay is no mode (no phantom components).
3. **Separation.** Each window is split into one band per mode (:mod:`.bands`, a partition of
   unity: a component cannot switch to another mode), its ends extended by prediction. A
   record sampled far above its highest band (a signal analyser's 204.8 kS/s for modes below
   a few hundred Hz) is first brought to the rate the bands need
   (:func:`.bands.reduce_rate`, at least :data:`.bands.REDUCED_SAMPLES_PER_CYCLE` samples per
   cycle of the highest band's stop edge): the same band signals at a fraction of the cost.
   Times are in seconds throughout; the windows are reported in the record's own samples.
4. **Extrema.** The extrema of each mode's band signal (:func:`.instantaneous.half_cycles`),
   from the first free one on - every cycle counts: the large first cycles carry the quadratic
   damping - down to :data:`FLOOR` times the noise RMS in the band, and no lower than
   :data:`PRECISION` of the window's largest band value (the splitting's own residue); a
   decay ends too at a half cycle outside :data:`HALF_CYCLE_RANGE` of the mode's (the motion
   has stopped, as dry friction stops it, and the band filter rings on).
5. **Laws.** Each candidate law is fitted to the extrema of all the mode's decays together
   (:func:`.laws.fit_law`, errors whitened with the band's noise correlation) and the laws are
   ranked by AICc (:func:`.laws.compare_laws`).
6. **Correction.** What the band filters still smear at a decay's start is measured on the
   fitted model itself: the model decays of every mode are put through the same padding,
   filters and extremum search, and the difference from the model's exact extrema is taken
   off the measured ones; the linear frequency is adjusted the same way from the crossings.
   The fits are then repeated until they settle (:data:`MAX_PASSES`), the last time with the
   record's noise added to the model, whose spread of the coefficients widens their intervals
   where the fit's own covariance falls short (:func:`_noise_spread`), and whose mean shift of
   each crossing (the noise changes the end padding's prediction) moves the model's crossings
   the frequency is adjusted to.
   Close modes (within :data:`CLOSE_RATIO`) are then fitted together to the record's own
   samples (:mod:`.joint_fit`): each band holds the other's first cycles, which no correction
   takes off well. Where their decays describe the record to its noise
   (:data:`JOINT_RESIDUAL`), that fit gives their quadratic law and linear frequency
   (:func:`_joint`), and their candidate laws are compared on the same samples
   (:func:`_joint_laws`).
7. **Backbone.** Frequency ``1 / (t[i+1] - t[i-1])`` at each zero crossing against the
   displacement amplitude (the geometric mean of the two neighbouring extrema). The natural
   frequency is the backbone's small-amplitude limit: the fitted model (its damping law, and
   ``w^2 = w0^2 + 3 alpha X^2 / 4``, harmonic balance of a cubic stiffness, kept only when the
   record resolves it) is fitted to the crossing times themselves, each weighted by its
   amplitude (:func:`_frequency_step`), not to the periods between them (whose weighted mean
   telescopes to a decay's first and last crossings).
8. **Start and range.** The first extrema of each decay are left out while the quadratic law's
   coefficients still move when more are (:func:`_stable_start`); how far they still move with
   later starts, beyond what the extrema left out explain, widens their intervals
   (:func:`_start_sensitivity`); the law fitted to the larger and the smaller half of the
   cycles must agree (:func:`_one_law`); the quadratic law's fluid term must grow with the
   square of the velocity, not another power (:func:`_law_power`); the largest half cycles
   must carry no in-phase third harmonic beyond their stiffness's (:func:`_crest`: a chain
   that compresses them flattens their crests); a component at three times a larger mode's
   frequency that falls faster than it is said to be its harmonic, not a mode
   (:func:`_harmonic_of`), and is left in that mode's record for the crests. Each check that
   fails is a warning.
9. **Forced start.** When step 8 leaves out cycles of the main mode's decays, or their
   extrema scatter far beyond the noise (:data:`FORCED_SCATTER`), the record is identified
   again from later starts (:func:`_forced_starts`). Where the frequency from there differs
   beyond its noise and is much more precise, from fewer cycles, and reads the same from
   later still, the cycles before were still forced (a random excitation that ends inside the
   record, which step 1 does not see), and that identification is the record's
   (:func:`_more_free`, :data:`FORCED_CONFIRM`).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np
import scipy.stats as sstats
from scipy.ndimage import median_filter
from scipy.signal import butter, hilbert, sosfiltfilt

from fsi_lab.dsp._signal import (
    _band_limited,
    as_record,
    check_rate,
    fail,
    normal_inverse,
    smooth_step,
    true_runs,
)
from fsi_lab.dsp.bands import ModeBands, reduce_rate, reduction_factor, split
from fsi_lab.dsp.crest import TOP_SHARE as CREST_SHARE
from fsi_lab.dsp.crest import half_cycle_harmonics, pooled_crest
from fsi_lab.dsp.decays import decay_segments, first_decay_peak, quiet_times
from fsi_lab.dsp.instantaneous import HalfCycles, half_cycles
from fsi_lab.dsp.joint_fit import DecayStart, JointFit, JointMode, fit_decays_jointly
from fsi_lab.dsp.laws import (
    AICC_TIE,
    LAWS,
    RESOLUTION,
    LawComparison,
    LawFit,
    Whitener,
    compare_laws,
    decay_rate,
    fit_law,
    fluid_power,
    simulate_decay,
)
from fsi_lab.dsp.spectrum import amplitude_spectrum, averaged_spectrum, find_peaks_interpolated
from fsi_lab.dsp.spikes import find_dropouts, find_spikes, without_dropouts, without_spikes
from fsi_lab.errors import AnalysisError

QUANTITIES = ("velocity", "displacement", "acceleration")
#: A decay's free part starts earlier than its largest sample at extrema this close to it.
LEVEL_BACK = 0.95
#: The largest of white noise over half a period is about 3 times its RMS: a new free decay
#: must rise well above this many times it (:func:`_windows`).
SPLIT_FLOOR = 4.0
#: A record with one free decay whose spectral peaks include COMB_LINES or more consecutive
#: multiples of one frequency (within COMB_TOLERANCE of it) is a comb: excited periodically,
#: too often for its decays to be told apart (a structure's modes are not harmonic).
COMB_LINES, COMB_TOLERANCE = 4, 0.02
#: A decay whose base (the reference) moves at more than this share of its largest envelope
#: (the median over the decay) is forced, not free.
FORCED_LEVEL = 0.02
#: A base whose largest envelope stands PULSE_MARGIN times above its white noise (RMS) was
#: excited by something that ends; it is still where its envelope's median is no more than
#: NOISE_ENVELOPE times that noise (white noise's envelope has a median of 1.18 times it).
PULSE_MARGIN, NOISE_ENVELOPE = 10.0, 1.5
#: A steady line within this ratio of a mode may hide under the mode's peak in the decays'
#: spectrum (a heavily damped mode's peak is that wide); it is looked for in their last
#: thirds (:func:`_late_lines`).
HIDDEN_RATIO = 1.5
#: ... of a mode whose spectral peak reaches this share of the largest.
HIDDEN_SHARE = 0.1
#: The decays are split on the record low-passed at this multiple of its dominant frequency.
SPLIT_BAND = 8.0
#: Each window of a release split at its modes' beating nodes (:func:`_beat_split`) peaks
#: below this share of the one before.
BEAT_FALL = 0.9
#: How the note on a largest spectral peak that stands out of nothing begins.
UNRESOLVED_PEAK = "the largest spectral peak, at"
#: A burst of broadband noise in a decay (a knock on the table, a vibrometer losing its
#: signal): the record's content above the split band, RMS over blocks of BURST_BLOCK periods
#: of the dominant oscillation (at least BURST_SAMPLES samples), rising BURST_RISE times above
#: both its lowest since the decay became free and the white noise's share there
#: (:func:`_burst_start`): decays end where one starts; no decay starts inside one that
#: outgrows the oscillation (:func:`_bursts`).
BURST_BLOCK, BURST_SAMPLES, BURST_RISE = 0.25, 32, 5.0
#: ... after its first BURST_KEPT cycles: bursts within them are left in (brief ones, a
#: vibrometer's speckle, matter little beside the largest cycles, and a decay cut there
#: would keep too few cycles for its laws).
BURST_KEPT = 10
#: ... and rising above this share of the record's largest value (a noise-free record's
#: content there is the processing's residue, which rises and falls at random).
BURST_LEVEL = 1e-3
#: A steady forced response before a decay (:func:`_plateau_end`): the half periods it is
#: judged on (down to PLATEAU_DOWN of the largest), the fewest in the flat part and in the
#: decay, how much better a hinge must fit than a straight line, and how slowly (relative to
#: the decay after it) the flat part may fall.
PLATEAU_DOWN, PLATEAU_MIN, PLATEAU_GAIN, PLATEAU_SLOPE = 0.3, 4, 4.0, 0.2
#: A forced response before a decay that is not steady (:func:`_forced_end`): judged in the
#: band from f / RISE_BAND to f RISE_BAND around the dominant frequency f (4th-order
#: Butterworth, zero phase), at RISE_SAMPLES samples per cycle or more; a half period's
#: maximum RISE_RATIO times below a later one that reaches RISE_LEVEL of the band's largest
#: is forced; the free decay after it rises by RISE_AFTER at most (more is a beat with another
#: mode in the band) and holds 2 MIN_CYCLES half periods above RISE_FLOOR times the band's
#: white noise.
RISE_BAND, RISE_SAMPLES, RISE_RATIO, RISE_LEVEL, RISE_AFTER, RISE_FLOOR = (
    1.15, 8.0, 2.0, 0.25, 1.3, 8.0)
#: ... and not within RISE_SETTLE periods of the record's first sample, where the band filter
#: settles: a decay recorded from its release there rises out of the filter's padding.
RISE_SETTLE = 5.0
#: A displacement record's first HOLD_SHARE of samples that stand still (their spread within
#: HOLD_STILL times the noise of their sample-to-sample steps) at more than HOLD_OFFSET times
#: that noise from where the record comes to rest (its last REST_SHARE) hold a static
#: deflection; the hold ends where the record first moves HOLD_DEPARTURE times that noise
#: away from the median of the HOLD_SHARE of samples before (:func:`_static_hold`: a
#: sensor's slow drift is followed).
HOLD_SHARE, HOLD_STILL, HOLD_OFFSET, HOLD_DEPARTURE, REST_SHARE = 0.02, 2.0, 10.0, 6.0, 0.1
#: ... and the deflection held reaches at least this share of the largest excursion after it.
HOLD_REACH = 0.5
#: Spectral peaks below this fraction of the largest are not candidate modes.
MODE_THRESHOLD = 0.01
#: ... but one of at least BROAD_HEIGHT of it whose area (height times half-power width) is
#: BROAD_AREA of the largest peak's or more is noted as a heavily damped mode left out.
BROAD_HEIGHT, BROAD_AREA = 1e-3, 0.1
#: A candidate's spectral peak must stand this many times above the spectrum's noise level.
NOISE_MARGIN = 10.0
#: A heavily damped mode rings for a few tens of cycles, and the spectrum of whole decays
#: dilutes it under their noise (a 2 % damped 400 Hz mode rings for 0.1 s of a 5 s decay). It
#: is looked for in the spectra of the decays' first EARLY_SHARES of the longest: a peak there
#: NOISE_MARGIN times above that spectrum's noise, with EARLY_CYCLES cycles or more in the
#: stretch, that falls to EARLY_FALL of its height or less over the next stretch of that
#: length, and lies off the candidates' harmonics up to EARLY_ORDER and their sums and
#: differences (f_i +- f_j, 2 f_i +- f_j: the faster falling waveform of nonlinear modes) by
#: EARLY_APART of its frequency or two of that spectrum's bins.
EARLY_SHARES = (1 / 4, 1 / 8, 1 / 16, 1 / 32, 1 / 64, 1 / 128)
EARLY_CYCLES, EARLY_FALL, EARLY_ORDER, EARLY_APART = 10, 0.5, 5, 0.03
#: The record's white noise is measured in blocks of at least this many samples
#: (:func:`_noise_rms`), at most :data:`NOISE_BLOCKS` of them.
NOISE_BLOCK = 1024
NOISE_BLOCKS = 16
#: A spectral peak is a mode of its own when the spectrum around it (its col) falls below this
#: fraction of its height.
VALLEY = 0.5
#: The decays' averaged spectrum has at least this many bins per dominant frequency.
SPECTRUM_BINS = 32
#: Samples a free-decay window needs to be analysed.
MIN_WINDOW = 32
#: A band's noise is measured on this many of its periods or more, before the excitation
#: and after its decays (the second half of what follows them), and counts when it exceeds
#: the white noise's share in that band by this factor (an RMS over 4 periods of band noise
#: errs by about 40 %; the phantoms this catches show 4 to 20 times the white share:
#: :func:`_band_noise_excess`).
TAIL_PERIODS, TAIL_EXCESS = 4.0, 2.0
#: A mode whose damping terms are jointly within DECAY_Z standard errors of 0 (their Wald
#: statistic below DECAY_Z^2 per term: no decay shown) and whose extrema scatter about its
#: law more than SCATTER_EXCESS times its noise (RMS) is noise, not a mode
#: (:func:`_scatter_without_decay`).
DECAY_Z, SCATTER_EXCESS = 2.0, 2.0
#: A spectral peak whose amplitude over the last third of the free decays is STEADY_SHARE or
#: more of that over their first third, and that is there before the record's excitation
#: at BEFORE_SHARE of that amplitude or more, is a steady line (mains hum, a machine nearby),
#: not a mode (:func:`_steady_line`). A record without STEADY_CYCLES cycles before its
#: excitation cannot show that: its lines must keep STRICT_SHARE (a lightly damped mode,
#: 20 Hz at a damping ratio of 3e-4, keeps 95 % over two thirds of a 2 s record).
STEADY_SHARE, BEFORE_SHARE, STRICT_SHARE = 0.9, 0.5, 0.99
#: The record's excitation starts where it first reaches this share of its largest sample.
ONSET_LEVEL = 0.2
#: Cycles each third of a window must hold for that test (its Hann window's selectivity).
STEADY_CYCLES = 6
#: Relative smoothing of the spectrum before the peak search: peaks closer merge.
PEAK_SMOOTHING = 0.05
#: Fewest samples per cycle of a mode.
MIN_SAMPLES_PER_CYCLE = 6.0
#: Fewest cycles of a free decay above the noise floor for a mode.
MIN_CYCLES = 3
#: Extrema are used down to FLOOR times the noise RMS in the band ...
FLOOR = 5.0
#: ... judged on the fitted envelope, after a first fit on those above FIRST_FLOOR times it;
FIRST_FLOOR = 3.0
#: and no lower than where the noise's lift of an extremum (``_Mode.lift``) is this share of
#: it. The lift's first-order correction holds below it; near 1/4 it takes an extremum to 0.
LIFT_SHARE = 0.1
#: A coefficient whose 95 % interval is wider than +- this share of it gets a warning: at such
#: a precision the estimates also carry a bias of a third of a standard error or more (at 3 %
#: noise and 500 Hz, intervals of +-15 to 35 % came with biases of +6 % (C_i) and -7 % (C_f),
#: beyond the 5 % and 10 % the validation holds them to).
POOR_PRECISION = 0.15
#: A cubic stiffness is fitted only when it moves the frequency by this share or more.
STIFFNESS_SHIFT = 2e-3
#: The natural frequency is held to the backbone measured at the decays' smallest amplitudes
#: (this share of the crossings, in at least BACKBONE_FOOT_BLOCKS blocks of
#: BACKBONE_FOOT_BLOCK): a difference beyond BACKBONE_FOOT_Z standard errors and the
#: validation's 0.2 % target is warned.
BACKBONE_FOOT_SHARE, BACKBONE_FOOT_BLOCKS, BACKBONE_FOOT_BLOCK, BACKBONE_FOOT_Z = 0.5, 4, 8, 3.0
#: ... of the crossings whose amplitude is this many times the band's noise or more.
BACKBONE_FOOT_SNR = 30.0
FREQUENCY_TARGET = 0.002
#: ... and its step's value lies this many standard errors from 0: 5 alone, 2 when the
#: measured half periods themselves move with amplitude that way, beyond 5 of theirs, by
#: STIFFNESS_SEEN or more (heavy damping moves a damped frequency with amplitude too: 2.2 %
#: over a 5 Hz decay with 9.5 % linear damping and the wet C_f, no stiffness in it).
STIFFNESS_Z, STIFFNESS_Z_SEEN, STIFFNESS_SEEN = 5.0, 2.0, 0.04
#: A stiffness is kept only where the half periods move that way with amplitude by this many
#: of their standard errors or more, and by half to twice the model's movement there (a model
#: that misfits an impact record's decay asked for a sixth of the softening its half periods
#: showed, at 4.4 of their standard errors: kept, it moved the frequency 0.07 % further off).
STIFFNESS_SEEN_Z = 2.0
#: Dropouts filled (:func:`_dropouts_filled`): those up to this many periods of the record's
#: dominant oscillation (a longer gap is beyond prediction).
DROPOUT_PERIODS = 1.0
#: Spikes whose times a note names (:func:`.spikes.find_spikes`).
SPIKES_NAMED = 5
#: A free decay's half cycles last this range of the mode's half period: beyond it the decay
#: has ended (:func:`_extrema`).
HALF_CYCLE_RANGE = (0.5, 2.0)
#: ... but the first ones out of it, up to this many, are the band filter settling.
SETTLING_HALF_CYCLES = 2
#: A spectral peak whose every decay falls at the rate of the base's motion in its band
#: (within FOLLOW_RATE of it, the base falling FOLLOW_FALL-fold or more over the decay) at a
#: gain of FOLLOW_GAIN or less (its acceleration over the base's in the band) is the base's:
#: a shaker's resonance in air read as a 30 Hz mode with C_f = -31 (its rate 14 1/s, the
#: base's 15, a gain of 1.9). The wet bench's modes fall at 2.5 1/s over a base at -0.6 to
#: +0.8 and stand 9 to 200 times above it; a 47.6 Hz mode the base follows back at its rate
#: stands 49 times above it.
FOLLOW_RATE, FOLLOW_FALL, FOLLOW_GAIN = 0.2, 2.0, 4.0
#: A mode is free once the base motion in its band has fallen below this share of its peak.
BAND_QUIET_LEVEL = 0.01
#: Share of each decay's first extrema left out by the start check (:func:`_start_check`).
LATE_SHARE = 0.2
#: At most this share of the shortest decay's extrema is left out by the start search.
MAX_DROP_SHARE = 0.3
#: A start search that leaves the law fitted below this share of the decays' largest
#: amplitude is warned: the large amplitudes, which carry C_f, follow something else.
START_KEPT_WARNING = 0.7
#: ... and when leaving the large amplitudes out changes the damping the law gives at the
#: largest by more than this share (not a noise-free record's rounding).
START_KEPT_CHANGE = 0.05
#: The power of the fluid term (step 8d) is warned of when 2 lies outside its 95 % interval
#: and the damping ratio it gives differs from the quadratic law's by more than this.
POWER_CHANGE = 0.05
#: ... or, whatever that change, when 2 lies more than this many standard errors from it: a
#: decay read through a measuring chain that compresses its largest values by 5 to 10 % (a
#: decoder or amplifier near the end of its range) gives a power of 1.92 +- 0.05 and a
#: damping ratio within 3 % of the quadratic law's, while C_f reads 6 to 9 % low.
POWER_Z = 3.0
#: Flattened crests (step 8e) are warned of when their in-phase third harmonic lies below
#: -CREST_MIN of the fundamental (a chain reading the largest cycle about 1 % low; a
#: compression of 5 to 10 % at the record's peak gives -0.5 to -1.8 %, noise or a close mode
#: on records read straight within +-0.3 %) ...
CREST_MIN = 0.003
#: ... by more than this many standard errors (the one-sided level of a normal's, 0.6 %, taken
#: on Student's t with the half cycles' degrees of freedom: 3.2 for 9 half cycles).
CREST_Z = 2.5
#: A component at HARMONIC_ORDER times a mode's frequency (within HARMONIC_TOLERANCE,
#: relative, by their half periods: a short harmonic's dozen extrema in noise read its
#: frequency 2.5 % off), at most HARMONIC_SHARE of it, whose extrema fall as that
#: mode's to a power above HARMONIC_POWER (faster than the mode: a waveform's harmonic falls
#: as its amplitude cubed, though a short one's few extrema in noise give 1.4 to 3) is taken
#: for its third harmonic (step 8f): a chain compressing an accelerometer's largest cycles by
#: 8 to 15 % shows one at 1 to 2 % of a 17 Hz mode, found as a mode at 51 Hz; so does the
#: quadratic damping of a 17 Hz mode recorded as acceleration (its harmonic falls as the
#: mode's amplitude squared).
HARMONIC_ORDER = 3
HARMONIC_TOLERANCE = 0.03
HARMONIC_SHARE = 0.1
HARMONIC_POWER = 1.0
#: ... and, for a mode without a cubic stiffness, at three times its frequency within
#: HARMONIC_Z standard errors of the two and HARMONIC_EXACT of the frequency (a chain's
#: harmonic of a 17 Hz mode lay 0.3 to 4.3 of them off, its few crossings' errors larger
#: than their scatter says; a mode at 3.03 times, 17).
HARMONIC_Z, HARMONIC_EXACT = 8.0, 1e-3
#: Moves of the coefficients beyond this many standard errors widen their intervals.
DRIFT_Z = 2.5
#: Step 9: a mode whose start search leaves out FORCED_CYCLES cycles or more of each decay
#: is identified again from its first extremum kept. When the frequency without those cycles
#: differs from the one with them by more than FORCED_Z of the larger standard error, and is
#: FORCED_PRECISION times as precise or more, they were forced, and the second identification
#: is kept: a 40 Hz mode whose random forcing ended inside the record, its decay taken from
#: the largest sample 10.8 cycles before the end, read 38.18 Hz +- 0.62 (the band around the
#: forced response's spectral peak) and 40.002 Hz +- 0.010 from the end. Cycles left out by a
#: law that holds only below some amplitude, or smeared by a close mode's band, change the
#: frequency by their noise alone (a second identification of the same decay is no more
#: precise). The frequency must move by FORCED_SHIFT (relative) too, a quarter of the
#: validation's target: a noise-free release leaves out cycles for its rounding, and its
#: frequency moved by 1e-8 at 50 standard errors.
FORCED_CYCLES, FORCED_Z, FORCED_PRECISION, FORCED_SHIFT = 2.0, 2.0, 3.0, 5e-4
#: A mode whose extrema scatter this many times as far as the white noise explains (60 to
#: 190 on random forcing that ends inside the record; 3.5 to 4 with 1/f noise) is identified
#: again from FORCED_PERIODS periods after its last decay's start, each start judged against
#: the last one kept (and confirmed, FORCED_CONFIRM). Of 795 records of four earlier hunts
#: for faults, read without a reference, 84 were identified again and 8 taken from later: six
#: random forcings and a sine dwell ending inside the record, and two modes 8 % apart beating
#: (read as one), read 0.23 to 4.5 % off and then within 0.03 %, their intervals covering the
#: truth (both beating modes found).
FORCED_SCATTER = 10.0
FORCED_PERIODS = (4, 8, 16, 32)
#: The start kept is confirmed from this many periods later, where the same mode must read
#: the same frequency (within FORCED_Z and FORCED_SHIFT): two modes 5 % apart beating, read
#: as one, read 17.38 Hz +- 0.018 from 32 periods on, 4.9 times as precisely as 16.93 Hz
#: +- 0.089 from the release (the modes at 17 and 17.85 Hz).
FORCED_CONFIRM = 8
#: The larger and the smaller half's laws (step 8b) are warned of as not one law beyond this
#: many standard errors (their intervals are widened from :data:`DRIFT_Z` on). The larger of
#: the two coefficients' z passes 2.5 on 9 to 12 % of clean records of one law (40 trials
#: each of two validation rows; the halves' errors are not quite independent) and 3 on 1 to
#: 3 %: at 2.5 the warning was a false alarm on one record in ten.
SPLIT_WARNING = 3.0
#: Starts of a decay tried by :func:`_stable_start` (extrema left out of every decay).
START_COUNTS = (0, 1, 2, 3, 5, 8, 13, 21, 34)
#: Later starts whose fits measure how far the coefficients depend on the start kept.
START_ALTERNATIVES = 2
#: Moves of a coefficient between starts within this many standard errors of the extrema
#: left out count as noise; beyond, the excess is a systematic error of the start.
START_Z = 2.0
#: The start's error is warned when it widens an interval more than START_WARNING-fold to
#: beyond +-START_WARNING_WIDTH of the value (a narrower interval says enough by itself).
START_WARNING, START_WARNING_WIDTH = 1.5, 0.05
#: A filter correction larger than this share of an extremum gets a warning.
CORRECTION_WARNING = 0.5
#: Most noise-free passes of the filter correction (step 6), each repeated while the
#: quadratic law still moves by PASS_TOLERANCE of its standard errors or more; then one pass
#: with the record's noise.
MAX_PASSES, PASS_TOLERANCE = 4, 0.3
#: Noisy model records measured in the last pass (an even number: antithetic pairs).
NOISE_REALIZATIONS = 16
#: Extrema at each end of a decay whose error spread is measured (the edge padding's).
EDGE_EXTREMA = 3
#: A mode's model decay larger than this multiple of the record's largest sample is a fit gone
#: astray, kept out of the correction.
MODEL_LIMIT = 3.0
#: Relative error scale (weight 1 / WILD_SCALE^2) of an extremum the correction cannot follow.
WILD_SCALE = 10.0
#: The preferred law's whitened residuals correlated more than this at lag 1 are warned.
RESIDUAL_RHO = 0.6
#: Largest lag-1 correlation of the crossing-time residuals the frequency's variance is widened
#: for (:func:`_frequency_step`; a 19-fold variance at most).
CROSSING_RHO_CAP = 0.9
#: Parts of each decay whose frequencies are compared (:func:`_frequency_wander`), and the
#: crossings a part needs to be compared.
FREQUENCY_PARTS = 3
FREQUENCY_PART_CROSSINGS = 6
#: Chance (under one frequency with the crossings' noise) of a spread between the parts as
#: large as the one found, below which the frequency is taken to wander.
FREQUENCY_WANDER_P = 1e-3
#: Modes whose frequencies lie within this ratio of a neighbour's are fitted together to the
#: record's samples (:func:`_joint`): their bands hold each other's first cycles. Band fits of
#: a 17 Hz mode beside one 1.6 to 1.75 times higher were 5 % (C_i) and 8 % (C_f) off with no
#: warning, their intervals covering C_f in 45 % of records at 1 % noise; fitted together,
#: 93 to 97 %. (The wet bench's 47.8 and 93.6 Hz modes, coupled by the fluid's drag along the
#: beam, are no sum of free decays: their joint fit leaves about twice the noise and is not
#: used, at the cost of two fits per record.)
CLOSE_RATIO = 2.2
#: The joint fit replaces the band fit only when its residual RMS is at most this multiple of
#: the record's white noise: the modes' decays then describe the record to its noise.
JOINT_RESIDUAL = 1.5
#: The joint fit's spans end this many periods of the group's lowest mode after its last
#: extremum above the noise floor.
JOINT_TAIL = 3.0
#: The joint fit compares the record with its decays as means of blocks no longer than 1 / this
#: of a period of the group's highest mode (:func:`.joint_fit.fit_decays_jointly`,
#: ``average``): as much information on the decays, at a cost set by the modes, not by the
#: sample rate (a 48 and 94 Hz pair recorded at 10 kHz took 10 s in full).
JOINT_SAMPLES_PER_CYCLE = 12
#: The joint fit keeps cubic stiffnesses only when they lower N ln(RSS) by this much per mode.
STIFFNESS_GAIN = 50.0
#: Seed of the simulated noise: the same record always gives the same numbers.
NOISE_SEED = 20261123
#: Confidence level of the intervals.
LEVEL = 0.95
#: Ratios and widenings beyond this are said to be "more than" it: their digits mean nothing.
SAID_AT_MOST = 1000.0
#: The band splitting's own precision, relative to a window's largest band value: its end
#: predictions leave a residue of up to about 1e-5 of it in the lowest band of a heavily damped
#: mode (measured on noise-free 5 Hz decays with 7.7 to 9.5 % damping, released at the
#: record's start: 2e-6 to 1e-5, alternating with the extrema), 1e-7 in upper bands; and the
#: base motion integrated for a relative signal leaves about 4e-7 of the record's largest
#: value at its end. Extrema below this share of their window's largest band value are not
#: used, and nothing below it of the record's largest value starts a free decay, however low
#: the noise: on records without noise (simulations) the bands' last extrema followed the
#: residue, and a 5 Hz mode read 3.6 Hz with C_i -28 %, the wet bench's 17 Hz mode 5.7 Hz.
#: On a record with noise the noise floor lies higher and this changes nothing.
PRECISION = 1e-5


@dataclass(frozen=True)
class DecayExtrema:
    """The extrema of one mode in one free decay.

    Attributes
    ----------
    window
        Index range ``[start, stop)`` of the decay's window in the record.
    times
        Time of each extremum, s from the record's first sample.
    values
        Signed extremum values as measured on the band signal (unit of the analysed quantity).
    amplitude
        ``|values|`` corrected for the filters' smear (step 6), used by the fits.
    crossings
        Zero-crossing times of the band signal over the kept extrema, s.
    scale
        Error standard deviation of each extremum relative to the decay's others (1 for
        most; more near a window's edge and for an extremum the correction could not
        describe), as the fits weighted them; None: all 1.
    """

    window: tuple[int, int]
    times: np.ndarray
    values: np.ndarray
    amplitude: np.ndarray
    crossings: np.ndarray
    scale: np.ndarray | None = None


@dataclass(frozen=True)
class Backbone:
    """Frequency against amplitude of one mode.

    Attributes
    ----------
    times
        Crossing times, s from the record's first sample.
    frequency
        ``1 / (t[i+1] - t[i-1])`` at each crossing, Hz.
    amplitude
        Displacement amplitude there (geometric mean of the neighbouring extrema), m (unit of
        the record integrated once for a velocity).
    decay
        Index of the free decay of each point.
    """

    times: np.ndarray
    frequency: np.ndarray
    amplitude: np.ndarray
    decay: np.ndarray


@dataclass(frozen=True)
class ModeIdentification:
    """What :func:`identify` found of one mode.

    Attributes
    ----------
    index
        Component number, 0 for the mode whose free decays carry the most energy.
    frequency_hz
        Small-amplitude (linear, undamped) natural frequency, Hz.
    frequency_ci
        Its 95 % interval, Hz.
    damped_frequency_hz
        The small-amplitude limit of the measured backbone (damped), Hz.
    spectral_peak_hz
        The peak of the decays' averaged spectrum the mode was found at, Hz.
    band_hz
        The flat part of the mode's band filter, Hz.
    quantity
        What the extrema are extrema of: ``"velocity"`` or ``"displacement"``.
    decays
        The extrema of each free decay that holds the mode.
    backbone
        Frequency against displacement amplitude, over :attr:`measured_decays`.
    laws
        Fits of the candidate damping laws, ranked.
    alpha
        Cubic stiffness per unit mass used in the fits, 1/(m^2 s^2) (0 unless the backbone
        resolves it).
    noise_floor
        Smallest extremum used (:data:`FLOOR` x the noise RMS in the band), unit of the
        quantity.
    correction
        Largest filter correction applied to an extremum, relative to that extremum.
    start_drift
        ``dropped``: first extrema of each decay left out because the law did not hold there
        yet (:func:`_stable_start`); ``kept_amplitude``: the largest extremum fitted over the
        largest measured (1 when none were left out), and ``kept_change``: how much
        leaving them out changed the damping rate the quadratic law gives at the largest
        amplitude, relative; ``untested``: 1 when most extrema lie
        in decays too short for that test; ``a`` and ``beta``: how far the quadratic law's
        coefficients still move, in standard errors, when more are left out (its covariance
        is widened when more than chance allows); ``split_a``, ``split_beta``: how far they
        differ between the larger and the smaller half of the extrema, in standard errors
        (:func:`_one_law`); ``start_a``, ``start_beta``: the factors their standard errors
        were widened by for the start's sensitivity (:func:`_start_sensitivity`);
        ``noise_a``, ``noise_beta``: those for the noise's spread through the filters'
        padding (:func:`_noise_spread`); ``fluid_power``, ``fluid_power_low``,
        ``fluid_power_high``: the power of the velocity the fluid term grows with and its 95 %
        interval (2 for the quadratic law), and ``fluid_power_change``: how much the damping
        ratio of a law with that power differs from the quadratic law's over the fitted
        extrema, relative (:func:`_law_power`); ``residual_rho``: the lag-1 correlation of the
        preferred law's whitened residuals (:func:`_residual_correlation`); ``band_noise``:
        the band's noise, measured before the excitation and after the decays, over the white
        noise's share in it, where measured (:func:`_band_noise_ratio`);
        ``extrema_scatter``: the extrema's scatter about the quadratic law's envelope over
        that share (:func:`_extrema_scatter`);
        ``frequency_wander``, ``frequency_low``, ``frequency_high``: when the early, middle
        and late cycles' frequencies disagree, the factor the frequency's standard error was
        widened by and the lowest and highest of them, Hz (:func:`_frequency_wander`);
        ``foot_difference``, ``foot_se``, ``foot_amplitude``, ``foot_frequency``: the
        backbone measured at the decays' smallest amplitudes against the fitted model's
        there, relative, its standard error, the largest amplitude among them and their
        mean frequency, Hz (:func:`_backbone_foot`). A
        mode fitted with its close neighbours to the record's samples (:func:`_take_joint`)
        has instead ``joint_modes``, ``joint_residual`` (the fit's residual over the white noise),
        ``joint_r2`` (the share of the record's variance over the fitted spans that the fit
        explains) and ``joint_widening_a``, ``joint_widening_beta``.
    warnings
        Sentences on how far to trust the numbers; empty when every check passed.
    measured_decays
        The extrema of each free decay as measured and corrected, the first ones
        :attr:`start_drift` leaves out of the fits included (:attr:`decays` less them).
    """

    index: int
    frequency_hz: float
    frequency_ci: tuple[float, float]
    damped_frequency_hz: float
    spectral_peak_hz: float
    band_hz: tuple[float, float]
    quantity: str
    decays: list[DecayExtrema]
    backbone: Backbone
    laws: LawComparison
    alpha: float
    noise_floor: float
    correction: float
    start_drift: dict[str, float] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    measured_decays: list[DecayExtrema] = field(default_factory=list)

    @property
    def quadratic(self) -> LawFit:
        """The fit of the linear + quadratic law."""
        return self.laws.fits["quadratic"]

    @property
    def extrema_count(self) -> int:
        """Extrema used by the fits."""
        return int(sum(d.amplitude.size for d in self.decays))


@dataclass(frozen=True)
class Identification:
    """What :func:`identify` found in a record.

    Attributes
    ----------
    modes
        One entry per mode, by decreasing height of its peak in the free decays' spectrum.
    windows
        Index ranges ``[start, stop)`` of the free decays analysed.
    free_windows
        The same as ``(start, free, stop)``: extrema count from ``free`` (the decay's largest
        sample, or a later end of the excitation).
    noise_rms
        RMS of the record's white noise, unit of the record.
    notes
        Spectral peaks left out and why.
    bands
        The band filters (one per mode, in increasing frequency).
    band_of
        Band index of each mode in :attr:`modes`.
    """

    modes: list[ModeIdentification]
    windows: list[tuple[int, int]]
    free_windows: list[tuple[int, int, int]]
    noise_rms: float
    notes: list[str]
    bands: ModeBands
    band_of: list[int]


# ----------------------------------------------------------------------------- steps
def _windows(x: np.ndarray, fs: float, f_dom: float, sigma: float,
             starts: Sequence[float] | None, resolution: float = 0.0,
             plateaus: list[tuple[int, int]] | None = None,
             forced: list[tuple[int, int]] | None = None,
             bursts: list[int] | None = None) -> list[tuple[int, int, int]]:
    """Free-decay windows ``(start, free, stop)``: analysis starts at ``start`` (a quarter
    period before the decay's largest sample, so an extremum there is a complete one),
    extrema count from ``free`` (the largest sample, or a later excitation end).

    The decays are split on the maxima of ``|x|`` over half periods (each holds an extremum)
    of the record low-passed at :data:`SPLIT_BAND` times the dominant frequency (less
    broadband noise: a fast decay stays above it for more cycles), those below
    :data:`SPLIT_FLOOR` times that record's noise RMS, or below ``resolution`` (the level,
    unit of x, under which the processing's own residue lies: :data:`PRECISION`), counted as
    that floor. A steady forced response that holds a decay's largest sample
    (:func:`_plateau_end`) is left out: the decay starts at the record's largest sample near
    its end, and ``plateaus`` (when given) gets its first and last sample. So is a forced
    response that rises again after the largest sample (:func:`_forced_end`; a burst of
    random forcing), into ``forced``. A decay ends where a burst of broadband noise starts
    (:func:`_burst_start`), into ``bursts``."""
    n = x.size
    period = 1.0 / f_dom
    cutoff = SPLIT_BAND * f_dom
    smooth, noise = x, sigma
    if 1.25 * cutoff < 0.45 * fs:
        smooth = _band_limited(x, fs, cutoff)
        noise = sigma * math.sqrt(min(1.0, 1.125 * cutoff / (0.5 * fs)))
    # Bursts of broadband noise: blocks whose content above the split band exceeds the
    # white noise's share there by BURST_RISE and the oscillation's below it.
    burst_rms, quiet = None, smooth
    width = max(BURST_SAMPLES, int(BURST_BLOCK * fs / f_dom))
    count = n // width
    if smooth is not x and count >= 2:
        burst_rms = np.sqrt(np.mean(((x - smooth)[:count * width]).reshape(count, width) ** 2,
                                    axis=1))
        burst_floor = max(BURST_RISE * sigma * math.sqrt(max(0.0, 1.0 - 1.25 * cutoff
                                                               / (0.5 * fs))),
                          BURST_LEVEL * float(np.max(np.abs(x))))
        lows = np.sqrt(np.mean(smooth[:count * width].reshape(count, width) ** 2, axis=1))
        inside = _bursts(burst_rms, lows, burst_floor)
        if inside.any():                # (a burst's low frequencies start no decay)
            quiet = smooth.copy()
            quiet[:count * width].reshape(count, width)[inside] = 0.0
    segments = decay_segments(quiet, fs, 0.5 * period, max(SPLIT_FLOOR * noise, resolution),
                              confirm=2)
    reach = max(1, int(0.25 * fs / f_dom))
    if len(segments) == 1 and quiet is smooth:
        segments = [(first_decay_peak(x, fs, period, max(10.0 * sigma, resolution)), n)]
    else:
        if len(segments) == 1:          # (a burst may outgrow the decay in the record)
            segments = [(first_decay_peak(quiet, fs, period, max(10.0 * noise, resolution)),
                         n)]
        # Each decay's largest sample in the record itself (the low-pass moves it a little).
        segments = [(max(0, b - reach) + int(np.argmax(np.abs(x[max(0, b - reach):b + reach]))),
                     e) for b, e in segments]
    out = []
    quarter = int(0.25 * fs / f_dom)
    band, band_floor = None, 0.0
    if fs >= RISE_SAMPLES * RISE_BAND * f_dom:
        band = np.abs(sosfiltfilt(butter(4, [f_dom / RISE_BAND, f_dom * RISE_BAND], "bandpass",
                                         fs=fs, output="sos"), x))
        band_floor = RISE_FLOOR * sigma * math.sqrt((RISE_BAND - 1.0 / RISE_BAND) * f_dom
                                                    / (0.5 * fs))
        band_top = float(np.max(band))
    given = [] if starts is None else [s * fs for s in starts]
    for first, stop in segments:
        begin = first
        if (end := _plateau_end(smooth, fs, f_dom, first, stop)) is not None:
            # a steady forced response ends there: its last maximum in the record itself
            lo = max(first, end - quarter)
            begin = lo + int(np.argmax(np.abs(x[lo:min(stop, end + quarter + 1)])))
            if plateaus is not None:
                plateaus.append((first, begin))
        elif (band is not None and not any(first <= s < stop for s in given)
              and (end := _forced_end(band, fs, f_dom, first, stop, band_floor,
                                      RISE_LEVEL * band_top)) is not None):
            # (a start given for this decay says where the excitation ended)
            lo = max(first, end - quarter)
            begin = lo + int(np.argmax(np.abs(x[lo:min(stop, end + quarter + 1)])))
            if forced is not None:
                forced.append((first, begin))
        free = _walk_back(x, fs, f_dom, begin)
        # Extrema nearly as large before the largest one: the record holds the free decay
        # from its start (release); the window opens a quarter period earlier so that its
        # first extremum is a whole one. Otherwise the excitation's build-up comes first: the
        # largest sample is still forced (the velocity peaks while a pulse still pushes), so
        # the window opens a quarter period after it, where a pulse no longer than that has
        # ended; the band filters' padding is then fitted to free motion alone.
        lead = quarter if free < begin else 0
        if free == begin and begin > 0:
            free = min(begin + quarter, stop - 1)
        if starts is not None:
            later = [int(math.ceil(s * fs)) for s in starts if first <= s * fs < stop]
            if later and max(later) > free:
                free, lead = max(later), 0
        if burst_rms is not None and inside[min(free // width + 1, count - 1)]:
            if bursts is not None:          # (no free decay starts inside a burst)
                bursts.append(free)
            continue
        if burst_rms is not None and (burst := _burst_start(
                burst_rms, width, free + int(BURST_KEPT * fs / f_dom), stop,
                burst_floor)) is not None:
            stop = burst
            if bursts is not None:
                bursts.append(burst)
        out.append((max(0, free - lead), free, stop))
    # A window must hold motion: the zero-phase low-pass rings ahead of a step (a noise-free
    # record released from rest after exact zeros), and with no noise to hide it that ringing
    # passes for a decay where the record itself is constant.
    out = [w for w in out if w[2] - w[0] >= MIN_WINDOW
           and float(np.ptp(x[w[0]:w[2]])) > 2.0 * resolution]
    # A window cut short by a late excitation end (a burst of random forcing split off as a
    # decay) holds no decay; it is left out when another holds MIN_CYCLES cycles (all short:
    # an impulse train too dense, which the candidates' notes then name).
    enough = [w for w in out if (w[2] - w[1]) * f_dom >= MIN_CYCLES * fs]
    return enough or out


def _bursts(high: np.ndarray, low: np.ndarray, floor: float) -> np.ndarray:
    """Which blocks lie in a burst of broadband noise: runs of blocks whose RMS above the
    split band (``high``) exceeds ``floor`` and the RMS below it (``low``), after which the
    oscillation is no larger than before (an impact also outgrows the oscillation in its
    block, a hammer's on an accelerometer, but a decay starts after it)."""
    loud = (high > floor) & (high > low)
    for first, stop in zip(*true_runs(loud)):
        before = low[first - 1] if first else 0.0
        # A burst starts: the content above the split band rises out of what it was. A high
        # mode decaying beside the dominant one only falls (at fs / 6 and as large, it was
        # taken for a burst at every other block, and no decay was left).
        risen = first == 0 or float(np.max(high[first:stop])) \
            > 2.0 * float(np.min(high[max(0, first - 3):first]))
        if np.any(low[stop:stop + 2] > 2.0 * before) or not risen:
            loud[first:stop] = False
    return loud


def _burst_start(rms: np.ndarray, width: int, after: int, stop: int, floor: float
                 ) -> int | None:
    """First sample of the first burst of broadband noise in a decay from sample ``after`` to
    ``stop``, or None: the first block (``width`` samples, RMS ``rms`` of the record's content
    above its split band) after the one holding ``after`` whose RMS exceeds :data:`BURST_RISE`
    times the lowest before it since then and ``floor`` (that many times the white noise's
    share). The excitation's own broadband content and higher modes only fall after the decay
    is free; a knock or a vibrometer losing its signal rises out of them."""
    first, last = after // width + 1, min(rms.size, stop // width)
    if last - first < 2:
        return None
    seen = np.minimum.accumulate(rms[first:last])
    rise = np.flatnonzero((rms[first + 1:last] > BURST_RISE * seen[:-1])
                          & (rms[first + 1:last] > floor))
    return (first + 1 + int(rise[0])) * width if rise.size else None


def _dominant(record: np.ndarray, fs: float) -> Any:
    """The record's dominant oscillation: the highest peak of its averaged spectrum that the
    sampling resolves (decays split on the half periods of a mode with 4 samples per cycle
    fall apart at every beat with the others), or the highest at all
    (:class:`.spectrum.SpectralPeaks`). ``fs`` in Hz.

    Raises
    ------
    AnalysisError
        No spectral peak: the record holds no oscillation.
    """
    func = "identify"
    freqs, amp = averaged_spectrum(record, fs, [(0, record.size)])
    resolved = freqs <= fs / MIN_SAMPLES_PER_CYCLE
    top = find_peaks_interpolated(freqs[resolved], amp[resolved], min_relative=0.05,
                                  max_peaks=1, smoothing=PEAK_SMOOTHING,
                                  fmin=2.0 * fs / record.size, _func=func)
    if top.frequencies.size == 0:
        top = find_peaks_interpolated(freqs, amp, min_relative=0.05, max_peaks=1,
                                      smoothing=PEAK_SMOOTHING, fmin=2.0 * fs / record.size,
                                      _func=func)
    if top.frequencies.size == 0:
        raise fail(func, "found no spectral peak: the record holds no oscillation above "
                         f"{2.0 * fs / record.size:.3g} Hz")
    return top


def _dropouts_filled(x: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``x`` with its dropouts (:func:`.spikes.find_dropouts`) of up to :data:`DROPOUT_PERIODS`
    periods of its dominant oscillation filled by linear prediction; the ranges filled and
    those left (``[start, stop)`` samples). ``fs`` in Hz."""
    found = find_dropouts(x)
    if not len(found):
        return x, found, found
    try:
        longest = DROPOUT_PERIODS * fs / float(_dominant(x - float(np.mean(x)),
                                                         fs).frequencies[0])
    except AnalysisError:                    # (no oscillation to predict)
        longest = 0.0
    short = found[:, 1] - found[:, 0] <= longest
    return without_dropouts(x, found[short]), found[short], found[~short]


def _times_of(samples: np.ndarray, fs: float) -> str:
    """``"0.45, 0.69 s and 1 more"``: the first :data:`SPIKES_NAMED` sample indices as times
    (s, ``fs`` in Hz), and how many more there are."""
    at = ", ".join(f"{i / fs:.6g}" for i in samples[:SPIKES_NAMED])
    more = len(samples) - SPIKES_NAMED
    return f"{at} s" + (f" and {more} more" if more > 0 else "")


def _runs(ranges: np.ndarray, fs: float) -> str:
    """``"3 runs of 5 to 28 samples (from 0.45, 0.69 s and 1 more)"``: sample ranges named."""
    lengths = ranges[:, 1] - ranges[:, 0]
    span = (f"{lengths.min()}" if lengths.min() == lengths.max()
            else f"{lengths.min()} to {lengths.max()}")
    return (f"{len(ranges)} run{'s' if len(ranges) > 1 else ''} of {span} samples (from "
            f"{_times_of(ranges[:, 0], fs)})")


def _plateau_end(x: np.ndarray, fs: float, f_dom: float, begin: int, stop: int) -> int | None:
    """Where a steady forced response that holds the decay's largest sample ``begin`` ends, or
    None when the motion decays from ``begin`` on.

    A sine dwell (or a burst of forcing) switched off inside the record holds its amplitude
    flat, then decays: the largest sample lies anywhere in the flat part, which is no free
    decay (a dwell 2 % below the mode's frequency read that frequency 0.5 % high). The
    logarithm of the maxima of ``|x|`` over half periods, from ``begin`` down to
    :data:`PLATEAU_DOWN` of the largest, is fitted by a straight line (a decay) and by a hinge
    (flat, then falling): a hinge that leaves :data:`PLATEAU_GAIN` times less residual and
    whose flat part falls at most :data:`PLATEAU_SLOPE` times as fast as the rest marks a
    plateau. A free decay never does: its quadratic damping makes it fall fastest at its
    start. ``fs`` and ``f_dom`` (the dominant oscillation) in Hz; ``begin`` and ``stop``
    sample indices of ``x``. Returns the sample of the plateau's last half-period maximum."""
    half = max(1, int(round(0.5 * fs / f_dom)))
    n = (stop - begin) // half
    if n < 2 * PLATEAU_MIN:
        return None
    blocks = np.abs(x[begin:begin + n * half]).reshape(n, half)
    peaks = begin + np.arange(n) * half + np.argmax(blocks, axis=1)
    h = np.abs(x[peaks])
    below = np.flatnonzero(h < PLATEAU_DOWN * h[0])
    count = int(below[0]) if below.size else h.size
    if count < 2 * PLATEAU_MIN or not np.all(h[:count] > 0):
        return None
    y = np.log(h[:count])
    k = np.arange(count, dtype=np.float64)
    line = np.polyval(np.polyfit(k, y, 1), k)
    rss_line = float(np.sum((y - line) ** 2))
    # Every hinge at once (j: half periods in the flat part), from running sums: the flat
    # part's mean and scatter, and the falling part's least-squares slope from the hinge on.
    j = np.arange(PLATEAU_MIN, count - PLATEAU_MIN + 1)
    head, head2 = np.cumsum(y)[j - 1], np.cumsum(y * y)[j - 1]
    tail = np.cumsum(y[::-1])[::-1][j]
    tail_k = np.cumsum((k * y)[::-1])[::-1][j]
    tail2 = np.cumsum((y * y)[::-1])[::-1][j]
    level = head / j
    m = count - j                                    # half periods after the hinge
    u2 = m * (m + 1.0) * (2.0 * m + 1.0) / 6.0       # sum of (k - j + 1)^2 over them
    zu = tail_k - (j - 1.0) * tail - level * m * (m + 1.0) / 2.0
    z2 = tail2 - 2.0 * level * tail + m * level * level
    rss = (head2 - head * level) + z2 - zu * zu / u2
    best = int(np.argmin(rss))
    hinge, slope = int(j[best]), float(zu[best] / u2[best])
    flat = float(np.polyfit(k[:hinge], y[:hinge], 1)[0])
    if (slope < 0.0 and float(rss[best]) * PLATEAU_GAIN <= rss_line
            and abs(flat) <= PLATEAU_SLOPE * -slope):
        return int(peaks[hinge - 1])
    return None


def _forced_end(band: np.ndarray, fs: float, f_dom: float, begin: int, stop: int,
                floor: float, level: float) -> int | None:
    """Where a forced response that holds the decay's largest sample ``begin`` ends, or None
    when the motion decays from ``begin`` on.

    Random forcing (a burst switched off inside the record) drives the dominant mode's
    amplitude up and down: its largest sample lies anywhere in the burst, and the decay taken
    from it read a 17 Hz mode at 16.5 Hz (interval +-0.12 Hz, no warning). A free decay's
    amplitude in its own band never rises: a half-period maximum of ``band`` (the envelope,
    ``|x|`` in the dominant mode's band, :data:`RISE_BAND`) :data:`RISE_RATIO` times below a
    later one marks forcing before the later one. The last such rise counts when its peak
    reaches ``level`` (:data:`RISE_LEVEL` of ``band``'s largest over the record, unit of
    ``band``), leaves ``2 MIN_CYCLES`` half periods above ``floor`` (the band's noise, unit of
    ``band``) and is followed by no rise of :data:`RISE_AFTER` (a beat with another mode in
    the band rises again and again), and when no start was given for the decay
    (:func:`_windows`). A rise at the window's end
    (``stop``: the next excitation) or within :data:`RISE_SETTLE` periods of the record's
    first sample is not looked at. ``fs`` and ``f_dom`` in Hz, ``begin`` and ``stop`` sample
    indices. Returns the sample of the rise's peak."""
    half = max(1, int(round(0.5 * fs / f_dom)))
    n = (stop - begin) // half
    if n < 4 * MIN_CYCLES:
        return None
    blocks = band[begin:begin + n * half].reshape(n, half)
    h = blocks.max(axis=1)
    end = n
    while end > 1 and h[end - 2] < h[end - 1]:      # the rise into the next excitation
        end -= 1
    h = h[:end]
    if h.size < 4 * MIN_CYCLES:
        return None
    later = np.maximum.accumulate(h[::-1])[::-1]            # the largest from each on
    above = np.cumsum((h > floor)[::-1])[::-1]              # half periods above the floor
    settled = begin + np.arange(h.size - 1) * half >= RISE_SETTLE * fs / f_dom
    rises = np.flatnonzero((np.maximum(h[:-1], floor) * RISE_RATIO < later[1:])
                           & (later[1:] >= level) & settled)
    for k in rises[::-1]:
        peak = k + 1 + int(np.argmax(h[k + 1:]))
        if above[peak] < 2 * MIN_CYCLES:
            continue
        free = h[peak:]
        low = np.minimum.accumulate(np.maximum(free, 3.0 * floor))
        if np.any(free[1:] > RISE_AFTER * low[:-1]):
            return None
        return int(begin + peak * half + int(np.argmax(blocks[peak])))
    return None


def _refuse_comb(frequencies: np.ndarray, f_dom: float) -> None:
    """Refuse a record whose one free decay shows a comb of spectral lines (:data:`COMB_LINES`
    consecutive multiples of one frequency f0): it is excited every 1 / f0 s, too often for
    the decays between to be told apart (:func:`_windows` found one), and each line would
    pass for a mode."""
    f = np.sort(frequencies[frequencies > 0])
    if f.size < COMB_LINES:
        return
    for f0 in np.unique(np.diff(f)):
        n = np.rint(f / f0)
        on = (n >= 1) & (np.abs(f - n * f0) <= COMB_TOLERANCE * f0)
        multiples = np.unique(n[on]).astype(int)
        run = max((len(list(g)) for _, g in itertools.groupby(
            enumerate(multiples), key=lambda p: p[1] - p[0])), default=0)
        if run >= COMB_LINES:
            lines = ", ".join(f"{v:.4g}" for v in f[on][:6])
            raise fail("identify", f"the record's spectrum is a comb of lines {f0:.4g} Hz apart "
                                   f"({lines} Hz): it is excited every {1.0 / f0:.3g} s "
                                   f"({f_dom / f0:.1f} cycles of its dominant oscillation at "
                                   f"{f_dom:.4g} Hz), too often for one free decay to be told "
                                   f"from the next; {_spacing_advice(f_dom)}")


def _spacing_advice(frequency: float) -> str:
    """What an impulse train needs for the mode at ``frequency`` (Hz)."""
    need = (MIN_CYCLES + 1.0) / frequency
    return (f"an impulse train's impulses must be at least {need:.2g} s apart ({MIN_CYCLES + 1} "
            f"cycles of the {frequency:.4g} Hz mode), and further apart when its decays are "
            "slow to fall below half their start")


def _static_hold(x: np.ndarray) -> tuple[int, float] | None:
    """A displacement record that holds a static deflection before its release: the samples
    it holds still for and how far from where it comes to rest (unit of ``x``), or None
    (see :data:`HOLD_SHARE`). Held, the record's level steps at the release from the
    deflection to the rest position, and that step's spectrum, strong at low frequencies,
    passes for the dominant oscillation and smears into the bands (a 17 Hz mode released from
    2 mm read C_f +78 %, at 16.7 Hz)."""
    head = x[:max(16, int(HOLD_SHARE * x.size))]
    steps = np.diff(head)
    noise = max(1.4826 * float(np.median(np.abs(steps - np.median(steps)))) / math.sqrt(2.0),
                PRECISION * float(np.max(np.abs(x))))      # (a record without noise)
    held = float(np.median(head))
    rest = float(np.median(x[-max(16, int(REST_SHARE * x.size)):]))
    if not (noise > 0.0 and float(np.std(head)) <= HOLD_STILL * noise
            and abs(held - rest) > HOLD_OFFSET * noise):
        return None
    # Each block of the head's length against the median of the block before: a sensor's
    # slow drift while the beam is held (2.6 % of a 7 s hold) moved the record away from the
    # head's level long before the release, the rest of the hold was left as a step, and
    # that step's spectrum hid the mode.
    size = head.size
    blocks = x[:x.size // size * size].reshape(-1, size)
    before = np.median(blocks[:-1], axis=1)
    away = np.abs(blocks[1:] - before[:, None]) > HOLD_DEPARTURE * noise
    moved = np.flatnonzero(away.ravel()) + size
    if moved.size == 0:
        return None
    # Released from a deflection, the record swings about the rest position from where it
    # was held: its largest excursion is about the deflection. A still lead-in before an
    # excitation lies near the rest position, however the record's end is read.
    if abs(held - rest) < HOLD_REACH * float(np.max(np.abs(x[moved[0]:] - rest))):
        return None
    return int(moved[0]), held - rest


def _unforced(windows: list[tuple[int, int, int]], reference: np.ndarray, fs: float,
              f_dom: float) -> list[tuple[int, int, int]]:
    """The windows whose base (``reference``, the base acceleration) is still while they last:
    the median of its envelope over the free part below :data:`FORCED_LEVEL` of its largest,
    or - when its largest stands :data:`PULSE_MARGIN` times above its own white noise (an
    excitation that ends; random forcing reaches 4 to 5 times its RMS) - no more than
    :data:`NOISE_ENVELOPE` times that noise (the accelerometer's noise alone: at 3 % of a
    weak pulse's peak, a still base read as still moving). Refuses the record when none is: a
    base that keeps moving (random or continuous excitation) forces the structure
    throughout, and no decay is free."""

    ref = reference - float(np.median(reference))
    env = np.abs(hilbert(ref))
    top = float(np.max(env))
    if top <= 0.0:
        return windows
    noise = _noise_rms(ref, fs, np.array([f_dom]))
    still = FORCED_LEVEL * top
    if top >= PULSE_MARGIN * noise:
        still = max(still, NOISE_ENVELOPE * noise)
    level = [float(np.median(env[free:stop])) for _, free, stop in windows]
    kept = [w for w, v in zip(windows, level) if v < still]
    if kept:
        return kept
    raise fail("identify", f"the base (the reference channel) keeps moving after every "
                           f"excitation: its envelope stays at {100 * min(level) / top:.0f} % "
                           f"of its largest or more over each decay, "
                           f"{min(level) / max(noise, 1e-300):.1f} times its own noise (a free "
                           f"decay needs it below {100 * FORCED_LEVEL:.0f} % or, after a "
                           f"pulse, below {NOISE_ENVELOPE:g} times that noise): the record "
                           "holds no free decay (a random or continuous excitation), and C_i "
                           "and C_f need free decays; end the excitation well before the "
                           "record ends"
                           + ("; or, if the base was still and its channel holds only its "
                              "sensor's noise (a hammer or pluck test: its largest envelope, "
                              f"{top / max(noise, 1e-300):.1f} times that noise, is what noise "
                              "alone reaches), analyse without it: --set analysis.reference="
                              if top < PULSE_MARGIN * noise else ""))


def _walk_back(x: np.ndarray, fs: float, f_dom: float, peak: int) -> int:
    """Where a free decay whose largest sample is ``peak`` starts: at ``peak``, or - when
    ``peak`` lies within the record's first cycles and the extrema before it, back to the
    record's first, are each within :data:`LEVEL_BACK` of the next - at the record's first
    extremum. A decay recorded from release starts with extrema of nearly equal size; one that
    follows an excitation inside the record starts at its largest sample."""
    half = max(1, int(round(0.5 * fs / f_dom)))
    reach = max(1, half // 4)
    ax = np.abs(x)
    here = peak
    for _ in range(2):
        lo, hi = here - half - reach, here - half + reach + 1
        if lo < 0:
            break
        before = lo + int(np.argmax(ax[lo:hi]))
        if not (0 < before < here) or ax[before] < LEVEL_BACK * ax[here]:
            return peak
        here = before
    return here if here < half + reach else peak


def _beat_split(x: np.ndarray, windows: list[tuple[int, int, int]]) -> bool:
    """Whether the free-decay ``windows`` (samples) could be one release split at the nodes
    of its modes' beating: several windows, each one's largest value under the one before's
    (:data:`BEAT_FALL`). A train of impulses restarts each decay near the first's height."""
    if len(windows) < 2:
        return False
    tops = [float(np.max(np.abs(x[a:c]))) for a, _, c in windows]
    return all(later < BEAT_FALL * earlier for earlier, later in zip(tops, tops[1:]))


def _candidates(x: np.ndarray, fs: float, windows: list[tuple[int, int, int]],
                band: tuple[float, float] | None, f_dom: float, sigma: float
                ) -> tuple[np.ndarray, np.ndarray, list[str], np.ndarray, np.ndarray]:
    """Candidate mode frequencies (Hz) and spectral amplitudes from the windows' averaged
    spectrum, notes on the peaks left out, the frequencies (Hz) of those left out that
    still stand out of the spectrum as modes do (undersampled, too slow for the windows, or
    steady lines): they keep bands of their own (guards), so no mode's band passes them; and
    the frequencies (Hz) of the steady lines among them (:func:`_steady_line`; ``sigma``: the
    record's white-noise RMS)."""
    notes = []
    guards = []
    steady = []
    segs = [(a, c) for a, _, c in windows]
    freqs, amp = _decay_spectrum(x, fs, segs, f_dom)
    longest = max(c - a for a, c in segs) / fs
    # Every local peak first (a weak mode on a strong one's tail has little prominence), then
    # those high enough, standing out of their surroundings and above the noise. From two
    # cycles of the longest decay up: a short window (a strong steady line, mains hum, cuts a
    # decay where its envelope beats) hid every mode below two of its own cycles.
    peaks = find_peaks_interpolated(freqs, amp, min_relative=1e-4, smoothing=PEAK_SMOOTHING,
                                    fmin=2.0 / longest, _func="identify")
    high = peaks.amplitudes >= MODE_THRESHOLD * float(np.max(peaks.amplitudes, initial=0.0))
    if band is not None:
        # a band asked for: its own peaks are measured against the largest in it (a heavily
        # damped mode's peak is low beside a lightly damped one's elsewhere)
        inside = (peaks.frequencies >= band[0]) & (peaks.frequencies <= band[1])
        if inside.any():
            high |= inside & (peaks.amplitudes
                              >= MODE_THRESHOLD * float(np.max(peaks.amplitudes[inside])))
    f, a = peaks.frequencies[high], peaks.amplitudes[high]
    level = _spectrum_level(freqs, amp, f, a)
    broad = _broad_small_peaks(freqs, amp, peaks.frequencies[~high], peaks.amplitudes[~high],
                               f, a, level)
    notes.extend(note for _, note in broad)
    keep = np.ones(f.size, dtype=bool)
    flanks = []
    for i, fi in enumerate(f):
        col = _col(fi, float(a[i]), f[:i][keep[:i]], freqs, amp)
        if col > VALLEY or a[i] < NOISE_MARGIN * level:
            keep[i] = False                 # a flank of a larger peak, or noise
            if col > VALLEY:
                flanks.append(fi)
            if i == 0 and a[i] >= NOISE_MARGIN * level and f_dom * longest >= MIN_CYCLES:
                notes.append(f"{UNRESOLVED_PEAK} {fi:.4g} Hz, does not stand out "
                             f"of the spectrum around it (it falls only to {100 * col:.0f} % "
                             f"of its height within an octave; a mode falls below "
                             f"{100 * VALLEY:.0f} %): no mode rings freely in the decays (one "
                             "damped so heavily that it loses most of its amplitude within a "
                             "cycle, or a response still forced)")
            continue
        if fs / fi < MIN_SAMPLES_PER_CYCLE:
            keep[i] = False
            guards.append(fi)
            notes.append(f"the spectral peak at {fi:.4g} Hz is undersampled ({fs / fi:.1f} "
                         f"samples per cycle at {fs:g} Hz; at least {MIN_SAMPLES_PER_CYCLE:g} "
                         "needed): left out")
        elif fi * longest < MIN_CYCLES:
            keep[i] = False
            guards.append(fi)
            notes.append(f"the spectral peak at {fi:.4g} Hz completes fewer than {MIN_CYCLES} "
                         f"cycles in the longest free decay ({longest:.3g} s): left out"
                         + (f" ({_spacing_advice(fi)})" if len(segs) > 1 else ""))
        elif (share := _steady_line(x, fs, segs, float(fi), sigma, f_dom)) is not None:
            keep[i] = False
            guards.append(fi)
            steady.append(fi)
            notes.append(f"the spectral peak at {fi:.4g} Hz does not decay: over the last "
                         f"third of the free decays it keeps {100 * share:.0f} % of its "
                         "amplitude over their first third"
                         + (", and it is there before the excitation" if share < STRICT_SHARE
                            else "") + ": a steady line (mains hum, a machine nearby, a mode "
                         "that hardly decays within the record); left "
                         "out, and subtracted from each free decay (fitted on its second "
                         "half)")
    # (a line hides under a strong peak: a mode's at least a tenth of the largest)
    strong = f[keep][a[keep] >= HIDDEN_SHARE * float(np.max(a[keep], initial=0.0))]
    for fi, share in _late_lines(x, fs, segs, f_dom, sigma, strong,
                                 np.concatenate([f[keep], guards]).astype(np.float64)):
        guards.append(fi)
        steady.append(fi)
        notes.append(f"the late parts of the free decays show a line at {fi:.4g} Hz that keeps "
                     f"{100 * share:.0f} % of its amplitude over their first third, hidden there "
                     "under a mode's peak: a steady line (mains hum, a machine nearby, a mode "
                     "that hardly decays within the record); left out, and subtracted from "
                     "each free decay (fitted on its second half)")
    f, a = f[keep], a[keep]
    known = np.concatenate([f, flanks, guards, [fi for fi, _ in broad]])
    for fi, height, fall, seconds in _early_peaks(x, fs, segs, known, f):
        if band is not None and band[0] <= fi <= band[1]:
            # asked for: a candidate, at the peak of the whole decays' spectrum nearest it
            close = np.abs(peaks.frequencies - fi) <= EARLY_APART * fi
            at = peaks.frequencies[close][np.argmax(peaks.amplitudes[close])] if close.any() \
                else fi
            f = np.append(f, at)
            a = np.append(a, float(np.interp(at, freqs, amp)))
            continue
        lo, hi = _band_around(fi, f)
        notes.append(f"the decays' first {seconds:.3g} s show a spectral peak at {fi:.4g} Hz, "
                     f"{height:.0f} times the noise there, that falls to {100 * fall:.0f} % of "
                     f"its height over the next {seconds:.3g} s: a heavily damped mode, lost "
                     "in the whole decays' spectrum under its noise; not reported; "
                     f"--set analysis.hvd.band_hz={lo:.3g},{hi:.3g} identifies it alone")
    if f_dom * longest < MIN_CYCLES:
        notes.append(f"the free decays last at most {longest:.3g} s, fewer than {MIN_CYCLES} "
                     f"cycles of the record's dominant oscillation at {f_dom:.4g} Hz"
                     + (f" ({_spacing_advice(f_dom)})" if len(segs) > 1 else ""))
    if band is not None and not np.any((f >= band[0]) & (f <= band[1])):
        listed = ", ".join(f"{v:.4g}" for v in np.sort(f)) or "none"
        raise fail("identify", f"band {band[0]:g} to {band[1]:g} Hz holds none of the record's "
                               f"modes (found at {listed} Hz); expected a band around one")
    return f, a, notes, np.array(guards, dtype=np.float64), np.array(steady, dtype=np.float64)


def _half_power_band(freqs: np.ndarray, amp: np.ndarray, f: float
                     ) -> tuple[float, float, float]:
    """The height (spectrum unit) and half-power edges (Hz) of the peak of the spectrum
    ``amp`` at ``f`` (Hz), on the spectrum smoothed over +-2 % of ``f`` as :func:`_col`
    smooths it (the bins of a noisy spectrum fall under a low peak's half power next to it: a
    2 % damped 228 Hz mode read 3 Hz wide, not 5)."""
    smooth = _smoothed_around(freqs, amp, f)
    k = int(np.argmin(np.abs(freqs - f)))
    height = float(smooth[k])
    below = smooth < height / math.sqrt(2.0)
    left = np.flatnonzero(below[:k])
    right = np.flatnonzero(below[k:])
    lo = freqs[left[-1]] if left.size else freqs[0]
    hi = freqs[k + right[0]] if right.size else freqs[-1]
    return height, float(lo), float(hi)


def _peak_area(freqs: np.ndarray, amp: np.ndarray, f: float) -> float:
    """The area (height times half-power width, spectrum unit times Hz) of the peak of the
    spectrum ``amp`` at ``f`` (Hz), from :func:`_half_power_band` (smoothing keeps the
    area)."""
    height, lo, hi = _half_power_band(freqs, amp, f)
    return height * (hi - lo)


def _band_around(f: float, modes: np.ndarray) -> tuple[float, float]:
    """A band (Hz) around a mode at ``f`` (Hz) for ``band_hz``: +-25 %, or up to the
    geometric mean with the nearest of the other ``modes`` (Hz) on either side."""
    below, above = modes[modes < f], modes[modes > f]
    lo = max(f / 1.25, math.sqrt(f * float(below.max()))) if below.size else f / 1.25
    hi = min(f * 1.25, math.sqrt(f * float(above.min()))) if above.size else f * 1.25
    return lo, hi


def _broad_small_peaks(freqs: np.ndarray, amp: np.ndarray, small_f: np.ndarray,
                       small_a: np.ndarray, f: np.ndarray, a: np.ndarray, level: float
                       ) -> list[tuple[float, str]]:
    """Notes on spectral peaks (``small_f``, Hz, heights ``small_a``) under
    :data:`MODE_THRESHOLD` of the largest of the candidates (``f``, ``a``) that still look
    like a mode's: at least :data:`BROAD_HEIGHT` of it, standing out of the spectrum and its
    noise (``level``) as a candidate must, and broad enough that their area (height times
    half-power width) is :data:`BROAD_AREA` of the largest peak's or more. A heavily damped
    mode's peak is low for its amplitude (its height goes as amplitude over damping): a
    316 Hz mode at 2 % damping whose release was 1.4 times a lightly damped 17 Hz mode's left
    a peak at 0.98 % of that mode's, and it was left out without a word. A peak whose
    half-power band (widened by :data:`EARLY_APART` of its frequency) holds a harmonic of a
    candidate, up to :data:`EARLY_ORDER`, may be that harmonic instead: the waveform of a
    mode with a nonlinear damping or stiffness has harmonics, broad where the damping is
    large (a 17 Hz quadratically damped decay, recorded as acceleration, showed one at 54 Hz
    with 10 % of the mode's area); its note says so. Returns each noted peak's frequency (Hz)
    with its note."""
    if not a.size or not small_f.size:
        return []
    top = int(np.argmax(a))
    area = _peak_area(freqs, amp, float(f[top]))
    noted = []
    for fi, ai in zip(small_f, small_a):
        if ai < BROAD_HEIGHT * a[top] or ai < NOISE_MARGIN * level \
                or _col(float(fi), float(ai), f, freqs, amp) > VALLEY:
            continue
        height, lo, hi = _half_power_band(freqs, amp, float(fi))
        share = height * (hi - lo) / area
        if share < BROAD_AREA:
            continue
        said = (f"the spectral peak at {fi:.4g} Hz stands out of the spectrum as a mode's, but "
                f"its height is {100 * ai / a[top]:.2g} % of the largest, under the "
                f"{100 * MODE_THRESHOLD:g} % a component needs, while its area (height times "
                f"width) is {100 * share:.0f} % of the largest's")
        apart = EARLY_APART * float(fi)
        harmonic = [(order, float(fc)) for fc in f for order in range(2, EARLY_ORDER + 1)
                    if lo - apart <= order * fc <= hi + apart]
        if harmonic:
            order, fc = min(harmonic, key=lambda h: abs(h[0] * h[1] - fi))
            noted.append((float(fi),
                f"{said}; its half-power band ({lo:.4g} to {hi:.4g} Hz) holds {order} times "
                f"the {fc:.4g} Hz peak's frequency: the harmonic a nonlinear damping or "
                "stiffness gives that mode's waveform, or a heavily damped mode; not "
                "reported (if it is a mode, band_hz, e.g. --set "
                "analysis.hvd.band_hz=LOW,HIGH around it, identifies it alone)"))
        else:
            noted.append((float(fi),
                f"{said}: a heavily damped mode, not reported; band_hz (e.g. --set "
                "analysis.hvd.band_hz=LOW,HIGH around it) identifies it alone"))
    return noted


def _early_peaks(x: np.ndarray, fs: float, segments: list[tuple[int, int]], known: np.ndarray,
                 modes: np.ndarray) -> list[tuple[float, float, float, float]]:
    """Heavily damped modes the spectrum of whole decays dilutes under its noise, found in
    the spectra of the decays' first parts (:data:`EARLY_SHARES` of the longest; ``segments``,
    sample ranges of ``x``): each as ``(frequency Hz, height over that spectrum's noise, the
    share of that height left over the next stretch of the same length, the stretch's length
    s)``, from the longest stretch that shows it, away from the ``known`` peaks (Hz: the
    candidates, those left out, and those already noted) and from the harmonics, sums and
    differences of the ``modes`` (Hz, the candidates kept; see :data:`EARLY_ORDER`)."""
    longest = max(c - a for a, c in segments)
    products = [k * f for f in modes for k in range(2, EARLY_ORDER + 1)]
    for fi, fj in itertools.permutations(modes, 2):
        products += [fi + fj, abs(fi - fj), 2.0 * fi + fj, abs(2.0 * fi - fj)]
    near = np.concatenate([np.asarray(known, dtype=np.float64), products])
    found: list[tuple[float, float, float, float]] = []
    for share in EARLY_SHARES:
        n = int(share * longest)
        if n < MIN_WINDOW:
            continue
        # (both stretches must move: a gap left as recorded, or an exporter's fill, does not)
        first = [(a, a + n) for a, c in segments if c - a >= 2 * n
                 and np.ptp(x[a:a + n]) > 0.0 and np.ptp(x[a + n:a + 2 * n]) > 0.0]
        if not first:
            continue
        freqs, amp = averaged_spectrum(x, fs, first)
        _, after = averaged_spectrum(x, fs, [(a + n, a + 2 * n) for a, _ in first])
        peaks = find_peaks_interpolated(freqs, amp, min_relative=1e-4, smoothing=PEAK_SMOOTHING,
                                        fmin=EARLY_CYCLES * fs / n, _func="identify")
        level = _spectrum_level(freqs, amp, peaks.frequencies, peaks.amplitudes)
        step = float(freqs[1] - freqs[0])
        for fi, ai in zip(peaks.frequencies, peaks.amplitudes):
            fi, ai = float(fi), float(ai)
            apart = max(EARLY_APART * fi, 2.0 * step)
            if ai < NOISE_MARGIN * level or fs / fi < MIN_SAMPLES_PER_CYCLE \
                    or (near.size and float(np.min(np.abs(near - fi))) <= apart) \
                    or _col(fi, ai, peaks.frequencies[peaks.amplitudes > ai], freqs,
                            amp) > VALLEY:
                continue
            k = int(round(fi / step))
            fall = float(np.max(after[max(k - 1, 0):k + 2])) / ai
            if fall > EARLY_FALL:
                continue
            if not any(abs(seen[0] - fi) <= apart for seen in found):
                found.append((fi, ai / level, fall, n / fs))    # (the finest resolution)
    return found


def _too_few_peaks(components: Any, f: np.ndarray, band: tuple[float, float] | None,
                   notes: list[str]) -> str | None:
    """Why ``components`` (an int, or ``"auto"``) asks for more modes than the frequencies
    ``f`` (Hz) of the peaks with free decays of their own inside ``band`` hold, or None; with
    ``notes``, why other peaks were left out. Asked once the peaks are known to be free
    decays: a peak that is none (a shaker's resonance driving the record) is not counted."""
    inside = f.size if band is None else int(np.sum((f >= band[0]) & (f <= band[1])))
    if components == "auto" or inside >= int(components):
        return None
    return (f"{int(components)} component(s) asked for, but the record's free decays show "
            f"{inside} usable spectral peak(s)"
            + (f" ({', '.join(f'{v:.4g}' for v in f)} Hz)" if f.size else "")
            + "; ask for fewer or use components = 'auto'"
            + "".join(f"; {note}" for note in notes))


def _late_lines(x: np.ndarray, fs: float, segments: list[tuple[int, int]], f_dom: float,
                sigma: float, modes: np.ndarray, known: np.ndarray
                ) -> list[tuple[float, float]]:
    """Steady lines (:func:`_steady_line`) that the decays' spectrum does not show as peaks of
    their own: mains hum at 50 Hz beside a heavily damped 45 Hz mode lies on that mode's peak,
    and its band then holds the hum after the decay has died (C_i came out negative, C_f
    doubled). Where the decays have fallen, in their last thirds, the line stands out alone.
    Returns ``(frequency Hz, share)`` of each line found away from the ``known`` peaks (Hz,
    more than two bins of the last thirds' spectrum) and under the peak of one of the
    ``modes`` (Hz: within :data:`HIDDEN_RATIO` of it; a slow mode far from the others, such as
    a beam's first in water, rings on nearly steadily and is no line), the strong candidates
    (:data:`HIDDEN_SHARE`)."""
    found = []
    for a, c in segments:                # (each on its own: one may still ring where
        third = (c - a) // 3             # another has fallen)
        if third < 64 or not np.ptp(x[c - third:c]) > 0.0:     # (a held exporter's fill)
            continue
        freqs, amp = averaged_spectrum(x, fs, [(c - third, c)])
        peaks = find_peaks_interpolated(freqs, amp, min_relative=0.01,
                                        smoothing=PEAK_SMOOTHING, fmin=2.0 * fs / third,
                                        _func="identify")
        level = _spectrum_level(freqs, amp, peaks.frequencies, peaks.amplitudes)
        apart = 2.0 * (freqs[1] - freqs[0])
        for fi, ai in zip(peaks.frequencies, peaks.amplitudes):
            if ai < NOISE_MARGIN * level or fs / fi < MIN_SAMPLES_PER_CYCLE or (
                    known.size and float(np.min(np.abs(known - fi))) <= apart) or not (
                    modes.size and float(np.min(np.abs(np.log(modes / fi))))
                    <= math.log(HIDDEN_RATIO)):
                continue
            share = _steady_line(x, fs, segments, float(fi), sigma, f_dom)
            if share is not None:
                found.append((float(fi), share))
                known = np.append(known, fi)
    return found


def _steady_line(x: np.ndarray, fs: float, segments: list[tuple[int, int]], frequency: float,
                 sigma: float, f_dom: float) -> float | None:
    """The share of :func:`_steady_share` when the peak at ``frequency`` (Hz) is a steady line
    (see :data:`STEADY_SHARE`), None when it is not. Before the excitation
    (:func:`_before_excitation`, ``f_dom`` the dominant frequency, Hz) a mode has not rung, a
    line has."""
    share, late = _steady_share(x, fs, segments, frequency, sigma)
    if not STEADY_SHARE <= share <= 1.0 / STEADY_SHARE:     # falls, or grows: no line
        return None
    before = x[:_before_excitation(x, fs, f_dom)]
    if before.size * frequency < STEADY_CYCLES * fs:
        return share if share >= STRICT_SHARE else None
    return share if _amplitude_at(before, fs, frequency) >= BEFORE_SHARE * late else None


def _before_excitation(x: np.ndarray, fs: float, f_dom: float) -> int:
    """Samples of ``x`` before its excitation: up to two periods of its dominant oscillation
    (``f_dom``, Hz) before it first reaches :data:`ONSET_LEVEL` of its largest sample."""
    onset = int(np.argmax(np.abs(x) >= ONSET_LEVEL * float(np.max(np.abs(x)))))
    return max(0, onset - int(2.0 * fs / f_dom))


def _amplitude_at(part: np.ndarray, fs: float, frequency: float) -> float:
    """Amplitude of a sinusoid at ``frequency`` (Hz) in ``part`` (Hann-windowed DFT, its
    mean removed; unit of ``part``)."""
    w = np.hanning(part.size)
    phase = np.exp(-2j * math.pi * frequency / fs * np.arange(part.size))
    return 2.0 * abs(complex(np.dot((part - part.mean()) * w, phase))) / float(np.sum(w))


def _steady_share(x: np.ndarray, fs: float, segments: list[tuple[int, int]],
                  frequency: float, sigma: float) -> tuple[float, float]:
    """The amplitude at ``frequency`` (Hz) over the last third of the ``segments`` (the free
    decays, sample ranges) relative to that over their first third (Hann-windowed, the
    segments' powers summed): near 0 for a mode, whose free decay falls, about 1 for a steady
    line. 0 (no test) when no segment's third holds :data:`STEADY_CYCLES` cycles, or when the
    last thirds' amplitude is not :data:`NOISE_MARGIN` times that of white noise of RMS
    ``sigma`` (a component gone within the first cycles, which the taper of the first third
    hides as well: a Duffing mode's third harmonic, swept down as it decays). Also returns
    the amplitude over the last thirds (RMS over the segments, unit of ``x``)."""
    early = late = noise = gain = 0.0
    for a, c in segments:
        third = (c - a) // 3
        if third * frequency < STEADY_CYCLES * fs:
            continue
        w = np.hanning(third)
        # Powers of the tapered DFT: amplitude x half the taper's sum, squared.
        scale = (0.5 * float(np.sum(w))) ** 2
        noise += sigma * sigma * float(np.dot(w, w))
        gain += scale
        early += scale * _amplitude_at(x[a:a + third], fs, frequency) ** 2
        late += scale * _amplitude_at(x[c - third:c], fs, frequency) ** 2
    if early <= 0.0 or late < NOISE_MARGIN ** 2 * noise:
        return 0.0, 0.0
    return math.sqrt(late / early), math.sqrt(late / gain)


def _without_lines(x: np.ndarray, fs: float, windows: list[tuple[int, int, int]],
                   lines: np.ndarray) -> np.ndarray:
    """``x`` with each steady line (frequencies, Hz) subtracted from each window: a sinusoid
    of constant amplitude, fitted (frequency, amplitude, phase, and an offset) by least
    squares on the window's second half, where its modes have decayed most, and taken off
    the whole window. Left in, a line's crossings pull the band filters' end predictions and
    the modes' first extrema (a 50 Hz hum at 2 % of a 17 Hz release moved its C_i by +3 %)."""
    from scipy.optimize import minimize_scalar

    out = x.copy()
    for start, _, stop in windows:
        for f in lines:
            half = out[(start + stop) // 2:stop]
            if half.size * f < STEADY_CYCLES * fs:
                continue
            t = np.arange(half.size) / fs
            span = fs / half.size
            f_fit = float(minimize_scalar(lambda freq, part=half: -_amplitude_at(part, fs, freq),
                                          bounds=(f - span, f + span), method="bounded").x)
            basis = np.column_stack((np.cos(2 * math.pi * f_fit * t),
                                     np.sin(2 * math.pi * f_fit * t), np.ones_like(t)))
            (c, s, _), *_ = np.linalg.lstsq(basis, half, rcond=None)
            whole = (np.arange(start, stop) - (start + stop) // 2) / fs
            out[start:stop] -= c * np.cos(2 * math.pi * f_fit * whole) \
                + s * np.sin(2 * math.pi * f_fit * whole)
    return out


def _decay_spectrum(x: np.ndarray, fs: float, segments: list[tuple[int, int]], f_dom: float
                    ) -> tuple[np.ndarray, np.ndarray]:
    """RMS average of the windows' amplitude spectra (as :func:`.spectrum.averaged_spectrum`),
    on a grid of at most ``f_dom`` / :data:`SPECTRUM_BINS` (zero-padded): the free decays of a
    dense impulse train last a few cycles, and their spectra's peaks must still fall between
    bins, not on the grid's first."""
    longest = max(c - a for a, c in segments)
    nfft = max(longest, int(math.ceil(SPECTRUM_BINS * fs / f_dom)))
    if nfft == longest:
        return averaged_spectrum(x, fs, segments)
    power = 0.0
    for a, c in segments:
        freqs, amp = amplitude_spectrum(x[a:c], fs, window="decay", nfft=nfft, _func="identify")
        power = power + amp * amp
    return freqs, np.sqrt(power / len(segments))


def _spectrum_level(freqs: np.ndarray, amp: np.ndarray, peaks: np.ndarray,
                    heights: np.ndarray) -> float:
    """The noise level of a spectrum ``amp`` (the median of its bins away from its peaks, see
    :func:`_away_from`), kept out of the octaves around only those of the ``peaks`` (Hz, by
    decreasing ``heights``) that stand :data:`NOISE_MARGIN` times above that level: a long
    record's noise shows peaks of its own above 1 % of a mode's, and an octave kept out around
    each of them leaves no noise to measure (only the lowest bins, which hold the release's
    step in displacement). Starts from the largest peak alone and repeats until the peaks kept
    out settle."""
    strong = peaks[:1]
    level = float(np.median(amp[_away_from(freqs, strong)]))
    for _ in range(4):
        now = peaks[heights >= NOISE_MARGIN * level]
        if now.size == 0 or np.array_equal(now, strong):
            break
        strong = now
        level = float(np.median(amp[_away_from(freqs, strong)]))
    return level


def _away_from(freqs: np.ndarray, peaks: np.ndarray) -> np.ndarray:
    """Mask of the frequencies (Hz) outside an octave around each of ``peaks`` and above the
    lowest few bins: where a record's spectrum shows its noise. Falls back to those above
    twice the highest peak, then to every bin, when too few remain."""
    ok = freqs > 4.0 * (freqs[1] - freqs[0])
    for p in peaks:
        ok &= (freqs < 0.5 * p) | (freqs > 2.0 * p)
    if ok.sum() < 32 and peaks.size:
        ok = freqs > 2.0 * float(np.max(peaks))
    if ok.sum() < 32:
        ok = np.ones(freqs.size, dtype=bool)
    return ok


def _noise_rms(x: np.ndarray, fs: float, peaks: np.ndarray) -> float:
    """RMS of the white noise in a record, from the median of its amplitude spectrum (Hann
    window) away from its spectral ``peaks`` (Hz): a Rayleigh-distributed bin's median is
    ``sigma sqrt(ln 2) sqrt(sum w^2)``.

    The spectrum is taken in blocks along the record (:data:`NOISE_BLOCK` samples or more, at
    most :data:`NOISE_BLOCKS`), and the noise from the quietest: one spectrum of the whole
    record counts the broadband content of the excitation (a pulse, the base's motion taken
    off) as noise wherever the window does not taper it. A decay recorded 1.5 s after the
    acquisition started measured 2.8 times its noise that way, which raised its extrema's noise
    correction and floor and moved its C_i by +3 %. Blocks of noise alone agree within their
    median's spread (a relative standard error of about ``0.9 / sqrt(bins)``, the Hann window's
    neighbouring bins being correlated); those within three of it of the lowest are averaged.
    Runs of one value at the record's ends (padding, a held last sample) and blocks whose
    samples are all equal are no measurement and are left out. A record shorter than two
    blocks (2048 samples) is still measured on one spectrum; a constant stretch inside a block
    (a dropout) reads low."""
    moving = np.flatnonzero(np.diff(x) != 0)
    if moving.size and moving[-1] + 2 - moving[0] >= NOISE_BLOCK:
        x = x[moving[0]:moving[-1] + 2]
    count = int(min(NOISE_BLOCKS, max(1, x.size // NOISE_BLOCK)))
    size = x.size // count
    w = np.hanning(size)
    away = _away_from(np.arange(size // 2 + 1) * (fs / size), peaks)
    scale = math.sqrt(math.log(2.0)) * math.sqrt(float(np.sum(w * w)))
    levels, flat = np.empty(count), np.zeros(count, dtype=bool)
    for k in range(count):
        block = x[k * size:(k + 1) * size]
        flat[k] = count > 1 and bool(np.all(block == block[0]))
        spec = np.abs(np.fft.rfft((block - block.mean()) * w if count > 1 else block * w))
        levels[k] = float(np.median(spec[away])) / scale
    levels = levels[~flat] if not flat.all() else levels
    spread = 0.9 / math.sqrt(float(np.count_nonzero(away)))
    kept = levels[levels <= float(levels.min()) * (1.0 + 3.0 * spread)]
    return float(np.sqrt(np.mean(kept ** 2)))


def _smoothed_around(freqs: np.ndarray, amp: np.ndarray, f: float) -> np.ndarray:
    """The spectrum ``amp`` (on the evenly spaced ``freqs``, Hz) smoothed by a running mean
    over +-2 % of ``f`` (Hz): a peak's surroundings without its bins' noise."""
    width = max(1, int(0.02 * f / (freqs[1] - freqs[0])))
    return np.convolve(amp, np.ones(2 * width + 1) / (2 * width + 1), mode="same")


def _col(f: float, amplitude: float, others: np.ndarray, freqs: np.ndarray,
         amp: np.ndarray) -> float:
    """How far the spectral peak at ``f`` (Hz, of height ``amplitude``) stands out, as its col
    over its height: the higher of the lowest points of the spectrum (smoothed over +-2 %)
    between it and the nearest larger peak on each side, or an octave away where there is
    none. A mode of its own has a col below :data:`VALLEY`; a bump on the flank of a heavily
    damped mode has none (about 1), a weak mode on the tail of a strong one has. Infinite
    when no bin lies between."""
    smooth = _smoothed_around(freqs, amp, f)
    cols = []
    for side in (-1.0, 1.0):
        beyond = others[(others - f) * side > 0]
        edge = float(beyond[np.argmin(np.abs(beyond - f))]) if beyond.size \
            else (0.5 * f if side < 0 else 2.0 * f)
        lo, hi = sorted((f, edge))
        between = (freqs > lo) & (freqs < hi)
        if not between.any():
            return math.inf
        cols.append(float(np.min(smooth[between])))
    return max(cols) / amplitude if amplitude > 0 else math.inf


def _extrema(signal: np.ndarray, fs: float, frequency: float, start: int, free: int,
             floor: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Times (s, record), values and crossings of the extrema of a band signal of the window
    starting at ``start``, from the first at or after sample ``free`` while above ``floor``
    and while each half cycle lasts :data:`HALF_CYCLE_RANGE` of the mode's."""
    hc = half_cycles(signal, fs, frequency)
    t = hc.times + start / fs
    sel = t >= (free - 1) / fs
    t, v = t[sel], hc.values[sel]
    above = np.abs(v) >= floor
    # The band filter settling on the window's start can leave its first extrema under the
    # floor too (a weak mode near fs/8 under a large low one): the decay begins after them.
    settling = 0
    while settling < min(SETTLING_HALF_CYCLES, above.size - 1) and not above[settling]:
        settling += 1
    if above[settling:settling + 1].all() and settling:
        t, v, above = t[settling:], v[settling:], above[settling:]
    run = int(np.argmin(above)) if not above.all() else above.size
    # A half cycle far longer or shorter than the mode's is no cycle of its free decay: the
    # motion has stopped (dry friction sticks) and what is left is the band filter's ringing
    # and the noise, above a floor that a quiet record sets low. The first
    # :data:`SETTLING_HALF_CYCLES` may be the band filter settling on the window's start (a
    # short first half cycle, under another mode's release): the decay begins after them
    # (ended there, a 26 Hz mode under a 5 Hz one was said to have no free decay at all).
    steps = np.diff(t[:run]) * 2.0 * frequency
    off = (steps < HALF_CYCLE_RANGE[0]) | (steps > HALF_CYCLE_RANGE[1])
    begin = 0
    while begin < min(SETTLING_HALF_CYCLES, off.size) and off[begin]:
        begin += 1
    later = np.flatnonzero(off[begin:])
    if later.size:
        run = begin + int(later[0]) + 1
    return t[begin:run], v[begin:run], hc.crossings + start / fs


def _band_quiet(parts: np.ndarray, fs: float) -> list[np.ndarray]:
    """Per band, the samples at which the reference (the base acceleration, split into the
    modes' bands: ``parts``) has calmed down in that band after each of its bursts
    (:func:`.decays.quiet_times` at :data:`BAND_QUIET_LEVEL`): a mode is forced at resonance
    by the base motion in its own band, however small the base's total motion."""
    return [np.rint(quiet_times(row, fs, level=BAND_QUIET_LEVEL) * fs).astype(np.int64)
            for row in parts]


def _too_short(windows: list[tuple[int, int, int]], modes: list[_Mode], fs: float) -> str:
    """Why no mode has a usable free decay, and how long the decays must be (or, when the
    longest is long enough, that the noise hides them: the notes that follow say how)."""
    longest = max(c - b for _, b, c in windows) / fs
    lowest = min(m.frequency for m in modes)
    need = MIN_CYCLES / lowest
    if longest >= need:
        return (f"no spectral peak has a free decay of {MIN_CYCLES} cycles above the noise "
                f"floor: the longest free decay, {longest:.3g} s, would hold them for the mode "
                f"at {lowest:.4g} Hz; the noise in its band is what hides them; ")
    spacing = (f"; {_spacing_advice(lowest)} (and further still for the decays to last "
               f"{need:.2g} s above the noise)" if len(windows) > 1 else "")
    return (f"no spectral peak has a free decay of {MIN_CYCLES} cycles above the noise floor: "
            f"the longest free decay lasts {longest:.3g} s, and the mode at {lowest:.4g} Hz "
            f"needs at least {need:.2g} s of free decay above the noise{spacing}; ")


def _unlifted(amplitude: np.ndarray, lift: float) -> np.ndarray:
    """Extremum amplitudes less the noise's average lift ``lift / A`` (U^2 / U)."""
    return amplitude - lift / amplitude


def _match(times: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Index into ``times`` of the nearest entry to each of ``reference``."""
    j = np.clip(np.searchsorted(times, reference), 1, max(times.size - 1, 1))
    if times.size == 1:
        return np.zeros(reference.size, dtype=np.int64)
    left = np.abs(times[j - 1] - reference) <= np.abs(times[j] - reference)
    return np.where(left, j - 1, j)


def _match_drifting(times: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """:func:`_match` for two sequences of like events (``times``: a model's extrema or zero
    crossings, s; ``reference``: the record's, s, in order) whose offset drifts: where the
    nearest entries' offsets jump by half the events' spacing or more between neighbours (the
    offset wrapped past the midpoint between two events), each reference is paired instead
    with the entry nearest to it less the offset of the last pair that kept to the drift.

    A strongly softening model whose frequency is still a few per cent off drifts by a half
    period in twenty cycles (a 10 % softening 40 Hz decay: 6 ms in 40 crossings of 12.5 ms
    apart). Paired by nearest times, the crossings of every other stretch were another
    cycle's; the frequency's step, fitted to those left, moved the frequency away from the
    record's (1.5 % off after five passes from 0.2 %), and the extrema's smear was taken from
    a neighbouring extremum's."""
    idx = _match(times, reference)
    if idx.size < 2 or times.size < 2:
        return idx
    spacing = float(np.median(np.diff(times)))
    offset = reference - times[idx]
    if float(np.max(np.abs(np.diff(offset)))) < 0.5 * spacing:
        return idx
    drift = float(offset[0])
    for i, when in enumerate(reference):
        j = int(_match(times, np.array([when - drift]))[0])
        idx[i] = j
        if abs(when - times[j] - drift) < 0.25 * spacing:
            drift = float(when - times[j])
    return idx


def _span_period(crossings: np.ndarray, t0: float, t1: float) -> float | None:
    """Mean half period (s) of the crossings between t0 and t1 (least-squares slope)."""
    c = crossings[(crossings >= t0) & (crossings <= t1)]
    if c.size < 3:
        return None
    k = np.arange(c.size)
    return float(np.polyfit(k, c, 1)[0])


def _pooled_half_period(decays: list[dict]) -> float | None:
    """The half period (s) of a mode's decays: each decay's (:func:`_span_period`), their
    median weighted by each decay's energy (the sum of its squared extrema), the two middle
    values averaged when the weights split evenly. A short or small stretch of something else
    (the residue at a noise-free record's end, split off as a decay of its own) cannot move
    it, as it moved the plain median of two decays halfway to itself."""
    values, weights = [], []
    for d in decays:
        h = _span_period(d["crossings"], d["times"][0], d["times"][-1])
        if h:
            values.append(h)
            weights.append(float(np.sum(np.square(d["values"]))))
    if not values:
        return None
    order = np.argsort(values)
    sorted_values = np.asarray(values)[order]
    cumulative = np.cumsum(np.asarray(weights)[order])
    half = 0.5 * cumulative[-1]
    k = int(np.searchsorted(cumulative, half))
    if math.isclose(cumulative[k], half) and k + 1 < sorted_values.size:
        return float(0.5 * (sorted_values[k] + sorted_values[k + 1]))
    return float(sorted_values[k])


@dataclass
class _Mode:
    """Working state of one mode during :func:`identify`."""

    band: int
    frequency: float
    floor: float
    correlation: Any
    decays: list[dict] = field(default_factory=list)
    w0: float = 0.0
    alpha: float = 0.0
    fits: dict[str, LawFit] = field(default_factory=dict)
    correction: float = 0.0
    w0_se: float = 0.0
    w0_dof: int = 1
    lift: float = 0.0
    noise: float = 0.0
    wild: int = 0
    drift: dict[str, float] = field(default_factory=dict)
    noise_power: float = 0.0
    noise_samples: int = 0
    joint: dict[str, Any] | None = None
    #: The frequency's wander over its decays, (widening, lowest, highest part's Hz), or None.
    wander: tuple[float, float, float] | None = None
    #: Whether a cubic stiffness was tried from the measured frequencies (:func:`_frequency_step`).
    stiffness_tried: bool = False


def _noise_before(modes: list[_Mode], record: np.ndarray, fs: float, bands: ModeBands,
                  f_dom: float, integrate: bool) -> None:
    """Each mode's band of the record before its excitation (:func:`_before_excitation`),
    added to the noise measured after its decays (``noise_power``): the band's own noise,
    measured where no mode rings. A band whose noise is coloured (a motion relative to a base whose
    accelerometer's noise grows at low frequencies) holds it above its white floor through
    the whole decay, and nothing is measured after it."""
    from scipy.signal import detrend

    end = _before_excitation(record, fs, f_dom)
    if end < MIN_WINDOW:
        return
    # Its own offset and trend off: the record's mean is the whole record's, and a drifting
    # sensor's slope is no noise of any band.
    parts = split(detrend(record[:end]), fs, bands, integrate=integrate)
    for mode in modes:
        before = parts[mode.band]
        mode.noise_power += float(np.dot(before, before))
        mode.noise_samples += before.size


def _band_noise_ratio(mode: _Mode, fs: float) -> float | None:
    """A mode's band noise (RMS, measured before the excitation and after its decays) over
    the white noise's share in its band (at least :data:`PRECISION` of the mode's largest
    extremum), or None with fewer than :data:`TAIL_PERIODS` periods to measure it on or a band
    noise below that share."""
    if mode.noise_samples * mode.frequency < TAIL_PERIODS * fs:
        return None
    band = math.sqrt(mode.noise_power / mode.noise_samples)
    # A noise-free record's bands hold its numerical residue, not noise: no ratio.
    largest = max((float(np.max(np.abs(d["values"]))) for d in mode.decays if d["values"].size),
                  default=0.0)
    if band < PRECISION * largest:
        return None
    # (nor is a white noise below it measured: the ratio is to what could be)
    return band / max(mode.noise, PRECISION * largest)


def _follows_base(mode: _Mode, base_envelope: np.ndarray, fs: float, follow: str
                  ) -> tuple[float, float, float] | None:
    """The decay rates (1/s, of the mode's extrema and of the base's envelope in its band at
    their times) and the gain (the extrema's acceleration over the base's, the median), over
    the mode's decays, when every decay long enough to judge falls as the base's motion in the
    mode's band falls (within :data:`FOLLOW_RATE` of its rate, the base falling by
    :data:`FOLLOW_FALL` or more over the decay) with a gain of :data:`FOLLOW_GAIN` or less;
    else None.

    A base still ringing at its own resonance drives the structure there, off the structure's
    resonances: the record's "decay" is the base's, at a gain of order 1. A mode ringing freely
    shakes the base back at its own rate too (the shaker gives a little), but stands far
    above it: tens of times on the simulated bench."""
    order = 1 if follow == "velocity" else 2
    found = []
    for d in mode.decays:
        t, amplitude = d["times"], d["amplitude"]
        if t.size < 2 * MIN_CYCLES or np.any(amplitude <= 0.0):
            continue
        base = np.interp(t, np.arange(base_envelope.size) / fs, base_envelope)
        if np.any(base <= 0.0):
            return None
        own = float(np.polyfit(t - t[0], np.log(amplitude), 1)[0])
        driven = float(np.polyfit(t - t[0], np.log(base), 1)[0])
        gain = float(np.median(amplitude * (2.0 * math.pi * mode.frequency) ** order / base))
        if not (driven * (t[-1] - t[0]) <= -math.log(FOLLOW_FALL)
                and abs(own - driven) <= FOLLOW_RATE * abs(driven) and gain <= FOLLOW_GAIN):
            return None
        found.append((own, driven, gain))
    return tuple(np.mean(found, axis=0)) if found else None


def _band_noise_excess(mode: _Mode, fs: float) -> float | None:
    """How many times the white noise's share its band's own noise is, for a mode none of
    whose decays keeps :data:`MIN_CYCLES` cycles above :data:`FIRST_FLOOR` times that noise
    and rises above :data:`FLOOR` times it; None when one does, or when the band's noise is
    not measured (:func:`_band_noise_ratio`) or within :data:`TAIL_EXCESS` of the white
    share. The record's noise is measured as white; in a band
    where it is not (a motion relative to the base, whose integrated noise grows as 1 / f below
    the modes) noise passes for decays above the white floor: phantom modes at 4 to 10 Hz on
    the wet bench driven at 0.02 V s. The floors of the modes kept are not raised (the 17 Hz
    mode's band there holds 2 to 3 times the white noise, and its C_f erred twice as much
    with a floor raised as much): their fits weigh the extrema by the scatter they show."""
    ratio = _band_noise_ratio(mode, fs)
    if ratio is None or ratio <= TAIL_EXCESS:
        return None
    band_noise = ratio * mode.noise
    for d in mode.decays:
        size = np.abs(d["values"])
        above = size >= FIRST_FLOOR * band_noise
        run = int(np.argmin(above)) if not above.all() else above.size
        # Band noise over a few seconds reaches 3 times its RMS, a decay's start is taken at
        # its largest excursion, and then it "decays": a free decay rises above 5 times it.
        if run >= 2 * MIN_CYCLES and float(size.max()) >= FLOOR * band_noise:
            return None
    return ratio


def _scatter_without_decay(mode: _Mode) -> float | None:
    """How many times as far as its noise explains (RMS) a mode's extrema scatter about its
    quadratic law, when that exceeds :data:`SCATTER_EXCESS` and its damping terms together
    are not :data:`DECAY_Z` standard errors from 0 (no decay shown); None otherwise. A mode's
    extrema follow a smooth envelope within the noise, however light its damping; the
    extrema of noise in a band whose noise exceeds the white estimate do neither."""
    fit = mode.fits["quadratic"]
    if fit.dof < 1 or not np.all(np.isfinite(fit.cov)):
        return None
    try:
        # Both terms at once: in a short decay they trade off, each within its errors of 0
        # while together they show a clear decay.
        wald = float(fit.params @ np.linalg.solve(fit.cov, fit.params))
    except np.linalg.LinAlgError:
        return None
    # A decay shown is one that falls: an envelope that grows significantly is no decay.
    falls = all(m.size and m[-1] < m[0] for m in fit.model)
    if wald >= DECAY_Z ** 2 * fit.params.size and falls:
        return None
    scatter = math.sqrt(fit.rss / fit.dof) / max(mode.noise, 1e-300)
    return scatter if scatter > SCATTER_EXCESS else None


def _extrema_scatter(mode: _Mode) -> float | None:
    """How far the extrema scatter about the quadratic law's envelope (the whitened
    residual RMS), over the white noise's share in the mode's band: about 1 when the band
    holds the record's white noise, several times more with noise that is not white (1/f
    noise of a sensor: 3.5 to 4 at 1 % of the peak) or a law that misfits. None when the
    fit has no degrees of freedom left."""
    fit = mode.fits.get("quadratic")
    if fit is None or fit.dof <= 0 or not math.isfinite(fit.rss):
        return None
    scatter = math.sqrt(fit.rss / fit.dof)
    # A noise-free record's extrema leave its numerical residue, not noise: no ratio.
    largest = max((float(np.max(d["amplitude"])) for d in mode.decays if d["amplitude"].size),
                  default=0.0)
    if scatter < PRECISION * largest:
        return None
    return scatter / max(mode.noise, 1e-300)


def _whiteners(mode: _Mode) -> list[Whitener]:
    """The :class:`.laws.Whitener` of each of the mode's decays (its band's noise correlation
    at the decay's extrema)."""
    return [Whitener(d["times"], np.sign(d["values"]), mode.correlation,
                     d.get("scale", np.ones(d["amplitude"].size))) for d in mode.decays]


def _fit_all(mode: _Mode, quantity: str, laws: Sequence[str]) -> None:
    """Fit every law to the mode's corrected extrema (starting from earlier fits)."""
    amps = [d["amplitude"] for d in mode.decays]
    whiteners = _whiteners(mode)
    fits = {}
    for law in laws:
        prior = mode.fits.get(law)
        fits[law] = fit_law(law, amps, mode.w0, alpha=mode.alpha, quantity=quantity,
                            whiteners=whiteners, start=None if prior is None else prior.params)
    mode.fits = fits


def _preferred(mode: _Mode) -> LawFit:
    return compare_laws(list(mode.fits.values())).fits[
        compare_laws(list(mode.fits.values())).preferred]


def _model_record(modes: list[_Mode], window: tuple[int, int, int], fs: float, follow: str,
                  output: str, w_index: int, limit: float, reach: Sequence[float]
                  ) -> np.ndarray:
    """The fitted decays of every mode in one window, summed, as ``output`` (the record's
    quantity), each kept before its first extremum over its band filter's ``reach`` (s, per
    band: :meth:`.bands.ModeBands.reach`). A mode whose model leaves ``limit`` (a fit gone
    astray: a growing decay) is left out, so it cannot spoil the correction of the others."""
    start, _, stop = window
    times = np.arange(start, stop) / fs
    out = np.zeros(stop - start)
    for mode in modes:
        fit = _preferred(mode)
        for j, d in enumerate(mode.decays):
            if d["w"] != w_index:
                continue
            start_value = math.copysign(float(fit.starts[j]), float(d["values"][0]))
            anchor = d.get("anchor", float(d["times"][0]))
            decay = simulate_decay(fit.law, fit.params, mode.w0, start_value, anchor, times,
                                   alpha=mode.alpha, quantity=follow, output=output)
            # Before its first free extremum the model runs backwards in time from its anchor.
            # The record holds the mode's oscillation there (the window opens after the
            # excitation; with a reference, a mode's extrema count only once the base has
            # calmed in its band, periods later), and the band filter carries it into the first
            # extrema as far as the filter reaches: the model is kept over that reach, so it is
            # padded and filtered as the record is (faded to zero a period before the anchor,
            # the smear taken off the first extrema was not theirs: up to 6 % of the first
            # extremum of the wet bench's ramp, C_f 25 % low). Further back the backward run
            # describes nothing the record holds (quadratic damping read backwards grows fast):
            # faded out over a period.
            keep = max(1.0, reach[mode.band] * mode.frequency)
            lead = np.clip((times - anchor) * mode.frequency + keep + 1.0, 0.0, 1.0)
            decay = decay * smooth_step(lead)
            if np.all(np.isfinite(decay)) and float(np.max(np.abs(decay))) <= limit:
                out += decay
    return out


def _correct(modes: list[_Mode], windows: list[tuple[int, int, int]], bands: ModeBands,
             record: np.ndarray, fs: float, follow: str, quantity: str,
             noise: float = 0.0) -> None:
    """Step 6: put the fitted model through the same padding, filters and extremum search as
    the record, and take the difference from the model's exact extrema off the measured ones;
    anchor the model's first extremum where the filters put the measured one; step the linear
    frequency (:func:`_frequency_step`).

    With ``noise`` (the record's white-noise RMS), the model is measured again with
    :data:`NOISE_REALIZATIONS` records of that noise added (in antithetic pairs, so the noise's
    first-order effects cancel in the mean): the mean error then includes what the noise adds
    on average (an extremum is found where the noise lifts it), and the spread of the first
    and last :data:`EDGE_EXTREMA` extrema of a decay, which the edge padding makes noisier
    than the others, sets their weights in the fit (``scale``). The model's zero crossings,
    which the frequency step pairs with the record's, are moved by the mean shift the noise
    gives them (:func:`_noisy_crossings`): the noise changes the prediction that pads each
    window's ends for the filters, and with it a band's first crossings (by 1.5 ms, a tenth of
    a half period, on a heavily damped 31 Hz mode under a 216 Hz one of 2.2 times its
    acceleration, noise 2.2 % of its largest acceleration: its frequency read 0.18 % low).
    """
    integrate = quantity == "acceleration"
    rng = np.random.default_rng(NOISE_SEED)
    reach = [bands.reach(k) for k in range(bands.count)]
    for w, window in enumerate(windows):
        if not any(d["w"] == w for m in modes for d in m.decays):
            continue
        model = _model_record(modes, window, fs, follow, quantity, w,
                              MODEL_LIMIT * float(np.max(np.abs(record[window[0]:window[2]]))),
                              reach)
        clean = split(model, fs, bands, integrate=integrate)
        noisy, noisy_crossings = _noisy_errors(modes, w, window, model, bands, fs, integrate,
                                               noise, rng)
        for mode in modes:
            here = _decays_in(mode, w)
            if not here:
                continue
            fit = _preferred(mode)
            hc = half_cycles(clean[mode.band], fs, mode.frequency)
            t_model = hc.times + window[0] / fs
            if t_model.size < 2:
                continue
            model_crossings = _noisy_crossings(
                hc.crossings, noisy_crossings.get(mode.band, []), mode.frequency) + window[0] / fs
            for j, d in here:
                measured = np.abs(d["values"])
                idx = _match_drifting(t_model, d["times"])
                exact = fit.model[j]
                if noisy:
                    errors = np.array(noisy[id(mode), j])
                    smear = errors.mean(axis=0)
                    spread = errors.std(axis=0, ddof=1) / max(mode.noise, 1e-300)
                    scale = np.ones(measured.size)
                    edge = np.r_[0:min(EDGE_EXTREMA, scale.size),
                                 max(scale.size - EDGE_EXTREMA, 0):scale.size]
                    scale[edge] = np.maximum(1.0, spread[edge])
                    corrected = measured - smear
                    d["noise_dev"] = errors - smear
                else:
                    smear = np.abs(hc.values[idx]) - exact
                    corrected = _unlifted(measured, mode.lift) - smear
                    scale = d.get("scale", np.ones(measured.size)).copy()
                # A correction this large means the model does not describe that extremum
                # (another mode's onset, a glitch): keep it as measured, with little weight.
                wild = ~((corrected > 0.5 * measured) & (corrected < 2.0 * measured))
                corrected[wild] = measured[wild]
                scale[wild] = np.maximum(scale[wild], WILD_SCALE)
                if "noise_dev" in d:
                    d["noise_dev"][:, wild] = 0.0
                d["amplitude"], d["scale"] = corrected, scale
                if (~wild).any():
                    mode.correction = max(mode.correction, float(np.max(
                        np.abs(smear[~wild]) / measured[~wild])))
                mode.wild += int(wild.sum())
                d["model_crossings"] = model_crossings
                # The model's first extremum sits at its anchor; the filters move it by as
                # much as they move the measured one: anchor the model that much earlier.
                anchor = d.get("anchor", float(d["times"][0]))
                d["anchor"] = anchor - (float(t_model[idx[0]]) - float(d["times"][0]))
    for mode in modes:
        _frequency_step(mode, follow, seed=noise == 0.0)


def _correction_passes(modes: list[_Mode], windows: list[tuple[int, int, int]],
                       bands: ModeBands, record: np.ndarray, fs: float, follow: str,
                       quantity: str, sigma: float, laws: Sequence[str]) -> None:
    """Step 6's passes: noise-free corrections (:func:`_correct`) until the quadratic law moves
    by less than :data:`PASS_TOLERANCE` of its standard errors (a large smear, in short decays,
    takes several; :data:`MAX_PASSES` at most), then one with the record's noise ``sigma``;
    every law refitted after each."""
    moved = math.inf
    for n_pass in range(MAX_PASSES + 1):
        last = n_pass == MAX_PASSES or (n_pass > 0 and moved < PASS_TOLERANCE)
        before = [m.fits["quadratic"] for m in modes]
        _correct(modes, windows, bands, record, fs, follow, quantity, sigma if last else 0.0)
        for mode in modes:
            _fit_all(mode, follow, laws)
        if last:
            break
        moved = max(float(np.max(np.abs(m.fits["quadratic"].params - b.params)
                                 / np.maximum(m.fits["quadratic"].se, 1e-300)))
                    for m, b in zip(modes, before))


def _clusters(modes: list[_Mode]) -> list[list[_Mode]]:
    """Groups of two or more modes, each within :data:`CLOSE_RATIO` of a neighbour's linear
    frequency (the fitted one: a heavily damped mode's spectral peak lies off it)."""
    order = sorted(modes, key=lambda m: m.w0)
    groups = [[order[0]]] if order else []
    for mode in order[1:]:
        if mode.w0 < CLOSE_RATIO * groups[-1][-1].w0:
            groups[-1].append(mode)
        else:
            groups.append([mode])
    return [g for g in groups if len(g) > 1]


def _joint(modes: list[_Mode], windows: list[tuple[int, int, int]], bands: ModeBands,
           record: np.ndarray, fs: float, follow: str, quantity: str, sigma: float,
           referenced: bool, laws: Sequence[str]) -> list[str]:
    """Step 6a: close modes fitted together to the record's samples
    (:func:`.joint_fit.fit_decays_jointly`), from their band fits. Each window where every
    mode of the group has a free decay gives a span, which starts where its excitation is
    over, or with a reference (``referenced``), at the latest first extremum of the group's
    modes (each counts once the base has calmed in its band), and ends :data:`JOINT_TAIL`
    periods after their last extremum above the floor (or at the window's end); the other
    modes' fitted decays are taken off it. A fit that describes the record to
    :data:`JOINT_RESIDUAL` times its white noise is kept in ``mode.joint``, to replace the
    band fit's quadratic law, linear frequency and cubic stiffness (0 unless fitting one
    lowers N ln(RSS) by :data:`STIFFNESS_GAIN` per mode). Returns notes."""
    notes = []
    reach = [bands.reach(k) for k in range(bands.count)]
    for group in _clusters(modes):
        members = {id(m) for m in group}
        names = " and ".join(f"{m.w0 / (2.0 * math.pi):.4g}" for m in group) + " Hz"
        others = [m for m in modes if id(m) not in members]
        # Only the windows where every mode of the group has a free decay: where one falls
        # short of its floor (a window cut at a beat of the two), it is still in the record,
        # and no model of the group would hold it.
        used = sorted(set.intersection(*({d["w"] for d in m.decays} for m in group)))
        if not used:
            notes.append(f"the modes at {names} lie close together, but no free decay holds "
                         "all of them above the noise floor: their band fits are kept")
            continue
        period = 2.0 * math.pi / min(m.w0 for m in group)
        target = np.array(record, dtype=np.float64)
        spans = []
        for w in used:
            start, free, stop = windows[w]
            here = [d for m in group for d in m.decays if d["w"] == w]
            first = max(int(math.ceil(float(d["times"][0]) * fs)) for d in here) \
                if referenced else free
            # Past the group's last extrema above the floor, a few periods: the rest of the
            # window holds the noise and little else.
            last = max(float(d["times"][-1]) for d in here) + JOINT_TAIL * period
            stop = min(stop, int(math.ceil(last * fs)))
            limit = MODEL_LIMIT * float(np.max(np.abs(record[start:stop])))
            target[start:stop] -= _model_record(others, (start, free, stop), fs, follow,
                                                quantity, w, limit, reach)
            spans.append((min(first, stop - 1), stop))
        guesses = []
        for m in group:
            fit = m.fits["quadratic"]
            guesses.append(JointMode("quadratic", fit.params, m.w0, [
                DecayStart(used.index(d["w"]),
                           math.copysign(float(fit.starts[j]), float(d["values"][0])),
                           float(d.get("anchor", d["times"][0])))
                for j, d in enumerate(m.decays) if d["w"] in used], alpha=m.alpha))
        # Linear springs, and cubic stiffnesses fitted from the band fits': the cubic ones
        # only where they explain clearly more of the record. A close mode's smear makes the
        # band fits find a stiffness: held fixed, one left two modes' damping swapped; fitted
        # freely, one traded itself against the damping (C_f +84 %) for no better fit.
        average = max(1, int(2.0 * math.pi * fs / (JOINT_SAMPLES_PER_CYCLE
                                                   * max(m.w0 for m in group))))
        # (a block mean holds the white noise of a sample over sqrt(average))
        scale = max(sigma / math.sqrt(average),
                    PRECISION * max(float(np.max(np.abs(target[a:b]))) for a, b in spans))
        fits = {}
        failure = ""
        for guess, free in (([dataclasses.replace(g, alpha=0.0) for g in guesses], False),
                            (guesses, True)):
            try:
                fits[free] = fit_decays_jointly(target, fs, spans, guess, quantity=follow,
                                                output=quantity, stiffness=free,
                                                average=average,
                                                target_rms=JOINT_RESIDUAL * scale)
            except AnalysisError as exc:
                failure = str(exc)
        if len(fits) == 2:
            cubic = _stiffness_gain(fits[False], fits[True]) > STIFFNESS_GAIN * len(group)
        else:
            cubic = True in fits
        found = fits.get(cubic)
        if found is None:
            notes.append(f"the modes at {names} lie close together; fitting them together to "
                         f"the record's samples failed ({failure}): their band fits are kept")
            continue
        ratio = found.residual_rms / scale
        usable = found.converged and ratio <= JOINT_RESIDUAL and all(
            np.all(np.isfinite(c)) for c in found.cov) and np.all(np.isfinite(found.w0))
        if not usable:
            notes.append(f"the modes at {names} lie close together; fitted together to the "
                         + (f"record's samples they leave {_times(ratio)} its white noise "
                            "unexplained" if found.converged else
                            "record's samples, the fit did not converge")
                         + ": their band fits are kept")
            continue
        # The group as fitted, the start of each refit with one mode's law replaced.
        fitted = [JointMode("quadratic", found.params[j], float(found.w0[j]),
                            [DecayStart(d.span, float(v), float(t)) for d, v, t in
                             zip(g.decays, found.starts[j], found.times[j])],
                            alpha=float(found.alpha[j]))
                  for j, g in enumerate(guesses)]
        for k, m in enumerate(group):
            m.joint = {"params": found.params[k], "cov": found.cov[k], "w0": float(found.w0[k]),
                       "alpha": float(found.alpha[k]),
                       "dof": found.dof, "r2": found.r2,
                       "residual": ratio, "modes": len(group), "widening": found.widening[k],
                       "laws": _joint_laws(group, k, found, fitted, target, fs, spans,
                                           follow, quantity, cubic, laws, average)}
        notes.append(f"the modes at {names} lie within a factor {CLOSE_RATIO:g} of each "
                     "other, so each one's band holds the other's first cycles: their C_i, C_f "
                     "and natural frequencies come from their decays fitted together to the "
                     f"record's samples (residual {ratio:.2f} times the record's white noise)")
    return notes


def _joint_laws(group: list[_Mode], k: int, found: JointFit, fitted: list[JointMode],
                target: np.ndarray, fs: float, spans: list[tuple[int, int]], follow: str,
                quantity: str, cubic: bool, laws: Sequence[str], average: int
                ) -> dict[str, dict] | None:
    """The other candidate laws of mode ``k`` of a jointly fitted group, fitted the same way:
    the group refitted to the record's samples with that mode's law replaced (from its band
    fit and ``fitted``, the group's joint fit as starting values). Each law gets its
    parameters, covariance, degrees of freedom and AICc on the record's samples, the
    quadratic law too, so that the laws are compared on what the quadratic law was taken
    from; None if a refit fails.

    The samples' noise is coloured where the joint fit widened its intervals: the likelihood
    of white noise would then count each sample as independent evidence. The sample count
    in the AICc is divided by the square of the widening of beta, so that the viscous law's
    AICc gap is about the square of C_f's z-score with its widened standard error, as the
    interval says, not the white noise's."""
    samples = found.samples
    effective = samples / max(float(found.widening[k][1]) ** 2, 1.0)

    def aicc(fit: JointFit) -> float:
        p = fit.samples - fit.dof
        rss = max(fit.residual_rms, 1e-300) ** 2 * samples
        return (effective * math.log(rss / samples) + 2.0 * p
                + 2.0 * p * (p + 1) / max(effective - p - 1, 1.0))

    own = len(LAWS["quadratic"])
    out = {"quadratic": {"params": found.params[k], "cov": found.cov[k][:own, :own],
                         "dof": found.dof, "aicc": aicc(found)}}
    for law in laws:
        if law == "quadratic" or law not in group[k].fits:
            continue
        modes = list(fitted)
        modes[k] = dataclasses.replace(modes[k], law=law, params=group[k].fits[law].params)
        try:
            fit = fit_decays_jointly(target, fs, spans, modes, quantity=follow, output=quantity,
                                     stiffness=cubic, average=average)
        except AnalysisError:
            return None
        n = len(LAWS[law])
        if not (np.all(np.isfinite(fit.cov[k])) and np.all(np.isfinite(fit.params[k]))):
            return None
        out[law] = {"params": fit.params[k], "cov": fit.cov[k][:n, :n], "dof": fit.dof,
                    "aicc": aicc(fit)}
    return out


def _stiffness_gain(linear: JointFit, cubic: JointFit) -> float:
    """How much better the joint fit with cubic stiffnesses describes the record than the
    linear one: ``N ln(RSS_linear / RSS_cubic)`` (AIC's likelihood term, N samples)."""
    return linear.samples * 2.0 * math.log(max(linear.residual_rms, 1e-300)
                                           / max(cubic.residual_rms, 1e-300))


def _take_joint(mode: _Mode) -> None:
    """The joint fit (step 6a) replaces the band fit's quadratic law, linear frequency and
    cubic stiffness.
    The start check of the band fit (step 8) measured its extrema, which the joint fit does
    not use: its entries leave ``drift``, and the joint fit's own enter it
    (``joint_modes``, ``joint_residual``, ``joint_r2``, ``joint_widening_a``,
    ``joint_widening_beta``)."""
    joint = mode.joint
    quad = mode.fits["quadratic"]
    mode.fits["quadratic"] = dataclasses.replace(
        quad, params=np.asarray(joint["params"], dtype=np.float64),
        cov=np.asarray(joint["cov"])[:-2, :-2], dof=int(joint["dof"]), alpha=joint["alpha"])
    if joint["laws"] is not None:
        for law, fit in joint["laws"].items():
            mode.fits[law] = dataclasses.replace(
                mode.fits[law], params=np.asarray(fit["params"], dtype=np.float64),
                cov=np.asarray(fit["cov"]), dof=int(fit["dof"]), aicc=float(fit["aicc"]),
                alpha=joint["alpha"])
    mode.w0, mode.alpha = joint["w0"], joint["alpha"]
    # (a wander of the band's crossings is the record's, whichever fit reads the frequency)
    mode.w0_se = math.sqrt(max(float(joint["cov"][-2, -2]), 0.0)) * (
        mode.wander[0] if mode.wander is not None else 1.0)
    mode.w0_dof = int(joint["dof"])
    band_checks = ("a", "beta", "dropped", "kept_amplitude", "kept_change", "untested")
    mode.drift = {k: v for k, v in mode.drift.items()
                  if k not in band_checks and not k.startswith("start_")}
    mode.drift.update({"joint_modes": float(joint["modes"]),
                       "joint_residual": float(joint["residual"]), "joint_r2": joint["r2"],
                       **{f"joint_widening_{name}": float(f)
                          for name, f in zip(quad.names, joint["widening"])}})


def _noisy_errors(modes: list[_Mode], w: int, window: tuple[int, int, int], model: np.ndarray,
                  bands: ModeBands, fs: float, integrate: bool, noise: float,
                  rng: np.random.Generator
                  ) -> tuple[dict[tuple[int, int], list[np.ndarray]], dict[int, list[np.ndarray]]]:
    """The :func:`_errors` of each mode's decay ``j`` in window ``w`` (keyed ``(id(mode),
    j)``) on each of the :data:`NOISE_REALIZATIONS` noisy model records (in antithetic pairs,
    in the order drawn), and each mode band's zero crossings on each (s from the window's
    start, keyed by band); both empty without ``noise``. One noisy record's bands are held at
    a time."""
    errors: dict[tuple[int, int], list[np.ndarray]] = {}
    crossings: dict[int, list[np.ndarray]] = {}
    for _ in range(NOISE_REALIZATIONS // 2 if noise > 0 else 0):
        extra = rng.normal(0.0, noise, model.size)
        for sign in (1.0, -1.0):
            parts = split(model + extra if sign > 0 else model - extra, fs, bands,
                          integrate=integrate)
            for mode in modes:
                here = _decays_in(mode, w)
                if not here:
                    continue
                fit = _preferred(mode)
                hc = half_cycles(parts[mode.band], fs, mode.frequency)
                crossings.setdefault(mode.band, []).append(hc.crossings)
                for j, d in here:
                    errors.setdefault((id(mode), j), []).append(
                        _errors(hc, window[0] / fs, d["times"], fit.model[j]))
            del parts
    return errors, crossings


def _decays_in(mode: _Mode, w: int) -> list[tuple[int, dict]]:
    """The mode's decays (with their index) found in window ``w``."""
    return [(j, d) for j, d in enumerate(mode.decays) if d["w"] == w]


def _noisy_crossings(clean: np.ndarray, noisy: list[np.ndarray], frequency: float) -> np.ndarray:
    """A model band's zero crossings ``clean`` (s) moved by their mean shift over the ``noisy``
    realisations' crossings (s; :func:`_noisy_errors`). Each clean crossing is paired with a
    realisation's nearest within a sixth of a period of ``frequency`` (Hz); one that fewer than
    half the realisations pair keeps its clean time, and so do all without realisations."""
    if not noisy or clean.size == 0:
        return clean
    total, count = np.zeros(clean.size), np.zeros(clean.size)
    for times in noisy:
        if times.size == 0:
            continue
        shift = times[_match(times, clean)] - clean
        paired = np.abs(shift) < 1.0 / (6.0 * frequency)
        total[paired] += shift[paired]
        count[paired] += 1.0
    enough = count >= 0.5 * len(noisy)
    return clean + np.where(enough, total / np.maximum(count, 1.0), 0.0)


def _errors(hc: HalfCycles, start: float, times: np.ndarray, exact: np.ndarray) -> np.ndarray:
    """Measured minus exact extremum amplitudes of a model band signal (its half cycles
    ``hc``, times in s from ``start``, s of the record), at the extrema nearest ``times`` (s,
    record)."""
    if hc.times.size == 0:
        return np.zeros(exact.size)
    idx = _match_drifting(hc.times + start, times)
    return np.abs(hc.values[idx]) - exact


def _crossings_to_pair(d: dict) -> tuple[np.ndarray, np.ndarray] | None:
    """A decay's zero crossings between its kept extrema and its filtered model's crossings
    (s), or None when either has fewer than 3."""
    t = d["times"]
    c = d["crossings"]
    c = c[(c > t[0]) & (c < t[-1])]
    mc = d.get("model_crossings")
    if mc is None or c.size < 3 or mc.size < 3:
        return None
    return c, mc


def _half_periods(d: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Half periods (s) of the data and of the filtered model between the crossings of the
    decay's kept extrema, and the extremum amplitude of each half cycle."""
    t = d["times"]
    both = _crossings_to_pair(d)
    if both is None:
        return None
    c, mc = both
    m = mc[_match_drifting(mc, c)]
    p_data, p_model = np.diff(c), np.diff(m)
    ok = (p_model > 0) & (np.abs(p_model / p_data - 1.0) < 0.2)
    ok[:EDGE_EXTREMA] = False                    # the window's edge: the filters' smear
    k = np.clip(np.searchsorted(t, 0.5 * (c[1:] + c[:-1])), 0, t.size - 1)
    return p_data[ok], p_model[ok], np.abs(d["amplitude"][k])[ok]


def _data_stiffening(p_data: np.ndarray, x_amp: np.ndarray, weight: np.ndarray
                     ) -> tuple[float, float]:
    """Relative change of the measured frequency from zero to the largest amplitude, from a
    weighted straight line of frequency^2 against amplitude^2, and its standard error."""
    w2 = (math.pi / p_data) ** 2
    # On the amplitude relative to the largest: in the record's own unit (1e-4 m, say) the
    # amplitude^2 column is 1e-8 of the other, and the covariance's pseudo-inverse drops it
    # (a standard error of 1e-20: any stiffening looked resolved).
    u = x_amp / max(float(np.max(x_amp)), 1e-300)
    design = np.stack((np.ones_like(u), u ** 2), axis=1) * weight[:, None]
    coef, *_ = np.linalg.lstsq(design, w2 * weight, rcond=None)
    resid = w2 * weight - design @ coef
    cov = np.linalg.pinv(design.T @ design) * float(resid @ resid) / max(w2.size - 2, 1)
    top = 1.0 / max(float(coef[0]), 1e-300)
    return 0.5 * float(coef[1]) * top, 0.5 * math.sqrt(max(float(cov[1, 1]), 0.0)) * top


def _crossing_times(d: dict) -> dict | None:
    """The zero crossings of a decay's band signal between its kept extrema, paired with the
    filtered model's (``model_crossings``): ``data`` and ``model`` times (s), ``sign`` of each
    crossing's slope (+-1, alternating), the ``amplitude`` there (geometric mean of the two
    neighbouring corrected extrema), the model's ``half`` period (s) and the extremum
    ``peak`` of the half cycle before each crossing (0 for the first), and ``ok``: the
    crossings the frequency is fitted to (not the window's first :data:`EDGE_EXTREMA`, where
    the filters smear; each paired with a model crossing of its own within a third of a half
    period, after the pairs' common offset). None when fewer than 3 crossings pair up."""
    t = d["times"]
    both = _crossings_to_pair(d)
    if both is None:
        return None
    c, mc = both
    idx = _match_drifting(mc, c)
    m = mc[idx]
    counts = np.bincount(idx, minlength=mc.size)
    half = float(np.median(np.diff(c)))
    lag = c - m
    # The pairs' common offset, or where it drifts (a model still far from a strongly
    # nonlinear record's frequency), the offset of the crossings around each.
    common = np.median(lag) if np.ptp(lag) < half / 3.0 else median_filter(lag, 9, mode="nearest")
    ok = (counts[idx] == 1) & (np.abs(lag - common) < half / 3.0)
    ok[:EDGE_EXTREMA] = False
    amp = np.abs(d["amplitude"])
    k = np.clip(np.searchsorted(t, c), 1, t.size - 1)
    at = np.sqrt(amp[k - 1] * amp[k])
    peak = np.r_[0.0, amp[np.clip(np.searchsorted(t, 0.5 * (c[1:] + c[:-1])), 0, t.size - 1)]]
    if ok.sum() < 3:
        return None
    return {"data": c, "model": m, "sign": 1.0 - 2.0 * (np.arange(c.size) % 2),
            "amplitude": at, "half": np.r_[0.0, np.diff(m)], "peak": peak, "ok": ok}


def _frequency_step(mode: _Mode, quantity: str, seed: bool = False) -> None:
    """Gauss-Newton step on the linear natural frequency (and the cubic stiffness when the
    record resolves it) from the zero-crossing times of the data and of the filtered model:
    both went through the same filters, so their difference is the model's error alone.

    The step is linear in the stiffness about the model's: from none, a stiffness that moves
    the frequency by percents is out of its reach (2 % of softening on a lightly damped decay
    was read as hardening, then left out, and C_f came out 9 % low). With ``seed`` (a pass
    that another follows), when the step keeps none but the measured frequencies clearly move
    with amplitude, the stiffness that movement gives by harmonic balance is the model's for
    the next pass, whose step keeps it (refined) or leaves it out by the same tests; tried
    once per mode.

    The crossing times themselves are fitted (with a free time offset per decay), each
    weighted by its amplitude (a crossing's time error is the noise over the signal's slope
    there) and whitened with the band's noise correlation. Their differences, the half
    periods, are not: each crossing's error enters two neighbouring half periods with opposite
    signs, so a weighted mean of half periods telescopes to its first and last crossings -
    on a heavily damped decay, to the window's first few cycles alone."""
    pairs = [(p, d) for p, d in ((_crossing_times(d), d) for d in mode.decays) if p is not None]
    if not pairs:
        return
    top = 0.0
    for p, _ in pairs:
        x_hp = p["peak"] / mode.w0 if quantity == "velocity" else p["peak"]
        top = max(top, float(np.max(x_hp)))
    # The stiffness column on the amplitude relative to the largest (``top``): in the record's
    # unit it can be 1e-11 of the other, and the covariance's pseudo-inverse would drop it.
    top = max(top, 1e-300) ** 2
    blocks, rhs = [], []
    x_seen = []
    for j, (p, _) in enumerate(pairs):
        ok = p["ok"]
        x_hp = p["peak"] / mode.w0 if quantity == "velocity" else p["peak"]
        x_seen.append(x_hp[1:])
        d_w0 = -(p["model"] - p["model"][0]) / mode.w0
        d_alpha = -np.cumsum(0.375 * p["half"] * (x_hp ** 2 / top)) / mode.w0 ** 2
        cols = np.zeros((ok.sum(), 2 + len(pairs)))
        cols[:, 0], cols[:, 1], cols[:, 2 + j] = d_w0[ok], d_alpha[ok], 1.0
        scale = float(np.max(p["amplitude"][ok])) / np.maximum(p["amplitude"][ok], 1e-300)
        white = Whitener(p["data"][ok], p["sign"][ok], mode.correlation, scale)
        rhs.append(white.apply(p["data"][ok] - p["model"][ok]))
        blocks.append(np.stack([white.apply(col) for col in cols.T], axis=1))
    jac, r = np.concatenate(blocks), np.concatenate(rhs)
    n = r.size
    x_all = np.concatenate(x_seen)
    use_alpha = n >= 8 + len(pairs) and np.ptp(x_all) > 0

    inner = np.ones(n, dtype=bool)          # a residual with a predecessor in its decay
    inner[np.cumsum([0] + [b.shape[0] for b in blocks[:-1]])] = False

    def solve(names: list[int]) -> tuple[np.ndarray, np.ndarray, int, np.ndarray]:
        sub = jac[:, names]
        step, *_ = np.linalg.lstsq(sub, r, rcond=None)
        resid = r - sub @ step
        dof = max(n - len(names), 1)
        # (the frequency column, s per rad/s, is 1e-8 of the offsets' on a 2 kHz decay of a
        # few ms: unscaled, its interval came out 1e-14 Hz wide)
        cov = normal_inverse(sub) * float(resid @ resid) / dof
        # What the band's noise correlation leaves correlated (a drift, a close mode's slow
        # beat) makes neighbouring residuals alike: the variance of a rate fitted to them
        # grows by (1 + rho) / (1 - rho) (rho: their lag-1 correlation, as for AR(1) errors).
        rho = float(resid[1:][inner[1:]] @ resid[:-1][inner[1:]]) / max(float(resid @ resid),
                                                                         1e-300)
        rho = min(max(rho, 0.0), CROSSING_RHO_CAP)
        return step, cov * (1.0 + rho) / (1.0 - rho), dof, resid

    offsets = list(range(2, 2 + len(pairs)))
    if use_alpha:
        step, cov, dof, resid = solve([0, 1, *offsets])
        alpha_new = mode.alpha + float(step[1]) / top
        se_alpha = math.sqrt(max(cov[1, 1], 0.0)) / top
        # Kept only when clearly resolved and large enough to matter: the frequency it moves
        # at the largest amplitude (harmonic balance) at least STIFFNESS_SHIFT.
        shift = 0.375 * alpha_new * top / mode.w0 ** 2
        # ... and only when the measured frequencies themselves move that way with amplitude
        # (a model with a misfitting damping law can ask for a stiffness the data do not show)
        halves = [h for h in (_half_periods(d) for _, d in pairs) if h is not None]
        visible, clear, seeded, seen = False, False, 0.0, 0.0
        if halves:
            p_data = np.concatenate([h[0] for h in halves])
            amp = np.concatenate([h[2] for h in halves])
            if p_data.size >= 3:
                x_amp = amp / mode.w0 if quantity == "velocity" else amp
                seen, seen_se = _data_stiffening(p_data, x_amp, x_amp / np.max(x_amp))
                clear = abs(seen) > 5.0 * seen_se
                # Compared with the model's shift where the half periods end: their first
                # ones, in the filters' smear, are left out, and under strong damping the
                # cycles left hold a fifth of the release (there a 12 % softening is 0.7 %,
                # seen by 2.6 to 4 of its standard errors at 1 % noise; taken at the release,
                # and asked for 5, the stiffness was left out, the frequency read 0.17 % low).
                shift_seen = 0.375 * alpha_new * float(np.max(x_amp)) ** 2 / mode.w0 ** 2
                visible = abs(seen) > STIFFNESS_SEEN_Z * seen_se and seen * shift_seen > 0 \
                    and 0.5 * abs(shift_seen) <= abs(seen) <= 2.0 * abs(shift_seen)
                if clear and abs(seen) >= STIFFNESS_SHIFT:
                    seeded = seen * mode.w0 ** 2 / (0.375 * float(np.max(x_amp)) ** 2)
        # (visible: the half periods' own stiffening agrees; where it is large and clear, the
        # step's crossings, whitened and widened for their correlation, may resolve it less:
        # on a 10 % softening decay 4.5 standard errors, and the stiffness left out read the
        # linear frequency 2 % low)
        z = STIFFNESS_Z_SEEN if visible and clear and abs(seen) >= STIFFNESS_SEEN \
            else STIFFNESS_Z
        if abs(alpha_new) <= z * se_alpha or abs(shift) < STIFFNESS_SHIFT or not visible:
            # The model's stiffness left out: the frequency's step is taken with its removal's
            # effect on the crossings (to first order) taken off them.
            r = r + jac[:, 1] * (mode.alpha * top)
            step, cov, dof, resid = solve([0, *offsets])
            mode.alpha = 0.0
            if seed and seeded and not mode.stiffness_tried:
                mode.alpha, mode.stiffness_tried = seeded, True
        else:
            mode.alpha = alpha_new
    else:
        step, cov, dof, resid = solve([0, *offsets])
    mode.w0 += float(step[0])
    mode.w0_se = math.sqrt(max(cov[0, 0], 0.0))
    mode.w0_dof = dof
    sizes = [b.shape[0] for b in blocks]
    mode.wander = _frequency_wander(jac, resid, sizes, mode.w0)
    if mode.wander is not None:
        mode.w0_se *= mode.wander[0]


def _frequency_wander(jac: np.ndarray, resid: np.ndarray, sizes: list[int],
                      w0: float) -> tuple[float, float, float] | None:
    """Whether the frequency fitted to every crossing (:func:`_frequency_step`) holds over the
    whole of each decay: the early, middle and late :data:`FREQUENCY_PARTS` of each decay's
    crossings get a frequency of their own (from the fit's whitened ``resid``, with the
    frequency's column of ``jac`` and its decay's offset, which the decays' blocks of
    ``sizes`` rows hold in columns 0 and 2 + j). An F test of the parts' own frequencies
    against one common to all (each part keeps its own offset either way), its residual
    variance widened for what correlation the parts' own fits leave at lag 1, says whether
    they differ beyond their noise (probability below :data:`FREQUENCY_WANDER_P`): a drifting
    frequency, a close mode or a line pulling some cycles, an amplitude-dependent stiffness
    too weak to fit. The frequency's interval, from the crossings' scatter about one
    frequency, is then too narrow.

    Returns the factor sqrt(F) the frequency's standard error is to be widened by (as a
    Birge ratio), with the lowest and highest part's frequency (Hz; the natural frequency
    ``w0``, rad/s, plus the part's departure), or None when the parts agree or fewer than two
    can be compared."""
    parts: list[tuple[np.ndarray, np.ndarray]] = []     # (frequency column, offset column)
    targets: list[np.ndarray] = []
    start = 0
    for j, size in enumerate(sizes):
        rows = np.arange(start, start + size)
        start += size
        for part in np.array_split(rows, FREQUENCY_PARTS):
            if part.size >= FREQUENCY_PART_CROSSINGS:
                parts.append((jac[part, 0], jac[part, 2 + j]))
                targets.append(resid[part])
    if len(parts) < 2:
        return None
    shifts, own = [], []
    for (freq, offset), y in zip(parts, targets):
        design = np.stack((freq, offset), axis=1)
        step, *_ = np.linalg.lstsq(design, y, rcond=None)
        shifts.append(float(step[0]))
        own.append(y - design @ step)
    rss_own = sum(float(e @ e) for e in own)
    # one frequency for all parts, an offset of its own for each
    n = sum(y.size for y in targets)
    common = np.zeros((n, 1 + len(parts)))
    row = 0
    for k, (freq, offset) in enumerate(parts):
        common[row:row + freq.size, 0] = freq
        common[row:row + freq.size, 1 + k] = offset
        row += freq.size
    y_all = np.concatenate(targets)
    step, *_ = np.linalg.lstsq(common, y_all, rcond=None)
    left = y_all - common @ step
    rss_common = float(left @ left)
    dof = n - 2 * len(parts)
    if dof < 1 or rss_own <= 0.0:
        return None
    lag = sum(float(e[1:] @ e[:-1]) for e in own) / rss_own
    rho = min(max(lag, 0.0), CROSSING_RHO_CAP)
    spread = (rss_common - rss_own) / (len(parts) - 1)
    f_ratio = spread / (rss_own / dof) / ((1.0 + rho) / (1.0 - rho))
    chance = sstats.f.sf(f_ratio, len(parts) - 1, dof) if math.isfinite(f_ratio) else 1.0
    if chance >= FREQUENCY_WANDER_P:
        return None
    hz = (w0 + np.array(shifts)) / (2.0 * math.pi)
    return math.sqrt(f_ratio), float(np.min(hz)), float(np.max(hz))


def _backbone(mode: _Mode, quantity: str) -> Backbone:
    """The measured backbone of a mode (step 7), displacement amplitudes."""
    times, freq, amp, decay = [], [], [], []
    for j, d in enumerate(mode.decays):
        c = d["crossings"]
        t = d["times"]
        a = np.abs(d["values"])
        inner = c[(c > t[0]) & (c < t[-1])]
        if inner.size < 3:
            continue
        f = 1.0 / (inner[2:] - inner[:-2])
        tc = inner[1:-1]
        k = np.searchsorted(t, tc)
        k = np.clip(k, 1, t.size - 1)
        amp_c = np.sqrt(a[k - 1] * a[k])
        if quantity == "velocity":
            amp_c = amp_c / (2.0 * math.pi * f)
        times.append(tc)
        freq.append(f)
        amp.append(amp_c)
        decay.append(np.full(tc.size, j))
    if not times:
        empty = np.empty(0)
        return Backbone(empty, empty, empty, np.empty(0, dtype=np.int64))
    return Backbone(np.concatenate(times), np.concatenate(freq), np.concatenate(amp),
                    np.concatenate(decay))


def _backbone_foot(bb: Backbone, w0: float, alpha: float, damped: float, noise: float,
                   quantity: str) -> tuple[float, float, float, float] | None:
    """The measured backbone's frequencies at the decays' smallest amplitudes (the lowest
    :data:`BACKBONE_FOOT_SHARE` of its crossings) against the fitted model's there (the
    linear angular frequency ``w0``, rad/s, with the cubic stiffness ``alpha`` by harmonic
    balance, times ``damped``: the damped over the undamped frequency): their mean relative
    difference, its standard error, the largest amplitude among them (m, or the record's
    unit) and their mean frequency (Hz); None with fewer than :data:`BACKBONE_FOOT_BLOCKS`
    blocks of them. Crossings under :data:`BACKBONE_FOOT_SNR` times the band's ``noise``
    (RMS, in the ``quantity`` followed) are left out: near the floor the noise pulls the
    crossings' frequencies towards its band's (+0.2 % at 10 times, on the wet mode)."""
    level = bb.amplitude * (2.0 * math.pi * bb.frequency if quantity == "velocity" else 1.0)
    usable = np.flatnonzero(level >= BACKBONE_FOOT_SNR * noise)
    n = int(BACKBONE_FOOT_SHARE * usable.size)
    if n < BACKBONE_FOOT_BLOCKS * BACKBONE_FOOT_BLOCK:
        return None
    # In time order (one decay's end after another's): a crossing's error enters two
    # frequencies two apart with opposite signs, so their mean's error is that of the first
    # and last crossings; the standard error from the scatter of block means, not of points.
    low = np.sort(usable[np.argsort(bb.amplitude[usable], kind="stable")[:n]])
    amp, freq = bb.amplitude[low], bb.frequency[low]
    stiffness = 1.0 + 0.75 * alpha * amp ** 2 / w0 ** 2
    # A softening fitted so strong that the model's frequency falls by half or more there is
    # beyond what harmonic balance describes, and a damping that halves it beyond a free
    # decay's: no model to compare with (a phantom mode's fit, its damping rate above its
    # frequency, put the model's at 1e-150 of it, and the difference printed 150 digits).
    if not (damped >= 0.5 and np.all(stiffness > 0.25)):
        return None
    model = (w0 / (2.0 * math.pi)) * damped * np.sqrt(stiffness)
    diff = freq / model - 1.0
    blocks = diff[:n // BACKBONE_FOOT_BLOCK * BACKBONE_FOOT_BLOCK].reshape(
        -1, BACKBONE_FOOT_BLOCK).mean(axis=1)
    se = float(np.std(blocks, ddof=1)) / math.sqrt(blocks.size)
    return float(np.mean(diff)), se, float(np.max(amp)), float(np.mean(freq))


def _decay_extrema(d: dict, windows: list[tuple[int, int, int]]) -> DecayExtrema:
    """The public record of one decay's extrema (``d``, a decay of a mode's ``decays``) in the
    analysed ``windows``."""
    inside = (d["crossings"] >= d["times"][0]) & (d["crossings"] <= d["times"][-1])
    return DecayExtrema(window=(windows[d["w"]][0], windows[d["w"]][2]), times=d["times"],
                        values=d["values"], amplitude=d["amplitude"],
                        crossings=d["crossings"][inside], scale=d.get("scale"))


def _natural_frequency(mode: _Mode) -> tuple[float, tuple[float, float], float]:
    """Small-amplitude natural frequency (Hz) with its interval and the damped one (Hz)."""
    q = float(sstats.t.ppf(0.5 + 0.5 * LEVEL, mode.w0_dof))
    half = q * mode.w0_se
    a = _preferred(mode).value("a")
    damped = math.sqrt(max(mode.w0 ** 2 - a * a, 1e-300))
    two_pi = 2.0 * math.pi
    return (mode.w0 / two_pi, ((mode.w0 - half) / two_pi, (mode.w0 + half) / two_pi),
            damped / two_pi)


def _part(decay: dict, sel: slice) -> dict:
    """One decay with only the extrema ``sel`` (its per-extremum arrays sliced; its model's
    anchor, which sits where the filters put the first extremum, moved with that extremum)."""
    part = {key: (val[sel] if key in ("times", "values", "amplitude", "scale")
                  else val[:, sel] if key == "noise_dev" else val)
            for key, val in decay.items()}
    if "anchor" in decay and part["times"].size:
        part["anchor"] = decay["anchor"] + float(part["times"][0] - decay["times"][0])
    return part


def _drop_first(decays: list[dict], count: int) -> list[dict] | None:
    """The decays without their first ``count`` extrema (None if one gets too short)."""
    if any(d["amplitude"].size - count < 2 * MIN_CYCLES for d in decays):
        return None
    return [_part(d, slice(count, None)) for d in decays]


def _drift(mode: _Mode, decays: list[dict], follow: str) -> tuple[LawFit, dict[str, float]]:
    """The quadratic law fitted to ``decays`` and how far its coefficients move, in standard
    errors, when the first :data:`LATE_SHARE` of each decay's extrema are left out: a free
    decay obeys its law from any point on, so they may move only as much as the extrema left
    out allow (the later fit's variance minus the full one's)."""
    trial = dataclasses.replace(mode, decays=decays, fits={})
    _fit_all(trial, follow, ("quadratic",))
    full = trial.fits["quadratic"]
    # Decays too short to lose their first extrema (the last of a train, cut by the record's
    # end) are left out of the later fit: it is still fitted to a part of the same extrema.
    sizes = [d["amplitude"].size for d in decays]
    long = [d for d, n in zip(decays, sizes) if n >= 2 * MIN_CYCLES + 2]
    if not long:
        return full, {}
    drop = max(2, int(LATE_SHARE * min(d["amplitude"].size for d in long)))
    late_decays = [_part(d, slice(drop, None)) for d in long
                   if d["amplitude"].size - drop >= 2 * MIN_CYCLES]
    if not late_decays:
        return full, {}
    late = dataclasses.replace(mode, decays=late_decays, fits={})
    _fit_all(late, follow, ("quadratic",))
    fit = late.fits["quadratic"]
    # Both on the later fit's noise scale: misfitting first extrema inflate the full fit's.
    s2 = fit.rss / max(fit.dof, 1)
    unscaled_full = full.cov / max(full.rss / max(full.dof, 1), 1e-300)
    unscaled_late = fit.cov / max(s2, 1e-300)
    z = {}
    for i, name in enumerate(full.names):
        # as Python floats: two undetermined fits' infinite variances give NaN, skipped below,
        # without numpy's warning
        allowed = max(float(unscaled_late[i, i]) - float(unscaled_full[i, i]),
                      1e-3 * abs(float(unscaled_late[i, i])), 0.0)
        spread = math.sqrt(max(s2, 0.0) * allowed)
        # A fit that pins nothing (an undetermined or exact one) is no test of the start.
        if math.isfinite(spread) and spread > 0.0:
            z[name] = float(fit.params[i] - full.params[i]) / spread
    return full, z


def _stable_start(mode: _Mode, follow: str, laws: Sequence[str]) -> dict[str, float]:
    """Step 8: where each decay's law starts to hold. The first extrema of a decay may still
    be forced (a base that still moves) or smeared: the quadratic law is refitted leaving out
    0, 1, 2, 3, 5, 8, ... first extrema of every decay until its coefficients no longer move
    when more are left out (:func:`_drift` within :data:`DRIFT_Z` standard errors); the
    decays then lose those extrema and every law is refitted. When no start is stable, the
    covariance of the quadratic fit is widened by the square of the excess. Returns the z of
    the start kept (``dropped``: extrema left out per decay)."""
    shortest = min(d["amplitude"].size for d in mode.decays)
    tried = 0
    every: LawFit | None = None            # the law fitted to every extremum
    for count in START_COUNTS:
        if count > MAX_DROP_SHARE * shortest:
            break
        decays = _drop_first(mode.decays, count) if count else mode.decays
        if decays is None:
            break
        try:
            full, z = _drift(mode, decays, follow)
        except AnalysisError:
            break
        every = every or full
        tried = count
        if not z or max(abs(v) for v in z.values()) <= DRIFT_Z:
            break
    top = max(float(np.max(np.abs(d["amplitude"]))) for d in mode.decays)
    if tried:
        mode.decays = _drop_first(mode.decays, tried)
        mode.fits = {}
        _fit_all(mode, follow, laws)
    kept = max(float(np.max(np.abs(d["amplitude"]))) for d in mode.decays) / max(top, 1e-300)
    # What leaving them out changed: the damping at the largest amplitude, by the law fitted
    # with them and by the law fitted without (a noise-free record may leave out cycles for a
    # drift of its rounding alone, which changes nothing)
    change = 0.0
    if tried and every is not None:
        rates = [float(decay_rate("quadratic", fit.params, np.array([top]), mode.w0, follow)[0])
                 for fit in (every, mode.fits["quadratic"])]
        change = abs(rates[1] - rates[0]) / max(abs(rates[0]), 1e-300)
    full, z = _drift(mode, mode.decays, follow)
    worst = max((abs(v) for v in z.values()), default=0.0)
    if worst > DRIFT_Z:
        mode.fits["quadratic"] = dataclasses.replace(
            mode.fits["quadratic"], cov=mode.fits["quadratic"].cov * (worst / DRIFT_Z) ** 2)
    sizes = np.array([d["amplitude"].size for d in mode.decays])
    short = float(np.sum(sizes[sizes < 2 * MIN_CYCLES + 2])) / float(np.sum(sizes))
    return {**z, "dropped": float(tried), "kept_amplitude": kept, "kept_change": change,
            "untested": float(not z or short > 0.5),
            **_start_sensitivity(mode, follow, tried, shortest)}


def _start_sensitivity(mode: _Mode, follow: str, tried: int, shortest: int,
                       law: str = "quadratic") -> dict[str, float]:
    """Step 8a: how much the quadratic law's coefficients depend on the start kept. The law
    is refitted with the decays starting at the next :data:`START_ALTERNATIVES` starts of
    :data:`START_COUNTS`; a coefficient may move between two starts as much as the extrema
    left out allow (the later fit's variance minus the kept one's, within :data:`START_Z`
    standard errors). What it moves beyond that is an error of the start, which no fit of the
    kept extrema sees: its square is added to the coefficient's variance. The drift test of
    :func:`_stable_start` asks whether a start is stable; this measures what remains when it
    passes with little power (a short decay in noise whose first cycles are still smeared).
    Returns ``start_<name>`` for each of the law's parameters (``start_a``, ``start_beta``):
    the factors its standard errors were widened by. ``law`` names another law to treat the
    same way (the preferred one, when it is not the quadratic: its coefficients are the ones
    the record supports)."""
    base = mode.fits[law]
    variance = np.diag(base.cov).copy()
    extra = np.zeros(variance.size)
    for count in [c for c in START_COUNTS if c > tried][:START_ALTERNATIVES]:
        if count > MAX_DROP_SHARE * shortest:
            break
        decays = _drop_first(mode.decays, count - tried)
        if decays is None:
            break
        trial = dataclasses.replace(mode, decays=decays, fits={})
        try:
            _fit_all(trial, follow, (law,))
        except AnalysisError:
            break
        later = trial.fits[law]
        with np.errstate(invalid="ignore"):  # inf - inf: NaN, which the check below refuses
            allowed = np.maximum(np.diag(later.cov) - variance, 0.0)
        moved = (later.params - base.params) ** 2
        extra = np.maximum(extra, moved - START_Z ** 2 * allowed)
    if not (np.all(np.isfinite(extra)) and np.all(np.isfinite(variance))
            and np.all(variance > 0.0)):
        return {}
    factor = np.sqrt((variance + extra) / variance)
    mode.fits[law] = dataclasses.replace(base, cov=base.cov * np.outer(factor, factor))
    return {f"start_{name}": float(f) for name, f in zip(base.names, factor)}


def _noise_spread(mode: _Mode, law: str = "quadratic") -> dict[str, float]:
    """Step 8c: the spread of the quadratic law's coefficients over the noisy model records of
    the correction (step 6): each realization's extremum errors, put through the fit's
    whitening and its first-order influence (:attr:`.laws.LawFit.influence`), move the
    coefficients as a refit would. The fit's own covariance treats each extremum's error as
    the band's noise; the filters' padding at a decay's ends makes its first and last
    extrema err together (the prediction that pads a window is fitted to noisy cycles), which
    in short decays moves C_i and C_f more than that. Where the realizations spread a
    coefficient more than its covariance says, its variance is raised to theirs. Returns
    ``noise_<name>`` for each of ``law``'s parameters (``noise_a``, ``noise_beta``): the
    factors its standard errors were widened by."""
    base = mode.fits[law]
    devs = [d.get("noise_dev") for d in mode.decays]
    if base.influence is None or any(v is None for v in devs) \
            or min(v.shape[0] for v in devs) < 4:
        return {}
    count = min(v.shape[0] for v in devs)
    whiteners = _whiteners(mode)
    moves = np.array([base.influence @ np.concatenate(
        [w.apply(d["noise_dev"][r]) for w, d in zip(whiteners, mode.decays)])
        for r in range(count)])
    spread = np.var(moves, axis=0, ddof=1)
    variance = np.diag(base.cov)
    if not (np.all(np.isfinite(spread)) and np.all(np.isfinite(variance))
            and np.all(variance > 0.0)):
        return {}
    factor = np.sqrt(np.maximum(spread / variance, 1.0))
    mode.fits[law] = dataclasses.replace(base, cov=base.cov * np.outer(factor, factor))
    return {f"noise_{name}": float(f) for name, f in zip(base.names, factor)}


def _other_law_spread(mode: _Mode, follow: str, laws: Sequence[str]) -> None:
    """Steps 8a and 8c for the preferred law when it is not the quadratic one: its
    coefficients (a viscous C_i, a dry friction force, with the three-term law a C_f) are
    then the ones the record supports, and their intervals need what the quadratic law's
    get. The factors enter ``drift`` as ``preferred_start_<name>`` and
    ``preferred_noise_<name>`` (``a``, ``beta``, ``gamma``: the preferred law's)."""
    preferred = compare_laws([mode.fits[law] for law in laws]).preferred
    if preferred == "quadratic":
        return
    tried = int(mode.drift.get("dropped", 0))
    shortest = min(d["amplitude"].size for d in mode.decays) + tried
    factors = {**_start_sensitivity(mode, follow, tried, shortest, preferred),
               **_noise_spread(mode, preferred)}
    mode.drift.update({f"preferred_{key}": value for key, value in factors.items()})


def _halves(decays: list[dict]) -> tuple[list[dict], list[dict]] | None:
    """Each decay's larger and smaller half of extrema (None if a half is too short)."""
    if any(d["amplitude"].size < 4 * MIN_CYCLES for d in decays):
        return None
    cuts = [d["amplitude"].size // 2 for d in decays]
    return ([_part(d, slice(0, c)) for d, c in zip(decays, cuts)],
            [_part(d, slice(c, None)) for d, c in zip(decays, cuts)])


def _one_law(mode: _Mode, follow: str) -> dict[str, float]:
    """Step 8b: the quadratic law fitted to the larger and to the smaller half of every decay's
    extrema on its own. One law holds over the whole amplitude range only if the two agree
    within their (independent) errors; if they differ by more than :data:`DRIFT_Z` combined
    standard errors, the quadratic fit's covariance is widened by the square of the excess
    (beyond what the start's drift already widened). Returns ``split_a`` and ``split_beta``
    (z of the differences, the larger half's minus the smaller's)."""
    halves = _halves(mode.decays)
    if halves is None:
        return {}
    fits = []
    for part in halves:
        trial = dataclasses.replace(mode, decays=part, fits={})
        try:
            _fit_all(trial, follow, ("quadratic",))
        except AnalysisError:
            return {}
        fits.append(trial.fits["quadratic"])
    large, small = fits
    out = {}
    for i, name in enumerate(large.names):
        var = float(large.cov[i, i] + small.cov[i, i])
        if not (math.isfinite(var) and var > 0.0):      # a half the law cannot pin down
            return {}
        out[f"split_{name}"] = float(large.params[i] - small.params[i]) / math.sqrt(var)
    worst = max(abs(out["split_a"]), abs(out["split_beta"]))
    applied = max((abs(v) for k, v in mode.drift.items() if k in ("a", "beta")),
                  default=0.0)
    if worst > DRIFT_Z and worst > applied:
        widen = (worst / max(applied, DRIFT_Z)) ** 2
        quad = mode.fits["quadratic"]
        mode.fits["quadratic"] = dataclasses.replace(quad, cov=quad.cov * widen)
    return out


def _law_power(mode: _Mode) -> dict[str, float]:
    """Step 8d: the power of the quadratic law's fluid term (:func:`.laws.fluid_power`): a
    drag that grows with another power of the velocity than its square is fitted well by
    the quadratic law too, with C_i and C_f that give the wrong damping ratio inside their own
    amplitude span. Its standard error is widened as the noise's spread widened C_f's
    (``noise_beta``). Returns ``fluid_power``, its 95 % interval (``fluid_power_low``,
    ``fluid_power_high``) and ``fluid_power_change`` (the largest relative difference of the
    damping ratio, over the fitted extrema, between the quadratic law and the law with that
    power); empty when C_f is not resolved (its interval includes 0: no fluid term to test)
    or the test cannot be made."""
    quad = mode.fits["quadratic"]
    if not quad.interval("beta", LEVEL)[0] > 0.0:
        return {}
    try:
        test = fluid_power(quad, _whiteners(mode))
    except AnalysisError:
        return {}
    test = dataclasses.replace(test, se=test.se * mode.drift.get("noise_beta", 1.0))
    low, high = test.interval(LEVEL)
    if not (math.isfinite(low) and math.isfinite(high)):
        return {}
    return {"fluid_power": test.power, "fluid_power_low": low, "fluid_power_high": high,
            "fluid_power_change": test.change}


def _crest(mode: _Mode, modes: list[_Mode], windows: list[tuple[int, int, int]],
           bands: ModeBands, record: np.ndarray, fs: float, follow: str, quantity: str
           ) -> dict[str, float]:
    """Step 8e: the in-phase third harmonic of the mode's largest half cycles
    (:func:`.crest.half_cycle_harmonics`, over the extrema its laws were fitted to), against
    the same measure of the fitted model of the record put through the same steps: the model
    holds what damping (a quadratic law adds a little in phase too), the stiffness and the
    band filters' smear of the first crossings give, and no measuring chain. Each decay is
    measured on the record less the other modes' bands, its half cycles between its band's
    crossings, in the record's ``quantity`` (an accelerometer's chain flattens the
    acceleration's crests: they are measured there, not on its integral, where the harmonic is
    a third as large). Returns ``crest_ratio`` (the record's half cycles less the model's, half
    cycle by half cycle, less the stiffness's share the difference of their half periods
    shows: :func:`.crest.pooled_crest`), ``crest_se``, ``crest_noise_se`` and ``crest_count``;
    empty when too few half cycles stand out."""
    reach = [bands.reach(k) for k in range(bands.count)]
    found: list[np.ndarray] = []
    model_found: list[np.ndarray] = []
    # Half cycles far below the largest weigh nothing in the harmonic (it grows as the
    # amplitude cubed): each decay is measured down to half the share the pooling keeps.
    top = max(float(np.max(np.abs(d["values"]))) for d in mode.decays)
    for w, window in enumerate(windows):
        here = [(d, large[-1]) for _, d in _decays_in(mode, w)
                if (large := np.flatnonzero(np.abs(d["values"]) >= 0.5 * CREST_SHARE * top)).size]
        if not here:
            continue
        start, _, stop = window
        data = record[start:stop]
        model = _model_record(modes, window, fs, follow, quantity, w,
                              MODEL_LIMIT * float(np.max(np.abs(data))), reach)
        for signal, out in ((data, found), (model, model_found)):
            parts = split(signal, fs, bands)
            # (the other modes' bands off, not those of lines left out: mains hum at 50 Hz
            # has a band of its own, which holds a 16.7 Hz mode's third harmonic)
            own = signal - sum(parts[m.band] for m in modes if m is not mode)
            crossings = half_cycles(parts[mode.band], fs, mode.frequency).crossings
            for d, last in here:
                t0, t1 = d["times"][0] - start / fs, d["times"][last] - start / fs
                out.append(half_cycle_harmonics(own, fs, crossings[(crossings >= t0)
                                                                   & (crossings <= t1)]))
    # The record's half cycles less the model's, each less the stiffness's share the
    # difference of their half periods shows: a stiffness too small for the model to keep (a
    # 3 % hardening) still shows in the record's crests.
    measured = pooled_crest(found, quantity, reference=model_found)
    if measured is None:
        return {}
    return {"crest_ratio": measured.ratio,
            "crest_se": measured.stderr, "crest_noise_se": measured.noise_stderr,
            "crest_count": float(measured.half_cycles)}


def _harmonic_of(mode: _Mode, modes: list[_Mode]) -> tuple[_Mode, float] | None:
    """Step 8f: the mode of ``modes`` whose third harmonic ``mode`` looks like (at a third of
    its frequency, ten times larger or more, and falling more slowly: ``mode``'s extrema
    follow its extrema at the same times as a power above :data:`HARMONIC_POWER`), and that
    power; None when no mode is."""
    for other in modes:
        # (by their half periods: a short decay's spectral peak is too coarse)
        if other is mode or abs(mode.w0 / (HARMONIC_ORDER * other.w0) - 1.0) \
                > HARMONIC_TOLERANCE:
            continue
        own, theirs = [], []
        for d in mode.decays:
            for o in other.decays:
                if o["w"] != d["w"]:
                    continue
                inside = (d["times"] >= o["times"][0]) & (d["times"] <= o["times"][-1])
                own.append(np.log(np.abs(d["values"][inside])))
                theirs.append(np.interp(d["times"][inside], o["times"],
                                        np.log(np.abs(o["values"]))))
        x, y = np.concatenate(theirs or [[]]), np.concatenate(own or [[]])
        if x.size < 2 * MIN_CYCLES or np.ptp(x) <= 0.0 \
                or np.max(y - x) > math.log(HARMONIC_SHARE):
            continue
        power = float(np.polyfit(x, y, 1)[0])
        # Without a stiffness that moves the mode's frequency with amplitude, its harmonic
        # lies at three times its frequency to within their noise: a mode of the structure
        # at 3.03 times, 17 standard errors off, was said to be one.
        off = abs(mode.w0 - HARMONIC_ORDER * other.w0)
        noise = math.hypot(mode.w0_se, HARMONIC_ORDER * other.w0_se)
        if power > HARMONIC_POWER and (other.alpha != 0.0 or off <= HARMONIC_Z * noise
                                       + HARMONIC_EXACT * mode.w0):
            return other, power
    return None


def harmonic_warning(fundamental_hz: float, ratio: float, power: float) -> list[str]:
    """The warning on a component found to be another mode's third harmonic (step 8f): it
    lies at ``ratio`` times the frequency of the mode at ``fundamental_hz`` (Hz) and its
    extrema fall as that mode's to the ``power``."""
    return [f"this component lies at {ratio:.3f} times the frequency of the mode at "
            f"{fundamental_hz:.4g} Hz, and its extrema fall as that mode's to the power "
            f"{power:.2f} (a harmonic's as its cube, or as its square where a quadratic "
            "damping makes it): it is most likely that mode's third harmonic (a damping or "
            "stiffness that changes with amplitude, such as the fluid's quadratic damping, or "
            "a measuring chain that compresses the largest cycles), not a mode of the "
            "structure, and its frequency and "
            "damping describe the nonlinearity, not a mode (a mode of the structure at exactly "
            "three times the frequency, damped as much in proportion, would look the same)"]


def crest_warning(ratio: float, se: float, noise_se: float, count: float) -> list[str]:
    """The warning on flattened crests (step 8e) when the in-phase third harmonic ``ratio``
    is below -:data:`CREST_MIN` and more than :data:`CREST_Z` standard errors below 0 (at the
    one-sided level of CREST_Z normal standard errors): the larger of ``se``, from the
    ``count`` half cycles' scatter (on Student's t with ``count`` - 1 degrees of freedom),
    and ``noise_se``, from the record's noise (normal); else none."""
    if se >= noise_se:
        limit = float(sstats.t.isf(sstats.norm.sf(CREST_Z), max(int(count) - 1, 1)))
    else:
        se, limit = noise_se, CREST_Z
    z = -ratio / max(se, 1e-300)
    if not (ratio < -CREST_MIN and z > limit):
        return []
    low, high = ratio - 1.96 * se, ratio + 1.96 * se
    return [f"the largest cycles' crests are flattened: they carry a third harmonic in phase "
            f"with the mode of {100 * ratio:.2f} % of it beyond what the fitted damping and "
            f"stiffness make (95 %: {100 * low:.2f} to {100 * high:.2f} %, {z:.1f} standard "
            "errors from 0). A measuring chain that reads the largest cycles low (here by "
            f"about {300 * -ratio:.0f} %: a vibrometer's decoder or an amplifier near the end "
            "of its range) makes it, and C_f then reads low, by several times that: keep the "
            "signal well inside the range"]


def fluid_power_warning(power: float, low: float, high: float, change: float) -> list[str]:
    """The warning on a fluid term's power (step 8d) when the quadratic law's 2 lies outside
    its 95 % interval ``low`` to ``high`` and a law with ``power`` changes the damping ratio
    by more than :data:`POWER_CHANGE` (relative ``change``) over the fitted amplitudes, or
    when 2 lies more than :data:`POWER_Z` standard errors (the interval's half width over
    1.96) from ``power``; else none."""
    if low <= 2.0 <= high:
        return []
    z = abs(power - 2.0) / max(0.5 * (high - low) / 1.96, 1e-300)
    if not (change > POWER_CHANGE or z > POWER_Z):
        return []
    return [f"the fluid damping grows as the velocity to the power {power:.2f} (95 %: "
            f"{low:.2f} to {high:.2f}, {z:.1f} standard errors from 2), not as its square: "
            f"over the fitted amplitudes, the damping ratio the quadratic law gives differs "
            f"by up to {100 * change:.0f} % from that of a law with this power, and C_i and "
            "C_f are the quadratic law's best fit to a decay it does not describe: a drag "
            "that is not quadratic (a flow regime that changes with amplitude, friction), or "
            "a measuring chain that reads the largest cycles low (a vibrometer's decoder or "
            "an amplifier near the end of its range compresses them, and C_f reads low by "
            "several times that change: keep the signal well inside the range)"]


def _residual_correlation(mode: _Mode, comparison: LawComparison) -> float:
    """Lag-1 correlation of the preferred law's residuals after the fit's whitening (NaN for
    fewer than 8 extrema). The extrema of a band signal err together as the band's noise does
    (:meth:`.bands.ModeBands.correlation`: the narrower the band, the more); whitened, the
    residuals of a law that describes the decay are white, and only what the law misses (a
    beat with a close mode, a drifting frequency, a missing term) leaves them correlated."""
    best = comparison.fits[comparison.preferred]
    parts = [whitener.apply(np.asarray(resid, dtype=np.float64))
             for whitener, resid in zip(_whiteners(mode), best.residuals)]
    r = np.concatenate(parts) if parts else np.empty(0)
    if r.size < 8 or not np.all(np.isfinite(r)):
        return math.nan
    # Residuals within the resolution extrema are measured to (a record without noise) are
    # the integration's residue, whose correlation says nothing of the law.
    largest = max((float(np.max(m)) for m in best.model if m.size), default=0.0)
    if best.rss <= r.size * (RESOLUTION * largest) ** 2:
        return math.nan
    r = r - r.mean()
    return float(r[1:] @ r[:-1]) / max(float(r @ r), 1e-300)


def _relative_width(fit: LawFit, name: str) -> float:
    """Half-width of a coefficient's 95 % interval over its value (inf at zero)."""
    low, high = fit.interval(name, LEVEL)
    value = abs(fit.value(name))
    return 0.5 * (high - low) / value if value > 0.0 else math.inf


def _off_peak(m: ModeIdentification) -> str:
    """A sentence when the mode's frequency disagrees with the spectral peak it was found at,
    else "". The damped frequencies of the identified oscillator over the record's amplitudes
    (one value, or a range with a cubic stiffness) must reach the peak within the larger of
    the frequency's 95 % half-interval, the peak's half-power half-width (decay rate / 2 pi)
    and half the spectral resolution of the longest decay (1 / (2 T)): a frequency off by
    more was pulled away by something else in the mode's band."""
    ci = _half_width(m)
    a = max(m.laws.fits[m.laws.preferred].value("a"), 0.0)
    span = max((float(d.times[-1] - d.times[0]) for d in m.decays), default=0.0)
    tol = max(ci if math.isfinite(ci) else math.inf, a / (2.0 * math.pi),
              0.5 / span if span > 0.0 else math.inf)
    w0 = 2.0 * math.pi * m.frequency_hz
    amp = m.backbone.amplitude[np.isfinite(m.backbone.amplitude)]
    x2 = np.array([0.0, float(np.max(amp)) ** 2]) if amp.size and m.alpha else np.zeros(1)
    damped = np.sqrt(np.maximum(w0 * w0 + 0.75 * m.alpha * x2 - a * a, 0.0)) / (2.0 * math.pi)
    lo, hi = float(np.min(damped)) - tol, float(np.max(damped)) + tol
    if lo <= m.spectral_peak_hz <= hi:
        return ""
    if a >= w0:     # the fit is an overdamped decay: it has no damped frequency to quote
        found = (f"the fitted damping (a = {a:.3g} 1/s, at least 2 pi times the natural "
                 f"frequency {m.frequency_hz:.5g} Hz) leaves no oscillation, and so misses")
    else:
        found = f"the damped natural frequency {float(np.min(damped)):.5g} Hz disagrees with"
    return (f"{found} the spectral peak the mode was found at ({m.spectral_peak_hz:.5g} Hz) by "
            f"more than either's precision ({tol:.2g} Hz): something else in the mode's band "
            "(another mode, a line, drift) pulls its zero crossings; the frequency is not to "
            "be trusted")


def _fold(factor: float) -> str:
    """``"1.4-fold"``; a widening of a few percent as ``"1.03-fold"``, not ``"1.0-fold"``; one
    beyond :data:`SAID_AT_MOST` as ``"more than 1000-fold"`` (its digits would mean nothing)."""
    if round(factor, 1) >= SAID_AT_MOST:
        return f"more than {SAID_AT_MOST:g}-fold"
    return f"{factor:.2f}-fold" if factor < 1.095 else f"{factor:.1f}-fold"


def _times(ratio: float) -> str:
    """``"4.4 times"``, or ``"more than 1000 times"`` beyond :data:`SAID_AT_MOST`."""
    if round(ratio, 1) >= SAID_AT_MOST:
        return f"more than {SAID_AT_MOST:g} times"
    return f"{ratio:.1f} times"


#: How the warnings name each law coefficient.
COEFFICIENT_LABELS = {"a": "C_i", "beta": "C_f", "gamma": "friction force"}


def _precision_warnings(fit: LawFit, prefix: str) -> list[str]:
    """Sentences on each of ``fit``'s coefficients that is negative, not resolved (its 95 %
    interval holds 0) or poorly determined (its interval wider than +-:data:`POOR_PRECISION`
    of the value), each begun with ``prefix``."""
    out = []
    for name in fit.names:
        label = prefix + COEFFICIENT_LABELS[name]
        value = fit.value(name)
        lo, hi = fit.interval(name, LEVEL)
        if hi < 0:
            out.append(f"{label} is negative ({COEFFICIENT_LABELS[name]} < 0 is no physical "
                       "damping: the law misfits or the decay is too short)")
        elif lo <= 0.0:
            out.append(f"{label} is not resolved: its 95 % interval includes 0 (the record "
                       "holds too little of that damping to measure it)")
        elif hi - lo > 2.0 * POOR_PRECISION * value:
            out.append(f"{label} is poorly determined: its 95 % interval is "
                       f"+-{50.0 * (hi - lo) / value:.0f} % of the value")
    return out


def _warnings(m: ModeIdentification) -> list[str]:
    """Sentences on how far to trust the mode's numbers."""
    out = []
    cmp = m.laws
    if "quadratic" in cmp.fits and cmp.preferred == "quadratic_coulomb":
        gap = cmp.delta["quadratic"] - cmp.delta[cmp.preferred]
        out.append(f"the record calls for dry (Coulomb) friction beside linear + quadratic "
                   f"damping (AICc lower by {gap:.1f}): C_i and C_f of the linear + quadratic "
                   "law leave the friction out and take its damping as theirs; read the "
                   "three-term law's C_i, C_f and friction force (its line below, "
                   "laws.quadratic_coulomb in the JSON)")
    elif "quadratic" in cmp.fits and cmp.preferred != "quadratic":
        other = {"viscous": "viscous (linear) damping alone",
                 "coulomb": "viscous + Coulomb (dry friction) damping"}[cmp.preferred]
        gap = cmp.delta["quadratic"] - cmp.delta[cmp.preferred]
        support = (f"AICc lower by {gap:.1f}" if gap > 0 else
                   f"AICc within {AICC_TIE:g} of the quadratic law's, {-gap:.1f} higher, with "
                   "fewer terms")
        out.append(f"the record supports {other} at least as well as linear + quadratic "
                   f"damping ({support}): C_i and C_f assume a law the record does not call for")
    quad = cmp.fits.get("quadratic")
    if quad is not None:
        out.extend(_precision_warnings(quad, ""))
    if cmp.preferred != "quadratic":       # (its numbers are the ones the record supports)
        out.extend(_precision_warnings(cmp.fits[cmp.preferred], "the preferred law's "))
    for law in dict.fromkeys(("quadratic", cmp.preferred)):
        if law in cmp.fits and not cmp.fits[law].converged:
            out.append(f"the least-squares fit of the {law} law (laws.{law} in the JSON) "
                       "stopped at its limit of evaluations with its coefficients still "
                       "moving: its numbers are not the law's best fit, nor are their "
                       "intervals or the choice of law to be trusted (the extrema may hold "
                       "too little of a term the law has, or follow no law well)")
    coloured = m.start_drift.get("band_noise", 0.0)
    scatter = m.start_drift.get("extrema_scatter", 0.0)
    if coloured > TAIL_EXCESS:
        out.append(f"the noise in this mode's band is {_times(coloured)} the record's white "
                   "noise there (measured before the excitation and after its decays: noise that "
                   "is not white, as in a motion relative to a base whose accelerometer noise "
                   "is integrated, or a line such as mains hum too close to the mode to be "
                   "told apart): the intervals take its size, not how it correlates from "
                   "cycle to cycle, and may be too narrow")
    elif scatter > SCATTER_EXCESS:
        out.append(f"the extrema scatter about the fitted envelope {_times(scatter)} as far as "
                   "the record's white noise in this mode's band explains: noise there that is "
                   "not white (a sensor's 1/f noise, a motion relative to a base whose "
                   "accelerometer noise is integrated, a line close to the mode), or a decay the "
                   "law does not describe; the intervals take the scatter's size, not how it "
                   "correlates from cycle to cycle, and may be too narrow, and the smallest "
                   "extrema, read down to a floor set by the white noise, are lifted by it "
                   "(C_i low, C_f high)")
    low, high = m.band_hz
    if not low <= m.frequency_hz <= high:
        out.append(f"the natural frequency {m.frequency_hz:.4g} Hz lies outside the mode's band "
                   f"({low:.4g} to {high:.4g} Hz, spectral peak {m.spectral_peak_hz:.4g} Hz): "
                   "it is not determined by this record")
    off = _off_peak(m)
    if off:
        out.append(off)
    foot = m.start_drift.get("foot_difference")
    if foot is not None and abs(foot) > max(FREQUENCY_TARGET,
                                            BACKBONE_FOOT_Z * m.start_drift["foot_se"]):
        out.append(f"the natural frequency ({m.frequency_hz:.5g} Hz, the fitted model's at zero "
                   f"amplitude) and the backbone measured at the decays' smallest amplitudes "
                   f"({m.start_drift['foot_frequency']:.5g} Hz on average, amplitudes up to "
                   f"{m.start_drift['foot_amplitude']:.3g} in the record's unit of "
                   f"displacement) differ by {100 * foot:+.2f} % "
                   "against the model there, beyond their noise: the fitted stiffness does not "
                   "describe the backbone over its whole range (a strong softening or "
                   "hardening, a stiffness that is not cubic); read the small-amplitude "
                   "frequency off the backbone's low end")
    wander = m.start_drift.get("frequency_wander")
    if wander is not None:
        low, high = m.start_drift["frequency_low"], m.start_drift["frequency_high"]
        # enough decimals to tell them apart (not "17 to 17 Hz")
        places = max(2, 1 - math.floor(math.log10(max(high - low, 1e-9))))
        out.append(f"the frequency is not the same over each decay: the early, middle and late "
                   f"cycles give {low:.{places}f} to {high:.{places}f} Hz, further apart than "
                   "their noise "
                   "explains (a drifting frequency, a close mode or a line pulling some cycles, "
                   "a stiffness that changes with amplitude); its interval is widened "
                   f"{_fold(wander)}")
    cycles = m.extrema_count / 2.0
    if cycles < 5:
        out.append(f"only {cycles:.1f} cycles above the noise floor: too few for a reliable "
                   "damping law")
    drift = max((abs(v) for k, v in m.start_drift.items() if k in ("a", "beta")), default=0.0)
    if drift > DRIFT_Z:
        out.append(f"C_i and C_f move by up to {drift:.1f} standard errors when the first "
                   "cycles of each decay are left out: the decay's start is not a free decay "
                   "with this law (a base still moving, a law that misfits the large cycles); "
                   f"their intervals are widened {_fold(drift / DRIFT_Z)}")
    kept = m.start_drift.get("kept_amplitude", 1.0)
    change = m.start_drift.get("kept_change", 0.0)
    if kept < START_KEPT_WARNING and change > START_KEPT_CHANGE:
        cycles = m.start_drift.get("dropped", 0.0) / 2.0
        out.append(f"the law holds only below {100 * kept:.0f} % of the decays' largest "
                   f"amplitude: their first {cycles:.1f} cycles do not follow it (fitted with "
                   "them, C_i and C_f move beyond their noise, and the damping it gives at "
                   f"the largest amplitude by {100 * change:.0f} %), so they were left out. "
                   "The large amplitudes follow another law (damping that grows with another "
                   "power of the velocity) or are still forced; C_i and C_f describe the "
                   "smaller amplitudes only")
    if m.start_drift.get("untested"):
        short = 2 * MIN_CYCLES + 2
        count = sum(d.amplitude.size < short for d in m.decays)
        if count:
            out.append(f"{count} of the {len(m.decays)} free decays are too short (fewer than "
                       f"{short} extrema above the noise floor) to test whether their first "
                       "cycles already follow the law: C_i and C_f assume they do, and rest on "
                       "the few cycles of each decay")
        else:
            out.append("whether the decays' first cycles already follow the law could not be "
                       "tested (the law could not be refitted without them): C_i and C_f "
                       "assume they do")
    start = max((m.start_drift.get(f"start_{name}", 1.0) for name in ("a", "beta")
                 if quad is not None and _relative_width(quad, name) > START_WARNING_WIDTH),
                default=1.0)
    if start > START_WARNING:
        out.append("C_i and C_f depend on where the decay is taken to start by more than their "
                   "noise explains (its first cycles are not yet a free decay of this law: a "
                   "forced response or an unresolved close mode still dying out); their "
                   f"intervals are widened up to {_fold(start)} for it")
    split = max(abs(m.start_drift.get("split_a", 0.0)), abs(m.start_drift.get("split_beta", 0.0)))
    if split > SPLIT_WARNING:
        widened = split / max(drift, DRIFT_Z)
        out.append(f"the larger and the smaller half of the cycles give C_i and C_f that differ "
                   f"by up to {split:.1f} standard errors: the damping is not one law over "
                   "this amplitude range (coupling with other modes, an amplitude-dependent "
                   "drag)" + (f"; their intervals are widened {_fold(widened)}"
                              if widened >= 1.005 else ""))
    # (dry friction the record supports bends the quadratic law's rate as another power of
    # the velocity would: the friction law's warning above says what the record calls for)
    if "fluid_power" in m.start_drift and "gamma" not in cmp.fits[cmp.preferred].names:
        out.extend(fluid_power_warning(*(m.start_drift[f"fluid_power{part}"]
                                         for part in ("", "_low", "_high", "_change"))))
    if "harmonic_of" in m.start_drift:
        out.extend(harmonic_warning(*(m.start_drift[f"harmonic_{part}"]
                                      for part in ("of", "ratio", "power"))))
    if "crest_ratio" in m.start_drift:
        out.extend(crest_warning(*(m.start_drift[f"crest_{part}"]
                                   for part in ("ratio", "se", "noise_se", "count"))))
    # A mode fitted jointly to the record's samples (step 6a) uses no smeared extremum.
    if m.correction > CORRECTION_WARNING and "joint_modes" not in m.start_drift:
        out.append(f"the band filters smear this mode's first cycles by up to "
                   f"{100 * m.correction:.0f} % (modes close together or heavily damped); "
                   "corrected with the fitted model, so the result leans on that model")
    rho = m.start_drift.get("residual_rho", math.nan)
    if math.isfinite(rho):
        if rho > RESIDUAL_RHO:
            out.append(f"the fitted law leaves correlated residuals (lag-1 correlation "
                       f"{rho:.2f}): the decay is not that of one mode with this law "
                       "(beating with a close mode, a drifting frequency or a missing term)")
    return out


# ----------------------------------------------------------------------------- main
def identify(x: Any, fs: float, *, quantity: str = "velocity", components: Any = "auto",
             band: Sequence[float] | None = None, decay_starts: Sequence[float] | None = None,
             reference: Any = None, laws: Sequence[str] = tuple(LAWS),
             min_frequency: float | None = None) -> Identification:
    """Identify the modes of a record from its free decays (see the module notes).

    Parameters
    ----------
    x
        Samples of one channel: velocity (m/s), displacement (m) or acceleration (m/s^2), or
        the same in any consistent unit U.
    fs
        Sample rate, Hz.
    quantity
        ``"velocity"``, ``"displacement"`` or ``"acceleration"`` (integrated to a velocity
        band by band).
    components
        ``"auto"`` (one per mode found) or the number of modes to report (those whose free
        decays carry the most energy; every mode found keeps its own band either way).
    band
        ``(low, high)``, Hz: only the modes inside are reported (all keep their bands).
    decay_starts
        Times (s) at which the excitation is known to have stopped: a decay's extrema count
        from the later of its largest sample and such a time (and step 9 does not look for
        a later start).
    reference
        The base acceleration on the same samples, or None: each mode's extrema then count
        from when the base's motion in that mode's band has calmed down as well, and a peak
        that only follows the base's own ringing (a shaker's resonance) is left out with a
        note. In units consistent with the record's: m/s^2 beside a record in m, m/s or
        m/s^2.
    laws
        Damping laws to fit (:data:`.laws.LAWS`); ``"quadratic"`` is always among them.
    min_frequency
        Hz, or None: modes below it are not reported (a note names each), though analysed
        like every other, so that their decays are modelled with their neighbours'. For a
        record its processing shapes at low frequencies: the motion relative to a base whose
        acceleration was integrated with a high-pass rings at the high-pass's corner after
        each excitation, a decay that is no mode.

    Returns
    -------
    Identification

    Raises
    ------
    AnalysisError
        A record that cannot be read (see :func:`._signal.as_record`), an unknown quantity or
        law, no oscillation, or no mode with a free decay above the noise: among them a record
        excited too often for its decays to be told apart and one whose ``reference`` keeps
        moving (no decay is free), each named with what it would need.

    Examples
    --------
    A decay with linear and quadratic damping, recorded from release:

    >>> import numpy as np
    >>> from fsi_lab.dsp.identify import identify
    >>> from fsi_lab.dsp.laws import simulate_decay
    >>> fs, w0 = 5000.0, 2 * np.pi * 20.0
    >>> t = np.arange(int(3 * fs)) / fs
    >>> v = simulate_decay("quadratic", [2.0, 150.0], w0, -0.05, 1 / 80.0, t)
    >>> mode = identify(v, fs).modes[0]
    >>> a, beta = mode.quadratic.params
    >>> print(f"{mode.frequency_hz:.3f} Hz, a = {a:.3f} 1/s, beta = {beta:.1f} 1/m")
    20.000 Hz, a = 2.000 1/s, beta = 150.0 1/m
    """
    first = _identify_once(x, fs, quantity, components, band, decay_starts, reference, laws,
                           min_frequency)
    if decay_starts is not None:
        return first

    def again(starts: list[float], after: float | None) -> Identification | None:
        try:
            return _identify_once(x, fs, quantity, components, band, starts, reference, laws,
                                  min_frequency, after)
        except AnalysisError:
            return None

    kept, mode, taken = first, first.modes[0], None
    for starts, after in _forced_starts(first, float(fs)):
        if (later := again(starts, after)) is None:
            continue
        other = _nearest(later.modes, mode)
        if _more_free(mode, other):     # (each later start judged against the last kept)
            kept, mode, taken = later, other, (starts, after)
    if taken is None:
        return first
    # A free decay reads the same from later still; two close modes' beat, which the first
    # reading took for one, reads another frequency at each phase of the beat.
    starts, after = taken
    shift = FORCED_CONFIRM / mode.damped_frequency_hz
    check = again([s + shift for s in starts], None if after is None else after + shift)
    if check is not None and _moved(mode, _nearest(check.modes, mode)):
        return first
    note = _forced_start_note(first.modes[0], mode, starts)
    return dataclasses.replace(kept, notes=[note, *kept.notes])


def _forced_starts(found: Identification, fs: float
                   ) -> list[tuple[list[float], float | None]]:
    """Step 9: later starts to identify the record again from, in the order tried, when its
    first identification shows cycles that may still be forced; else none. Each is the
    decays' starts (s, as ``decay_starts``) and the time (s) before which no decay is taken,
    or None. When the start search (:func:`_stable_start`) left out :data:`FORCED_CYCLES`
    cycles or more of each decay of the mode that carries the record: each decay from a
    quarter period before its first extremum kept (so that it holds that extremum). When the
    extrema scatter about the law :data:`FORCED_SCATTER` times as far as the white noise
    explains (a response to random forcing, whose amplitude wanders, and whose dips may split
    it into several decays), and the record's last decay holds half of them or more (the
    forcing's end and the free decay after it): the record from :data:`FORCED_PERIODS`
    periods after where that decay was taken to start."""
    mode = found.modes[0]
    period = 1.0 / mode.damped_frequency_hz
    tries: list[tuple[list[float], float | None]] = []
    if mode.start_drift.get("dropped", 0.0) >= 2.0 * FORCED_CYCLES:
        tries.append(([float(d.times[0]) - 0.25 * period for d in mode.decays if d.times.size],
                      None))
    last = mode.decays[-1]
    free = found.free_windows[-1][1] / fs
    if (mode.start_drift.get("extrema_scatter", 0.0) >= FORCED_SCATTER
            and last.times[0] >= free
            and 2 * last.amplitude.size >= sum(d.amplitude.size for d in mode.decays)):
        tries += [([free + k * period], free + k * period) for k in FORCED_PERIODS]
    return tries


def _nearest(modes: list[ModeIdentification], mode: ModeIdentification) -> ModeIdentification:
    """The one of ``modes`` whose natural frequency lies nearest ``mode``'s."""
    return min(modes, key=lambda m: abs(m.frequency_hz - mode.frequency_hz))


def _half_width(mode: ModeIdentification) -> float:
    """The half-width (Hz) of ``mode``'s natural frequency's 95 % interval."""
    return 0.5 * (mode.frequency_ci[1] - mode.frequency_ci[0])


def _standard_error(mode: ModeIdentification) -> float:
    """The standard error (Hz) of ``mode``'s natural frequency, from its 95 % interval."""
    return _half_width(mode) / float(sstats.norm.ppf(0.5 + 0.5 * LEVEL))


def _moved(mode: ModeIdentification, other: ModeIdentification) -> bool:
    """Whether the frequency of ``other``, the same mode identified from another start,
    differs from ``mode``'s by more than :data:`FORCED_Z` of the larger standard error and
    :data:`FORCED_SHIFT` of itself."""
    moved = abs(other.frequency_hz - mode.frequency_hz)
    return bool(moved > FORCED_Z * max(_standard_error(mode), _standard_error(other))
                and moved > FORCED_SHIFT * mode.frequency_hz)


def _more_free(mode: ModeIdentification, other: ModeIdentification) -> bool:
    """Whether ``other``, the same mode identified from a later start, shows the cycles
    before it forced: its frequency has moved (:func:`_moved`) and is
    :data:`FORCED_PRECISION` times as precise or more, from twice :data:`MIN_CYCLES` cycles
    or more. From fewer cycles of a free decay the frequency is no more precise."""
    se_with, se_without = _standard_error(mode), _standard_error(other)
    return bool(math.isfinite(se_with) and 0.0 < se_without < math.inf
                and other.extrema_count >= 4 * MIN_CYCLES
                and _moved(mode, other)
                and se_with >= FORCED_PRECISION * se_without)


def _forced_start_note(mode: ModeIdentification, other: ModeIdentification,
                       starts: list[float]) -> str:
    """The note that the record's first identification, of ``mode``, is replaced by the one
    from ``starts`` (s), of ``other``."""
    half_with, half_without = _half_width(mode), _half_width(other)
    when = ", ".join(f"{s:.4g}" for s in starts)
    return (f"the mode at {mode.frequency_hz:.4g} Hz (+-{half_with:.2g} Hz) reads "
            f"{other.frequency_hz:.5g} Hz (+-{half_without:.2g} Hz) from {when} s on, "
            f"{_times(half_with / half_without)} as precisely from fewer cycles: its "
            "cycles before were no free decay of one mode (still forced, as by a random "
            "excitation or a sweep that ends inside the record, or beating with a close mode "
            "the first reading did not separate); the record is analysed from there (a start "
            "given for a decay, analysis.hvd.start_s or identify's decay_starts, turns this "
            "check off)")


def _identify_once(x: Any, fs: float, quantity: str, components: Any,
                   band: Sequence[float] | None, decay_starts: Sequence[float] | None,
                   reference: Any, laws: Sequence[str], min_frequency: float | None,
                   after: float | None = None) -> Identification:
    """Steps 0 to 8 of :func:`identify`, with its arguments; no decay that ends before
    ``after`` (s, or None) is taken (step 9)."""
    func = "identify"
    fs = check_rate(fs, func)
    record = as_record(x, func, min_samples=64)
    if reference is not None:
        reference = as_record(reference, func, min_samples=64, name="reference",
                              check_clipping=False, allow_constant=True)
        if reference.size != record.size:
            raise fail(func, f"reference has {reference.size} samples, the record "
                             f"{record.size}; expected the base acceleration on the same samples")
    if quantity not in QUANTITIES:
        raise fail(func, f"quantity = {quantity!r}; expected one of {', '.join(QUANTITIES)}")
    laws = tuple(dict.fromkeys(["quadratic", *laws]))
    for law in laws:
        if law not in LAWS:
            raise fail(func, f"law {law!r} is unknown; expected some of {', '.join(LAWS)}")
    if min_frequency is not None and not (isinstance(min_frequency, (int, float, np.number))
                                          and math.isfinite(min_frequency)
                                          and min_frequency >= 0.0):
        raise fail(func, f"min_frequency = {min_frequency!r}; expected None or a frequency "
                         "in Hz, >= 0")
    if components != "auto" and not (isinstance(components, (int, np.integer))
                                     and not isinstance(components, bool) and components >= 1):
        raise fail(func, f"components = {components!r}; expected 'auto' or an integer >= 1")
    band_t = None
    if band is not None:
        band_t = (float(band[0]), float(band[1]))
        if not 0.0 < band_t[0] < band_t[1]:
            raise fail(func, f"band = {band!r}; expected (low, high) in Hz with 0 < low < high")
    follow = "displacement" if quantity == "displacement" else "velocity"
    # Dropouts and spikes first: one in a still stretch would hide it, one in the base would
    # ring in its bands and read as motion.
    record, dropouts, unfilled = _dropouts_filled(record, fs)
    base_dropouts = np.empty((0, 2), dtype=np.int64)
    if reference is not None:
        reference, base_dropouts, _ = _dropouts_filled(reference, fs)
    spikes = find_spikes(record)
    if spikes.size:
        record = without_spikes(record, spikes)
    if reference is not None and (base_spikes := find_spikes(reference)).size:
        reference = without_spikes(reference, base_spikes)
    hold = _static_hold(record) if quantity == "displacement" else None
    if hold is not None:                 # the held part at the rest level, its noise kept
        record = record.copy()
        record[:hold[0]] -= hold[1]
    record = record - float(np.mean(record))
    # Dominant oscillation and the noise: the spectrum of the whole record.
    top = _dominant(record, fs)
    f_dom = float(top.frequencies[0])
    sigma = _noise_rms(record, fs, top.frequencies)
    plateaus: list[tuple[int, int]] = []
    forced: list[tuple[int, int]] = []
    bursts: list[int] = []
    windows = _windows(record, fs, f_dom, sigma, decay_starts,
                       PRECISION * float(np.max(np.abs(record))), plateaus, forced, bursts)
    if after is not None:
        windows = [w for w in windows if w[2] > after * fs]
    if not windows:
        raise fail(func, f"found no free decay of at least {MIN_WINDOW} samples")
    if reference is not None:
        windows = _unforced(windows, reference, fs, f_dom)
    cand_f, cand_a, notes, guards, steady = _candidates(record, fs, windows, band_t, f_dom,
                                                        sigma)
    if any(note.startswith(UNRESOLVED_PEAK) for note in notes) and _beat_split(record, windows):
        # Modes released together whose sum dips and swells within a cycle or two (three at
        # 1.3, 2 and 6 times the lowest) are split at each deep node: the spectrum of the
        # first short window, the largest, merged them into one hump that stands out of
        # nothing. One decay, then, if the whole stands out.
        merged = [(windows[0][0], windows[0][1], windows[-1][2])]
        whole = _candidates(record, fs, merged, band_t, f_dom, sigma)
        if not any(note.startswith(UNRESOLVED_PEAK) for note in whole[2]):
            windows = merged
            cand_f, cand_a, notes, guards, steady = whole
    for a, b in plateaus:
        notes.insert(0, f"the record holds a steady oscillation from {a / fs:.4g} to "
                        f"{b / fs:.4g} s before it decays (a forcing such as a sine dwell "
                        "switched off there): no free decay, the decay is taken from its end")
    if forced:
        spans = ", ".join(f"{a / fs:.4g} to {b / fs:.4g} s" for a, b in forced)
        notes.insert(0, f"the oscillation at {f_dom:.4g} Hz is still forced from {spans}: its "
                        f"amplitude within +-{100 * (RISE_BAND - 1):.0f} % of that frequency "
                        f"rises {RISE_RATIO:g}-fold or more after falling, which no free decay "
                        "does (a random or other excitation still running); "
                        + ("each decay is" if len(forced) > 1 else "the decay is")
                        + " taken from the end of that span (a start given for a decay, "
                        "analysis.hvd.start_s or identify's decay_starts, says where the "
                        "excitation ended and turns this check off)")
    if bursts:
        notes.insert(0, "the record holds bursts of broadband noise (a knock, a vibrometer "
                        f"losing its signal), at {_times_of(np.array(sorted(bursts)), fs)}: its "
                        "content above the modes rises out of a decay more than "
                        f"{BURST_RISE:g}-fold, or outgrows the oscillation, as no free decay's "
                        "does; decays end where one starts, and none is taken from inside one")
    if spikes.size:
        notes.insert(0, f"{spikes.size} isolated sample{'s' if spikes.size > 1 else ''} "
                        f"stand{'' if spikes.size > 1 else 's'} far off the oscillation their "
                        f"neighbours trace (at {_times_of(spikes, fs)}: spikes, as a vibrometer's "
                        "signal dropouts or a digitiser's glitches give, or noise with far "
                        "heavier tails than Gaussian): each is replaced by the cubic through "
                        "its two neighbours on either side (left in, their broadband energy "
                        "lifts the extrema the damping laws are fitted to)")
    if len(unfilled):
        notes.insert(0, f"{_runs(unfilled, fs)} of equal samples in the record, which it "
                        f"jumps into or out of, last more than {DROPOUT_PERIODS:g} period of "
                        "its dominant oscillation: beyond prediction, they are left as recorded "
                        "(a decay across one is split there, and its extrema near one are no "
                        "free decay's)")
    if len(dropouts) or len(base_dropouts):
        where = f"{_runs(dropouts, fs)} in the record" if len(dropouts) else ""
        if len(base_dropouts):
            where += (" and " if where else "") + f"{_runs(base_dropouts, fs)} in the reference"
        notes.insert(0, f"{where} hold equal samples that the signal jumps into or out of: "
                        "dropouts, as a vibrometer or a digitiser that loses its signal holds or "
                        "zeroes its output; each is filled by linear prediction from the "
                        "samples on both sides (left in, a zeroed run's steps lift the extrema "
                        "the damping laws are fitted to)")
    if hold is not None:
        notes.insert(0, f"the record holds still for its first {hold[0] / fs:.3g} s, "
                        f"{hold[1]:.3g} (the record's unit) away from where it comes to rest (a "
                        "static deflection held before the release): that offset is taken off "
                        "the held part")
    if steady.size:
        record = _without_lines(record, fs, windows, steady)
    if len(windows) == 1:
        _refuse_comb(cand_f, f_dom)
    if cand_f.size == 0:
        where = f" inside {band_t[0]:g} to {band_t[1]:g} Hz" if band_t else ""
        raise fail(func, f"found no usable spectral peak{where}; "
                         + ("; ".join(notes) if notes else "the record holds no free decay"))
    sigma = _noise_rms(record, fs, cand_f)
    # Peaks left out but standing out as modes do keep bands of their own (not analysed), so
    # that no mode's band passes them (their crossings would pull its frequency away).
    guards = guards[(guards < 0.9 * 0.5 * fs)
                    & (np.min(np.abs(guards[:, None] / cand_f[None, :] - 1.0), axis=1) > 0.1)]
    bands = ModeBands.around(np.concatenate((cand_f, guards)), fs)
    integrate = quantity == "acceleration"
    modes = []
    for k in range(bands.count):
        f_k = float(bands.centres[k])
        if not np.any(cand_f == f_k):
            continue
        noise_k = sigma * math.sqrt(bands.noise_fraction(k, fs, integrate))
        # An extremum of signal + band-limited noise is found where the noise's slope moves
        # it: on average noise^2 <w_n^2> / (2 A w^2) too large (<w_n^2>: the noise's mean
        # square angular frequency). Taken off each extremum (``lift``).
        lift = noise_k ** 2 * bands.mean_square_frequency(k, integrate) \
            / (2.0 * (2.0 * math.pi * f_k) ** 2)
        # A band far wider than its mode (a lone high mode beside it) lifts extrema by more
        # than that first-order share near FLOOR: they are read only where it is LIFT_SHARE.
        floor = max(FLOOR * noise_k, math.sqrt(lift / LIFT_SHARE), 1e-300)
        modes.append(_Mode(band=k, frequency=f_k, floor=floor,
                           correlation=bands.correlation(k), lift=lift, noise=noise_k))
    # A record sampled far above its highest band is analysed at a reduced rate: the bands see
    # the same signals, at a fraction of the cost. Its white noise keeps its density (the RMS
    # per sample falls as the rate); the windows' ends are kept on the reduced samples inside.
    full_windows = windows
    record_noise = sigma
    factor = reduction_factor(bands, fs)
    if factor > 1:
        record = reduce_rate(record, fs, factor, bands)
        if reference is not None:
            reference = reduce_rate(reference, fs, factor, bands)
        windows = [(-(-a // factor), -(-b // factor), -(-c // factor)) for a, b, c in windows]
        fs /= factor
        sigma /= math.sqrt(factor)
    # Steps 3 and 4: extrema of each mode in each window, from where the mode is free (its
    # band of the base acceleration has calmed down too, when the reference is given).
    base_parts = split(reference, fs, bands) if reference is not None else None
    base_free = _band_quiet(base_parts, fs) if base_parts is not None else None
    _noise_before(modes, record, fs, bands, f_dom, integrate)
    for w, (start, free, stop) in enumerate(windows):
        if stop - start < MIN_WINDOW:         # (a short window at a reduced rate)
            continue
        parts = split(record[start:stop], fs, bands, integrate=integrate)
        resolution = PRECISION * max(float(parts.max()), -float(parts.min()))
        for mode in modes:
            first = free
            if base_free is not None:
                later = base_free[mode.band][(base_free[mode.band] >= start)
                                             & (base_free[mode.band] < stop)]
                first = max(first, int(later.max())) if later.size else first
            t, v, c = _extrema(parts[mode.band], fs, mode.frequency, 0, first - start,
                               max(FIRST_FLOOR / FLOOR * mode.floor, resolution))
            # The band after the decay has fallen under the floor: its second half (the
            # decay's remainder far below it) measures the band's own noise, when it holds
            # half the periods that measure needs (a decay cut by the window's end leaves a
            # few samples of itself and of the band filters' end).
            after = int(math.ceil(t[-1] * fs)) if t.size else max(first - start, 0)
            rest = parts[mode.band][after:]
            rest = rest[rest.size // 2:]
            if rest.size * mode.frequency >= 0.5 * TAIL_PERIODS * fs:
                mode.noise_power += float(np.dot(rest, rest))
                mode.noise_samples += rest.size
            t = t + start / fs
            c = c + start / fs
            if t.size >= 2 * MIN_CYCLES:
                mode.decays.append({"w": w, "times": t, "values": v,
                                    "amplitude": _unlifted(np.abs(v), mode.lift),
                                    "crossings": c, "resolution": resolution})
    dropped = [m for m in modes if not m.decays]
    for m in dropped:
        notes.append(f"the spectral peak at {m.frequency:.4g} Hz has no free decay of "
                     f"{MIN_CYCLES} cycles above the noise floor: not a mode of the record")
    for m in modes:
        if m.decays and (excess := _band_noise_excess(m, fs)) is not None:
            dropped.append(m)
            notes.append(f"the spectral peak at {m.frequency:.4g} Hz has no free decay of "
                         f"{MIN_CYCLES} cycles above its band's own noise, {excess:.1f} times "
                         "the record's white noise there (measured before the excitation and "
                         "after the decays: noise that is not white, as in a motion relative to "
                         "the base): not a mode of the record")
            m.decays = []
    followers = []
    if base_parts is not None and any(m.decays for m in modes):
        base_envelopes = np.abs(hilbert(base_parts, axis=-1))
        for m in modes:
            if m.decays and (rates := _follows_base(m, base_envelopes[m.band], fs, follow)):
                followers.append(m)
                notes.append(f"the spectral peak at {m.frequency:.4g} Hz decays as the base's own "
                             f"motion in its band does ({-rates[0]:.3g} against {-rates[1]:.3g} "
                             "1/s, the base falling by half or more over each decay) and moves "
                             f"only {rates[2]:.2g} times as much (in acceleration): the base "
                             "rings there (a shaker's own resonance) and drives the record; not "
                             "a free decay of the structure")
                m.decays = []
    modes = [m for m in modes if m.decays]
    if not modes:
        if followers and not dropped:
            raise fail(func, "no spectral peak has a free decay of its own; " + "; ".join(notes))
        raise fail(func, _too_short(windows, dropped + followers, fs) + "; ".join(notes))
    too_few = _too_few_peaks(components, np.array([m.frequency for m in modes]), band_t, notes)
    if too_few is not None:
        raise fail(func, too_few)
    # Step 5: first fits, then the floor judged on the fitted envelope.
    for mode in modes:
        half = _pooled_half_period(mode.decays)
        mode.w0 = math.pi / half if half else 2.0 * math.pi * mode.frequency
        _fit_all(mode, follow, laws)
        fit = mode.fits["quadratic"]
        a = max(fit.value("a"), 0.0)
        mode.w0 = math.sqrt(mode.w0 ** 2 + a * a)
        kept = []
        for j, d in enumerate(mode.decays):
            n_keep = int(np.sum(fit.model[j] >= max(mode.floor, d["resolution"])))
            if n_keep >= 2 * MIN_CYCLES:
                kept.append({key: (val[:n_keep] if key in ("times", "values", "amplitude")
                                   else val) for key, val in d.items()})
        mode.decays = kept
    lost = [m for m in modes if not m.decays]
    for m in lost:
        notes.append(f"the spectral peak at {m.frequency:.4g} Hz has no free decay of "
                     f"{MIN_CYCLES} cycles above the noise floor: not a mode of the record")
    modes = [m for m in modes if m.decays]
    if not modes:
        raise fail(func, _too_short(windows, lost, fs) + "; ".join(notes))
    for mode in modes:
        mode.fits = {}
        _fit_all(mode, follow, laws)
    kept = []
    for m in modes:
        scatter = _scatter_without_decay(m)
        if scatter is None:
            kept.append(m)
            continue
        notes.append(f"the spectral peak at {m.frequency:.4g} Hz shows no free decay: its "
                     "extrema neither fall (their damping terms do not differ from 0 by "
                     f"{DECAY_Z:g} standard errors, or make them grow) nor follow a smooth "
                     f"envelope (they scatter {scatter:.1f} times as far as the record's "
                     "white noise explains): noise that is not white (a motion relative to "
                     "the base, whose integrated noise grows at low frequencies), not a mode")
    modes = kept
    if not modes:
        raise fail(func, "no spectral peak shows a free decay; " + "; ".join(notes))
    # Step 6: filter correction, the last pass with the record's noise.
    _correction_passes(modes, windows, bands, record, fs, follow, quantity, sigma, laws)
    notes += _joint(modes, windows, bands, record, fs, follow, quantity, sigma,
                    base_free is not None, laws)
    # Steps 7 and 8: where the laws start to hold; backbones and natural frequencies.
    results = []
    # Step 8f: a component that is a larger mode's third harmonic is warned of, and is not
    # taken off that mode's record before its crests are measured (step 8e): it is what
    # they hold.
    harmonics = {id(m): h for m in modes if (h := _harmonic_of(m, modes)) is not None}
    for mode in modes:
        # The backbone and the extrema measured hold every cycle: the start search below
        # leaves the first extrema out of the damping law's fit, not out of the curves.
        bb = _backbone(mode, follow)
        measured = [_decay_extrema(d, full_windows) for d in mode.decays]
        mode.drift = _stable_start(mode, follow, laws)
        if mode.joint is None:
            mode.drift.update(_one_law(mode, follow))
            mode.drift.update(_noise_spread(mode))
            mode.drift.update(_law_power(mode))
            _other_law_spread(mode, follow, laws)
        else:               # (the band fit's range checks would only widen what it replaces)
            _take_joint(mode)
        if (ratio := _band_noise_ratio(mode, fs)) is not None:
            mode.drift["band_noise"] = ratio
        if mode.joint is None and (scatter := _extrema_scatter(mode)) is not None:
            mode.drift["extrema_scatter"] = scatter
        if mode.wander is not None:
            mode.drift.update(zip(("frequency_wander", "frequency_low", "frequency_high"),
                                  mode.wander))
        if id(mode) in harmonics:
            fundamental, power = harmonics[id(mode)]
            mode.drift.update(harmonic_of=fundamental.w0 / (2.0 * math.pi),
                              harmonic_ratio=mode.w0 / fundamental.w0, harmonic_power=power)
        crest_modes = [m for m in modes if harmonics.get(id(m), (None,))[0] is not mode]
        mode.drift.update(_crest(mode, crest_modes, windows, bands, record, fs, follow,
                                 quantity))
        f0, f0_ci, fd = _natural_frequency(mode)
        foot = _backbone_foot(bb, mode.w0, mode.alpha, fd / f0, mode.noise, follow)
        if foot is not None:
            mode.drift.update(zip(("foot_difference", "foot_se", "foot_amplitude",
                                   "foot_frequency"), foot))
        comparison = compare_laws([mode.fits[law] for law in laws])
        # A joint fit's residual is judged on the record's samples (JOINT_RESIDUAL), not on
        # the band extrema it does not use.
        mode.drift["residual_rho"] = (_residual_correlation(mode, comparison)
                                      if mode.joint is None else math.nan)
        decays = [_decay_extrema(d, full_windows) for d in mode.decays]
        flat = bands.flat(mode.band)
        results.append(ModeIdentification(
            index=0, frequency_hz=f0, frequency_ci=f0_ci, damped_frequency_hz=fd,
            spectral_peak_hz=mode.frequency, band_hz=flat, quantity=follow, decays=decays,
            backbone=bb, laws=comparison, alpha=mode.alpha, noise_floor=mode.floor,
            correction=mode.correction, start_drift=mode.drift, measured_decays=measured))
    # By decreasing height of the mode's peak in the free decays' spectrum (of the record's
    # own quantity): the mode that carries the record first, as the spectrum shows it. Not by
    # the extrema kept: their number follows the frequency, and the start search (step 8)
    # may leave a mode's largest cycles out.
    height = dict(zip(cand_f.tolist(), cand_a.tolist()))
    ranked = sorted(range(len(results)), key=lambda i: -height[results[i].spectral_peak_hz])
    # Every mode found has its own band (so none leaks into another's); those asked for are
    # reported: inside ``band``, the largest ``components``.
    if band_t is not None:
        ranked = [i for i in ranked if band_t[0] <= results[i].spectral_peak_hz <= band_t[1]]
    if min_frequency is not None:
        for i in ranked:
            if results[i].spectral_peak_hz < min_frequency:
                notes.append(f"the mode at {results[i].spectral_peak_hz:.4g} Hz lies below "
                             f"{min_frequency:.4g} Hz, the lowest frequency reported "
                             "(min_frequency; in a motion relative to the base, the base's "
                             "integration rings below it after each excitation): not reported")
        ranked = [i for i in ranked if results[i].spectral_peak_hz >= min_frequency]
    if components != "auto":
        left = ranked[int(components):]
        if left:
            found = [f"{f:.4g}" for f in sorted(results[i].frequency_hz for i in left)]
            listed = ", ".join(found[:-1]) + " and " + found[-1] if len(found) > 1 else found[0]
            where = " in the band asked for" if band_t is not None else ""
            notes.append(f"{len(ranked)} modes with free decays are found{where}; components = "
                         f"{int(components)} reports the largest (by their peaks in the decays' "
                         "spectrum): "
                         + (f"the mode at {listed} Hz is" if len(left) == 1 else
                            f"the modes at {listed} Hz are")
                         + " not reported (components = 'auto' reports every one)")
        ranked = ranked[:int(components)]
    if not ranked:
        low = max(band_t[0] if band_t else 0.0, min_frequency or 0.0)
        high = f" to {band_t[1]:g} Hz" if band_t else " Hz up"
        raise fail(func, f"no mode with a free decay above the noise from {low:g}{high}; "
                         + "; ".join(notes))
    final = []
    for index, i in enumerate(ranked):
        m = results[i]
        m = ModeIdentification(**{**m.__dict__, "index": index})
        final.append(ModeIdentification(**{**m.__dict__, "warnings": _warnings(m)}))
    return Identification(modes=final, windows=[(a, c) for a, _, c in full_windows],
                          free_windows=list(full_windows), noise_rms=record_noise, notes=notes,
                          bands=bands,
                          band_of=[modes[i].band for i in ranked])
