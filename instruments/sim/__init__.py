"""The simulated bench: instruments that answer on real wires (TCP and pseudo-terminals) with the
physics of the profile's beam behind them. See :mod:`.bench`.

This package's ``__init__`` imports nothing, so that ``fsi-lab`` can list the ``bench``
subcommand without loading the simulation.
"""
