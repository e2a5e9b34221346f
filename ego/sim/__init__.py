"""The traffic simulator boundary: the :class:`TrafficSim` protocol the scenarios use,
backend-neutral types, :class:`SimError`, and the registry of backends by name with their
capabilities (:func:`make_sim`). ``ego.sumo`` (SUMO through libsumo) and ``ego.highway_env``
implement it; nothing above this package imports a backend directly."""

from __future__ import annotations

from ego.sim.instances import exclusive_running, sharing_instances
from ego.sim.protocol import TrafficCommands, TrafficSim
from ego.sim.registry import BACKENDS, Backend, Capabilities, SimSetup, backend, check_options, make_sim, register
from ego.sim.types import Collision, Departure, SimError, VehicleSpec, VehicleType

__all__ = [
    "BACKENDS",
    "Backend",
    "Capabilities",
    "Collision",
    "Departure",
    "SimError",
    "SimSetup",
    "TrafficCommands",
    "TrafficSim",
    "VehicleSpec",
    "VehicleType",
    "backend",
    "check_options",
    "exclusive_running",
    "make_sim",
    "register",
    "sharing_instances",
]
