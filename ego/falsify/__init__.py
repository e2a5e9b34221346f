"""Falsification: search a parameter space for runs that violate a requirement (``ego falsify``)."""
