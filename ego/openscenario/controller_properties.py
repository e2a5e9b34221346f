"""A file's controller on the ego as ego's parameters: the one table saying which controller
``Property`` means which ego parameter (the rest are read and not used, each with its reason).

The ego is driven by ego's controller under test (``-c``); the controller the file assigns
the ego (its ``ObjectController``) says what the file expects of that driver. Where one of
its properties means what an ego parameter means, its value becomes that parameter's
default for the run (``--set`` still rules): :data:`MAPPED`. Every other property of the
controllers the public files use is listed in :data:`NOT_USED` with the reason.
docs/openscenario.md's table is generated from these two (``python -m ego.docs results
--page openscenario``; ``tests/test_xosc_controller_properties.py`` checks it).

The properties apply when the controller drives the ego from the start: its
``ObjectController`` assigns it, and the file activates its longitudinal domain in Init or
activates it nowhere (ego's controller drives the ego throughout). A controller activated
only by the storyboard, or assigned by an ``AssignControllerAction``, changes nothing: ego
sets its parameters once, before the run.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

from ego.openscenario import model as M
from ego.openscenario.xmltree import ScenarioFileError

#: the reference player's controller kinds whose longitudinal law is its ACC (ControllerACC;
#: ControllerALKS runs the same ACC): the set speed and time gap mean the same in both
ACC = ("ACCController", "ALKSController")
#: the reference player's UN R157 controller (ControllerALKS_R157SM)
R157 = ("ALKS_R157SM_Controller",)


@dataclass(frozen=True)
class PropertyMap:
    """One controller ``Property`` that means an ego parameter.

    ``controllers``: the controller kinds it applies to (the controller's name, or its
    ``esminiController`` property, as the reference player picks the kind); ``when``: other
    properties it applies with (the reference player reads it only then); ``scale``: the ego
    value is the property's value times this (units); the allowed range is the ego
    parameter's own, from ``floor`` up when the parameter's lowest value is a sentinel (a
    cruise_speed of -1 holds ego_speed: no set speed)."""

    name: str
    controllers: tuple[str, ...]
    param: str
    unit: str
    meaning: str
    when: tuple[tuple[str, str], ...] = ()
    scale: float = 1.0
    floor: float | None = None


@dataclass(frozen=True)
class NotUsed:
    """A controller ``Property`` ego reads and does not use, and why."""

    name: str
    controllers: tuple[str, ...]
    reason: str


MAPPED: tuple[PropertyMap, ...] = (
    PropertyMap(
        "setSpeed",
        ACC,
        "cruise_speed",
        "m/s",
        "the speed the ACC holds without a leader (ControllerACC: m/s, used in `override` mode; in `additive` mode, "
        "its default, the ego's speed at activation replaces it)",
        when=(("mode", "override"),),
        floor=0.0,
    ),
    PropertyMap(
        "timeGap",
        ACC,
        "follow_headway",
        "s",
        "the time gap the ACC keeps to the car ahead (ControllerACC: follow distance 3 m + timeGap x speed; ego's: "
        "follow_gap + follow_headway x the leader's speed, once its front TTC trigger has fired)",
    ),
    PropertyMap(
        "aebTTC",
        R157,
        "aeb_ttc",
        "s",
        "the front time-to-collision below which the AEB brakes fully (ControllerALKS_R157SM reads it for its "
        "`ReferenceDriver` model only)",
        when=(("model", "ReferenceDriver"),),
    ),
)

NOT_USED: tuple[NotUsed, ...] = (
    NotUsed(
        "mode",
        ACC + R157,
        "how the reference player combines the controller with other actions; ego's "
        "controller always drives the ego, the storyboard's actions on it moving its references",
    ),
    NotUsed(
        "lateralDist",
        ACC,
        "the ACC's lateral window for leaders; ego's surround sensor picks the front object by the ego's lane",
    ),
    NotUsed("virtual", ACC, "the reference player's calculate-only mode; ego's controller always drives"),
    NotUsed(
        "model",
        R157,
        "which R157 model the reference player runs (Regulation, ReferenceDriver, RSS, FSM); "
        "ego's is its manoeuvre and AEB",
    ),
    NotUsed(
        "cruise",
        R157,
        "whether the reference player's R157 model runs its ACC; ego's cruise holds its speed "
        "reference and follows once triggered",
    ),
    NotUsed("fullStop", R157, "stop fully, or brake until safe; ego's in-lane braking brakes to the leader's speed"),
    NotUsed(
        "cutInPerceptionDelayMode",
        R157,
        "the reference driver's perception delay (distance or time); ego's controller has none",
    ),
    NotUsed("pedestrianRiskEvaluationTime", R157, "the reference driver's reaction time to a pedestrian; none in ego"),
    NotUsed(
        "lateralTrigDistance",
        R157,
        "the reference driver's cut-in trigger; ego triggers on the front TTC (ttc_threshold)",
    ),
    NotUsed("overlapTolerance", R157, "the reference driver's overlap check; ego's sensor finds the front object"),
    NotUsed("alwaysTrigOnScenario", R157, "the reference driver acts outside the critical zone; no such mode in ego"),
    NotUsed("logLevel", R157, "the reference player's logging"),
    NotUsed("logging", ("ECE_ALKS_RefDriverController",), "the reference player's logging"),
    NotUsed(
        "sloppiness",
        ("SloppyDriverController",),
        "a driver model's random speed and offset errors; ego's controller under test is what is tested",
    ),
    NotUsed(
        "speedFactor",
        ("InteractiveController", "OffroadFollower"),
        "a keyboard driver's or follower's speed scale; no such input in ego",
    ),
    NotUsed("steeringRate", ("InteractiveController", "OffroadFollower"), "a keyboard driver's steering rate"),
    NotUsed(
        "headstartTime",
        ("ExternalController", "FollowGhostController"),
        "the ghost's head start: ego's ego follows no ghost",
    ),
    NotUsed("useGhost", ("ExternalController",), "the ghost's head start: ego's ego follows no ghost"),
    NotUsed(
        "laneChangeTime",
        ("FollowRouteController",),
        "a route follower's lane-change time: the ego changes "
        "lanes when the storyboard or its manoeuvre says, at its controller's pace",
    ),
    NotUsed("targetDistance", ("OffroadFollower",), "an off-road follower's distance to the entity it follows"),
    NotUsed(
        "esminiController",
        ("*",),
        "names the reference player's controller kind (read to pick this table's rows and ghosts)",
    ),
)


def controller_kind(control: M.ObjectControl) -> str:
    """The reference player's kind of a controller: its ``esminiController`` property, else
    its name (ControllerCatalog entries name the kind; inline ones are named after it)."""
    return control.properties.get("esminiController") or control.name


@dataclass(frozen=True)
class Applied:
    """A mapped property of the ego's controller: its value as the ego parameter's."""

    row: PropertyMap
    value: float
    line: int


@dataclass(frozen=True)
class EgoController:
    """What the ego's controller's properties do in this run."""

    control: M.ObjectControl | None
    applied: tuple[Applied, ...] = ()
    #: (property, why not used) for every other property
    unused: tuple[tuple[str, str], ...] = ()
    #: why nothing applies (a controller activated only by the storyboard), or ""
    inactive: str = ""


def allowed(cfg_cls: type, row: PropertyMap) -> tuple[float, float]:
    """The range a mapped property's value (in the ego parameter's unit) may take."""
    f = next(f for f in dataclasses.fields(cfg_cls) if f.name == row.param)
    lo, hi = f.metadata.get("min"), f.metadata.get("max")
    lo = row.floor if row.floor is not None else lo
    return (-math.inf if lo is None else lo), (math.inf if hi is None else hi)


def ego_controller(model: M.Scenario, ego: str, cfg_cls: type, activated_later: int = 0) -> EgoController:
    """The ego's controller in ``model`` and its properties as ego parameters of ``cfg_cls``
    (the file's configuration class). ``activated_later``: the line of a storyboard action
    activating or assigning the ego's controller (0: none). A mapped value outside the ego
    parameter's range is a :class:`ScenarioFileError` at the property's line."""
    control = model.controllers.get(ego)
    if control is None:
        return EgoController(None)
    if ego not in model.init_activations and activated_later:
        why = f"activated only by the storyboard (line {activated_later}): ego sets its parameters before the run"
        return EgoController(control, (), tuple((p, why) for p in control.properties), why)
    kind = controller_kind(control)
    props = control.properties
    applied, unused = [], []
    for name, text in props.items():
        row = next(
            (r for r in MAPPED if r.name == name and kind in r.controllers),
            None,
        )
        if row is None:
            why = next(
                (n.reason for n in NOT_USED if n.name == name and (kind in n.controllers or "*" in n.controllers)),
                f"no ego parameter means it for a {kind}",
            )
            unused.append((name, why))
            continue
        missing = [f"{k}={v}" for k, v in row.when if props.get(k, "") != v]
        if missing:
            unused.append((name, f"a {kind} reads it only with {', '.join(missing)}"))
            continue
        line = control.lines[name]
        try:
            value = float(text) * row.scale
        except ValueError:
            raise ScenarioFileError(
                control.file,
                line,
                f"bad value for controller property {name!r}: {text!r} (expected a number, "
                f"{row.unit}: ego's {row.param})",
            ) from None
        lo, hi = allowed(cfg_cls, row)
        if not (lo <= value <= hi) or math.isnan(value):
            raise ScenarioFileError(
                control.file,
                line,
                f"controller property {name!r} = {text} is outside ego's {row.param} range [{lo:g}, {hi:g}] {row.unit}",
            )
        applied.append(Applied(row, value, line))
    return EgoController(control, tuple(applied), tuple(unused))


def applied_event(info: EgoController, config: object, path: str) -> str:
    """The run's event line: which properties became which ego parameters (and which
    ``--set`` overrode), and which were read and not used."""
    c = info.control
    assert c is not None
    where = f"{Path(path).name}:{c.line}" + ("" if c.file == Path(path) else f", its entry in {c.file.name}")
    head = f"the ego's controller {c.name!r} ({where})"
    if info.inactive:
        return f"{head}: its properties are not used ({info.inactive})"
    parts = []
    for a in info.applied:
        now = getattr(config, a.row.param)
        if now == a.value:
            parts.append(f"{a.row.name} {a.value:g} -> {a.row.param}")
        else:
            parts.append(f"{a.row.name} {a.value:g} -> {a.row.param}, overridden by --set ({now:g})")
    said = "; ".join(parts) if parts else "no property maps onto an ego parameter"
    rest = f"; read, not used: {', '.join(n for n, _ in info.unused)}" if info.unused else ""
    return f"{head}: {said}{rest} (docs/openscenario.md)"


def markdown_table() -> str:
    """docs/openscenario.md's table of controller properties."""
    rows = [
        "| property | controller kinds | ego parameter | unit | applies | meaning / reason |",
        "|---|---|---|---|---|---|",
    ]
    for r in MAPPED:
        when = ", ".join(f"`{k}={v}`" for k, v in r.when) or "always"
        scale = "" if r.scale == 1.0 else f" (x {r.scale:g})"
        rows.append(
            f"| `{r.name}` | {', '.join(r.controllers)} | `{r.param}`{scale} | {r.unit} | {when} | {r.meaning} |"
        )
    for n in NOT_USED:
        kinds = "any" if n.controllers == ("*",) else ", ".join(n.controllers)
        rows.append(f"| `{n.name}` | {kinds} | read, not used | | | {n.reason} |")
    return "\n".join(rows)
