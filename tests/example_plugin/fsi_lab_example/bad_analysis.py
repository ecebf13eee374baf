"""An analysis plugin that declares its requirement wrongly: ``requires`` is a string, not a
tuple of result kinds. fsi-lab refuses it when loading it, saying what to write."""

from fsi_lab.contract import AnalysisPlugin, AnalysisResult
from fsi_lab.hookspecs import hookimpl


def _run(context, params):
    return AnalysisResult()


@hookimpl
def fsi_lab_analyses():
    return [AnalysisPlugin("bad-requires", (), _run, requires="components",
                           help="Declares requires as a string.")]
