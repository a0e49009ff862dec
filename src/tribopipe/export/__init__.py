"""Outputs regenerated from the friction map: tables, simulator input, plots."""
