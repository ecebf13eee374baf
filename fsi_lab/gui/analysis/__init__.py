"""The Analysis tab: what the analysis chain stored in a run file, drawn by the plugins' views.

The tabs are the views plugins register through the ``fsi_lab_addviews`` hook
(:class:`fsi_lab.presentation.AnalysisView`; fsi-lab's own analyses register theirs from
``fsi_lab.plugins.analysis.views``), a generic view for every other analysis of the run (its
datasets plotted with their units and tabled with its values:
:mod:`~fsi_lab.gui.analysis.generic_view`), a table of the identified values (the columns the
plugins register and the plain values of every analysis) and every dataset of every analysis in
a browser. Each view reads ``/analysis/<channel>/<plugin>/`` of the run file; a missing or
failed group is shown as "not computed" or with its failure message, never as an exception.
Nothing here knows an analysis by name.

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

Modules (what a plugin's own view builds on is public: the View base, the plotting primitives,
the dataset helpers and the stepper):

- :mod:`~fsi_lab.gui.analysis.tab`: :class:`~fsi_lab.gui.analysis.tab.AnalysisViews`, the tab
  the main window shows;
- :mod:`~fsi_lab.gui.analysis.view`: :class:`~fsi_lab.gui.analysis.view.View`, the base of
  every figure;
- :mod:`~fsi_lab.gui.analysis.generic_view`: the view of an analysis without one of its own;
- :mod:`~fsi_lab.gui.analysis.datasets`: what the views take out of a run's results;
- :mod:`~fsi_lab.gui.analysis.plotting`: curves, points, axis ranges and display decimation;
- :mod:`~fsi_lab.gui.analysis.stepper`: drawing a slice per turn of the event loop;
- :mod:`~fsi_lab.gui.analysis.summary`, :mod:`~fsi_lab.gui.analysis.dataset_browser`: the
  Results and All datasets tabs;
- :mod:`~fsi_lab.gui.analysis.parameters`: the analysis parameter panel.
"""
