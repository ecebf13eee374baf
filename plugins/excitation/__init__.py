"""Excitation plugins: drive waveforms in volts at the signal source."""
