"""Scenarios from ASAM OpenSCENARIO XML files (.xosc) on OpenDRIVE roads (.xodr).

* :mod:`~ego.openscenario.xmltree` - the XML tree with line numbers, the one-line errors;
* :mod:`~ego.openscenario.expressions` - ``$param`` references and ``${...}`` expressions;
* :mod:`~ego.openscenario.registry` - the element registry: one declaration per element ego
  reads (:mod:`~ego.openscenario.structure`, :mod:`~ego.openscenario.actions`,
  :mod:`~ego.openscenario.conditions`), the allow-list, the dispatch and the subset table;
* :mod:`~ego.openscenario.loader` - the supported subset, checked and read into
  :mod:`~ego.openscenario.model`;
* :mod:`~ego.openscenario.roads` - .xodr to SUMO with netconvert (cached), lane positions;
* :mod:`~ego.openscenario.dynamics` and :mod:`~ego.openscenario.runtime` - the storyboard;
* :mod:`~ego.openscenario.scenario` - the one module that makes a file a scenario of ego.

See docs/openscenario.md.
"""

from __future__ import annotations


def is_scenario_file(name: object) -> bool:
    """True for a scenario name that is an OpenSCENARIO file path (ends in .xosc)."""
    return isinstance(name, str) and name.lower().endswith(".xosc")
