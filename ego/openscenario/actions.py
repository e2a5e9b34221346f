"""The OpenSCENARIO actions ego runs: one :class:`~ego.openscenario.registry.ActionKind`
each (its element and sub-elements, how it is read, what it drives, how it runs), registered
by element name. Adding an action is one class here (or in a module of its own that
registers it: docs/architecture.md, "Adding an OpenSCENARIO action")."""

from __future__ import annotations

import dataclasses
import math
from bisect import bisect_right
from collections.abc import Callable
from typing import Any

import numpy as np

from ego.openscenario import model as M
from ego.openscenario.curves import clothoid, nurbs
from ego.openscenario.dynamics import DYNAMICS_LIMITS, Transition, lateral_duration, offset_duration, speed_duration
from ego.openscenario.ego_refs import EgoGap, EgoPath, SpeedKnots, to_lane_frame
from ego.openscenario.files import warn
from ego.openscenario.registry import ActionKind, register
from ego.openscenario.runtime import EPS, INF, ActionRun, Storyboard, speed_profile_knots
from ego.openscenario.xmltree import DOCS, Node
from ego.params import ConfigError

# the builder's (``b``) readers: num, int_, bool_, str_, enum, one, entity_ref, position,
# dynamics, scoped, vertices (ego.openscenario.loader._Builder)


class Teleport(ActionKind):
    tag, within, contains, model = "TeleportAction", ("PrivateAction",), ("Position",), M.TeleportAction
    in_init, init_note, places, on_ego = "yes", "TeleportAction", True, True
    note = (
        "puts the entity's reference point (its box centre less the file's `center.x`, as in `Init`) at the "
        "position (`test_xosc_reference_point.py`); places an entity that has no start position yet (not in the "
        "simulation until then: see `Init`); on the "
        "ego during the run: its plant's pose becomes the position's (the reference point there, the position's "
        "heading), its speeds and steering kept, its lane there found again (the offset from that lane's centre "
        "held as its lateral reference, as an Init offset) and its position references moved along with it; only "
        "onto the ego's road (its lane frame) and with ego's own plant, else a warning and nothing moves "
        "(`test_xosc_ego_teleport.py`)"
    )

    def build(self, b: Any, node: Node) -> M.TeleportAction:
        position = b.one(node, "Position")
        p = b.one(position)
        o = p.child("Orientation")
        heading, line = None, 0
        if p.tag == "WorldPosition" and "h" in p.attrs:
            heading, line = b.num(p, "h"), p.line
        elif o is not None and "h" in o.attrs and b.enum(o, "type", ("relative", "absolute"), "absolute") == "absolute":
            heading, line = b.num(o, "h"), o.line
        return M.TeleportAction(b.position(position), node.line, heading, line)

    def start(self, run: ActionRun, t: float) -> None:
        drv = run.board.driver
        x, y, h = drv.position_xy(run.action.position, run.board.states)
        if run.is_ego:
            drv.ego_teleport(x, y, h, run.action.line)
        else:
            drv.teleport(run.actor, x, y, h)
        run.finished = True


class Controller(ActionKind):
    tag, within, model = "ControllerAction", ("PrivateAction",), M.ControllerAction
    contains = ("ActivateControllerAction", "AssignControllerAction")
    parts = {"AssignControllerAction": ("Controller", "CatalogReference")}
    domains, on_ego, in_init, init_note = (), True, "ignored", "ControllerAction"
    label = (
        "`ControllerAction` (`ActivateControllerAction`, `AssignControllerAction`), `ActivateControllerAction` (1.0)"
    )
    also = ("ActivateControllerAction", "AssignControllerAction")
    note = (
        "done at once; the ego keeps ego's controller, the others their driver or script (see `ObjectController`);"
        " an ego controller activated or assigned only here, by the storyboard, sets no ego parameter (ego sets "
        "them before the run: [Controller properties](#controller-properties));"
        " `OverrideControllerValueAction` refused (its values are pedal, brake, gear and steering inputs of a "
        "driver: none is an ego parameter)"
    )

    def build(self, b: Any, node: Node) -> M.ControllerAction:
        activates = assigns = False
        for c in node.children:
            if c.tag == "AssignControllerAction":
                b.controller(c)
                assigns = True
            elif c.tag == "ActivateControllerAction":
                activates = _activates(b, c)
        return M.ControllerAction(node.line, activates, assigns)


def _activates(b: Any, node: Node) -> bool:
    """An ActivateControllerAction activates the longitudinal domain (the standard: an
    attribute left out leaves its domain as it is)."""
    return "longitudinal" in node.attrs and b.bool_(node, "longitudinal")


class ActivateController(ActionKind):
    """OpenSCENARIO 1.0's ActivateControllerAction (directly in a PrivateAction)."""

    tag, within, model = "ActivateControllerAction", ("PrivateAction",), M.ControllerAction
    domains, on_ego, in_init = (), True, "ignored"

    def build(self, b: Any, node: Node) -> M.ControllerAction:
        return M.ControllerAction(node.line, _activates(b, node))


class Appearance(ActionKind):
    """AppearanceAction's LightStateAction (1.2): a vehicle's lights."""

    tag, within, model = "AppearanceAction", ("PrivateAction",), M.AppearanceAction
    contains = ("LightStateAction",)
    parts = {
        "LightStateAction": ("LightType", "LightState"),
        "LightType": ("VehicleLight", "UserDefinedLight"),
        "VehicleLight": (),
        "UserDefinedLight": (),
        "LightState": ("Color",),
        "Color": ("ColorRgb", "ColorCmyk"),
        "ColorRgb": (),
        "ColorCmyk": (),
    }
    domains, on_ego, in_init, init_note = (), True, "ignored", "AppearanceAction"
    label = "`AppearanceAction`/`LightStateAction` (1.2)"
    note = (
        "read (the light's `mode` on, off or flashing) and done at once, changing nothing: ego draws no lights, "
        "and neither the plant, SUMO's drivers nor the surround sensor depend on them; `AnimationAction` refused"
    )

    def build(self, b: Any, node: Node) -> M.AppearanceAction:
        lsa = b.one(node, "LightStateAction")
        b.one(lsa, "LightType")
        b.enum(b.one(lsa, "LightState"), "mode", ("on", "off", "flashing"))
        b.num(lsa, "transitionTime", 0.0, nonneg=True)
        return M.AppearanceAction(node.line)


class Visibility(ActionKind):
    tag, within, model = "VisibilityAction", ("PrivateAction",), M.VisibilityAction
    contains, parts = ("SensorReferenceSet",), {"SensorReferenceSet": ("SensorReference",), "SensorReference": ()}
    domains, on_ego, in_init, init_note = (), True, "runs", "VisibilityAction"
    note = (
        "done at once: `sensors` false hides the entity from the ego's surround sensor (no front or rear "
        "object, gap or TTC from it, so no manoeuvre nor AEB for it; it still collides: SUMO's collisions and "
        "the outline check the sensor makes for the bodies it sees, made for it, `test_xosc_road_edges.py`) "
        "until a "
        "`VisibilityAction` with `sensors` true; on the ego it changes nothing (no other entity has a "
        "sensor); a 1.2 `SensorReferenceSet` (named sensors) is read, and the one surround sensor is meant; "
        "`graphics` is read and changes nothing (ego's recordings draw every body); `traffic` false is "
        "refused in one line (SUMO's drivers always see every vehicle: their car-following cannot leave one "
        "out). **As the reference player reads them**, an attribute left out (the schema requires all three; "
        "esmini's `cut-in_visibility.xosc` writes only `sensors`, or `graphics` and `sensors`) is true"
    )

    def build(self, b: Any, node: Node) -> M.VisibilityAction:
        traffic = b.bool_(node, "traffic", True)
        if not traffic:
            raise b.error(
                node,
                f'a <VisibilityAction> with traffic="false" is not supported by ego: SUMO\'s drivers see every '
                f"vehicle (see {DOCS})",
            )
        refs = node.child("SensorReferenceSet")
        for r in refs.all("SensorReference") if refs is not None else ():
            b.str_(r, "name")
        return M.VisibilityAction(b.bool_(node, "graphics", True), traffic, b.bool_(node, "sensors", True), node.line)

    def start(self, run: ActionRun, t: float) -> None:
        if not run.is_ego:
            run.board.driver.visibility(run.actor, run.action.sensors)
        run.finished = True


class Speed(ActionKind):
    tag, within, model = "SpeedAction", ("LongitudinalAction",), M.SpeedAction
    contains = ("SpeedActionDynamics", "SpeedActionTarget")
    parts = {
        "SpeedActionDynamics": (),
        "SpeedActionTarget": ("AbsoluteTargetSpeed", "RelativeTargetSpeed"),
        "AbsoluteTargetSpeed": (),
        "RelativeTargetSpeed": (),
    }
    domains, on_ego, in_init = ("long",), True, "yes"
    init_note = "SpeedAction"
    note = (
        "`AbsoluteTargetSpeed`, `RelativeTargetSpeed` (delta, factor, continuous; a missing "
        "`speedTargetValueType`, which the schema requires, is delta with a warning, **as the reference player "
        "reads it**; a negative `AbsoluteTargetSpeed`, which the reference player drives backwards, is refused in one "
        "line: neither SUMO's drivers nor ego's plant reverse); shapes step, linear, cubic, "
        "sinusoidal over time, rate (the mean rate for cubic and sinusoidal) or distance; a `value` of 0 is a "
        "step (the standard); a step may leave out `value` and `dynamicsDimension` (the schema asks for both; a "
        "step has no duration, and the reference player's files omit them); a negative rate is read by its "
        "magnitude (**deviation**: the standard requires a rate >= 0, but the reference player esmini plays the "
        "negative braking rates its example files write, `-4`, `-6`, as their magnitude, and ego follows it so "
        "those files run as they do there); a negative time or distance is refused; linear-over-rate is SUMO's "
        "own per-step deceleration (exactly emergency-brake's lead), except while a lane change moves the car "
        "(SUMO then takes a set speed at once: the profile is commanded step by step, within 1e-6 of the closed "
        "form, `test_xosc_player_forms.py`); the others are commanded step by step along the closed form"
    )

    def build(self, b: Any, node: Node) -> M.SpeedAction:
        dyn = b.dynamics(b.one(node, "SpeedActionDynamics"))
        target = b.one(b.one(node, "SpeedActionTarget"))
        if target.tag == "AbsoluteTargetSpeed":
            value = b.num(target, "value")
            if value < 0.0:  # the reference player drives the car backwards (its light_state.xosc)
                raise b.error(
                    target,
                    f"a negative target speed ({value:g} m/s: driving backwards) is not supported by ego: SUMO's "
                    f"drivers and ego's own plant drive forwards only (see {DOCS})",
                )
            return M.SpeedAction(dyn, value, line=node.line)
        if "speedTargetValueType" not in target.attrs:
            # the schema requires it; the reference player reads a missing one as delta
            warn(
                f"{b.path}:{target.line}: <RelativeTargetSpeed> has no speedTargetValueType (the schema requires "
                f"it): delta, as the reference player reads it"
            )
        return M.SpeedAction(
            dyn,
            b.num(target, "value"),
            b.entity_ref(target),
            b.enum(target, "speedTargetValueType", ("delta", "factor"), "delta"),
            b.bool_(target, "continuous"),
            node.line,
        )

    def init_runs(self, action: M.SpeedAction) -> bool:
        # a continuous relative speed: the start is the other's Init speed plus the delta,
        # and the action keeps following it from t = 0
        return action.relative_to is not None and action.continuous

    def start(self, run: ActionRun, t: float) -> None:
        b, a, drv = run.board, run.action, run.board.driver
        me = b.states[run.actor]
        # the ego's references move on from where they are (its measured speed wobbles)
        v0 = drv.ego_references()[0] if run.is_ego else me.speed
        target = a.value
        if a.relative_to is not None:
            ref = b.states[a.relative_to].speed
            target = ref + a.value if a.relative_kind == "delta" else ref * a.value
        target = max(target, 0.0)
        dyn = a.dynamics
        T = speed_duration(dyn.shape, dyn.dimension, dyn.value, v0, target)
        run.profile = Transition(t, v0, target, T, dyn.shape)
        if run.is_ego:
            rel = (a.relative_to, a.relative_kind, a.value) if (a.relative_to and a.continuous) else None
            drv.ego_speed(run.profile, rel)
            run.finished = not a.continuous
            return
        if dyn.shape == "linear" and dyn.dimension == "rate" and v0 != target and not drv.blind(run.actor):
            drv.speed_rate(run.actor, target, dyn.value)  # SUMO's own per-step rate: exact
            run.native = True
        else:
            run.native = False

    def step(self, run: ActionRun, t: float) -> None:
        b, a, drv = run.board, run.action, run.board.driver
        p = run.profile
        if run.is_ego:
            return  # the ego's references follow the other's speed themselves (ego_speed's relative)
        if a.continuous and a.relative_to is not None and p.done(t):
            ref = b.states[a.relative_to].speed
            target = max(ref + a.value if a.relative_kind == "delta" else ref * a.value, 0.0)
            drv.speed(run.actor, target, INF)
            return
        if run.native and drv.blind(run.actor):
            # a scripted lateral move makes SUMO take a set speed at once (no braking
            # limit): the rest of the profile is commanded step by step
            run.native = False
        if not run.native:
            drv.speed(run.actor, p.value(t + b.h), max(p.peak_rate, 0.0))
        if p.done(t + b.h) and not a.continuous:
            run.finished = True


def _lateral_start(run: ActionRun, t: float, target: float, T: float, shape: str) -> None:
    """Start a lateral profile (lane change, lane offset) from where the actor is to ``target``."""
    drv, me = run.board.driver, run.board.states[run.actor]
    start = drv.ego_references()[1] if run.is_ego else me.d_ref
    run.profile = Transition(t, start, target, T, shape)
    if run.is_ego:  # the ego's controller follows the profile; the action ends with it
        drv.ego_lateral(run.profile)


def _lateral_step(kind: ActionKind, run: ActionRun, t: float) -> None:
    """Move the actor's reference point along its lateral profile for [t, t + step] (the driver
    places it there, turned to the profile's slope; straight along its lane at the end): the
    ``step`` of a lane change and of a lane offset."""
    drv, p = run.board.driver, run.profile
    if p is None:  # not started (its target lane does not exist)
        return
    if not run.is_ego:
        h = run.board.h
        # at the profile's end the car is straight along its lane (its rate there is 0)
        drv.lateral(run.actor, p.value(t + h), p.peak_rate, 0.0 if p.done(t + h) else p.rate(t + h))
    if p.done(t + run.board.h) and not getattr(run.action, "continuous", False):
        run.finished = True
        if not run.is_ego:
            drv.release(run.actor)


class LaneChange(ActionKind):
    tag, within, model = "LaneChangeAction", ("LateralAction",), M.LaneChangeAction
    in_init, init_note = "runs", "LaneChangeAction"
    domains, on_ego, releases = ("lat",), True, True
    contains = ("LaneChangeActionDynamics", "LaneChangeTarget")
    parts = {
        "LaneChangeActionDynamics": (),
        "LaneChangeTarget": ("AbsoluteTargetLane", "RelativeTargetLane"),
        "AbsoluteTargetLane": (),
        "RelativeTargetLane": (),
    }
    note = (
        "`AbsoluteTargetLane` (the lane of that OpenDRIVE id, by the ids netconvert keeps: until the issue-39-lht "
        "branch it was counted from the centre line, so past a border lane netconvert leaves out, as "
        "`e6mini.xodr`'s lanes -1 and +1, it went one lane too far out: esmini's `follow_ghost.xosc` ego "
        "changed to lane -4 instead of -2 and back; `test_xosc_left_hand.py`), `RelativeTargetLane` (+ to the "
        "left in the reference entity's driving direction), `targetLaneOffset`; shapes over time, distance (distance at "
        "the speed at the start) or rate (the peak lateral speed in m/s, as the ALKS files' `MaxLateralVelocity`: "
        "T = k \\|D\\| / rate, k = 1 linear, 3/2 cubic, pi/2 sinusoidal, D from where the entity is to the target); "
        "the entity's reference point (its box centre less the file's `center.x` along its heading) is on the "
        "closed form at every SUMO step, measured from SUMO's own pose (front bumper, angle, length), within "
        "1e-6 m in the ego's lane frame, on a straight road and on an arc, and ends on the target "
        "(`test_xosc_reference_point.py`): ego places the SUMO car each step (moveToXY along its route: it stays "
        "a vehicle on the lane its front is on, which the others follow and see) where its reference point is "
        "after the step, moved along the lane frame at the speed commanded for the step and turned to the "
        "profile's slope (atan of its lateral rate over its speed; along the lane at the end and for a step), "
        "blind to others while moving as cut-in's car; afterwards SUMO drives it on at that lateral place (on "
        "an arc its body's front and back on one offset of netconvert's polyline lane: within 1 mm of the "
        "target on a 200 m arc, as SUMO's own cars keep their lane there); a scripted car changing across the "
        "centre line into the other direction's lanes (the reference player's `acc-test.xosc` overtaking, "
        "`RelativeTargetLane` +1 from a one-lane direction) is driven by ego from where it crosses (as a car "
        "turned against its lane, see the positions' row: its box centre on the profile) and stays so; a `RelativeTargetLane` counts across "
        "the road's lanes of both directions (from the oncoming lane back right, as `light_state.xosc` does), and "
        "one asking for more lanes beside its reference than the road has less one is refused before the run"
    )

    def build(self, b: Any, node: Node) -> M.LaneChangeAction:
        dyn = b.dynamics(b.one(node, "LaneChangeActionDynamics"))
        target = b.one(b.one(node, "LaneChangeTarget"))
        offset = b.num(node, "targetLaneOffset", 0.0)
        if target.tag == "AbsoluteTargetLane":
            return M.LaneChangeAction(dyn, b.int_(target, "value"), None, 0, offset, node.line)
        return M.LaneChangeAction(dyn, None, b.entity_ref(target), b.int_(target, "value"), offset, node.line)

    def start(self, run: ActionRun, t: float) -> None:
        a, b = run.action, run.board
        drv, me = b.driver, b.states[run.actor]
        try:
            if a.target_lane is not None:
                centre = drv.lane_centre(a.target_lane)
            elif run.is_ego and a.relative_to == b.ego:  # from the lane the ego is commanded to
                centre = drv.lane_centre(0, drv.ego_references()[1], a.relative_lanes)
            else:
                centre = drv.lane_centre(0, b.states[a.relative_to].d, a.relative_lanes)
        except ConfigError as exc:  # found only when it starts (where the reference is then)
            # not a refusal mid-run (``ego list`` cannot know where the reference will be):
            # the action ends at once without moving the actor
            warn(f"{b.scenario.path}:{a.line}: at t = {t:.2f} s: {exc}: the lane change is skipped")
            b.log("action", f"t = {t:.2f} s: LaneChangeAction skipped: {exc}")
            run.finished = True
            return
        target = centre + a.target_offset
        here = drv.ego_references()[1] if run.is_ego else me.d_ref
        dyn = a.dynamics
        _lateral_start(
            run, t, target, lateral_duration(dyn.shape, dyn.dimension, dyn.value, me.speed, target - here), dyn.shape
        )

    step = _lateral_step


class LaneOffset(ActionKind):
    tag, within, model = "LaneOffsetAction", ("LateralAction",), M.LaneOffsetAction
    in_init, init_note = "runs", "LaneOffsetAction"
    domains, on_ego, releases = ("lat",), True, True
    contains = ("LaneOffsetActionDynamics", "LaneOffsetTarget")
    parts = {
        "LaneOffsetActionDynamics": (),
        "LaneOffsetTarget": ("AbsoluteTargetLaneOffset", "RelativeTargetLaneOffset"),
        "AbsoluteTargetLaneOffset": (),
        "RelativeTargetLaneOffset": (),
    }
    note = (
        "absolute and relative targets; the duration from `maxLateralAcc`: cubic sqrt(6 D / a), sinusoidal pi "
        "sqrt(D / (2 a)), linear 2 sqrt(D / a); the entity's reference point on the closed form as a lane "
        "change's (`test_xosc_reference_point.py`); an offset that leaves the car's centre far beyond the road's "
        "outer edge does not stay there once the action ends: SUMO pulls the car back (on straight3 a 1.8 m wide "
        "car offset 3 m right of the right lane's centre ends 2.21 m right of it; 2 m stays)"
    )

    def build(self, b: Any, node: Node) -> M.LaneOffsetAction:
        d = b.one(node, "LaneOffsetActionDynamics")
        acc = b.raw(d, "maxLateralAcc", None)
        shape = b.enum(d, "dynamicsShape", M.SHAPES)
        if acc is None and shape != "step":
            raise b.error(d, f"<LaneOffsetActionDynamics> needs maxLateralAcc for dynamicsShape {shape}")
        target = b.one(b.one(node, "LaneOffsetTarget"))
        rel = b.entity_ref(target) if target.tag == "RelativeTargetLaneOffset" else None
        return M.LaneOffsetAction(
            shape,
            None if acc is None else b.num(d, "maxLateralAcc", positive=True),
            b.num(target, "value"),
            rel,
            b.bool_(node, "continuous"),
            node.line,
        )

    def start(self, run: ActionRun, t: float) -> None:
        a, b = run.action, run.board
        drv, me = b.driver, b.states[run.actor]
        base = b.states[a.relative_to].d if a.relative_to is not None else drv.lane_centre_of(me.d)
        target = base + a.value
        here = drv.ego_references()[1] if run.is_ego else me.d_ref
        _lateral_start(run, t, target, offset_duration(a.shape, a.max_lateral_acc, target - here), a.shape)

    step = _lateral_step


class LongitudinalDistance(ActionKind):
    tag, within, model = "LongitudinalDistanceAction", ("LongitudinalAction",), M.LongitudinalDistanceAction
    in_init, init_note = "runs", "LongitudinalDistanceAction"
    contains = ("DynamicConstraints",)
    parts = {"DynamicConstraints": ()}
    domains, on_ego = ("long",), True
    note = (
        "`distance` or `timeGap` (times the actor's own speed, as the standard), `freespace` (between the boxes) "
        "or centres, `displacement` trailing (default, `any`) or leading, `continuous` (else it ends once held "
        "within 1 cm); without `DynamicConstraints` the actor is at the distance after one step and then exactly "
        "there every step (within 1e-6: `test_xosc_alks_forms.py`); with them it keeps `maxAcceleration`, "
        "`maxDeceleration`, `maxSpeed` and closes at the speed from which its braking limit still stops at the "
        "distance a step later; on the ego the same law drives the reference point its longitudinal reference "
        "follows (see How the ego is chosen)"
    )

    def build(self, b: Any, n: Node) -> M.LongitudinalDistanceAction:
        has_d, has_t = "distance" in n.attrs, "timeGap" in n.attrs
        if has_d == has_t:
            raise b.error(n, "<LongitudinalDistanceAction> needs one of distance and timeGap")
        disp = b.enum(n, "displacement", ("trailingReferencedEntity", "leadingReferencedEntity", "any"), "any")
        limits = _limits(
            b, n, ("maxAcceleration", "max_accel"), ("maxDeceleration", "max_decel"), ("maxSpeed", "max_speed")
        )
        return M.LongitudinalDistanceAction(
            b.entity_ref(n),
            b.num(n, "distance", nonneg=True) if has_d else None,
            b.num(n, "timeGap", nonneg=True) if has_t else None,
            b.bool_(n, "freespace"),
            b.bool_(n, "continuous"),
            disp == "leadingReferencedEntity",
            line=n.line,
            **limits,
        )

    def start(self, run: ActionRun, t: float) -> None:
        if run.is_ego:
            # the ego's longitudinal reference follows a reference point driven by the law
            b = run.board
            run.law = EgoGap(t, b.states[run.actor].s, b.driver.ego_references()[0])
            b.driver.ego_longitudinal(run.law)

    def step(self, run: ActionRun, t: float) -> None:
        """The speed over [t, t + step] that puts the actor at the held distance from the
        entity at t + step (:func:`distance_speed`); a non-continuous action ends once the
        distance is held (within 1 cm). On the ego the law drives its reference point."""
        b, a = run.board, run.action
        h = b.h
        me, ref = b.states[run.actor], b.states[a.entity]
        if run.is_ego:
            law = run.law
            s, v0 = law.longitudinal(t)
        else:
            s, v0 = me.s, me.speed
        v = distance_speed(a, s, v0, ref.s, ref.speed, me.length, ref.length, h)
        if run.is_ego:
            law.advance(t, v, h, ref.speed)
        else:
            constrained = math.isfinite(a.max_accel) or math.isfinite(a.max_decel)
            b.driver.speed(run.actor, v, abs(v - me.speed) / h if constrained else INF)
        sign = 1.0 if a.leading else -1.0
        extra = 0.5 * (me.length + ref.length) if a.freespace else 0.0
        gap = sign * (s - ref.s) - extra
        held = a.distance if a.distance is not None else (a.time_gap or 0.0) * v0
        if not a.continuous and abs(gap - held) < 0.01:
            run.finished = True


def distance_speed(
    a: M.LongitudinalDistanceAction,
    s: float,
    v: float,
    ref_s: float,
    ref_v: float,
    length: float,
    ref_length: float,
    h: float,
) -> float:
    """The standard's LongitudinalDistanceAction as a law: the actor's speed over the next
    step ``h`` (s) from its box centre ``s`` and speed ``v`` and the referenced entity's
    (``ref_s``, ``ref_v``; lengths for freespace), that puts it at the held distance from the
    entity at the end of the step (the entity driving on at its speed), within the action's
    dynamic constraints: unconstrained the position error is closed in one step, with them at
    the speed from which the braking (or accelerating) limit still ends at the goal."""
    sign = 1.0 if a.leading else -1.0  # the actor ahead of (+) or behind (-) the entity
    extra = 0.5 * (length + ref_length) if a.freespace else 0.0
    ref_next = ref_s + ref_v * h
    constrained = math.isfinite(a.max_accel) or math.isfinite(a.max_decel)
    if a.distance is not None or constrained:
        held = a.distance if a.distance is not None else (a.time_gap or 0.0) * ref_v
        err = ref_s + sign * (held + extra) - s
        close = abs(err) / h
        stop = a.max_decel if err > 0.0 else a.max_accel  # what ends the closing
        if math.isfinite(stop):
            # the relative speed from which ``stop`` still ends at the goal, a step later
            close = min(-stop * h + math.sqrt((stop * h) ** 2 + 2.0 * stop * abs(err)), close)
        out = ref_v + math.copysign(close, err)
    else:
        # s + v h = ref_next + sign (tg v + extra): the gap is tg times the actor's speed
        tg = a.time_gap or 0.0
        denom = h - sign * tg
        out = (ref_next + sign * extra - s) / denom if abs(denom) > EPS else v
    lo = max(v - a.max_decel * h, 0.0)
    hi = min(v + a.max_accel * h, a.max_speed)
    return min(max(out, lo), hi)


class LateralDistance(ActionKind):
    tag, within, model = "LateralDistanceAction", ("LateralAction",), M.LateralDistanceAction
    in_init, init_note = "runs", "LateralDistanceAction"
    contains, parts = ("DynamicConstraints",), {"DynamicConstraints": ()}
    domains, releases = ("lat",), True
    note = (
        "`distance` (left out: 0, the standard's default) across the road between the reference points (box "
        "centres less the file's `center.x` along their headings; the actor placed as a lane change's) or, with "
        "`freespace`, between the boxes (half widths subtracted); `displacement` leftToReferencedEntity, "
        "rightToReferencedEntity or any (the side the actor is on at the start; on the entity's line: left); "
        "`coordinateSystem` read as the road's (entity, lane, road: across the ego's start lane frame); the "
        "entity's lateral position a step ahead is taken from its last step's lateral speed; without "
        "`DynamicConstraints` the actor is at the distance after one step and then exactly there every step "
        "(within 1e-6, `test_xosc_road_edges.py`); with them `maxSpeed` limits its lateral speed, "
        "`maxAcceleration` its lateral speed's growth and `maxDeceleration` its fall (it closes at the speed "
        "from which that deceleration still stops at the distance a step later); `continuous` false ends once "
        "held within 1 cm; not on the ego"
    )

    def build(self, b: Any, n: Node) -> M.LateralDistanceAction:
        disp = b.enum(n, "displacement", ("leftToReferencedEntity", "rightToReferencedEntity", "any"), "any")
        if "coordinateSystem" in n.attrs:
            b.enum(n, "coordinateSystem", ("entity", "lane", "road", "trajectory"))
        limits = _limits(
            b, n, ("maxAcceleration", "max_accel"), ("maxDeceleration", "max_decel"), ("maxSpeed", "max_speed")
        )
        return M.LateralDistanceAction(
            b.entity_ref(n),
            b.num(n, "distance", 0.0, nonneg=True),
            b.bool_(n, "freespace"),
            b.bool_(n, "continuous"),
            {"leftToReferencedEntity": 1, "rightToReferencedEntity": -1}.get(disp, 0),
            line=n.line,
            **limits,
        )

    def start(self, run: ActionRun, t: float) -> None:
        b, a = run.board, run.action
        me, ref = b.states[run.actor], b.states[a.entity]
        run.v = 0.0  # the actor's lateral speed as commanded (m/s, + left)
        run.s0 = ref.d_ref  # the entity's lateral position a step ago
        run.t0 = a.side or (1.0 if me.d_ref >= ref.d_ref else -1.0)

    def step(self, run: ActionRun, t: float) -> None:
        """The lateral position at t + step: the entity's there (moving on at its last step's
        lateral speed) plus the held distance on the actor's side, reached within the
        constraints."""
        b, a = run.board, run.action
        h = b.h
        me, ref = b.states[run.actor], b.states[a.entity]
        extra = 0.5 * (me.width + ref.width) if a.freespace else 0.0
        ref_next = 2.0 * ref.d_ref - run.s0
        run.s0 = ref.d_ref
        err = ref_next + run.t0 * (a.distance + extra) - me.d_ref
        v = err / h
        if math.isfinite(a.max_decel):
            stop = a.max_decel
            v = math.copysign(min(abs(v), -stop * h + math.sqrt((stop * h) ** 2 + 2.0 * stop * abs(err))), err)
        if abs(v) > abs(run.v) or v * run.v < 0.0:  # speeding up sideways (or turning round)
            grow = a.max_accel * h
            v = min(max(v, run.v - grow), run.v + grow)
        else:
            fall = a.max_decel * h
            v = min(max(v, run.v - fall), run.v + fall)
        v = min(max(v, -a.max_speed), a.max_speed)
        run.v = v
        peak = a.max_speed if math.isfinite(a.max_speed) else 100.0 / h
        gap = run.t0 * (me.d_ref - ref.d_ref) - extra
        ends = not a.continuous and abs(gap - a.distance) < 0.01
        # unconstrained it is there after one step: a jump across; at its end SUMO drives it on
        # from the last placement: either way the car along its lane
        rate = v if math.isfinite(a.max_speed) and not ends else 0.0
        b.driver.lateral(run.actor, me.d_ref + v * h, peak, rate)
        if ends:
            run.finished = True
            b.driver.release(run.actor)


def _limits(b: Any, n: Node, *names: tuple[str, str]) -> dict[str, float]:
    """The DynamicConstraints' limits given (attribute -> model field), each > 0."""
    limits: dict[str, float] = {}
    dc = n.child("DynamicConstraints")
    for attr, key in names:
        if dc is not None and attr in dc.attrs:
            limits[key] = b.num(dc, attr, positive=True)
    return limits


class SpeedProfile(ActionKind):
    tag, within, model = "SpeedProfileAction", ("LongitudinalAction",), M.SpeedProfileAction
    in_init, init_note = "runs", "SpeedProfileAction"
    contains = ("DynamicConstraints", "SpeedProfileEntry")
    parts = {"DynamicConstraints": (), "SpeedProfileEntry": ()}
    domains, on_ego = ("long",), True
    label = "`SpeedProfileAction` (1.2)"
    note = (
        "the speed goes linearly through its `SpeedProfileEntry`s, each entry's `speed` reached in its `time` "
        "(none or 0: at the `DynamicConstraints`' `maxAcceleration`/`maxDeceleration`, a step without them), plus "
        "the `entityRef`'s speed at the start when given; `followingMode` follow keeps those limits (an entry too "
        "quick for them takes longer), position follows the times; commanded step by step (within 1e-6 of the "
        "profile, `test_xosc_player_forms.py`). **Deviation:** the jerk limits (`maxAccelerationRate`, "
        "`maxDecelerationRate`) are read and not applied (the reference player smooths with them in follow mode); "
        "on the ego its speed reference"
    )

    def build(self, b: Any, n: Node) -> M.SpeedProfileAction:
        entries = []
        for e in n.all("SpeedProfileEntry"):
            time = b.num(e, "time", nonneg=True, at_most=DYNAMICS_LIMITS["time"]) if "time" in e.attrs else None
            entries.append((b.num(e, "speed"), time))
        if not entries:
            raise b.error(n, "<SpeedProfileAction> needs at least one <SpeedProfileEntry>")
        limits = _limits(b, n, ("maxAcceleration", "max_accel"), ("maxDeceleration", "max_decel"))
        rel = b.entity_ref(n) if "entityRef" in n.attrs else None
        mode = b.enum(n, "followingMode", ("position", "follow"))
        return M.SpeedProfileAction(tuple(entries), rel, mode, line=n.line, **limits)

    def start(self, run: ActionRun, t: float) -> None:
        a, states = run.action, run.board.states
        ref = states[a.relative_to].speed if a.relative_to else 0.0
        # the ego's speed reference goes through the knots from where it is
        v0 = run.board.driver.ego_references()[0] if run.is_ego else states[run.actor].speed
        run.knots = speed_profile_knots(a, t, v0, ref)
        if run.is_ego:
            run.law = SpeedKnots(*run.knots)
            run.board.driver.ego_speed(run.law, None)

    def step(self, run: ActionRun, t: float) -> None:
        ts, vs = run.knots
        t1 = t + run.board.h
        if run.is_ego:
            run.finished = t1 >= ts[-1] - EPS
            return
        v = vs[-1] if t1 >= ts[-1] else float(np.interp(t1, ts, vs))
        run.board.driver.speed(run.actor, max(v, 0.0), INF)
        if t1 >= ts[-1] - EPS:
            run.finished = True


class Synchronize(ActionKind):
    tag, within, model = "SynchronizeAction", ("PrivateAction",), M.SynchronizeAction
    in_init, init_note = "runs", "SynchronizeAction"
    contains = ("TargetPositionMaster", "TargetPosition", "FinalSpeed")
    parts = {
        "TargetPositionMaster": "Position",
        "TargetPosition": "Position",
        "FinalSpeed": ("AbsoluteSpeed", "RelativeSpeedToMaster"),
        "AbsoluteSpeed": (),
        "RelativeSpeedToMaster": (),
    }
    domains = ("long",)
    note = (
        "the actor reaches `TargetPosition` when the master reaches `TargetPositionMaster` (positions as road s, "
        "along the ego road's reference line), the master taken to drive on at its speed and the plan redone every step: "
        "without `FinalSpeed` the constant speed d / T (a step at the start, as the standard gives the action no "
        "dynamics), with `FinalSpeed` (`AbsoluteSpeed`, `RelativeSpeedToMaster` delta or factor of the master's "
        "speed at each step) the speed profile v + b t + c t^2 that ends at the final speed and covers the "
        "distance; ends when the master arrives. Measured (`test_xosc_player_forms.py`: master at 25 m/s 200 m "
        "from its target, actor 50 m from its own): the actor is at its target to 1e-6 m when the master arrives, "
        "6 cm past it with a final speed of 10 m/s (10.0000 m/s at arrival); not on the ego; the actor keeps its "
        "lane"
    )

    def build(self, b: Any, a: Node) -> M.SynchronizeAction:
        final, kind = None, "absolute"
        fs = a.child("FinalSpeed")
        if fs is not None:
            sp = b.one(fs)
            if sp.tag == "AbsoluteSpeed":
                final = b.num(sp, "value", nonneg=True)
            else:
                kind = b.enum(sp, "speedTargetValueType", ("delta", "factor"))
                final = b.num(sp, "value")
        return M.SynchronizeAction(
            b.entity_ref(a, "masterEntityRef"),
            b.position(b.one(a, "TargetPositionMaster")),
            b.position(b.one(a, "TargetPosition")),
            final,
            kind,
            a.line,
        )

    def start(self, run: ActionRun, t: float) -> None:
        pass  # commanded step by step

    def step(self, run: ActionRun, t: float) -> None:
        """The speed over the next step on the profile that puts the actor at its target when
        the master reaches its own, the master driving on at its speed (re-planned every
        step): with a final speed v_f, v(tau) = v + b tau + c tau^2 with v(T) = v_f and its
        integral over [0, T] the distance left; without, the constant speed d / T. Ends when
        the master is at its target."""
        b, a = run.board, run.action
        h, drv = b.h, b.driver
        me, master = b.states[run.actor], b.states[a.master]
        s_m = drv.road_frame(*drv.position_xy(a.master_target, b.states)[:2])[0]
        s_a = drv.road_frame(*drv.position_xy(a.target, b.states)[:2])[0]
        d_m, d = s_m - master.s, s_a - me.s
        if d_m <= EPS:
            run.finished = True
            return
        if master.speed <= EPS:
            return  # the master stands: no arrival time to meet
        T = d_m / master.speed
        if a.final_speed is None:
            v = d / T
        else:
            vf = a.final_speed
            if a.final_kind == "delta":
                vf = master.speed + a.final_speed
            elif a.final_kind == "factor":
                vf = master.speed * a.final_speed
            if T <= h:
                v = vf
            else:
                dv, dd = vf - me.speed, d - me.speed * T
                c = (3.0 * dv * T - 6.0 * dd) / T**3
                bb = (dv - c * T * T) / T
                v = me.speed + bb * h + c * h * h
        drv.speed(run.actor, max(v, 0.0), INF)


class AssignRoute(ActionKind):
    tag, within, model = "AssignRouteAction", ("RoutingAction",), M.AssignRouteAction
    contains = ("Route", "CatalogReference")
    parts = {"Route": ("ParameterDeclarations", "Waypoint"), "Waypoint": ("Position",)}
    domains, in_init, init_note = ("route",), "runs", "AssignRouteAction"
    label = "`AssignRouteAction` with a `Route`, `AcquirePositionAction`"
    also = ("Route", "AcquirePositionAction")
    note = (
        "the entity's SUMO route becomes the shortest way (by length, whatever the `routeStrategy`) from the "
        "road it is on through each `Waypoint`'s road in turn, then straight on while a road has one successor "
        "(so the car does not stop at the last waypoint; it leaves the network where that way ends); SUMO's "
        "driver drives it (speed and lane changes as without a route); an `AcquirePositionAction` is a route to "
        "its one position; a waypoint whose road cannot be reached from the one before is refused before the "
        "run with its line; a `Route` may come from a `RouteCatalog` (`CatalogReference`, its parameters "
        "assigned; its errors named in the catalog file, an unreachable waypoint at the reference's line); "
        "`closed` routes refused (a `RoutePosition` names a point of a route: see the positions row); not "
        "on the ego (it drives its start road) nor on a car ego drives against its lane"
    )

    def build(self, b: Any, node: Node) -> M.AssignRouteAction:
        ref = node.child("CatalogReference")
        if ref is not None:  # a Route of a RouteCatalog: read in its file, with its parameters
            route, cb = b.entry_builder(ref, "Route")
            action = self._route(cb, route, node, scoped=False)
            # the waypoints' errors found later (unreachable roads) name the reference's line
            points = tuple(dataclasses.replace(p, line=ref.line) for p in action.waypoints)
            return M.AssignRouteAction(points, node.line)
        return self._route(b, b.one(node, "Route"), node)

    def _route(self, b: Any, route: Node, node: Node, scoped: bool = True) -> M.AssignRouteAction:
        if b.bool_(route, "closed", False):
            raise b.error(route, f"a closed <Route> is not supported by ego (see {DOCS})")
        outer = b.values
        if scoped:
            b.values = b.scoped(route)
        try:
            points = []
            for wp in route.all("Waypoint"):
                b.enum(wp, "routeStrategy", ("fastest", "shortest", "leastIntersections", "random"))
                points.append(b.position(b.one(wp, "Position")))
        finally:
            b.values = outer
        if len(points) < 2:
            raise b.error(route, f"<Route> needs at least two <Waypoint> (found {len(points)})")
        return M.AssignRouteAction(tuple(points), node.line)

    def start(self, run: ActionRun, t: float) -> None:
        run.board.driver.route(run.actor, run.action.waypoints)
        run.finished = True


class AcquirePosition(AssignRoute):
    tag, within, model = "AcquirePositionAction", ("RoutingAction",), M.AssignRouteAction
    contains, parts = ("Position",), {}
    init_note, note = "AcquirePositionAction", ""

    def build(self, b: Any, node: Node) -> M.AssignRouteAction:
        return M.AssignRouteAction((b.position(b.one(node, "Position")),), node.line)


def trajectory_points(
    a: M.FollowTrajectoryAction,
    pos: Callable[[M.Position], tuple[float, float, float]],
    start: tuple[float, float, float] | None = None,
) -> tuple[list[tuple[float, float]], list[float] | None]:
    """The points of a trajectory's shape and their times (None: no times): ``pos`` gives a
    position's world (x, y, heading); a clothoid spline whose first segment has no start
    position starts at ``start`` (the following entity's reference point and heading)."""
    if a.vertices:
        pts = [pos(v.position) for v in a.vertices]
        return [(p[0], p[1]) for p in pts], [v.time for v in a.vertices]  # type: ignore[misc]
    if a.nurbs is not None:
        nb = a.nurbs
        ctrl = [pos(p.position)[:2] for p in nb.points]
        ptimes = [p.time for p in nb.points]
        has_times = all(tt is not None for tt in ptimes)
        x, y, tt = nurbs(ctrl, nb.weights, nb.knots, nb.order, ptimes if has_times else None)  # type: ignore[arg-type]
        return list(zip(x.tolist(), y.tolist())), (None if tt is None else tt.tolist())
    x0, y0, h0 = start if start is not None else (0.0, 0.0, 0.0)
    xy: list[tuple[float, float]] = []
    times: list[float] | None = []
    for k, seg in enumerate(a.segments):
        if seg.start is not None:
            x0, y0, h0 = pos(seg.start)
        h0 += seg.h_offset
        xs, ys, hs, ss = clothoid(x0, y0, h0, seg.k0, seg.k1, seg.length)
        pts = list(zip(xs.tolist(), ys.tolist()))
        xy.extend(pts if not xy else pts[1:])
        x0, y0, h0 = float(xs[-1]), float(ys[-1]), float(hs[-1])
        if times is not None and seg.time is not None:
            t1 = a.segments[k + 1].time if k + 1 < len(a.segments) else a.end_time
            if t1 is None:
                times = None
                continue
            seg_times = (seg.time + (t1 - seg.time) * ss / seg.length).tolist()
            times.extend(seg_times if not times else seg_times[1:])
        else:
            times = None
    return xy, times


def along_path(xy: list[tuple[float, float]], s: float, t: float = 0.0) -> tuple[float, float, float]:
    """The point ``s`` along the polyline ``xy`` (clamped to it) and ``t`` to its left, with the
    polyline's heading there: (x, y, heading)."""
    walked, last = 0.0, None
    for (x0, y0), (x1, y1) in zip(xy, xy[1:]):
        seg = math.hypot(x1 - x0, y1 - y0)
        if seg <= 0.0:
            continue
        last = (x0, y0, x1, y1, seg, walked)
        if s <= walked + seg:
            break
        walked += seg
    if last is None:
        raise ValueError("the trajectory has no length")
    x0, y0, x1, y1, seg, walked = last
    u = min(max((s - walked) / seg, 0.0), 1.0)
    h = math.atan2(y1 - y0, x1 - x0)
    x, y = x0 + u * (x1 - x0), y0 + u * (y1 - y0)
    return x - t * math.sin(h), y + t * math.cos(h), h


class FollowTrajectory(ActionKind):
    tag, within, model = "FollowTrajectoryAction", ("RoutingAction",), M.FollowTrajectoryAction
    in_init, init_note = "runs", "FollowTrajectoryAction"
    contains = ("Trajectory", "TrajectoryRef", "TimeReference", "TrajectoryFollowingMode")
    parts = {
        "Trajectory": ("ParameterDeclarations", "Shape"),
        "TrajectoryRef": ("Trajectory",),
        "TimeReference": ("None", "Timing"),
        "TrajectoryFollowingMode": (),
        "Shape": ("Polyline", "Clothoid", "ClothoidSpline", "Nurbs"),
        "Polyline": ("Vertex",),
        "Vertex": ("Position",),
        "Clothoid": ("Position",),
        "ClothoidSpline": ("Segment",),
        "Segment": ("PositionStart",),
        "PositionStart": "Position",
        "Nurbs": ("ControlPoint", "Knot"),
        "ControlPoint": ("Position",),
        "Knot": (),
        "None": (),
        "Timing": (),
    }
    releases, on_ego = True, True
    label = "`FollowTrajectoryAction` with `Polyline`, `Clothoid`, `ClothoidSpline` (1.3) or `Nurbs`"
    also = ("Polyline", "Clothoid", "ClothoidSpline", "Nurbs")
    note = (
        "the entity's reference point (its box centre less the box's `center.x`) moves along the shape; `Timing` "
        "absolute or relative with scale and offset (vertex, control point or clothoid times), or none (the "
        "entity's speed at the start); `initialDistanceOffset`; on the ego its lateral reference (timed, its "
        "longitudinal one too: see How the ego is chosen). A `Clothoid` (curvature, "
        "`curvaturePrime`; the 1.0 `curvatureDot` read as the same rate per metre, as the reference player reads "
        "it) and a `ClothoidSpline`'s `Segment`s (`curvatureStart` to `curvatureEnd`, `hOffset`, `PositionStart`; "
        "the first without one starts at the entity; **as the reference player reads them** (the schema requires "
        "both curvatures): its pre-standard spelling `curvStart`/`curvEnd` is the same, a missing start curvature "
        "is the previous segment's end (0 for the first) and a missing end curvature the segment's start, an "
        "arc) start at their position with its heading "
        "and are integrated exactly (Simpson on 2 cm panels, sampled every 0.1 m: within 1e-6 m of the Fresnel "
        "integrals, `test_xosc_trajectories.py`); their times: `startTime`/`stopTime` (a spline's `timeStart`s "
        "and `timeEnd`), linear in length between them. A `Nurbs` (order, `ControlPoint`s with weights, "
        "`Knot`s: as many as points plus order, non-decreasing) is the rational B-spline sampled at 2001 "
        "parameters; a control point's time is combined like its position (as the reference player does; the "
        "standard gives no time between control points); catalog trajectories refused"
    )

    def domains_of(self, action: M.FollowTrajectoryAction, ego: bool) -> tuple[str, ...]:
        # on the ego an untimed path is a lateral reference only (its speed stays the ego's)
        return ("lat",) if ego and action.timing is None else self.domains

    def build(self, b: Any, inner: Node) -> M.FollowTrajectoryAction:
        traj_node = inner.child("Trajectory")
        if traj_node is None:
            ref = inner.child("TrajectoryRef")
            if ref is None:
                raise b.error(inner, "<FollowTrajectoryAction> needs a <Trajectory>")
            traj_node = b.one(ref, "Trajectory")
        outer_values = b.values
        b.values = b.scoped(traj_node)  # the trajectory's own parameters
        vertices: tuple[M.Vertex, ...] = ()
        segments: tuple[M.ClothoidSegment, ...] = ()
        nurbs, end_time = None, None
        try:
            shape = b.one(b.one(traj_node, "Shape"))
            if shape.tag == "Polyline":
                vertices = tuple(self.vertices(b, shape))
                times = [v.time for v in vertices]
            elif shape.tag == "Clothoid":
                segments = (self.clothoid(b, shape),)
                end_time = b.num(shape, "stopTime", None, nonneg=True)
                times = [segments[0].time, end_time]
            elif shape.tag == "ClothoidSpline":
                segs: list[M.ClothoidSegment] = []
                for seg in shape.all("Segment"):
                    segs.append(self.segment(b, seg, segs[-1].k1 if segs else 0.0))
                segments = tuple(segs)
                if not segments:
                    raise b.error(shape, "<ClothoidSpline> needs at least one <Segment>")
                end_time = b.num(shape, "timeEnd", None, nonneg=True)
                times = [sg.time for sg in segments] + [end_time]
            else:
                nurbs = self.nurbs(b, shape)
                times = [p.time for p in nurbs.points]
        finally:
            b.values = outer_values
        timing = None
        tr = inner.child("TimeReference")
        tm = tr.child("Timing") if tr is not None else None
        if tm is not None:
            timing = (
                b.enum(tm, "domainAbsoluteRelative", ("absolute", "relative")),
                b.num(tm, "scale", positive=True),
                b.num(tm, "offset"),
            )
            if any(t is None for t in times):
                what = {"Polyline": "<Vertex>", "Nurbs": "<ControlPoint>"}.get(shape.tag)
                raise b.error(
                    shape,
                    f"every {what} needs a time when the trajectory has <Timing>"
                    if what
                    else f"<{shape.tag}> needs its times (start and end) when the trajectory has <Timing>",
                )
            if any(y <= x for x, y in zip(times, times[1:])):  # type: ignore[operator]
                raise b.error(shape, f"the times of <{shape.tag}> must increase")
        return M.FollowTrajectoryAction(
            vertices,
            timing,
            b.num(inner, "initialDistanceOffset", 0.0),
            inner.line,
            segments=segments,
            end_time=end_time,
            nurbs=nurbs,
        )

    @staticmethod
    def vertices(b: Any, poly: Node) -> list[M.Vertex]:
        vertices = []
        for v in poly.all("Vertex"):
            t = b.raw(v, "time", None)
            vertices.append(M.Vertex(None if t is None else b.num(v, "time"), b.position(b.one(v, "Position"))))
        if len(vertices) < 2:
            raise b.error(poly, f"<Polyline> needs at least two <Vertex> (found {len(vertices)})")
        return vertices

    @staticmethod
    def clothoid(b: Any, node: Node) -> M.ClothoidSegment:
        k0, length = b.num(node, "curvature"), b.num(node, "length", positive=True)
        prime = b.num(node, "curvaturePrime", None)
        if prime is None:
            prime = b.num(node, "curvatureDot", 0.0)  # 1.0's name, read as the same rate per metre
        start = b.position(b.one(node, "Position"))
        return M.ClothoidSegment(
            start, k0, k0 + prime * length, length, 0.0, b.num(node, "startTime", None, nonneg=True)
        )

    @staticmethod
    def segment(b: Any, node: Node, previous: float) -> M.ClothoidSegment:
        """A ClothoidSpline segment. As the reference player reads it: its pre-standard
        ``curvStart``/``curvEnd`` spelling is the same; a missing start curvature is the previous
        segment's end (0 for the first), a missing end curvature the segment's start (an arc)."""
        spelt = [n for n in ("curvatureStart", "curvatureEnd") if n in node.attrs]
        old = [n for n in ("curvStart", "curvEnd") if n in node.attrs]
        if spelt and old:
            raise b.error(node, "<Segment> mixes curvatureStart/curvatureEnd with curvStart/curvEnd (write one form)")
        start, end = ("curvStart", "curvEnd") if old else ("curvatureStart", "curvatureEnd")
        k0 = b.num(node, start, previous)
        k1 = b.num(node, end, k0)
        ps = node.child("PositionStart")
        start = b.position(ps) if ps is not None else None
        h_offset = b.num(node, "hOffset", 0.0)
        if abs(h_offset) >= math.pi:
            raise b.error(node, f"bad value for hOffset in <Segment>: {h_offset:g} (expected within ]-pi, pi[)")
        time = b.num(node, "timeStart", None, nonneg=True)
        return M.ClothoidSegment(start, k0, k1, b.num(node, "length", positive=True), h_offset, time)

    @staticmethod
    def nurbs(b: Any, node: Node) -> M.Nurbs:
        order = b.int_(node, "order", minimum=2)
        points, weights = [], []
        for cp in node.all("ControlPoint"):
            t = b.raw(cp, "time", None)
            points.append(M.Vertex(None if t is None else b.num(cp, "time"), b.position(b.one(cp, "Position"))))
            weights.append(b.num(cp, "weight", 1.0, positive=True))
        knots = [b.num(k, "value") for k in node.all("Knot")]
        if len(points) < order:
            raise b.error(node, f"<Nurbs> of order {order} needs at least {order} <ControlPoint> (found {len(points)})")
        if len(knots) != len(points) + order:
            raise b.error(
                node,
                f"<Nurbs> needs {len(points) + order} <Knot> ({len(points)} control points + order {order}; "
                f"found {len(knots)})",
            )
        if any(y < x for x, y in zip(knots, knots[1:])) or knots[len(points)] <= knots[order - 1]:
            raise b.error(node, "the <Knot> values of <Nurbs> must not decrease and must span its curve")
        return M.Nurbs(order, tuple(points), tuple(weights), tuple(knots))

    def start(self, run: ActionRun, t: float) -> None:
        b, a = run.board, run.action
        xy, times = self.path(run)
        run.xy = xy
        run.cum = [0.0]
        for (x0, y0), (x1, y1) in zip(run.xy, run.xy[1:]):
            run.cum.append(run.cum[-1] + math.hypot(x1 - x0, y1 - y0))
        if a.timing is not None and times is not None:
            domain, scale, offset = a.timing
            base = 0.0 if domain == "absolute" else t
            run.times = [base + tt * scale + offset for tt in times]
        else:
            run.times = None
            run.v = b.states[run.actor].speed
            run.t0 = t
            run.s0 = a.initial_distance_offset
        if run.is_ego:
            # the ego's references: the path's offset at its s (and, timed, its s at the time)
            lead_in = None
            if run.times is not None and t < run.times[0]:
                cx = b.scenario.entities[run.actor].vehicle.center_x
                lead_in = (t, b.states[run.actor].s - cx)
            run.law = EgoPath(*to_lane_frame(b.driver.road_frame, run.xy), run.times, lead_in)
            b.driver.ego_trajectory(run.law)

    @staticmethod
    def path(run: ActionRun) -> tuple[list[tuple[float, float]], list[float] | None]:
        """The shape's points (the entity's reference point) and their times (None: no times)."""
        b, a = run.board, run.action
        me = b.states[run.actor]
        cx = b.scenario.entities[run.actor].vehicle.center_x
        start = (me.x - cx * math.cos(me.yaw), me.y - cx * math.sin(me.yaw), me.yaw)
        return trajectory_points(a, lambda p: b.driver.position_xy(p, b.states), start)

    @staticmethod
    def point(run: ActionRun, t: float) -> tuple[float, float, float, float, bool]:
        """(x, y, heading, speed, at the end) on the trajectory at time ``t``."""
        xy, cum = run.xy, run.cum
        if run.times is not None:
            times = run.times
            if t <= times[0]:
                i, u = 0, 0.0
            elif t >= times[-1]:
                i, u = len(times) - 2, 1.0
            else:
                i = min(bisect_right(times, t) - 1, len(times) - 2)
                u = (t - times[i]) / (times[i + 1] - times[i])
            seg = cum[i + 1] - cum[i]
            speed = seg / (times[i + 1] - times[i])
            end = t >= times[-1] - EPS
        else:
            s = min(run.s0 + run.v * (t - run.t0), cum[-1])
            i = min(max(bisect_right(cum, s) - 1, 0), len(cum) - 2) if s > 0 else 0
            seg = cum[i + 1] - cum[i]
            u = (s - cum[i]) / seg if seg > 0 else 1.0
            speed, end = run.v, s >= cum[-1] - EPS
        (x0, y0), (x1, y1) = xy[i], xy[i + 1]
        heading = math.atan2(y1 - y0, x1 - x0)
        return x0 + u * (x1 - x0), y0 + u * (y1 - y0), heading, speed, end

    def step(self, run: ActionRun, t: float) -> None:
        if run.is_ego:
            b = run.board
            e = b.states[run.actor]
            # the action ends when the ego's reference point (its box centre less center.x) has
            # passed the path's end, or a timed path's time is over
            cx = b.scenario.entities[run.actor].vehicle.center_x
            run.finished = run.law.done(t, e.s - cx)
            return
        x, y, heading, speed, end = self.point(run, t + run.board.h)
        # the path is the reference point's: SUMO places the box centre center.x ahead of it
        cx = run.board.scenario.entities[run.actor].vehicle.center_x
        run.board.driver.place(run.actor, x + cx * math.cos(heading), y + cx * math.sin(heading), heading, speed)
        if end:
            run.finished = True
            run.board.driver.release(run.actor)


#: a vehicle category's body when a TrafficDefinition names only the category (ego's choices:
#: (length, width, max speed) of a typical one; the standard gives none)
CATEGORY_BODIES = {
    "car": (4.5, 1.8, 55.0),
    "van": (5.2, 2.0, 45.0),
    "truck": (12.0, 2.55, 30.0),
    "bus": (12.0, 2.55, 30.0),
    "semitrailer": (16.5, 2.55, 30.0),
    "trailer": (8.0, 2.55, 30.0),
    "motorbike": (2.2, 0.8, 50.0),
    "bicycle": (1.8, 0.6, 12.0),
}


def _category_body(category: str, line: int) -> M.Vehicle:
    length, width, vmax = CATEGORY_BODIES[category]
    return M.Vehicle(f"traffic {category}", category, length, width, 1.5, 0.0, vmax, 3.0, 6.0, line)


class Traffic(ActionKind):
    """A TrafficAction (source, sink, swarm, stop): done at once, it starts (or stops) a traffic
    process that runs with the simulation (``ego/openscenario/traffic.py``)."""

    tag, within, model = "TrafficAction", ("GlobalAction",), M.TrafficAction
    contains = ("TrafficSourceAction", "TrafficSinkAction", "TrafficSwarmAction", "TrafficStopAction")
    parts = {
        "TrafficSourceAction": ("Position", "TrafficDefinition", "TrafficDistribution"),
        "TrafficSinkAction": ("Position", "TrafficDefinition", "TrafficDistribution"),
        "TrafficSwarmAction": (
            "CentralObject",
            "TrafficDefinition",
            "TrafficDistribution",
            "InitialSpeedRange",
            "DirectionOfTravelDistribution",
        ),
        "TrafficStopAction": (),
        "CentralObject": (),
        "InitialSpeedRange": (),
        "DirectionOfTravelDistribution": (),
        "TrafficDefinition": ("VehicleCategoryDistribution", "ControllerDistribution", "VehicleRoleDistribution"),
        "VehicleCategoryDistribution": ("VehicleCategoryDistributionEntry",),
        "VehicleCategoryDistributionEntry": (),
        "ControllerDistribution": ("ControllerDistributionEntry",),
        "ControllerDistributionEntry": ("Controller", "CatalogReference"),
        "VehicleRoleDistribution": ("VehicleRoleDistributionEntry",),
        "VehicleRoleDistributionEntry": (),
        "TrafficDistribution": ("TrafficDistributionEntry",),
        "TrafficDistributionEntry": ("EntityDistribution", "Properties"),
        "EntityDistribution": ("EntityDistributionEntry",),
        "EntityDistributionEntry": ("ScenarioObjectTemplate",),
        "ScenarioObjectTemplate": ("CatalogReference", "Vehicle", "ObjectController"),
    }
    domains, on_ego, is_global, in_init, section = (), True, True, "yes", "global"
    label = "`GlobalAction`/`TrafficAction`: `TrafficSourceAction`, `TrafficSinkAction`, `TrafficSwarmAction`, "
    label += "`TrafficStopAction` (1.2)"
    also = ("TrafficSourceAction", "TrafficSinkAction", "TrafficSwarmAction", "TrafficStopAction")
    note = (
        "SUMO vehicles driven by SUMO's drivers (the reference player has no sources or sinks): a source adds "
        "`rate` vehicles a second (the first at its start) on the lane nearest its `Position`, within `radius` "
        "along it, inserted at the highest speed SUMO's driver finds safe there up to `speed` (its top speed "
        "from then on); a sink removes, up to `rate` a second (every one without `rate`), the vehicles the "
        "file's traffic actions added whose centre comes within `radius` of its position (**deviation**: not "
        "the file's entities, which the storyboard refers to, nor ego's own background traffic); a swarm keeps "
        "`numberOfVehicles` in the ellipse around its `CentralObject` (`semiMajorAxis` along the object's "
        "heading, `semiMinorAxis` across) and outside `innerRadius`, on the lanes of the ego's road in its "
        "direction, up to `velocity` (or `InitialSpeedRange`'s middle) as a source's, removing the ones that "
        "leave it and adding new ones anywhere in it (at most 5 a step after the first fill); the vehicles: a "
        "`TrafficDefinition`'s categories by weight (ego's typical bodies: a car 4.5 m x 1.8 m...) or a "
        "`TrafficDistribution`'s (1.3) `ScenarioObjectTemplate`s by the product of the weights (a swarm without "
        "either, as the reference player reads it: cars), drawn and placed seeded by the run's seed; seen by "
        "the surround sensor and the collision check as any car; `TrafficStopAction` (1.2) ends the traffic "
        "action of its `trafficName`; in `Init` or an `Action`"
    )

    def build(self, b: Any, node: Node) -> M.TrafficAction:
        name = b.str_(node, "trafficName", "")
        inner = b.one(node)
        kind = {
            "TrafficSourceAction": "source",
            "TrafficSinkAction": "sink",
            "TrafficSwarmAction": "swarm",
            "TrafficStopAction": "stop",
        }[inner.tag]
        if kind == "stop":
            if not name:
                raise b.error(node, "<TrafficStopAction> needs the TrafficAction's trafficName")
            return M.TrafficAction("stop", name, line=node.line)
        bodies = self.bodies(b, inner)
        if kind == "swarm":
            central = b.entity_ref(b.one(inner, "CentralObject"))
            speed = b.num(inner, "velocity", None, nonneg=True)
            rng = inner.child("InitialSpeedRange")
            if speed is None and rng is not None:
                speed = 0.5 * (b.num(rng, "lowerLimit") + b.num(rng, "upperLimit"))
            inner_r = b.num(inner, "innerRadius", nonneg=True)
            major, minor = b.num(inner, "semiMajorAxis", positive=True), b.num(inner, "semiMinorAxis", positive=True)
            count = b.int_(inner, "numberOfVehicles", minimum=0)
            return M.TrafficAction(
                kind, name, None, 0.0, math.inf, speed, bodies, central, inner_r, major, minor, count, node.line
            )
        position = b.position(b.one(inner, "Position"))
        radius = b.num(inner, "radius", nonneg=True)
        if kind == "source":
            rate = b.num(inner, "rate", positive=True)
            speed = b.num(inner, "speed", None, nonneg=True)
            if speed is None:
                speed = b.num(inner, "velocity", None, nonneg=True)
        else:
            rate = b.num(inner, "rate", positive=True) if "rate" in inner.attrs else math.inf
            speed = None
        return M.TrafficAction(kind, name, position, radius, rate, speed, bodies, line=node.line)

    @staticmethod
    def bodies(b: Any, inner: Node) -> tuple[tuple[float, M.Vehicle], ...]:
        out: list[tuple[float, M.Vehicle]] = []
        td = inner.child("TrafficDefinition")
        if td is not None:
            vcd = b.one(td, "VehicleCategoryDistribution")
            for e in vcd.all("VehicleCategoryDistributionEntry"):
                cat = b.enum(e, "category", tuple(CATEGORY_BODIES))
                out.append((b.num(e, "weight", nonneg=True), _category_body(cat, e.line)))
        dist = inner.child("TrafficDistribution")
        if dist is not None:
            for te in dist.all("TrafficDistributionEntry"):
                w0 = b.num(te, "weight", nonneg=True)
                for ee in b.one(te, "EntityDistribution").all("EntityDistributionEntry"):
                    tmpl = b.one(ee, "ScenarioObjectTemplate")
                    obj = next((c for c in tmpl.children if c.tag in ("CatalogReference", "Vehicle")), None)
                    if obj is None:
                        raise b.error(tmpl, "<ScenarioObjectTemplate> needs a <Vehicle> or <CatalogReference>")
                    out.append((w0 * b.num(ee, "weight", nonneg=True), b.body(obj, "traffic")))
        if td is None and dist is None:
            if inner.tag == "TrafficSourceAction":
                raise b.error(inner, f"<{inner.tag}> needs a <TrafficDefinition> or a <TrafficDistribution>")
            out.append((1.0, _category_body("car", inner.line)))  # a sink's are unused
        if not out or sum(w for w, _ in out) <= 0.0:
            raise b.error(inner, f"<{inner.tag}>'s vehicles have no positive weight")
        return tuple(out)

    def apply(self, board: Storyboard, action: M.TrafficAction) -> None:
        board.driver.traffic_action(action)
        board.log("action", f"t = {board.t:.2f} s: traffic {action.kind} {action.name!r}".replace(" ''", ""))


#: a ParameterAction's and a VariableAction's own elements
VALUE_PARTS: dict[str, tuple[str, ...]] = {
    "SetAction": (),
    "ModifyAction": ("Rule",),
    "Rule": ("AddValue", "MultiplyByValue"),
    "AddValue": (),
    "MultiplyByValue": (),
}


def _value_action(b: Any, node: Node, kind: str) -> M.ParameterAction:
    """A ParameterAction or VariableAction: set, add to or multiply a declared value."""
    name = b.str_(node, "parameterRef" if kind == "parameter" else "variableRef")
    if kind == "parameter":
        declared = {k: (type(v), v) for k, v in b.values.items()}
    else:
        declared = {k: (type(p.value), p.value) for k, p in b.variables.items()}
    if name not in declared:
        raise b.error(node, f"{kind} {name!r} is not declared (declared: {', '.join(declared) or 'none'})")
    initial = declared[name][1]
    op_node = b.one(node)
    if op_node.tag == "SetAction":
        value: object = b.str_(op_node, "value")
        if isinstance(initial, (int, float)) and not isinstance(initial, bool):
            value = b.num(op_node, "value")
        return M.ParameterAction(kind, name, "set", value, initial, node.line)
    rule = b.one(b.one(op_node, "Rule"))
    if isinstance(initial, bool) or not isinstance(initial, (int, float)):
        raise b.error(rule, f"<{rule.tag}> needs a numeric {kind} ({name!r} is {initial!r})")
    op = "add" if rule.tag == "AddValue" else "multiply"
    return M.ParameterAction(kind, name, op, b.num(rule, "value"), initial, node.line)


class Parameter(ActionKind):
    """A GlobalAction's ParameterAction: done once when its event starts, whoever the actors."""

    tag, within, model = "ParameterAction", ("GlobalAction",), M.ParameterAction
    domains, on_ego, is_global, section = (), True, True, "global"
    init_hint = "declare the value it sets"
    contains, parts = ("SetAction", "ModifyAction"), VALUE_PARTS
    label = "`GlobalAction`/`ParameterAction`, `VariableAction` (1.2), `VariableDeclarations`, `VariableCondition`"
    also = ("VariableAction", "VariableDeclarations", "VariableCondition")
    note = (
        "in an `Action` (not in `Init`: declare the value instead), done once when its event starts, whatever the "
        "maneuver group's actors: `SetAction`, `ModifyAction` with `AddValue` or `MultiplyByValue` (a numeric "
        "parameter or variable only); what changes is what `ParameterCondition`s and `VariableCondition`s see "
        "from the next storyboard step on (the standard's parameters are read before the run: every attribute "
        "keeps the value it was read with); a value is one per name (a story's parameter of the same name as the "
        "file's shares it)"
    )

    def build(self, b: Any, node: Node) -> M.ParameterAction:
        return _value_action(b, node, "parameter")

    def apply(self, board: Storyboard, action: M.ParameterAction) -> None:
        board.assign(action)


class Variable(ActionKind):
    """A GlobalAction's VariableAction (1.2): as a ParameterAction, on a declared variable
    (documented in :class:`Parameter`'s row)."""

    tag, within, model = "VariableAction", ("GlobalAction",), M.ParameterAction
    domains, on_ego, is_global, section = (), True, True, "global"
    init_hint = "declare the value it sets"
    contains, parts = ("SetAction", "ModifyAction"), VALUE_PARTS

    def build(self, b: Any, node: Node) -> M.ParameterAction:
        return _value_action(b, node, "variable")

    def apply(self, board: Storyboard, action: M.ParameterAction) -> None:
        board.assign(action)


class Entity(ActionKind):
    """A GlobalAction's EntityAction: AddEntityAction, DeleteEntityAction."""

    tag, within, model = "EntityAction", ("GlobalAction",), M.EntityAction
    contains = ("AddEntityAction", "DeleteEntityAction")
    init_hint = "an entity's TeleportAction in Init places it; one without is not in the simulation"
    parts = {"AddEntityAction": ("Position",), "DeleteEntityAction": ()}
    domains, on_ego, is_global, section = (), True, True, "global"
    label = "`GlobalAction`/`EntityAction`: `AddEntityAction`, `DeleteEntityAction`"
    also = ("AddEntityAction", "DeleteEntityAction")
    note = (
        "in an `Action` (not in `Init`, where a `TeleportAction` places an entity), done at once: "
        "`AddEntityAction` puts an entity that is not in the simulation (one without a start in `Init`, or "
        "deleted) at its `Position`, at its Init speed (0 without one), as a `TeleportAction` on it does; an "
        "entity already there is moved there; `DeleteEntityAction` takes it out of SUMO: the actions on it end, "
        "conditions on it or relative to it no longer hold, until it is added again; the ego can be neither "
        "added nor deleted (refused before the run with the action's line)"
    )

    def build(self, b: Any, node: Node) -> M.EntityAction:
        name = b.entity_ref(node)
        inner = b.one(node)
        if inner.tag == "AddEntityAction":
            return M.EntityAction(name, b.position(b.one(inner, "Position")), node.line)
        return M.EntityAction(name, None, node.line)

    def apply(self, board: Storyboard, action: M.EntityAction) -> None:
        name = action.entity
        if action.position is None:
            if name not in board.absent:
                board.log("action", f"t = {board.t:.2f} s: {name} leaves the simulation (DeleteEntityAction)")
                board.remove(name)
            return
        drv = board.driver
        x, y, h = drv.position_xy(action.position, board.states)
        drv.teleport(name, x, y, h)


class Environment(ActionKind):
    tag, within, model, in_init = "EnvironmentAction", ("GlobalAction",), M.EnvironmentAction, "yes"
    domains, on_ego, is_global, section = (), True, True, "global"
    contains = ("Environment", "CatalogReference")
    parts = {
        "Environment": ("ParameterDeclarations", "TimeOfDay", "Weather", "RoadCondition"),
        "TimeOfDay": (),
        "Weather": ("Sun", "Fog", "Precipitation", "Wind"),
        "Sun": (),
        "Fog": (),
        "Precipitation": (),
        "Wind": (),
        "RoadCondition": ("Properties",),
    }
    label = "`GlobalAction`/`EnvironmentAction` (in `Init` or an `Action`), `EnvironmentCatalog`"
    note = (
        "done at once, inline or from an `EnvironmentCatalog` (`CatalogReference`, with `ParameterAssignments`): "
        "`TimeOfDay` and `Weather` (sun, fog, precipitation, wind) change nothing in ego's dynamics or its sensor; "
        "a `RoadCondition`'s `frictionScaleFactor` k (> 0) scales the road's friction from then on: the ego's "
        "tyres (report 000's plant: the rear friction circle `mu_max` 0.7 and the tyres' peak factor `Dy` 0.7 "
        "become 0.7 k, and with ABS the brake and drive command limit, the friction circle, with them; a full "
        "stop from v then takes v^2 / (2 (0.7 k + f) g), f = 0.01 the rolling resistance, "
        "`test_xosc_environment.py`), and SUMO's drivers: every SUMO vehicle's (and vehicle type's) `decel` and "
        "`emergencyDecel` become k times their own (the file's `maxDeceleration`, ego's traffic's), so SUMO's "
        "car-following brakes no harder than the road carries; a scripted speed change keeps the rate the file "
        "gives it (the storyboard rules its entities). A later `RoadCondition` scales from the own values "
        "again (not compounded). A plant without a friction (the FMU or report 002's) refuses a scale other "
        "than 1 in one line"
    )

    def build(self, b: Any, env_action: Node) -> M.EnvironmentAction:
        """Checked (every attribute resolves); a RoadCondition's friction scale kept."""
        ref = env_action.child("CatalogReference")
        if ref is not None:
            env, b = b.entry_builder(ref, "Environment")  # the entry's parameters, the reference's assignments
        else:
            env = b.one(env_action, "Environment")
        outer = b.values
        if ref is None:
            b.values = b.scoped(env)
        friction = None
        try:
            stack = [env]
            while stack:
                n = stack.pop()
                for attr in n.attrs:
                    b.raw(n, attr)
                stack.extend(c for c in n.children if c.tag != "ParameterDeclarations")
            rc = env.child("RoadCondition")
            if rc is not None:
                friction = b.num(rc, "frictionScaleFactor", positive=True)
        finally:
            b.values = outer
        return M.EnvironmentAction(env_action.line, friction)

    def apply(self, board: Storyboard, action: M.EnvironmentAction) -> None:
        if action.friction is not None:
            board.driver.friction(action.friction)
            board.log("action", f"t = {board.t:.2f} s: road friction scaled by {action.friction:g}")


for _kind in (
    Teleport,
    Controller,
    ActivateController,
    Appearance,
    Visibility,
    Speed,
    LaneChange,
    LaneOffset,
    LongitudinalDistance,
    LateralDistance,
    SpeedProfile,
    Synchronize,
    AssignRoute,
    AcquirePosition,
    FollowTrajectory,
    Parameter,
    Variable,
    Entity,
    Environment,
    Traffic,
):
    register(_kind())
