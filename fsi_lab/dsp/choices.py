"""The named choices the signal-processing functions accept, in a module of their own.

The analysis plugins offer them as parameter choices (``choices=`` of a
:class:`~fsi_lab.params.Param`); keeping them here, free of scipy and numba, lets fsi-lab list
the plugins and check a profile without loading the analysis. Each function's module imports
its choices from here and checks its argument against them.
"""

from __future__ import annotations

#: Windows of :func:`fsi_lab.dsp.spectrum.amplitude_spectrum`.
WINDOWS = ("hann", "blackmanharris", "flattop", "boxcar", "decay")
#: Offsets :func:`fsi_lab.dsp.instantaneous.instantaneous` removes before the zero crossings
#: ("cycles": from successive extrema, see that module).
OFFSETS = ("cycles", "mean", "none")
#: Damping-curve estimators of :func:`fsi_lab.dsp.damping.damping_from_peaks`.
DAMPING_METHODS = ("decrement", "envelope-fit", "eq5", "eq7")
#: Record-end extensions of :func:`fsi_lab.dsp.hvd.hvd`.
PADDINGS = ("predict", "mirror")
#: Regression weights of :func:`fsi_lab.dsp.equivalent_damping.equivalent_damping`.
WEIGHTINGS = ("amplitude", "uniform")
