"""The SUMO networks shipped with ego: one folder per network (see ego.sumo.net).

This folder is their source of truth in the checkout; an installed ego carries it as the
package ``ego.sumo_nets`` (pyproject.toml maps it), found through importlib.resources.
"""
