"""The motorway's names, kept importable from here: the parts live in
:mod:`ego.scenarios.motorway` (world, plant, surround view), the manoeuvre in
:mod:`ego.scenarios.manoeuvre` and the safety layer in :mod:`ego.scenarios.safety`."""

from __future__ import annotations

from ego.scenarios.motorway import (  # noqa: F401 - re-exported
    EDGE,
    EGO_BOX,
    LANE_NAMES,
    LOG_REACH,
    N_LANES,
    ROUTE,
    TRAFFIC_TYPE,
    HighwayConfig,
)
from ego.sim.types import EGO  # noqa: F401 - re-exported
