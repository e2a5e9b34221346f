"""The safety layer: a filter between the controller's action and the plant.

:class:`SafetyLayer` holds the friction limit (the whole friction circle as the largest
braking command; the plant's ABS trims it further) and the automatic emergency brake
(AEB): while the AEB is engaged the longitudinal command becomes full braking, whatever
the controller asked; the steering passes through. It engages when braking in lane needs
``aeb_decel``, when a lane change needs the friction limit to stay behind the car its outline
still overlaps and does not move out of its way first
(:meth:`ego.scenarios.manoeuvre.EvasiveManoeuvre.limit_braking_behind`: the lane change steers
on, braking at the limit), or when a collision is imminent.
Engaging is decided once per control
period from the surround view (:meth:`SafetyLayer.update`); the manoeuvre is told
(:meth:`ego.scenarios.manoeuvre.EvasiveManoeuvre.emergency_stop`) so it can leave a lane
change it should not finish while braking hard.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

from ego.models.nonlinear_bicycle import NonlinearBicycleParams
from ego.scenarios.events import INF
from ego.scenarios.sensor import Detection

#: the AEB's own requirement: once active it brakes hard within 1 s (or the ego is nearly
#: stopped, or the AEB has let go)
AEB_SLOWS = (
    "aeb_slows",
    "always (aeb_active implies eventually[0:1] (accel <= -4 m/s^2 or speed <= 1 m/s or not aeb_active))",
)


def braking_need(front: Detection, ds: float, margin: float = 0.0) -> float:
    """Constant deceleration (m/s^2) that keeps the ego (speed ``ds`` m/s along the road)
    ``margin`` (m) behind the ``front`` object (0 when nothing is ahead). A front object
    braking at b: the ego must stop within the gap plus that object's stopping distance,
    v^2 / (2 (gap - margin + v_f^2 / (2 b))), but no less than closing^2 / (2 (gap - margin))
    (the object may stop braking); one at constant speed: closing^2 / (2 (gap - margin)) when
    closing in."""
    if front.gap == INF:
        return 0.0
    room = max(front.gap - margin, 0.1)
    closing = ds - front.speed
    need = closing * closing / (2.0 * room) if closing > 0.0 else 0.0
    decel = -front.accel
    if decel > 0.5:
        v = max(ds, 0.0)
        need = max(need, v * v / (2.0 * (room + front.speed * front.speed / (2.0 * decel))))
    return need


def braking_impact_speed(gap: float, ds: float, front_speed: float, front_accel: float, decel: float) -> float:
    """Relative speed (m/s) at which an ego at ``ds`` m/s, braking at ``decel`` m/s^2 from now,
    reaches a front object ``gap`` m ahead at ``front_speed`` m/s that brakes on at its
    measured ``front_accel`` (m/s^2, negative when braking) down to a stop; 0 when the ego stops
    behind it. The pessimistic premise of braking in lane: the ego cannot know where the
    object stops braking. Exact: the gap is a quadratic in time between the two stops."""
    contact = braking_contact(gap, ds, front_speed, front_accel, decel)
    return 0.0 if contact is None else contact[1]


def braking_reach(gap: float, ds: float, front_speed: float, front_accel: float, decel: float) -> float:
    """How far (m) the ego travels braking at ``decel`` before it reaches the front object
    (as :func:`braking_impact_speed`) or, if it does not, before it stops."""
    if decel <= 0.0:
        return INF
    v0 = max(ds, 0.0)
    contact = braking_contact(gap, ds, front_speed, front_accel, decel)
    if contact is None:
        return v0 * v0 / (2.0 * decel)
    t = contact[0]  # the ego is still moving then: a stopped ego closes no gap
    return v0 * t - 0.5 * decel * t * t


def braking_contact(
    gap: float, ds: float, front_speed: float, front_accel: float, decel: float
) -> tuple[float, float] | None:
    """(time s, relative speed m/s) of the first contact in :func:`braking_impact_speed`'s
    premise, or None when the ego stops behind the front object."""
    if gap == INF or decel <= 0.0:
        return None
    ve, vf = max(ds, 0.0), max(front_speed, 0.0)
    ae, af = decel, max(-front_accel, 0.0)
    g = gap
    t_e = ve / ae  # when the ego stops
    t_f = vf / af if af > 0.0 else INF  # when the front object stops
    t = 0.0
    for end in sorted((t_e, t_f, INF)):
        if end <= t:
            continue
        # over [t, end]: gap(tau) = g - (ve - vf) tau - (af - ae) tau^2 / 2 with both speeds as
        # at t and each deceleration 0 once its car has stopped
        a_e = ae if t < t_e else 0.0
        a_f = af if t < t_f else 0.0
        closing, rel = ve - vf, a_f - a_e  # d(gap)/dtau = -closing - rel tau
        span = end - t
        tau = _first_root(g, closing, rel, span)
        if tau is not None:
            return t + tau, max(closing + rel * tau, 0.0)
        if span == INF:
            return None
        g -= closing * span + 0.5 * rel * span * span
        ve, vf = max(ve - a_e * span, 0.0), max(vf - a_f * span, 0.0)
        t = end
    return None


def _first_root(g: float, closing: float, rel: float, span: float) -> float | None:
    """The first tau in [0, span] with g - closing tau - rel tau^2 / 2 = 0 (g > 0), or None."""
    if g <= 0.0:
        return 0.0
    if abs(rel) < 1e-12:
        return g / closing if closing > 0.0 and g / closing <= span else None
    # rel/2 tau^2 + closing tau - g = 0
    disc = closing * closing + 2.0 * rel * g
    if disc < 0.0:
        return None
    root = disc**0.5
    taus = sorted(r for r in ((-closing + root) / rel, (-closing - root) / rel) if r >= 0.0)
    return next((r for r in taus if r <= span), None)


def clears_sideways(view: Any, ttc: float) -> bool:
    """The ego moves out of the front object's way sideways within ``ttc`` (s), at the
    relative speed across the lane it has now."""
    front: Detection = view.sensor.front
    # the ego moves away from the object's side at this relative speed (m/s)
    clearing: float = -front.side * (view.dd - front.lateral_speed)
    return clearing > 0.0 and front.overlap / clearing < ttc


def friction_limit(params: NonlinearBicycleParams) -> float:
    """The largest deceleration (m/s^2) the tyres and the rolling resistance give:
    F_max / m + f g."""
    return params.F_max / params.m + params.f * params.g


class AebManoeuvre(Protocol):
    """What the AEB asks of the manoeuvre it guards (:class:`ego.scenarios.manoeuvre.EvasiveManoeuvre`)."""

    def braking_in_lane(self) -> bool: ...
    def changing_lane(self) -> bool: ...
    def limit_braking_behind(self, need: float) -> bool: ...
    def emergency_stop(self) -> None: ...


class SafetyLayer:
    """AEB and the friction limit between the controller and the plant.

    ``view`` is the surround view (:class:`ego.scenarios.motorway.SurroundView`), ``config``
    the scenario's (``aeb``, ``aeb_decel``, ``aeb_ttc``), ``event(kind, text, level)`` the
    run's event log and ``clock()`` the run's time (s)."""

    __slots__ = ("config", "view", "event", "clock", "manoeuvre", "active", "time", "engagements", "full_brake")

    def __init__(self, config: Any, view: Any, event: Callable[..., None], clock: Callable[[], float]) -> None:
        self.config = config
        self.view = view
        self.event = event
        self.clock = clock
        self.manoeuvre: AebManoeuvre | None = None  #: told when the AEB engages (``emergency_stop``)
        self.active = False
        self.time: float | None = None  #: when the AEB first engaged
        self.engagements = 0
        self.full_brake = 0.0

    def reset(self, plant: Any) -> None:
        p = plant.model.params
        self.active = False
        self.time = None
        self.engagements = 0
        #: the AEB's command: the whole friction circle as braking force (ABS trims it)
        self.full_brake = -p.F_max / p.Nw

    def filter(self, action: tuple[float, float]) -> tuple[float, float]:
        """The action the plant gets: full braking while the AEB is engaged."""
        if self.active:
            return self.full_brake, action[1]
        return action

    def update(self) -> None:
        """Engage or release the AEB (see ``aeb`` in the configuration)."""
        c = self.config
        view = self.view
        if not self.active:
            man = self.manoeuvre
            assert man is not None  # compose gives the AEB its manoeuvre
            braking_in_lane = man.braking_in_lane()
            if view.ttc_front >= c.aeb_ttc and not braking_in_lane and not man.changing_lane():
                return  # the common case, decided without computing the need
            front = view.sensor.front
            need = braking_need(front, view.ds)
            # limit_braking_behind asks only in a lane change
            # imminent() only below the AEB's TTC (above it, it is False)
            if (
                (braking_in_lane and need >= c.aeb_decel)
                or man.limit_braking_behind(need)
                or (view.ttc_front < c.aeb_ttc and self.imminent())
            ):
                man.emergency_stop()
                self.active = True
                self.engagements += 1
                if self.time is None:
                    self.time = self.clock()
                self.event(
                    "aeb",
                    f"AEB engages: braking at the friction limit (front {front.id}, gap "
                    f"{front.gap:.1f} m, TTC {view.ttc_front:.2f} s, needs {need:.1f} m/s^2)",
                    "WARN",
                )
        else:
            front = view.sensor.front
            need = braking_need(front, view.ds)
            # it brakes until it no longer closes in: a release while closing hands a fast
            # approach back to a slow position loop
            closing = view.ds - front.speed if front.gap != INF else 0.0
            if need < 0.5 * c.aeb_decel and closing <= 0.0 and not self.imminent():
                self.active = False
                self.event("aeb", f"AEB releases (needs {need:.1f} m/s^2)")

    def imminent(self) -> bool:
        """The front TTC is below ``aeb_ttc`` and the ego does not clear the front object
        sideways before it would hit it (a lane change leaving a braking car)."""
        view = self.view
        ttc = view.ttc_front
        if ttc >= self.config.aeb_ttc:
            return False
        return not clears_sideways(view, ttc)
