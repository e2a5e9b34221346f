"""Sweeps: many runs over a parameter space on a process pool or a Ray cluster."""
