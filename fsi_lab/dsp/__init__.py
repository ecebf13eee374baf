"""fsi-lab's signal-processing library: the algorithms behind the analysis plugins.

Arrays in, arrays out, in the style of :mod:`scipy.signal`: each function takes samples and a
sample rate (Hz), checks its input and raises :class:`fsi_lab.errors.AnalysisError` (a
``ValueError``) with a message naming the function, the condition found and what would be
accepted. Usable from a notebook without a run file or a profile::

    from fsi_lab.dsp.spectrum import spectral_peaks
    from fsi_lab.dsp.instantaneous import instantaneous

Modules
-------
spectrum
    Amplitude spectra and interpolated spectral peaks.
instantaneous
    Zero-crossing frequency and extremum amplitude (Londono et al. 2015).
decays
    Split a record into its free decays.
hvd
    Hilbert Vibration Decomposition (Feldman 2006, 2011).
integrate
    Frequency-domain integration with predicted padding.
backbone, damping, equivalent_damping
    Backbone and damping curves; C_i and C_f by harmonic balance (the paper's Eqs. 24-25).
frf
    H1 / H2 transfer functions; natural frequencies and damping ratios of their peaks.
joint_fit
    Free decays of close modes fitted together to the record's samples, with HAC intervals.
modal_fit
    A mode fitted to an FRF peak through the Welch estimate's leakage, with a jackknife
    interval.
crest
    The in-phase third harmonic of a decay's largest half cycles: a measuring chain that
    reads them low.
coupling
    A high-pass in the measuring chain (an AC coupling) read off a release at the start of a
    velocity record.
"""
