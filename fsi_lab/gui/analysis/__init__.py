"""The Analysis tab: what the analysis chain stored in a run file, drawn as the paper draws it.

Views (each reads ``/analysis/<channel>/<plugin>/`` of the run file; a missing or failed group
is shown as "not computed" or with its failure message, never as an exception):

- HVD components with their envelopes (paper Fig. 6);
- instantaneous frequency against time (HVD and zero crossings);
- backbone: frequency against displacement and velocity amplitude (Figs. 14-16);
- damping ratio against displacement and velocity amplitude (Figs. 19-20);
- the equivalent damping C_q against displacement amplitude with its first-order fit, R^2 and
  95 % intervals of C_i and C_f (Fig. 21);
- the modal model overlaid on the measurement;
- spectra and FRF; a table of the identified values; and every dataset of every plugin
  (third-party ones included) in a browser.

The parameter panel edits the chain's parameters with forms from the plugins' schemas; a change
re-runs the analysis as ``fsi-lab analyze RUN.h5 --set ...`` in a child process (see
:mod:`fsi_lab.gui.analysis_job`; the chain runs in order because later plugins use earlier
results), then the views reload.

Drawing keeps the window responsive: the run file is read on a worker thread
(:func:`fsi_lab.gui.results.load_results`); a view is drawn only when its tab is shown, a step
(a plot, a curve) at a time, by a :class:`~fsi_lab.gui.analysis.stepper.Stepper` that gives the
event loop back every few milliseconds and lets each figure be painted once, when it is
complete; the parameter forms of a new run are built after its figures, a form at a time.
Curves are decimated for display to two points (the min and max of a bin) per pixel of the
figure's width (:func:`fsi_lab.gui.decimate.min_max_decimate`); the run file keeps every
sample. A figure takes the space the layout gives it, so that drawing one never resizes (and
repaints) the others.

Modules:

- :mod:`~fsi_lab.gui.analysis.tab`: :class:`~fsi_lab.gui.analysis.tab.AnalysisViews`, the tab
  the main window shows;
- :mod:`~fsi_lab.gui.analysis.names`: the dataset names the analysis plugins write;
- :mod:`~fsi_lab.gui.analysis.datasets`: what the views take out of a run's results;
- :mod:`~fsi_lab.gui.analysis.plotting`: curves, points, axis ranges and display decimation;
- :mod:`~fsi_lab.gui.analysis.view`: :class:`~fsi_lab.gui.analysis.view.View`, the base of
  every figure;
- :mod:`~fsi_lab.gui.analysis.time_views`, :mod:`~fsi_lab.gui.analysis.amplitude_views`,
  :mod:`~fsi_lab.gui.analysis.equivalent_damping_view`,
  :mod:`~fsi_lab.gui.analysis.modal_model_view`, :mod:`~fsi_lab.gui.analysis.spectrum_view`:
  the figures;
- :mod:`~fsi_lab.gui.analysis.stepper`: drawing a slice per turn of the event loop;
- :mod:`~fsi_lab.gui.analysis.overview`, :mod:`~fsi_lab.gui.analysis.summary`,
  :mod:`~fsi_lab.gui.analysis.dataset_browser`: the Overview, Results and All datasets tabs;
- :mod:`~fsi_lab.gui.analysis.parameters`: the analysis parameter panel.
"""
