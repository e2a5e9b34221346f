"""The RelativeClearanceCondition (OpenSCENARIO 1.2): whether an area of lanes around a
triggering entity is clear of other entities, measured along the lanes of the ego's road
(the lane frame the other distance conditions use), from SUMO's vehicle outlines."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from ego.openscenario import model as M
from ego.openscenario.registry import ConditionKind, Storyboard, register_condition
from ego.openscenario.runtime import EPS, EntityState
from ego.openscenario.xmltree import Node


@dataclass(frozen=True)
class Clearance:
    """A RelativeClearanceCondition's area: ``backward`` and ``forward`` (m) along the
    triggering entity's lane, in its driving direction, from its reference point (its box's
    ends with ``free_space``); ``lanes`` the (from, to) ranges of lanes relative to its own
    (0; + left in its driving direction; none: every lane); ``opposite``: lanes of the other
    driving direction count too; ``entities``: the entities looked for (none: every one)."""

    forward: float
    backward: float
    free_space: bool
    opposite: bool
    lanes: tuple[tuple[int, int], ...]
    entities: tuple[str, ...]


def extents(board: Storyboard, e: EntityState, name: str) -> tuple[float, float, float, float, int]:
    """An entity's reference point (s, d) in the lane frame, its box's half extents along and
    across the frame (m), and its driving direction (+1 along s, -1 against it)."""
    x1, y1 = e.x + math.cos(e.yaw), e.y + math.sin(e.yaw)
    s1, d1 = board.driver.road_frame(x1, y1)
    s0, d0 = board.driver.road_frame(e.x, e.y)
    a = math.atan2(d1 - d0, s1 - s0)  # the heading relative to the frame
    ca, sa = abs(math.cos(a)), abs(math.sin(a))
    half_s = 0.5 * (e.length * ca + e.width * sa)
    half_d = 0.5 * (e.length * sa + e.width * ca)
    cx = board.scenario.entities[name].vehicle.center_x
    return e.s - cx * math.cos(a), e.d - cx * math.sin(a), half_s, half_d, 1 if math.cos(a) >= 0.0 else -1


def lane_of(bands: list[tuple[float, float, int]], d: float) -> int:
    """The index (right to left) of the band holding ``d`` (the nearest one off the road)."""
    for i, (low, high, _) in enumerate(bands):
        if low <= d < high:
            return i
    return min(range(len(bands)), key=lambda i: min(abs(d - bands[i][0]), abs(d - bands[i][1])))


class RelativeClearance(ConditionKind):
    tag, contains = "RelativeClearanceCondition", ("RelativeLaneRange", "EntityRef")
    parts = {"RelativeLaneRange": ()}
    note = (
        "(1.2) holds while no entity (of its `EntityRef`s; none: any) is in the area of lanes around the triggering "
        "entity: from `distanceBackward` behind to `distanceForward` ahead of its reference point along its "
        "lane, in its driving direction (both 0 if omitted; with `freeSpace` from its box's rear and front ends, "
        "and another entity counts when any part of its box is in the area, else when its reference point is), "
        "over the lanes of the `RelativeLaneRange`s (`from`, `to`: lanes relative to the triggering entity's, "
        "0 its own, + left in its driving direction; none: every lane), those of the other driving direction only "
        "with `oppositeLanes`; where none of the range's lanes is there it does not hold (no clearance to have: "
        "esmini's `two_plus_one_road.xosc` waits so for its added lane). Along and across the lanes of the ego's road (the other distance conditions' lane "
        "frame), boxes from SUMO's vehicle outlines (`test_xosc_clearance.py`: against hand-computed gaps)"
    )

    def build(self, b: Any, c: Node, base: dict[str, Any]) -> M.Condition:
        ranges = []
        for r in c.all("RelativeLaneRange"):
            low, high = b.int_(r, "from"), b.int_(r, "to")
            if low > high:
                raise b.error(r, f"<RelativeLaneRange> from = {low} is above to = {high} (expected from <= to)")
            ranges.append((low, high))
        area = Clearance(
            forward=b.num(c, "distanceForward", 0.0, nonneg=True),
            backward=b.num(c, "distanceBackward", 0.0, nonneg=True),
            free_space=b.bool_(c, "freeSpace"),
            opposite=b.bool_(c, "oppositeLanes"),
            lanes=tuple(ranges),
            entities=tuple(b.entity_ref(r) for r in c.all("EntityRef")),
        )
        return M.Condition(kind=c.tag, value=area, **base)

    def holds(self, board: Storyboard, c: M.Condition, e: EntityState, name: str) -> bool:
        area: Clearance = c.value  # type: ignore[assignment]
        bands = board.driver.lane_bands()
        s, d, half_s, _, way = extents(board, e, name)
        own = lane_of(bands, d)
        lanes = set()
        for k, (_, _, direction) in enumerate(bands):
            if direction != bands[own][2] and not area.opposite:
                continue
            rel = (k - own) * way  # + left in the triggering entity's driving direction
            if not area.lanes or any(a <= rel <= b for a, b in area.lanes):
                lanes.add(k)
        if not lanes:
            return False  # no lane of the range beside the entity: no clearance to have
        # the area along the lane frame: [lo, hi] in s
        if area.free_space:
            centre = e.s
            ahead, behind = centre + way * (half_s + area.forward), centre - way * (half_s + area.backward)
        else:
            ahead, behind = s + way * area.forward, s - way * area.backward
        lo, hi = min(ahead, behind), max(ahead, behind)
        for other in area.entities or tuple(board.states):
            if other == name:
                continue
            o = board.states[other]
            o_s, o_d, o_half_s, o_half_d, _ = extents(board, o, other)
            if area.free_space:
                along = o.s + o_half_s >= lo - EPS and o.s - o_half_s <= hi + EPS
                across = any(o.d + o_half_d > bands[k][0] + EPS and o.d - o_half_d < bands[k][1] - EPS for k in lanes)
            else:
                along = lo - EPS <= o_s <= hi + EPS
                across = lane_of(bands, o_d) in lanes
            if along and across:
                return False
        return True


register_condition(RelativeClearance())
