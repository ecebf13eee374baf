"""A plugin that imports fine but breaks the contract: it returns a dict, not descriptors."""

from fsi_lab.hookspecs import hookimpl


@hookimpl
def fsi_lab_excitations():
    return [{"name": "not-a-descriptor"}]
