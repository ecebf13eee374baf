"""Example third-party fsi-lab plugins (a working one and two broken ones)."""
