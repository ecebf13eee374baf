"""Instrument plugins shipped with fsi-lab (installed as ``fsi_lab.instruments``)."""
