"""Excitation and analysis plugins shipped with fsi-lab (installed as ``fsi_lab.plugins``)."""
