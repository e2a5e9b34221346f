"""Read an OpenSCENARIO XML file into :mod:`ego.openscenario.model`, refusing anything outside
ego's subset before anything runs.

Every refusal is one line ``FILE:LINE: what`` (:class:`ScenarioFileError`); an element
outside the subset reads ``FILE:LINE: <Element> is not supported by ego (see
docs/openscenario.md)``.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping
from dataclasses import replace
from functools import lru_cache
from pathlib import Path
from typing import Any

from ego.checks import resolved
from ego.openscenario import actions as _actions  # noqa: F401 - registers the actions
from ego.openscenario import conditions as _condition_kinds  # noqa: F401 - registers the conditions
from ego.openscenario import files, v09
from ego.openscenario import model as M
from ego.openscenario import structure as _structure  # noqa: F401 - declares the structural elements
from ego.openscenario.dynamics import DYNAMICS_LIMITS, MAX_SECONDS
from ego.openscenario.expressions import ExpressionError, resolve
from ego.openscenario.registry import ACTIONS, CONDITIONS, action_of, allowed, init_kinds
from ego.openscenario.xmltree import DOCS, Node, ScenarioFileError, parse_file

#: the catalog element (in CatalogLocations) each catalog entry kind is looked for in
CATALOG_OF = {
    "Vehicle": "VehicleCatalog",
    "Pedestrian": "PedestrianCatalog",
    "MiscObject": "MiscObjectCatalog",
    "Controller": "ControllerCatalog",
    "Maneuver": "ManeuverCatalog",
    "Environment": "EnvironmentCatalog",
    "Route": "RouteCatalog",
}
PEDESTRIAN_CATEGORIES = ("pedestrian", "wheelchair", "animal")
MISC_CATEGORIES = (
    "none",
    "obstacle",
    "pole",
    "tree",
    "vegetation",
    "barrier",
    "building",
    "parkingSpace",
    "patch",
    "railing",
    "trafficIsland",
    "crosswalk",
    "streetLamp",
    "gantry",
    "soundBarrier",
    "wind",
    "roadMark",
)

#: a vehicle's Performance limits where the file leaves one out, as the reference player (esmini)
#: fills them in (its Vehicle's defaults: 100 m/s, 10 m/s^2, 10 m/s^2)
PERFORMANCE_DEFAULTS = {"maxSpeed": 100.0, "maxAcceleration": 10.0, "maxDeceleration": 10.0}
VEHICLE_CATEGORIES = ("car", "van", "truck", "trailer", "semitrailer", "bus", "motorbike", "bicycle")
#: SUMO's limits for a pedestrian's or misc object's body (it is moved only by the storyboard)
STANDING_MAX_SPEED, STANDING_ACCEL = 30.0, 10.0


def unsupported(path, node: Node) -> ScenarioFileError:
    return ScenarioFileError(path, node.line, f"<{node.tag}> is not supported by ego (see {DOCS})")


def _check_tree(path, node: Node) -> None:
    """Refuse the first element outside the subset (depth first, in file order)."""
    _check_against(path, node, allowed())


def _check_against(path, node: Node, children: dict[str, frozenset[str]]) -> None:
    kids = children.get(node.tag)
    if kids is None:
        raise unsupported(path, node)
    for c in node.children:
        if c.tag not in kids:
            raise unsupported(path, c)
        _check_against(path, c, children)


def elements(root: Node) -> list[tuple[str, int, bool]]:
    """Every element of the file: (tag, line, supported), in file order (``ego list``)."""
    out = []
    children = allowed()

    def walk(node: Node, within: frozenset[str] | None) -> None:
        ok = (within is None or node.tag in within) and node.tag in children
        out.append((node.tag, node.line, ok))
        for c in node.children:
            walk(c, children.get(node.tag, frozenset()) if ok else frozenset())

    walk(root, None)
    return out


@lru_cache(maxsize=32)
def _read(path: str, mtime: float, size: int, lenient: bool) -> Node:
    return _as_10(path, parse_file(path), lenient)


def _as_10(path: str | os.PathLike, root: Node, lenient: bool = False) -> Node:
    """The file's tree as ego reads it: an OpenSCENARIO 0.9 file mapped onto 1.0
    (:mod:`ego.openscenario.v09`), each element at its line of the 0.9 file."""
    return v09.migrate(path, root, lenient) if v09.is_09(root) else root


def read_tree(path: str | os.PathLike, lenient: bool = False) -> Node:
    """The parsed file (cached by path, mtime and size: sweeps resolve a file many times);
    ``lenient``: a 0.9 element the mapping refuses stays in the tree as it is (``ego list``)."""
    p = Path(path)
    try:
        st = p.stat()
    except OSError:
        return _as_10(p, parse_file(p), lenient)  # parse_file names the problem
    return _read(str(resolved(p, "scenario file")), st.st_mtime, st.st_size, lenient)


TYPES = ("double", "integer", "unsignedInt", "unsignedShort", "int", "string", "boolean", "dateTime")


#: the value ranges of OpenSCENARIO's integer parameter types (XML Schema's)
INT_RANGES = {
    "int": (-(2**31), 2**31 - 1),
    "integer": (-(2**31), 2**31 - 1),
    "unsignedInt": (0, 2**32 - 1),
    "unsignedShort": (0, 65535),
}


def convert(kind: str, raw: object, what: str) -> object:
    """``raw`` as a value of OpenSCENARIO parameter type ``kind`` (ValueError naming ``what``)."""
    if kind == "double":
        try:
            v = float(raw)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            raise ValueError(f"bad value for {what}: {raw!r} (expected a number)") from None
        if not math.isfinite(v):
            raise ValueError(f"bad value for {what}: {raw!r} (expected a finite number)")
        return v
    if kind in ("integer", "int", "unsignedInt", "unsignedShort"):
        try:
            f = float(raw)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            raise ValueError(f"bad value for {what}: {raw!r} (expected an integer)") from None
        lo, hi = INT_RANGES[kind]
        shown = repr(raw) if len(str(raw)) <= 40 else f"{str(raw)[:20]!r}... ({len(str(raw))} characters)"
        if not math.isfinite(f) or f != int(f) or (kind.startswith("unsigned") and f < 0):
            raise ValueError(
                f"bad value for {what}: {shown} (expected {'an' if kind[0] == 'i' else 'an unsigned'} integer)"
            )
        if not lo <= f <= hi:
            raise ValueError(f"bad value for {what}: {shown} (expected an {kind}: a whole number from {lo} to {hi})")
        return int(f)
    if kind == "boolean":
        if isinstance(raw, bool):
            return raw
        text = str(raw).strip().lower()
        if text in ("true", "1"):
            return True
        if text in ("false", "0"):
            return False
        raise ValueError(f"bad value for {what}: {raw!r} (expected true or false)")
    return str(raw)


def declared_parameters(path: str | os.PathLike) -> dict[str, M.Parameter]:
    """The file's ParameterDeclarations (name -> Parameter), checked."""
    root = read_tree(path)
    _check_root(path, root)
    return _declarations(path, root.child("ParameterDeclarations"), {})


def header_description(path: str | os.PathLike) -> str:
    """The file's FileHeader description ("" without one)."""
    header = read_tree(path).child("FileHeader")
    return header.attrs.get("description", "") if header is not None else ""


def _check_root(path, root: Node) -> None:
    """An OpenSCENARIO file of a version ego reads (checked before its elements: a file of
    another version is refused for its version, not for its first element of another schema),
    every element in ego's subset (a 0.9 file is read as 1.0 by :func:`read_tree`)."""
    if root.tag != "OpenSCENARIO":
        raise ScenarioFileError(
            path, root.line, f"<{root.tag}> is not an OpenSCENARIO file (expected <OpenSCENARIO> as the root element)"
        )
    _version(path, root)
    _check_tree(path, root)


def turned_message(what: str) -> str:
    """The refusal of an entity turned against its lane's direction where ego cannot take it."""
    return (
        f"an <Orientation> turning the entity against its lane's direction ({what}) is not supported by ego: "
        f"SUMO drives every lane its own way; ego drives a car against its lane only from an Init "
        f"<LanePosition> on the ego's road (see {DOCS})"
    )


def _check_turned(path, stories, init_runs) -> None:
    """An entity turned against its lane is an Init start only (a car ego drives itself along
    its lane the other way); anywhere else it is refused with the Orientation's line."""
    for x in M.walk((stories, init_runs)):
        if isinstance(x, M.LanePosition) and x.turned:
            raise ScenarioFileError(path, x.turned, turned_message("outside <Init>"))


def _trajectory_start(actions) -> M.TeleportAction | None:
    """A TeleportAction to the start of the first trajectory among an entity's running Init
    actions (its first vertex or control point, a clothoid's start position), if it has one."""
    for a in actions:
        start = getattr(a, "start_position", None)
        if start is not None:
            return M.TeleportAction(start, a.line)
    return None


def _version(path, root: Node) -> tuple[int, int]:
    """(revMajor, revMinor) of the file's FileHeader: 1.0 to 1.3 (a 0.9 file is read as 1.0)."""
    header = root.child("FileHeader")
    if header is None:
        raise ScenarioFileError(path, root.line, "<OpenSCENARIO> needs a <FileHeader>")
    try:
        version = (_rev(header.attrs.get("revMajor", "")), _rev(header.attrs.get("revMinor", "")))
    except ValueError:
        raise ScenarioFileError(path, header.line, "<FileHeader> needs integer revMajor and revMinor") from None
    if version[0] != 1 or not 0 <= version[1] <= 3:
        raise ScenarioFileError(
            path,
            header.line,
            f"OpenSCENARIO {version[0]}.{version[1]} is not supported by ego (0.9 and 1.0 to 1.3; see {DOCS})",
        )
    return version


def _declarations(
    path, node: Node | None, outer: Mapping[str, object], overrides: Mapping[str, object] | None = None
) -> dict[str, M.Parameter]:
    """The declarations in order, each value resolved with the ones before it; a name in
    ``overrides`` takes that value instead (so a later ``$ref`` to it sees the override)."""
    out: dict[str, M.Parameter] = {}
    if node is None:
        return out
    values = dict(outer)
    overrides = overrides or {}
    decls = node.all("ParameterDeclaration")
    for d in decls:
        name = d.attrs.get("name")
        kind = d.attrs.get("parameterType")
        if not name:
            raise ScenarioFileError(path, d.line, "<ParameterDeclaration> needs attribute name")
        _check_declared(path, d, name, kind, "parameter", out, last_wins=True)
        if "value" not in d.attrs:
            raise ScenarioFileError(path, d.line, f"parameter {name!r} needs attribute value")
        raw = d.attrs["value"]
        try:
            raw = overrides[name] if name in overrides else resolve(raw, values)
            value = convert(kind, raw, f"parameter {name!r}")
        except (ExpressionError, ValueError) as exc:
            raise ScenarioFileError(path, d.line, str(exc)) from None
        out[name] = M.Parameter(name, kind, value, d.line)
        values[name] = value
    # value constraints (1.2) after every declaration: a constraint may name a later parameter
    for name, d in {d.attrs["name"]: d for d in decls}.items():  # a name declared twice: its last
        groups = tuple(_constraint_group(path, g, values) for g in d.all("ConstraintGroup"))
        if groups:
            out[name] = replace(out[name], constraints=groups)
            _check_constraints(path, out[name], d.line)
    return out


def _check_declared(
    path, d: Node, name: str, kind: str | None, what: str, out: Mapping[str, M.Parameter], last_wins: bool = False
) -> None:
    """A parameter's or variable's (``what``) declaration: a known type, declared once (a
    parameter declared twice in one scope: the last declaration holds, with a warning, as the
    reference player reads it - its declarations stack, the latest found first)."""
    if kind not in TYPES:
        raise ScenarioFileError(
            path, d.line, f"bad {what}Type {kind!r} of {what} {name!r} (allowed: {', '.join(TYPES)})"
        )
    if name in out:
        twice = f"{what} {name!r} is declared twice (first on line {out[name].line})"
        if not last_wins:
            raise ScenarioFileError(path, d.line, twice)
        files.warn(f"{path}:{d.line}: {twice}: this last declaration holds, as the reference player reads it")


def _assigned_name(a: Node) -> str:
    """A ParameterAssignment's parameterRef: the parameter's name (a leading ``$``, as the
    reference player's files write it, is the same name)."""
    ref = a.attrs.get("parameterRef", "")
    if not ref:
        raise ScenarioFileError("", a.line, "<ParameterAssignment> needs attribute parameterRef")
    return ref[1:] if ref.startswith("$") and not ref.startswith("${") else ref


def _variables(path, node: Node | None, values: Mapping[str, object]) -> dict[str, M.Parameter]:
    """The file's VariableDeclarations (1.2): name, type and initial value (an expression may
    name parameters)."""
    out: dict[str, M.Parameter] = {}
    for d in node.all("VariableDeclaration") if node is not None else ():
        name, kind = d.attrs.get("name"), d.attrs.get("variableType")
        if not name or "value" not in d.attrs:
            raise ScenarioFileError(path, d.line, "<VariableDeclaration> needs attributes name and value")
        _check_declared(path, d, name, kind, "variable", out)
        try:
            value = convert(kind, resolve(d.attrs["value"], values), f"variable {name!r}")
        except (ExpressionError, ValueError) as exc:
            raise ScenarioFileError(path, d.line, str(exc)) from None
        out[name] = M.Parameter(name, kind, value, d.line)
    return out


def _constraint_group(path, g: Node, values: Mapping[str, object]) -> tuple[M.ValueConstraint, ...]:
    out = []
    for vc in g.all("ValueConstraint"):
        rule, raw = vc.attrs.get("rule"), vc.attrs.get("value")
        if rule not in M.RULES:
            raise ScenarioFileError(
                path, vc.line, f"bad value for rule in <ValueConstraint>: {rule!r} (allowed: {', '.join(M.RULES)})"
            )
        if raw is None:
            raise ScenarioFileError(path, vc.line, "<ValueConstraint> needs attribute value")
        try:
            out.append(M.ValueConstraint(rule, resolve(raw, values), vc.line, raw))
        except ExpressionError as exc:
            raise ScenarioFileError(path, vc.line, str(exc)) from None
    if not out:
        raise ScenarioFileError(path, g.line, "<ConstraintGroup> needs at least one <ValueConstraint>")
    return tuple(out)


def satisfies(value: object, c: M.ValueConstraint) -> bool:
    """Whether a parameter's ``value`` meets one value constraint: numbers compared as numbers
    (also a string parameter holding one, as lane ids are), other values as text (equalTo,
    notEqualTo only; an ordering rule on text is false)."""
    try:
        lhs, rhs = float(value), float(c.value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        lhs_s = str(value).lower() if isinstance(value, bool) else str(value)
        rhs_s = str(c.value).lower() if isinstance(c.value, bool) else str(c.value)
        if c.rule == "equalTo":
            return lhs_s == rhs_s
        return c.rule == "notEqualTo" and lhs_s != rhs_s
    return {
        "greaterThan": lhs > rhs,
        "lessThan": lhs < rhs,
        "greaterOrEqual": lhs >= rhs,
        "lessOrEqual": lhs <= rhs,
        "equalTo": lhs == rhs,
        "notEqualTo": lhs != rhs,
    }[c.rule]


def _fmt(v: object) -> str:
    return f"{v:g}" if isinstance(v, float) else str(v)


def _check_constraints(path, p: M.Parameter, line: int) -> None:
    """One ConstraintGroup met (all its constraints) or a one-line error: the parameter, its
    value, the rule it breaks and that rule's line (with several groups, each group's first
    broken rule)."""
    broken = []
    for g in p.constraints:
        bad = [c for c in g if not satisfies(p.value, c)]
        if not bad:
            return
        broken.append(bad[0])
    first = broken[0]
    rules = "; ".join(f"{c.rule} {_fmt(c.value)} (line {c.line})" for c in broken)
    what = "its value constraint" if len(broken) == 1 else "a rule of each of its constraint groups"
    raise ScenarioFileError(path, first.line, f"parameter {p.name!r} = {_fmt(p.value)} breaks {what}: {rules}")


class _Builder:
    """Builds the model from a checked tree with parameter ``values``."""

    def __init__(self, path: Path, values: dict[str, object]) -> None:
        self.path, self.values = path, values
        self.scenario = path  #: the scenario file (catalog folders are relative to it)
        self.entities: dict[str, M.Entity] = {}
        self.catalog_dirs: dict[str, list[str]] = {}  #: catalog kind -> its folders as written
        self.variables: dict[str, M.Parameter] = {}  #: the file's VariableDeclarations (1.2)
        #: the last Maneuver a catalog reference found: (catalog file, its node, its values)
        self.maneuver_entry: tuple[Path, Node, dict[str, object]] | None = None

    def scenario_tree(self) -> Node:
        """The scenario file's parsed tree (a catalog entry's element reads the scenario's)."""
        return read_tree(self.scenario)

    # -- attributes ----------------------------------------------------------------------------
    def error(self, node: Node, message: str) -> ScenarioFileError:
        return ScenarioFileError(self.path, node.line, message)

    def raw(self, node: Node, name: str, default: object = ...) -> object:
        if name not in node.attrs:
            if default is ...:
                raise self.error(node, f"<{node.tag}> needs attribute {name}")
            return default
        try:
            return resolve(node.attrs[name], self.values)
        except ExpressionError as exc:
            raise self.error(node, str(exc)) from None

    def num(
        self,
        node: Node,
        name: str,
        default: object = ...,
        positive: bool = False,
        nonneg: bool = False,
        at_most: tuple[float, str] | None = None,
    ) -> float:
        v = self.raw(node, name, default)
        if v is None:
            return v  # type: ignore[return-value]
        try:
            f = convert("double", v, f"{name} in <{node.tag}>")
        except ValueError as exc:
            raise self.error(node, str(exc)) from None
        if positive and f <= 0.0:
            raise self.error(node, f"bad value for {name} in <{node.tag}>: {f:g} (expected > 0)")
        if nonneg and f < 0.0:
            raise self.error(node, f"bad value for {name} in <{node.tag}>: {f:g} (expected >= 0)")
        if at_most is not None and abs(f) > at_most[0]:
            limit, unit = at_most
            raise self.error(node, f"bad value for {name} in <{node.tag}>: {f:g} (expected at most {limit:g} {unit})")
        return f  # type: ignore[return-value]

    def int_(self, node: Node, name: str, default: object = ..., minimum: int | None = None) -> int:
        v = self.raw(node, name, default)
        try:
            i = convert("integer", v, f"{name} in <{node.tag}>")
        except ValueError as exc:
            raise self.error(node, str(exc)) from None
        if minimum is not None and i < minimum:  # type: ignore[operator]
            raise self.error(node, f"bad value for {name} in <{node.tag}>: {i} (expected >= {minimum})")
        return i  # type: ignore[return-value]

    def execution_count(self, node: Node, default: object = ...) -> int:
        """``maximumExecutionCount`` (the schema: an unsignedInt >= 1); -1, which the schema
        does not allow, is unlimited with a warning, as the reference player reads it (esmini's
        ``StoryBoardElement::End`` runs an element again while its count is -1)."""
        name = "maximumExecutionCount"
        v = self.int_(node, name, default)
        if v == -1:
            files.warn(
                f"{self.path}:{node.line}: {name}=-1 in <{node.tag}> (the schema allows >= 1): unlimited, "
                "as the reference player reads it"
            )
            return M.UNLIMITED
        if v < 1:
            raise self.error(node, f"bad value for {name} in <{node.tag}>: {v} (expected >= 1, or -1: unlimited)")
        return v

    def bool_(self, node: Node, name: str, default: object = ...) -> bool:
        v = self.raw(node, name, default)
        try:
            return convert("boolean", v, f"{name} in <{node.tag}>")  # type: ignore[return-value]
        except ValueError as exc:
            raise self.error(node, str(exc)) from None

    def str_(self, node: Node, name: str, default: object = ...) -> str:
        return str(self.raw(node, name, default))

    def enum(self, node: Node, name: str, allowed, default: object = ...) -> str:
        v = self.str_(node, name, default)
        if v not in allowed:
            raise self.error(node, f"bad value for {name} in <{node.tag}>: {v!r} (allowed: {', '.join(allowed)})")
        return v

    def one(self, node: Node, tag: str | None = None) -> Node:
        """The single child (``tag``, or any) the element needs."""
        kids = node.children if tag is None else node.all(tag)
        if len(kids) != 1:
            what = f"<{tag}>" if tag else "child element"
            raise self.error(node, f"<{node.tag}> needs exactly one {what} (found {len(kids)})")
        return kids[0]

    def entity_ref(self, node: Node, name: str = "entityRef") -> str:
        ref = self.str_(node, name)
        if ref not in self.entities:
            raise self.error(
                node, f"unknown entity {ref!r} in <{node.tag}> (entities: {', '.join(self.entities) or 'none'})"
            )
        return ref

    # -- entities ---------------------------------------------------------------------------
    def vehicle(self, node: Node, name: str) -> M.Vehicle:
        cat = self.enum(node, "vehicleCategory", VEHICLE_CATEGORIES)
        perf = self.one(node, "Performance")
        self.no_trailer(node)
        return M.Vehicle(
            name=name,
            category=cat,
            **self.box(node),
            max_speed=self.performance(perf, "maxSpeed", name),
            max_accel=self.performance(perf, "maxAcceleration", name),
            max_decel=self.performance(perf, "maxDeceleration", name),
            line=node.line,
        )

    def performance(self, perf: Node, attr: str, name: str) -> float:
        """A vehicle's Performance limit; one the file leaves out (the schema requires all three)
        is the reference player's default (:data:`PERFORMANCE_DEFAULTS`), with a warning."""
        if attr not in perf.attrs:
            value = PERFORMANCE_DEFAULTS[attr]
            files.warn(
                f"{self.path}:{perf.line}: <Performance> of {name or 'a catalog vehicle'} has no {attr} (the schema "
                f"requires it): {value:g} {'m/s' if attr == 'maxSpeed' else 'm/s^2'}, the reference player's default"
            )
            return value
        return self.num(perf, attr, positive=True)

    def no_trailer(self, node: Node) -> None:
        """A vehicle's <Trailer> is accepted when it attaches nothing (an empty entityRef or
        entryName: the reference player's catalog entries carry one for every car); a
        trailer that is really attached is refused (ego drives single bodies)."""
        for tr in node.all("Trailer"):
            for ref in tr.children:
                if ref.tag == "Vehicle":  # a trailer written inline (esmini's semi_truck_with_extra_trailer)
                    raise self.error(
                        ref,
                        f"a trailer (Vehicle {ref.attrs.get('name', '')!r}) is not supported by ego: it runs single "
                        f"vehicles (see {DOCS})",
                    )
                attr = "entityRef" if ref.tag == "EntityRef" else "entryName"
                name = self.str_(ref, attr)
                if name:
                    raise self.error(
                        ref,
                        f"a trailer ({attr} {name!r}) is not supported by ego: it runs single vehicles (see {DOCS})",
                    )

    def box(self, node: Node) -> dict[str, float]:
        """An entity's BoundingBox: its dimensions and the centre's x from the reference point."""
        bb = self.one(node, "BoundingBox")
        center, dims = self.one(bb, "Center"), self.one(bb, "Dimensions")
        return {
            "length": self.num(dims, "length", positive=True),
            "width": self.num(dims, "width", positive=True),
            "height": self.num(dims, "height", positive=True),
            "center_x": self.num(center, "x"),
        }

    def body(self, node: Node, name: str) -> M.Vehicle:
        """A Vehicle, Pedestrian or MiscObject element (or a catalog reference to one)."""
        if node.tag == "CatalogReference":
            return self.catalog_entry(node, ("Vehicle", "Pedestrian", "MiscObject"), name)  # type: ignore[return-value]
        if node.tag == "Vehicle":
            return self.vehicle(node, name)
        return self.standing(node, name)

    def standing(self, node: Node, name: str) -> M.Vehicle:
        """A pedestrian or misc object: a body of its bounding box that stands still unless
        the storyboard moves it."""
        ped = node.tag == "Pedestrian"
        if ped:
            cat = self.enum(node, "pedestrianCategory", PEDESTRIAN_CATEGORIES)
        else:
            cat = self.enum(node, "miscObjectCategory", MISC_CATEGORIES)
        self.num(node, "mass", nonneg=True)
        return M.Vehicle(
            name=name,
            category=cat,
            **self.box(node),
            max_speed=STANDING_MAX_SPEED,
            max_accel=STANDING_ACCEL,
            max_decel=STANDING_ACCEL,
            line=node.line,
            kind="pedestrian" if ped else "miscObject",
        )

    def catalog_file(self, node: Node, catalog: str, kinds: tuple[str, ...]) -> Path:
        """The catalog file named ``catalog`` in the file's catalog directories: the file
        ``catalog.xosc``, else the file whose <Catalog name> is ``catalog``; then, found
        elsewhere (:mod:`ego.openscenario.files`), ``catalog.xosc`` in each search folder (under
        each directory as written, and alone)."""
        written = [d for k in kinds for d in self.catalog_dirs.get(CATALOG_OF[k], [])]
        written += [d for ds in self.catalog_dirs.values() for d in ds if d not in written]
        if not written:
            raise self.error(
                node, f"<CatalogReference> to {catalog!r} but no <{CATALOG_OF[kinds[0]]}> in <CatalogLocations>"
            )
        places = [files.candidates(self.scenario, f"{w.rstrip('/')}/{catalog}.xosc") for w in written]
        firsts = [f for first, _ in places for f in first]
        for f in firsts:
            if f.is_file():
                return resolved(f, "catalog file")
        for f in firsts:
            d = resolved(f.parent, "catalog folder")
            # a "folder" that is the catalog file itself (esmini's 0.9 examples write
            # Directory path="../xosc/Catalogs/VehicleCatalog", a file without extension)
            for g in sorted(d.glob("*.xosc")) if d.is_dir() else [d] if d.is_file() else ():
                cat = read_tree(g).child("Catalog")
                if cat is not None and cat.attrs.get("name") == catalog:
                    return g
        rest = list(dict.fromkeys(f for _, others in places for f in others if f not in firsts))
        for f in rest:
            if f.is_file():
                files.warn(
                    f"{self.scenario}: catalog {catalog!r} is not in {', '.join(written)}; found as {f} "
                    f"(see docs/openscenario.md)"
                )
                return resolved(f, "catalog file")
        raise self.error(node, f"catalog {catalog!r} not found ({files.looked(firsts + rest)})")

    def entry_builder(self, ref: Node, kind: str) -> tuple[Node, _Builder]:
        """The ``kind`` element a CatalogReference names (a Route, an Environment) and a
        builder that reads it in its catalog file with the entry's parameters and the
        reference's assignments (this scenario's entities, catalogs and variables)."""
        self.maneuver_entry = None
        self.catalog_entry(ref, (kind,), "")
        assert self.maneuver_entry is not None  # catalog_entry found it or raised
        file, node, values = self.maneuver_entry
        cb = type(self)(file, values)
        cb.entities, cb.catalog_dirs, cb.variables = self.entities, self.catalog_dirs, self.variables
        return node, cb

    def catalog_entry(self, node: Node, kinds: tuple[str, ...], name: str) -> M.Vehicle | None:
        """The entry a CatalogReference names, of one of ``kinds`` (a Controller entry is
        checked and gives None)."""
        catalog, entry = self.str_(node, "catalogName"), self.str_(node, "entryName")
        file = self.catalog_file(node, catalog, kinds)
        root = read_tree(file)
        cat = root.child("Catalog")
        if root.tag != "OpenSCENARIO" or cat is None:
            raise ScenarioFileError(file, root.line, "not an OpenSCENARIO catalog (expected <Catalog>)")
        for v in cat.children:
            if v.tag not in CATALOG_OF:
                raise unsupported(file, v)
            if v.attrs.get("name") != entry:
                continue
            if v.tag not in kinds:
                raise self.error(
                    node, f"catalog entry {entry!r} is a <{v.tag}>, not a <{'> or <'.join(kinds)}> (in {file})"
                )
            _check_tree(file, v)
            # the catalog's own parameters, then the reference's assignments
            decl = _declarations(file, v.child("ParameterDeclarations"), self.values)
            values = {**self.values, **{k: p.value for k, p in decl.items()}}
            assigns = node.child("ParameterAssignments")
            for a in assigns.all("ParameterAssignment") if assigns is not None else ():
                ref = _assigned_name(a)
                if ref not in decl:
                    raise self.error(
                        a,
                        f"catalog entry {entry!r} declares no parameter {ref!r}"
                        f" (declared: {', '.join(decl) or 'none'})",
                    )
                try:
                    values[ref] = convert(decl[ref].type, self.raw(a, "value"), f"parameter {ref!r}")
                except ValueError as exc:
                    raise self.error(a, str(exc)) from None
            if v.tag in ("Controller", "Maneuver", "Environment", "Route"):
                self.maneuver_entry = (file, v, values)
                return None
            return _Builder(file, values).body(v, name)
        names = [v.attrs.get("name", "?") for v in cat.children]
        if kinds == ("Controller",):
            # ego's semantics do not depend on a controller entry (the ego is driven by -c's
            # controller, the others by SUMO's driver or their script): a warning, where the
            # reference player stops (its examples name entries no version of its catalog has)
            assigns = node.child("ParameterAssignments")
            for a in assigns.all("ParameterAssignment") if assigns is not None else ():
                self.raw(a, "value")  # the assigned values are still the scenario's to resolve
            files.warn(
                f"{self.path}:{node.line}: no entry {entry!r} in catalog {catalog!r} ({file}; entries: "
                f"{', '.join(names)}): the controller is left out (ego drives the ego with its own controller, "
                f"SUMO the others; see {DOCS})"
            )
            return None
        raise self.error(node, f"no entry {entry!r} in catalog {catalog!r} (entries: {', '.join(names)})")

    def controller(self, node: Node) -> M.ObjectControl:
        """An ObjectController or AssignControllerAction: its controller (inline or from a
        catalog) is checked; ego drives the ego with ``-c``'s controller, SUMO the others.
        Returns the controller's name and properties (resolved, with their lines; an entry
        missing from its catalog: its name alone)."""
        c = self.one(node)
        if c.tag == "CatalogReference":
            self.maneuver_entry = None
            self.catalog_entry(c, ("Controller",), "")
            if self.maneuver_entry is None:  # an entry missing from its catalog: left out with a warning
                return M.ObjectControl(self.str_(c, "entryName"), {}, {}, self.path, node.line)
            file, c, values = self.maneuver_entry
            b = _Builder(file, values)
        else:
            b = self
        props: dict[str, str] = {}
        lines: dict[str, int] = {}
        ps = c.child("Properties")
        for p in ps.all("Property") if ps is not None else ():
            name = b.str_(p, "name")
            props[name], lines[name] = b.str_(p, "value"), p.line
        return M.ObjectControl(b.str_(c, "name"), props, lines, b.path, node.line)

    # -- positions ------------------------------------------------------------------------------
    def position(self, node: Node) -> M.Position:
        p = self.one(node)
        tag = p.tag
        o = p.child("Orientation")
        turned = 0  # (an absolute heading is the TeleportAction's, checked where the lane is known)
        if o is not None and self.enum(o, "type", ("relative", "absolute"), "absolute") == "relative":
            h = self.num(o, "h", 0.0)
            if math.cos(h) < 0.0:  # turned more than 90 degrees from its lane's direction
                if tag != "LanePosition":
                    raise self.error(o, turned_message(f"relative h = {h:g} rad, in a <{tag}>"))
                turned = o.line  # an Init start of a car driving against its lane: checked by load
        if tag == "WorldPosition":
            h = self.raw(p, "h", None)
            return M.WorldPosition(self.num(p, "x"), self.num(p, "y"), None if h is None else self.num(p, "h"), p.line)
        if tag == "LanePosition":
            road, lane, s = self.str_(p, "roadId"), self.int_(p, "laneId"), self.num(p, "s", nonneg=True)
            if lane == 0:  # OpenDRIVE's lane 0 is the reference line: offset is t from it
                return M.RoadPosition(road, s, self.num(p, "offset", 0.0), p.line)
            return M.LanePosition(road, lane, s, self.num(p, "offset", 0.0), p.line, turned)
        if tag == "RoadPosition":
            return M.RoadPosition(self.str_(p, "roadId"), self.num(p, "s", nonneg=True), self.num(p, "t"), p.line)
        if tag == "RelativeLanePosition":
            if "dsLane" in p.attrs:
                raise self.error(p, f"dsLane in <RelativeLanePosition> is not supported by ego (use ds; see {DOCS})")
            return M.RelativeLanePosition(
                # a missing dLane (the schema requires it) is 0, as the reference player reads it
                self.entity_ref(p),
                self.int_(p, "dLane", 0),
                self.num(p, "ds", 0.0),
                self.num(p, "offset", 0.0),
                p.line,
            )
        if tag == "RelativeObjectPosition":
            # dx and dy are required by the schema; the reference player reads a missing one as 0
            return M.RelativeObjectPosition(self.entity_ref(p), self.num(p, "dx", 0.0), self.num(p, "dy", 0.0), p.line)
        if tag == "TrajectoryPosition":
            self.one(self.one(p, "TrajectoryRef"), "Trajectory")  # a catalog trajectory is refused by the check
            trajectory = ACTIONS["FollowTrajectoryAction"].build(self, p)
            if trajectory.segments and trajectory.segments[0].start is None:
                raise self.error(
                    p, "a <TrajectoryPosition>'s clothoid spline needs the <PositionStart> of its first <Segment>"
                )
            return M.TrajectoryPosition(trajectory, self.num(p, "s", nonneg=True), self.num(p, "t", 0.0), p.line)
        if tag == "RoutePosition":
            return self.route_position(p)
        if tag == "RelativeWorldPosition":
            return M.RelativeWorldPosition(self.entity_ref(p), self.num(p, "dx"), self.num(p, "dy"), p.line)
        return M.RelativeRoadPosition(self.entity_ref(p), self.num(p, "ds"), self.num(p, "dt"), p.line)

    def route_position(self, p: Node) -> M.RoutePosition:
        """A <RoutePosition>: its route (inline or from a RouteCatalog, read as an
        AssignRouteAction's) and its one InRoutePosition form."""
        waypoints = ACTIONS["AssignRouteAction"].build(self, self.one(p, "RouteRef")).waypoints
        form = self.one(self.one(p, "InRoutePosition"))
        if form.tag == "FromCurrentEntity":
            return M.RoutePosition(waypoints, 0.0, 0, 0.0, p.line, self.entity_ref(form))
        path_s = self.num(form, "pathS", nonneg=True)
        if form.tag == "FromRoadCoordinates":
            return M.RoutePosition(waypoints, path_s, 0, self.num(form, "t"), p.line)
        if form.tag == "FromLaneCoordinates":
            lane = self.int_(form, "laneId")
            if lane == 0:
                raise self.error(form, "laneId 0 in <FromLaneCoordinates> is the reference line, not a lane")
            return M.RoutePosition(waypoints, path_s, lane, self.num(form, "laneOffset", 0.0), p.line)
        raise self.error(
            form,
            f"<InRoutePosition> holds <{form.tag}>; allowed: FromCurrentEntity, FromRoadCoordinates, "
            "FromLaneCoordinates",
        )

    # -- actions ------------------------------------------------------------------------------
    def dynamics(self, node: Node) -> M.Dynamics:
        shape = self.enum(node, "dynamicsShape", M.SHAPES)
        # a step has no duration: its dimension and value change nothing (the reference
        # player's files often omit them; the schema asks for both)
        dim = self.enum(node, "dynamicsDimension", M.DIMENSIONS, "time" if shape == "step" else ...)
        # a rate is read by its magnitude, as the reference player (esmini) reads the negative
        # braking rates its files write; a duration or distance must not be negative
        if shape == "step" and "value" not in node.attrs:
            return M.Dynamics("step", dim, 0.0)
        value = self.num(node, "value", at_most=DYNAMICS_LIMITS[dim])
        if dim == "rate":
            value = abs(value)
        elif value < 0.0:
            raise self.error(node, f"bad value for value in <{node.tag}>: {value:g} (expected >= 0)")
        if value == 0.0:
            return M.Dynamics("step", dim, 0.0)  # a transition of no duration is a step (the standard)
        return M.Dynamics(shape, dim, value)

    def private_action(self, node: Node) -> M.PrivateAction:
        """A PrivateAction: its action (directly in it, or in a LongitudinalAction,
        LateralAction or RoutingAction) read by its registered kind."""
        a = self.one(node)
        if a.tag not in ACTIONS:
            a = self.one(a)
        return ACTIONS[a.tag].build(self, a)

    def global_action(self, node: Node) -> M.EnvironmentAction | M.ParameterAction:
        """A GlobalAction's action, read by its registered kind."""
        inner = self.one(node)
        return ACTIONS[inner.tag].build(self, inner)

    def scoped(self, node: Node) -> dict[str, object]:
        """The parameter values inside ``node``: its own ``ParameterDeclarations`` (possibly
        empty) on top of the values outside it (an inner name shadows an outer one)."""
        decl = _declarations(self.path, node.child("ParameterDeclarations"), self.values)
        return {**self.values, **{k: p.value for k, p in decl.items()}} if decl else self.values

    # -- triggers ---------------------------------------------------------------------------
    def trigger(self, node: Node | None) -> M.Trigger | None:
        if node is None:
            return None
        groups = []
        for g in node.all("ConditionGroup"):
            conds = tuple(self.condition(c) for c in g.all("Condition"))
            if not conds:
                raise self.error(g, "<ConditionGroup> needs at least one <Condition>")
            groups.append(conds)
        return M.Trigger(tuple(groups))

    def condition(self, node: Node) -> M.Condition:
        # a condition's name identifies nothing (conditions are not storyboard elements): one
        # whose expression does not evaluate (the reference player's cut-in.xosc writes
        # "${BrakeCondition_HWT + _ + $HeadwayTime_Brake}") is kept as its text
        try:
            name = self.str_(node, "name")
        except ScenarioFileError:
            name = str(node.attrs.get("name", ""))
        base: dict[str, Any] = {
            "name": name,
            "delay": self.num(node, "delay", nonneg=True, at_most=(MAX_SECONDS, "s: a day")),
            "edge": self.enum(node, "conditionEdge", M.EDGES, "none"),  # the schema requires it; esmini reads none
            "line": node.line,
        }
        inner = self.one(node)
        if inner.tag == "ByValueCondition":
            return self.value_condition(self.one(inner), base)
        return self.entity_condition(inner, base)

    def value_condition(self, c: Node, base: dict[str, Any]) -> M.Condition:
        """A ByValueCondition's condition, read by its registered kind."""
        return CONDITIONS[c.tag].build(self, c, base)

    def entity_condition(self, inner: Node, base: dict[str, Any]) -> M.Condition:
        """A ByEntityCondition: its triggering entities and its condition (read by its kind)."""
        te = self.one(inner, "TriggeringEntities")
        refs = tuple(self.entity_ref(e) for e in te.all("EntityRef"))
        if not refs:
            raise self.error(te, "<TriggeringEntities> needs at least one <EntityRef>")
        base["triggering"] = refs
        base["triggering_rule"] = self.enum(te, "triggeringEntitiesRule", ("any", "all"))
        c = self.one(self.one(inner, "EntityCondition"))
        return CONDITIONS[c.tag].build(self, c, base)


def load(path: str | os.PathLike, overrides: Mapping[str, object] | None = None) -> M.Scenario:
    """The scenario in ``path`` with its parameters set to their defaults, then ``overrides``
    (a declared parameter's name -> value; undeclared names are not looked at here)."""
    path = Path(path)
    root = read_tree(path)
    _check_root(path, root)
    header = root.child("FileHeader")
    version = _version(path, root)
    defaults = _declarations(path, root.child("ParameterDeclarations"), {})
    given = {k: v for k, v in (overrides or {}).items() if k in defaults}
    try:
        params = _declarations(path, root.child("ParameterDeclarations"), {}, given)
    except ScenarioFileError as exc:
        from ego.params import ConfigError

        raise ConfigError(exc.detail) from None
    values: dict[str, object] = {k: p.value for k, p in params.items()}
    params = defaults
    b = _Builder(path, values)
    b.variables = _variables(path, root.child("VariableDeclarations"), values)
    cl = root.child("CatalogLocations")
    for vc in cl.children if cl is not None else ():
        if not vc.children:  # <RouteCatalog/>: the reference player's files write empty ones; it locates nothing
            continue
        d = b.one(vc, "Directory")
        b.catalog_dirs.setdefault(vc.tag, []).append(b.str_(d, "path"))

    net = root.child("RoadNetwork")
    logic = net.child("LogicFile") if net is not None else None
    if logic is None:
        raise ScenarioFileError(
            path,
            (net or root).line,
            "the scenario needs <RoadNetwork><LogicFile filepath=...> (an .xodr or a SUMO .net.xml)",
        )
    rel = b.str_(logic, "filepath")
    if not rel.endswith((".xodr", ".net.xml")):
        raise b.error(logic, f"bad road file {rel!r} (expected an OpenDRIVE .xodr or a SUMO .net.xml)")
    found, places = files.locate(path, rel, "road file")
    if found is None:
        raise b.error(logic, f"road file {rel!r} not found ({files.looked(places)})")
    road = resolved(found, "road file")

    ents = root.child("Entities")
    ghosts: set[str] = set()
    controllers: dict[str, M.ObjectControl] = {}
    for so in ents.all("ScenarioObject") if ents is not None else ():
        name = b.str_(so, "name")
        if name in b.entities:
            raise b.error(so, f"entity {name!r} is declared twice")
        kids = [c for c in so.children if c.tag != "ObjectController"]
        if len(kids) != 1:
            raise b.error(so, f"<ScenarioObject> needs exactly one child element (found {len(kids)})")
        for oc in so.all("ObjectController"):
            control = b.controller(oc)
            props = control.properties
            controllers.setdefault(name, control)  # several (1.3): the first is the entity's own
            # a ghost (the reference player's): the entity a FollowGhost controller follows
            # (its "ghost" property), or one driven by a ghost controller
            if "ghost" in props:
                ghosts.add(props["ghost"])
            if "GhostController" in (props.get("esminiController"), control.name):
                ghosts.add(name)
        b.entities[name] = M.Entity(name, b.body(kids[0], name), so.line)
    if not b.entities:
        raise ScenarioFileError(path, (ents or root).line, "the scenario needs at least one entity")

    sb = root.child("Storyboard")
    if sb is None:
        raise ScenarioFileError(path, root.line, "<OpenSCENARIO> needs a <Storyboard>")
    init: dict[str, list[M.PrivateAction]] = {name: [] for name in b.entities}
    init_runs: dict[str, list[M.PrivateAction]] = {}
    init_node = sb.child("Init")
    actions = init_node.child("Actions") if init_node is not None else None
    init_globals: list[object] = []
    for ga in actions.all("GlobalAction") if actions is not None else ():
        global_action = b.global_action(ga)
        if action_of(global_action).in_init == "no":
            hint = action_of(global_action).init_hint
            raise ScenarioFileError(
                path,
                ga.children[0].line,
                f"<{ga.children[0].tag}> in <Init> is not supported by ego ({hint}; see {DOCS})",
            )
        if action_of(global_action).in_init == "yes":
            init_globals.append(global_action)  # done at the storyboard's first step
    activations: dict[str, int] = {}
    for priv in actions.all("Private") if actions is not None else ():
        ref = b.entity_ref(priv)
        for pa in priv.all("PrivateAction"):
            act = b.private_action(pa)
            kind = action_of(act)
            if isinstance(act, M.ControllerAction) and act.activates:
                activations.setdefault(ref, pa.children[0].line)
            if kind.in_init == "ignored":
                continue
            if kind.in_init not in ("yes", "runs") or not kind.init_ok(act):
                raise ScenarioFileError(
                    path,
                    pa.children[0].line,
                    f"<{pa.children[0].tag}> in <Init> is not supported by ego (Init takes {init_kinds()}; see {DOCS})",
                )
            if kind.in_init == "yes":
                init[ref].append(act)
            if kind.init_runs(act):
                init_runs.setdefault(ref, []).append(act)
    for name, acts in init.items():
        start = _trajectory_start(init_runs.get(name, ()))
        if start is not None and not any(isinstance(a, M.TeleportAction) for a in acts):
            # no TeleportAction, a trajectory from t = 0: the entity starts at its first point
            # (the reference player puts it there at its first step)
            acts.insert(0, start)
        # an entity without a TeleportAction (or trajectory) in Init has no start: it is not in
        # the simulation until a TeleportAction places it (the ego needs one: FileScenario)

    stories = []
    names: dict[str, int] = {}
    for st in sb.all("Story"):
        # the story's own parameters: visible inside it, shadowing the file's
        outer_values = b.values
        b.values = b.scoped(st)
        acts = []
        for act in st.all("Act"):
            groups = []
            for mg in act.all("ManeuverGroup"):
                # the schema requires <Actors>; the reference player reads an empty group (esmini's
                # straight_500m.xosc) as one with no actors and nothing to do
                actors_node = b.one(mg, "Actors") if mg.children else None
                actors = tuple(b.entity_ref(e) for e in actors_node.all("EntityRef")) if actors_node else ()
                mans = []
                for man in mg.children:
                    if man.tag == "Maneuver":
                        mans.append(_maneuver(b, man, names))
                    elif man.tag == "CatalogReference":
                        # a Maneuver from a ManeuverCatalog: built with its catalog's
                        # parameters and the reference's assignments, errors in its own file
                        b.maneuver_entry = None
                        b.catalog_entry(man, ("Maneuver",), "")
                        file, node, cat_values = b.maneuver_entry  # type: ignore[misc]
                        cb = _Builder(file, cat_values)
                        cb.entities, cb.catalog_dirs, cb.variables = b.entities, b.catalog_dirs, b.variables
                        cb.scenario = b.scenario
                        mans.append(_maneuver(cb, node, names, scoped=False))
                groups.append(M.ManeuverGroup(b.str_(mg, "name"), b.execution_count(mg), actors, tuple(mans), mg.line))
                names.setdefault(groups[-1].name, mg.line)
            acts.append(
                M.Act(
                    b.str_(act, "name"),
                    tuple(groups),
                    b.trigger(act.child("StartTrigger")),
                    b.trigger(act.child("StopTrigger")),
                    act.line,
                )
            )
            names.setdefault(acts[-1].name, act.line)
        b.values = outer_values
        stories.append(M.Story(b.str_(st, "name", ""), tuple(acts), st.line))
        names.setdefault(stories[-1].name, st.line)
    stop = b.trigger(sb.child("StopTrigger"))
    _check_turned(path, stories, init_runs)
    scenario = M.Scenario(
        path,
        header.attrs.get("description", ""),
        version,
        params,
        values,
        road,
        logic.line,
        b.entities,
        init,
        tuple(stories),
        stop,
        init_runs=init_runs,
        init_globals=tuple(init_globals),
        ghosts=frozenset(g for g in ghosts if g in b.entities),
        controllers=controllers,
        init_activations=activations,
    )
    _check_refs(scenario, names)
    return scenario


def _rev(text: str) -> int:
    """A FileHeader revision by its leading number: the reference player's files write "1+"."""
    m = re.match(r"\s*(\d+)", text)
    if m is None:
        raise ValueError(text)
    return int(m.group(1))


def _maneuver(b: _Builder, man: Node, names: dict[str, int], scoped: bool = True) -> M.Maneuver:
    """A Maneuver element (inline or a catalog entry) with its events; an inline one's own
    ParameterDeclarations are seen inside it (a catalog entry's are in ``b``'s values with the
    reference's assignments: ``scoped`` False)."""
    if scoped:
        outer = b.values
        b.values = b.scoped(man)
        try:
            return _maneuver(b, man, names, scoped=False)
        finally:
            b.values = outer
    events = []
    for ev in man.all("Event"):
        acts_ = tuple(
            M.Action(
                b.str_(a, "name", ""),  # nameless as the reference player reads it (see Storyboard)
                b.global_action(a.children[0])
                if a.children and a.children[0].tag == "GlobalAction"
                else b.private_action(b.one(a, "PrivateAction")),
                a.line,
            )
            for a in ev.all("Action")
        )
        if not acts_:
            raise b.error(ev, "<Event> needs at least one <Action>")
        events.append(
            M.Event(
                b.str_(ev, "name"),
                b.enum(ev, "priority", M.PRIORITIES),
                b.execution_count(ev, 1),
                acts_,
                b.trigger(ev.child("StartTrigger")),
                ev.line,
            )
        )
        for a in acts_:
            names.setdefault(a.name, a.line)
        names.setdefault(events[-1].name, ev.line)
    # the schema asks for a name; the reference player's files sometimes leave it out (it only
    # matters to a reference, which then cannot name it), as a Story's
    out = M.Maneuver(b.str_(man, "name", ""), tuple(events), man.line)
    names.setdefault(out.name, man.line)
    return out


def _conditions(scenario: M.Scenario):
    triggers = [scenario.stop]
    for st in scenario.stories:
        for act in st.acts:
            triggers += [act.start, act.stop]
            for g in act.groups:
                for man in g.maneuvers:
                    triggers += [ev.start for ev in man.events]
    for t in triggers:
        for group in t.groups if t is not None else ():
            yield from group


def _paths(scenario: M.Scenario):
    """(element type, path of names from its story down) of every storyboard element."""
    for st in scenario.stories:
        yield "story", (st.name,)
        for act in st.acts:
            pa = (st.name, act.name)
            yield "act", pa
            for g in act.groups:
                pg = (*pa, g.name)
                yield "maneuverGroup", pg
                for man in g.maneuvers:
                    pm = (*pg, man.name)
                    yield "maneuver", pm
                    for ev in man.events:
                        yield "event", (*pm, ev.name)
                        for a in ev.actions:
                            yield "action", (*pm, ev.name, a.name)


def _check_refs(scenario: M.Scenario, names: dict[str, int]) -> None:
    """StoryboardElementStateConditions name existing elements of their type, by name or
    qualified (``Event::Action``, OpenSCENARIO 1.1); an error names the line of the reference."""
    known = {(kind, q) for kind, path in _paths(scenario) for q in M.qualified_names(path)}
    for c in _conditions(scenario):
        if c.kind == "StoryboardElementStateCondition" and (c.element_type, c.element_ref) not in known:
            raise ScenarioFileError(
                scenario.path,
                c.ref_line or c.line,
                f"unknown storyboard {c.element_type} {c.element_ref!r} "
                f"(elements: {', '.join(names) or 'none'}; qualify with '::', e.g. 'Event::Action')",
            )
