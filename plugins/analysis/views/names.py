"""Names of the datasets the analysis views read, as fsi-lab's analysis plugins write them."""

# One name per dataset: the one the plugin that fills the view writes (plugins/analysis/*.py,
# listed in docs/run-format.md). Per-component datasets have one row per component.

# hvd: the components, their envelopes and instantaneous frequencies, and the mask of the
# samples near the record ends that are not trusted
HVD_COMPONENTS = "components"
HVD_ENVELOPES = "envelopes"
HVD_FREQUENCIES = "frequencies"
HVD_EDGE = "edge_mask"
# instantaneous: the zero-crossing frequency and the times it is given at
ZC_TIME = "frequency_times"
ZC_FREQUENCY = "frequency"
# backbone and damping: the points' displacement and velocity amplitudes (both plugins)
DISPLACEMENT_AMPLITUDE = "amplitude"
VELOCITY_AMPLITUDE = "velocity_amplitude"
# backbone: frequency against displacement amplitude, and against velocity amplitude
FREQUENCY = "frequency"
VELOCITY_FREQUENCY = "velocity_frequency"
# damping: damping ratio (against both amplitudes)
ZETA = "zeta"
# equivalent-damping: C_q and the displacement amplitude it is given at
CQ = "c_q"
CQ_AMPLITUDE = "amplitude"
# spectrum (frequency, amplitude, peaks) and frf (frequency)
SPECTRUM_FREQUENCY = "frequency"
SPECTRUM_AMPLITUDE = "amplitude"
SPECTRUM_PEAKS = "peak_frequencies"
