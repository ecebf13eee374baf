"""The built-in analyses' views in the GUI, registered through the ``fsi_lab_addviews`` hook.

This module imports no Qt: each view is named by a :class:`fsi_lab.contract.Deferred`, imported
when the GUI builds its tabs. The figures are drawn as the paper draws them:

- the Overview: HVD component with its envelope, instantaneous frequency, backbone and the C_q
  fit side by side (:mod:`.overview`);
- HVD components with their envelopes (paper Fig. 6) and the instantaneous frequency against
  time (HVD and zero crossings) (:mod:`.time_views`);
- backbone: frequency against displacement and velocity amplitude (Figs. 14-16), and damping
  ratio against both (Figs. 19-20) (:mod:`.amplitude_views`);
- the equivalent damping C_q against amplitude (displacement, or the modal amplitude its
  coefficients belong to) with its first-order fit, R^2 and 95 % intervals of C_i and C_f
  (Fig. 21) (:mod:`.equivalent_damping_view`);
- the modal model overlaid on the measurement (:mod:`.modal_model_view`);
- spectra and FRF (:mod:`.spectrum_view`).

It also gives the curves the runs browser compares across runs (backbone, damping, C_q), the
columns of the tables of identified values (C_i, C_f and R^2) and the Sequence tab's figure of a
sequence's aggregation (every run's backbone, damping and C_q on one amplitude axis:
:mod:`.aggregation_view`). The dataset names the views read are in :mod:`.names`.
"""

from __future__ import annotations

from fsi_lab.contract import Deferred
from fsi_lab.hookspecs import hookimpl
from fsi_lab.presentation import AggregationView, AnalysisView, ComparisonCurve, SummaryColumn

_HERE = "fsi_lab.plugins.analysis.views"

#: (title, analyses drawn, module:class), in the order of the tabs.
VIEWS = (
    ("Overview", ("hvd", "instantaneous", "backbone", "equivalent-damping"),
     "overview:OverviewView"),
    ("HVD components", ("hvd",), "time_views:HVDView"),
    ("Instantaneous frequency", ("hvd", "instantaneous"), "time_views:FrequencyView"),
    ("Backbone", ("backbone",), "amplitude_views:BackboneView"),
    ("Damping", ("damping",), "amplitude_views:DampingView"),
    ("Cq fit", ("equivalent-damping",), "equivalent_damping_view:EquivalentDampingView"),
    ("Modal model", ("modal-model",), "modal_model_view:ModalModelView"),
    ("Spectrum / FRF", ("spectrum", "frf"), "spectrum_view:SpectrumView"),
)

# The amplitude axes are named for the runs compared, as the views name them (.labels): the
# displacement at the measuring point, and for C_q the coordinate its coefficients belong to.
_MEASURED = Deferred(f"{_HERE}.labels:compared_amplitude")
CURVES = (
    ComparisonCurve("backbone", "backbone", "amplitude", "frequency",
                    "displacement amplitude at the measuring point", "frequency", "m", "Hz",
                    "displacement_amplitude_m", "frequency_hz",
                    summary=("backbone", "amplitude", "frequency_hz"), x_label_for=_MEASURED),
    ComparisonCurve("damping", "damping", "amplitude", "zeta",
                    "displacement amplitude at the measuring point", "damping ratio ζ", "m",
                    None, "displacement_amplitude_m", "zeta",
                    summary=("damping", "amplitude", "zeta"), x_label_for=_MEASURED),
    ComparisonCurve("equivalent_damping", "equivalent-damping", "amplitude", "c_q",
                    "amplitude", "C_q", "m", "kg/(m s)", "amplitude_m", "c_q",
                    x_label_for=Deferred(f"{_HERE}.labels:compared_cq_amplitude")),
)

COLUMNS = (
    SummaryColumn("c_i", "C_i (kg/(m s))", "equivalent_damping.c_i",
                  "equivalent_damping.c_i_ci95", order=10),
    SummaryColumn("c_f", "C_f (kg/m²)", "equivalent_damping.c_f",
                  "equivalent_damping.c_f_ci95", order=20),
    SummaryColumn("r2", "R²", "equivalent_damping.r2", order=30),
)


@hookimpl
def fsi_lab_addviews(views):
    for order, (title, analyses, target) in enumerate(VIEWS):
        views.add(AnalysisView(title, analyses, Deferred(f"{_HERE}.{target}"), order=10 * order))
    for curve in CURVES:
        views.add_curve(curve)
    for column in COLUMNS:
        views.add_column(column)
    views.add_aggregation_view(AggregationView(
        "Backbone, damping and C_q", Deferred(f"{_HERE}.aggregation_view:AggregationCurvesView"),
        order=0))
