"""Traffic events, computed by ego (SUMO reports time-to-collision only to files).

Pure functions: time-to-collision and gap acceptance for a lane change.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

INF = math.inf


def time_to_collision(gap: float, closing_speed: float) -> float:
    """gap / closing speed (s) when closing, else infinity. ``gap`` bumper to bumper (m)."""
    if gap <= 0.0:
        return 0.0
    if closing_speed <= 1e-9 or gap == INF:
        return INF
    return gap / closing_speed


@dataclass(frozen=True)
class GapRule:
    """Critical gaps for merging into a lane: gap >= min_gap + time * closing speed."""

    min_gap: float  #: (m)
    time: float  #: (s)

    def required(self, closing_speed: float) -> float:
        return self.min_gap + self.time * max(0.0, closing_speed)


@dataclass(frozen=True)
class LaneCheck:
    """Gap acceptance of one adjacent lane."""

    side: str  #: "left" or "right"
    exists: bool
    lead_gap: float = INF
    lead_required: float = 0.0
    lag_gap: float = INF
    lag_required: float = 0.0

    @property
    def accepted(self) -> bool:
        return self.exists and self.lead_gap >= self.lead_required and self.lag_gap >= self.lag_required

    @property
    def margin(self) -> float:
        """How much the tighter of the two gaps exceeds its requirement (m)."""
        return min(self.lead_gap - self.lead_required, self.lag_gap - self.lag_required)

    def explain(self) -> str:
        if not self.exists:
            return f"{self.side}: no lane"

        def part(name: str, gap: float, req: float) -> str:
            g = "free" if gap == INF else f"{gap:.1f} m"
            ok = ">=" if gap >= req else "<"
            return f"{name} gap {g} {ok} {req:.1f} m"

        verdict = "accepted" if self.accepted else "rejected"
        return (
            f"{self.side}: {part('lead', self.lead_gap, self.lead_required)}, "
            f"{part('lag', self.lag_gap, self.lag_required)} -> {verdict}"
        )


def check_lane(
    side: str,
    exists: bool,
    ego_speed: float,
    planned_speed: float,
    lead_gap: float,
    lead_speed: float,
    lag_gap: float,
    lag_speed: float,
    rule: GapRule,
) -> LaneCheck:
    """Accept the lane if the gap ahead suits the ego's current speed and the gap behind
    suits a follower closing on the ego at the speed it will drive (``planned_speed``)."""
    if not exists:
        return LaneCheck(side, False)
    return LaneCheck(
        side,
        True,
        lead_gap=lead_gap,
        lead_required=rule.required(ego_speed - lead_speed),
        lag_gap=lag_gap,
        lag_required=rule.required(lag_speed - planned_speed),
    )


def choose_lane(left: LaneCheck, right: LaneCheck) -> tuple[str | None, str]:
    """The accepted lane with the larger margin (left on a tie), or None; and why."""
    accepted = [c for c in (left, right) if c.accepted]
    why = "; ".join(c.explain() for c in (left, right))
    if not accepted:
        return None, f"{why}; no acceptable lane: brake in lane"
    best = max(accepted, key=lambda c: (c.margin, c.side == "left"))
    if len(accepted) == 2:
        why += f"; chose {best.side} (larger margin {best.margin:.1f} m)"
    else:
        why += f"; chose {best.side}"
    return best.side, why


def boxes_overlap(a: tuple[float, float, float, float, float], b: tuple[float, float, float, float, float]) -> bool:
    """Do two oriented rectangles (centre x, y in m, yaw rad, length, width in m) overlap?

    Separating-axis test on the four edge normals: two convex shapes are disjoint iff
    their projections on one of those axes are.
    """
    ax, ay, apsi, al, aw = a
    bx, by, bpsi, bl, bw = b
    dx, dy = bx - ax, by - ay
    ca, sa, cb, sb = math.cos(apsi), math.sin(apsi), math.cos(bpsi), math.sin(bpsi)
    for ux, uy in ((ca, sa), (-sa, ca), (cb, sb), (-sb, cb)):
        # half extent of each box along (ux, uy), and the centre distance along it
        ra = 0.5 * (al * abs(ca * ux + sa * uy) + aw * abs(-sa * ux + ca * uy))
        rb = 0.5 * (bl * abs(cb * ux + sb * uy) + bw * abs(-sb * ux + cb * uy))
        if abs(dx * ux + dy * uy) > ra + rb:
            return False
    return True
