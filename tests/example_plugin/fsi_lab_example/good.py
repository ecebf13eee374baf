"""A working third-party plugin: one excitation and four analyses.

``rms`` and ``crossings`` provide nothing to later analyses and return an AnalysisResult;
``component-rms`` requires the built-in ``hvd``'s typed components and provides a typed result
of its own kind; ``hvd-count`` is written to the contract that preceded typed results (it
requires the analysis ``hvd`` by name and reads its stored attributes).
"""

from dataclasses import dataclass

import numpy as np

from fsi_lab.contract import AnalysisPlugin, AnalysisResult, ExcitationPlugin, Result
from fsi_lab.errors import AnalysisError
from fsi_lab.hookspecs import hookimpl
from fsi_lab.params import Param
from fsi_lab.plugins.analysis.results import Components


def _chirp(params, rate):
    t = np.arange(int(params["duration"] * rate)) / rate
    f0, f1 = params["f_start"], params["f_stop"]
    phase = 2 * np.pi * (f0 * t + (f1 - f0) * t**2 / (2 * params["duration"]))
    return params["amplitude"] * np.sin(phase)


def _rms(context, params):
    data = context.channel.data
    value = float(np.sqrt(np.mean((data - np.mean(data)) ** 2))) * params["scale"]
    return AnalysisResult(datasets={"squared": data**2}, units={"squared": "(unit)^2"},
                          attrs={"rms": value}, summary={"rms": value})


def _crossings(context, params):
    data = context.channel.data - np.mean(context.channel.data)
    count = int(np.count_nonzero(np.signbit(data[1:]) != np.signbit(data[:-1])))
    if count < params["minimum"]:
        raise AnalysisError(
            f"crossings: channel {context.channel.name}: {count} zero crossings, "
            f"need at least {params['minimum']}"
        )
    return AnalysisResult(summary={"components": [{"index": 0, "crossings": count}]})


@dataclass
class ComponentRms(Result):
    """RMS of each component of the decomposition, in the unit of the components."""

    kind = "component-rms"

    rms: np.ndarray
    unit: str

    def record(self):
        return AnalysisResult(
            datasets={"rms": self.rms}, units={"rms": self.unit},
            attrs={"largest": float(self.rms.max())},
            summary={"components": [{"index": k, "component_rms": float(v)}
                                    for k, v in enumerate(self.rms)]})


def _component_rms(context, params):
    components = context.result(Components)        # hvd's, typed (required: always there)
    rows = components.decomposition.components
    return ComponentRms(rms=np.sqrt(np.mean(rows**2, axis=1)), unit=components.unit)


def _hvd_count(context, params):
    # Written before typed results: hvd named as an analysis, its stored attributes read.
    return AnalysisResult(summary={"hvd_count": int(context.results["hvd"].attrs["n_components"])})


@hookimpl
def fsi_lab_excitations():
    return [ExcitationPlugin(
        name="chirp",
        params=(Param("amplitude", "float", "V", 0.1, minimum=0.0, maximum=5.0,
                      help="Peak source voltage."),
                Param("f_start", "float", "Hz", 1.0, minimum=0.0, help="Start frequency."),
                Param("f_stop", "float", "Hz", 50.0, minimum=0.0, help="Stop frequency."),
                Param("duration", "float", "s", 1.0, minimum=0.01, help="Sweep length.")),
        generate=_chirp, help="Linear sine sweep.")]


@hookimpl
def fsi_lab_analyses():
    return [
        AnalysisPlugin("rms", (Param("scale", "float", "", 1.0, help="Factor applied."),), _rms,
                       help="RMS of the channel."),
        AnalysisPlugin("crossings", (Param("minimum", "int", "", 1, minimum=0,
                                           help="Fewest zero crossings accepted."),),
                       _crossings, help="Counts zero crossings."),
        AnalysisPlugin("component-rms", (), _component_rms, requires=(Components,),
                       provides=ComponentRms, help="RMS of each hvd component."),
        AnalysisPlugin("hvd-count", (), _hvd_count, requires=("hvd",),
                       help="Number of hvd components."),
    ]
