"""highway-env as a second traffic simulator for ego's motorway scenarios.

:class:`~ego.highway_env.bridge.HighwayEnvBridge` has the small interface the scenarios use
of :class:`~ego.sumo.bridge.SumoBridge` (insert vehicles, push the ego's pose, step, the
surroundings, the collisions, the scripted actors' commands), implemented on highway-env's
straight road with its IDM/MOBIL drivers, so the scenario logic, controllers, metrics and
recording are the same on both. highway-env is an optional extra (``pip install
ego[highway]``): it is imported only here, and only when the backend is asked for.
"""

from __future__ import annotations

from ego.sim.registry import BACKENDS as _REGISTRY

#: the traffic simulators a scenario can run on (``ego run --backend``): the names of
#: ``ego.sim.registry.BACKENDS``
BACKENDS = tuple(_REGISTRY)
