"""A fast slice of the real-data rows of ``make validate``: pysdkit's beam recording (an impact
on a beam, three accelerometers, 2560 Hz, 0.5 s; MIT licence) against the damped natural
frequencies pysdkit documents for it (30.78, 215.6, 585.9, 1115.3 Hz, from Yu, Shock and
Vibration 2019), with pyOMA2's SSI as the peer on the same data. Nothing is fetched: the
record is a file of the installed pysdkit (dev extra).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fsi_lab.dsp.identify import identify
from validation.real_data import (
    TARGET,
    Peer,
    Record,
    fsi_lab_modes,
    pysdkit_beam,
    replica,
    ssi_modes,
)


@pytest.fixture(scope="module")
def beam():
    return pysdkit_beam()


@pytest.fixture(scope="module")
def found(beam):
    """fsi-lab's identification of the first channel."""
    return identify(beam.signals[0], beam.fs, quantity="acceleration")


def test_the_record_is_what_the_package_documents(beam):
    assert beam.signals.shape == (3, 1280)
    assert beam.fs == 2560.0
    assert beam.reference_hz == (30.78, 215.6, 585.9, 1115.3)


@pytest.fixture(scope="module")
def peers(beam):
    """pyOMA2's SSI on the three channels together."""
    return ssi_modes(beam)


def test_fsi_lab_natural_frequencies_against_the_reference_and_the_ssi_peer(beam, peers):
    """The 215.6 Hz mode within 0.2 % of the reference on every channel; the 30.78 Hz mode on
    channels 0 and 1 within 0.3 % of it, the two channels agreeing, and each 95 % interval
    holding SSI's value from the same record.

    History: channel 1 (whose largest peak is the undersampled 586 Hz mode) was refused
    outright, channel 2's 215.6 Hz mode came out at 210.8 Hz (the mode's band passed the
    undersampled modes left out, and a cubic stiffness whose standard error the record's unit
    had made 1e-20 pulled the small-amplitude limit away). Then the frequency was fitted to the
    half periods between crossings, whose weighted mean telescopes to the decay's first
    crossings: 30.58 Hz (-0.64 %, 95 %: 30.21 to 30.96) and 30.47 Hz (-1.0 %) on channels 0
    and 1, 216.77 Hz (+0.54 %) on channel 1. Fitted to the crossing times: 30.696 and 30.697 Hz
    (-0.27 %, 95 %: 30.64 to 30.75 on both), 215.88, 215.64 and 215.76 Hz (+0.13, +0.02,
    +0.08 %).

    The 30.78 Hz reference is the paper's (a blind source separation and a single-mode fit;
    pysdkit's own test holds it to 2 %). This 0.5 s record gives 30.68 to 30.71 Hz per channel
    by a least-squares fit of five damped sinusoids, 30.68 to 30.74 Hz by pyOMA2's SSI on all
    three channels depending on its block rows (30.74 at the 40 used here); an identification of
    records made like it with known truth (tests/analysis/test_identify_frequency.py) is
    within 0.1 %. What is left of the -0.27 % is the record's, not the estimator's."""
    rows = fsi_lab_modes(beam)
    for ours in rows[1]:
        assert not ours.refused, ours.refused
        assert ours.frequency == pytest.approx(215.6, rel=TARGET), ours.channel
    ssi = peers[0].frequency
    low = [ours for ours in rows[0] if not ours.refused]
    assert [ours.channel for ours in low] == [0, 1], [o.refused for o in rows[0]]
    for ours in low:
        assert ours.frequency == pytest.approx(30.78, rel=0.003), ours.channel
        assert ours.frequency_ci[0] <= ssi <= ours.frequency_ci[1], (ours, ssi)
    assert low[0].frequency == pytest.approx(low[1].frequency, rel=5e-4)
    # Every channel's damping ratios agree with SSI's within 20 % (measured: 0.0270, 0.0268
    # against 0.0280; 0.0046, 0.0042, 0.0048 against 0.0047). An impact taken for a burst of
    # noise moved channel 1's start and read 0.0029 there.
    for ours, peer in [(o, peers[0]) for o in low] + [(o, peers[1]) for o in rows[1]]:
        assert ours.zeta == pytest.approx(peer.zeta, rel=0.2), (ours.channel, peer.frequency)
    # The two upper modes have 4.4 and 2.3 samples per cycle: left out, each with a note.
    for ours in rows[2]:
        assert "undersampled" in ours.refused


def test_fsi_lab_leaves_the_undersampled_modes_out_with_a_note(found):
    assert len(found.modes) == 2
    for mode in found.modes:
        assert mode.frequency_ci[0] <= mode.frequency_hz <= mode.frequency_ci[1]
    for hz in ("586", "111"):
        assert any(hz in note and "undersampled" in note for note in found.notes)


def test_ssi_peer_within_0_2_percent_and_damping_agrees_with_fsi_lab(beam, found, peers):
    # Measured: -0.14, +0.04, +0.03, -0.01 %.
    for peer, reference in zip(peers, beam.reference_hz):
        assert peer.frequency == pytest.approx(reference, rel=TARGET)
    # No reference damping is documented: fsi-lab's viscous damping ratios and SSI's agree
    # within 20 % (measured 0.0260 against 0.0280, 0.0052 against 0.0047).
    for mode in found.modes:
        peer = min(peers, key=lambda p: abs(p.frequency - mode.damped_frequency_hz))
        zeta = mode.laws.fits["viscous"].value("a") / (2 * math.pi * mode.frequency_hz)
        assert zeta == pytest.approx(peer.zeta, rel=0.2)


def test_a_replica_rebuilds_a_record_of_damped_sinusoids_and_measures_its_broadband_noise():
    """A record made of two damped sinusoids after 20 quiet samples, with white noise of RMS
    0.02: rebuilt from the modes' frequencies and damping ratios within 5 % of the noise, and
    the noise measured within 15 % (the median of a periodogram of 16 segments)."""
    fs, n, start = 2560.0, 4096, 20
    t = (np.arange(n) - start) / fs
    modes = [Peer(30.0, 0.03), Peer(215.0, 0.005), Peer(math.nan, math.nan)]
    clean = np.zeros(n)
    for mode, amplitude, phase in zip(modes[:2], (4.0, 25.0), (0.3, 1.2)):
        damped = 2.0 * np.pi * mode.frequency
        rate = mode.zeta * damped / math.sqrt(1.0 - mode.zeta ** 2)
        clean += amplitude * np.exp(-rate * t) * np.sin(damped * t + phase)
    clean[:start] = 0.0
    noisy = clean + 0.02 * np.random.default_rng(5).standard_normal(n)
    record = Record("two modes", "test", noisy[None, :], fs, "acceleration", (30.0, 215.0, 500.0),
                    free_from=start)
    rebuilt, sigma = replica(record, modes, 0)
    assert sigma == pytest.approx(0.02, rel=0.15)
    assert np.sqrt(np.mean((rebuilt - clean) ** 2)) < 0.05 * 0.02
    assert np.all(rebuilt[:start] == 0.0)
