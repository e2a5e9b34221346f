"""The traffic around the ego, logged at every SUMO step (:class:`TrafficLog`).

A SUMO scenario hands each SUMO step's vehicles to a :class:`TrafficCollector` - the rows
its surround sensor or a libsumo subscription already delivers, so logging costs a list
append per step - and the collector keeps those within :data:`RADIUS` of the ego's centre,
in batches of numpy work (every :data:`BATCH` steps, so memory stays bounded in long runs).
``RunResult.traffic`` is the log built once at the end.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from itertools import chain
from typing import Any

import numpy as np

#: m: a vehicle is logged while its centre is within this distance of the ego's centre
RADIUS = 50.0
#: m a subscription must reach beyond RADIUS: SUMO measures from front bumpers, not from
#: centres (half of two vehicle lengths, trucks included)
REACH_MARGIN = 20.0
#: SUMO steps collected before they are filtered into arrays
BATCH = 256

#: the unit of every field of :class:`TrafficLog`
UNITS = {"t": "s", "vehicle": "-", "x": "m", "y": "m", "heading": "rad", "speed": "m/s", "length": "m", "width": "m"}
#: the traffic log's columns as the exports write them, in order
COLUMNS = tuple(UNITS)


@dataclass(frozen=True)
class TrafficLog:
    """Every other vehicle within RADIUS (50 m) of the ego's centre, at every SUMO step.

    One row per (SUMO step, vehicle), in time order. ``t`` is the run's time (the trace's
    ``t``) at that SUMO step. In the platoon, where every follower is an ego, the log holds
    every vehicle within RADIUS of some follower's centre: the leader and the followers.
    """

    ids: tuple[str, ...]  # the vehicle ids seen, in first-seen order
    t: np.ndarray  # float64 (n,)  s, simulation time of the SUMO step
    vehicle: np.ndarray  # int32 (n,)    index into ids
    x: np.ndarray  # float64 (n,)  m, world frame, centre of the vehicle's box
    y: np.ndarray  # float64 (n,)  m
    heading: np.ndarray  # float64 (n,)  rad, world frame, counter-clockwise from +x
    speed: np.ndarray  # float64 (n,)  m/s
    length: np.ndarray  # float64 (n,)  m
    width: np.ndarray  # float64 (n,)  m

    def __len__(self) -> int:
        return len(self.t)

    def of(self, vid: str) -> np.ndarray:
        """The row indices of vehicle ``vid`` (time order)."""
        return np.flatnonzero(self.vehicle == self.ids.index(vid))


def traffic_columns(log: TrafficLog) -> dict[str, np.ndarray]:
    """The traffic log as columns (:data:`COLUMNS`), ``vehicle`` as the vehicles' ids."""
    ids = np.array(log.ids, dtype=object)
    return {
        name: ids[np.asarray(log.vehicle, dtype=np.intp)] if name == "vehicle" else getattr(log, name)
        for name in COLUMNS
    }


_FIELDS = ("x", "y", "heading", "speed", "length", "width")


class TrafficCollector:
    """Collects each SUMO step's vehicles; :meth:`log` filters the rest and builds the log.

    ``add`` takes the rows as :meth:`ego.sumo.bridge.SumoBridge.surroundings` gives them
    (centre x, y m, yaw rad, speed m/s, length, width m) and the centres (x, y in m) the
    radius is measured from: one per ego, the same number at every step.
    """

    __slots__ = ("radius", "_pending", "_ids", "_chunks")

    def __init__(self, radius: float = RADIUS) -> None:
        self.radius = radius
        self._pending: list[tuple[float, Any, Any, Any]] = []
        self._ids: dict[str, int] = {}
        self._chunks: list[np.ndarray] = []  #: (k, 8): t, vehicle, then _FIELDS

    def add(self, t: float, centres: Any, ids: Sequence[str], rows: Any) -> None:
        """The vehicles at time ``t`` (s) and the centres: one (x, y) or a sequence of them,
        the same number at every step; kept by reference until the next batch."""
        pending = self._pending
        pending.append((t, centres, ids, rows))
        if len(pending) >= BATCH:
            self._filter()

    def _filter(self) -> None:
        pending, self._pending = self._pending, []
        counts = np.fromiter((len(p[2]) for p in pending), dtype=np.intp, count=len(pending))
        if not counts.sum():
            return
        rows = np.array(list(chain.from_iterable(p[3] for p in pending)), dtype=float).reshape(-1, 6)
        step = np.repeat(np.arange(len(pending)), counts)
        centres = np.array([p[1] for p in pending], dtype=float)
        if centres.ndim == 2:  # one (x, y) per step
            centres = centres[:, None, :]
        centres = centres[step]
        d2 = ((rows[:, None, :2] - centres) ** 2).sum(axis=2).min(axis=1)
        keep = np.flatnonzero(d2 <= self.radius * self.radius)
        if not keep.size:
            return
        names = list(chain.from_iterable(p[2] for p in pending))
        index = self._ids
        vehicle = [index.setdefault(names[i], len(index)) for i in keep]
        times = np.fromiter((p[0] for p in pending), dtype=float, count=len(pending))[step[keep]]
        self._chunks.append(np.column_stack([times, vehicle, rows[keep]]))

    def log(self) -> TrafficLog:
        """Everything collected so far as a :class:`TrafficLog`."""
        self._filter()
        data = np.concatenate(self._chunks) if self._chunks else np.zeros((0, 8))
        cols = {name: np.ascontiguousarray(data[:, 2 + i]) for i, name in enumerate(_FIELDS)}
        return TrafficLog(tuple(self._ids), np.ascontiguousarray(data[:, 0]), data[:, 1].astype(np.int32), **cols)
