"""Roads of scenario files: OpenDRIVE (.xodr) converted by SUMO's netconvert, or a SUMO
``.net.xml`` as it is, and OpenDRIVE lane positions on the converted network.

A converted road is cached by the hash of its content and of the conversion options in
``$XDG_CACHE_HOME/ego/opendrive`` (default ``~/.cache/ego/opendrive``): a sweep converts once.

netconvert samples OpenDRIVE's curves (arcs, clothoids) into polyline points every
``--opendrive.curve-resolution`` metres (:data:`CURVE_RESOLUTION`; SUMO's default is 2 m)
written with 6 decimals (its default 2 would put centimetre noise on every point);
:func:`refine_shape` then evens out the steps for ego's lane frame, so that its curvature on
a converted arc and clothoid matches the analytic value within 1e-3 1/m.
"""

from __future__ import annotations

import hashlib
import math
import os
import re
import subprocess
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from ego.openscenario.lane_shapes import exact_lane_shapes
from ego.openscenario.xmltree import ScenarioFileError

#: m between the points netconvert samples an OpenDRIVE curve at
CURVE_RESOLUTION = 0.5
OPTIONS = (
    "--opendrive.curve-resolution",
    repr(CURVE_RESOLUTION),
    "--output.original-names",
    "true",
    "--geometry.min-dist",
    "0.001",
    "--no-turnarounds",
    "true",
    "--offset.disable-normalization",
    "true",
    "--precision",
    "6",
    "--no-warnings",
    "true",
)
#: netconvert's option making every OpenDRIVE lane a SUMO lane (border, shoulder, sidewalk...:
#: those of no driving type disallow every vehicle class); used only to find such a lane's
#: geometry when a file places an entity on it (:meth:`RoadMap.lane_s_offset`)
ALL_LANES = ("--opendrive.import-all-lanes", "true")


#: the version of :func:`for_netconvert`'s copy and of what is done to netconvert's network
#: (:func:`ego.openscenario.lane_shapes.exact_lane_shapes`), part of a converted road's cache
#: key (a road converted before a change of either is converted again)
COPY_VERSION = "copy 4"


def cache_dir() -> Path:
    """Where converted roads are kept: ``$XDG_CACHE_HOME/ego/opendrive`` or ``~/.cache/ego/opendrive``."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "ego" / "opendrive"


#: netconvert's bounds: a road it cannot convert in this time or memory is refused (esmini's
#: crest-curve.xodr with its roadside objects took > 7 GiB and minutes; see :data:`_OBJECTS`)
NETCONVERT_SECONDS = 120
NETCONVERT_MEMORY = 4 << 30


def _bounded() -> None:  # pragma: no cover - runs in the child before exec
    """netconvert's limits: its address space, and it dies with the process that started it."""
    try:
        import resource

        resource.setrlimit(resource.RLIMIT_AS, (NETCONVERT_MEMORY, NETCONVERT_MEMORY))
    except (ImportError, ValueError, OSError):
        pass
    try:
        import ctypes
        import signal

        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, int(signal.SIGKILL))  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


def network_file(road: Path, turned: frozenset[str] = frozenset(), all_lanes: bool = False) -> Path:
    """The SUMO network of ``road``: a ``.net.xml`` itself, an ``.xodr`` converted (cached;
    with ``all_lanes`` every OpenDRIVE lane made a SUMO lane, :data:`ALL_LANES`, a network kept
    apart). A failed conversion is one line naming the file and netconvert's first error. The
    edges of its left-hand roads (``rule="LHT"``) and of the roads ``turned`` (a file's ego
    headed against its right-hand lane: the road read as left-hand traffic) are turned round
    (:func:`left_hand`)."""
    if str(road).endswith(".net.xml"):
        return road
    from ego.checks import MAX_ROAD_BYTES, read_limited
    from ego.sumo.net import sumo_binary

    data = read_limited(road, "road file", MAX_ROAD_BYTES)
    check_lane_widths(road, data)
    lht = left_hand_roads(road, data) | turned

    exe = sumo_binary("netconvert")
    options = (*OPTIONS, *ALL_LANES) if all_lanes else OPTIONS
    what = (*options, COPY_VERSION, *(("lefthand", *sorted(lht)) if lht else ()))
    key = hashlib.sha256(data + "\0".join(what).encode() + str(exe).encode()).hexdigest()[:24]
    out = cache_dir() / f"{key}.net.xml"
    if out.is_file():
        return out
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{key}.{os.getpid()}.net.xml")
    env = {**os.environ, "SUMO_HOME": str(exe.parent.parent)}
    source, patched = road, for_netconvert(road, data)
    if patched is not None:  # netconvert's copy (see for_netconvert)
        source = out.with_name(f".{key}.{os.getpid()}.xodr")
        source.write_bytes(patched)
    try:
        proc = subprocess.run(
            [str(exe), "--opendrive-files", str(source), "-o", str(tmp), *options],
            capture_output=True,
            text=True,
            env=env,
            check=False,
            timeout=NETCONVERT_SECONDS,
            preexec_fn=_bounded,
        )
    except subprocess.TimeoutExpired:
        tmp.unlink(missing_ok=True)
        raise ScenarioFileError(
            road, None, f"netconvert did not convert this OpenDRIVE file within {NETCONVERT_SECONDS} s"
        ) from None
    finally:
        if source != road:
            source.unlink(missing_ok=True)
    if proc.returncode != 0 or not tmp.is_file():
        tmp.unlink(missing_ok=True)
        lines = [ln.strip() for ln in (proc.stderr + proc.stdout).splitlines() if ln.strip()]
        first = next((ln for ln in lines if ln.startswith("Error")), lines[0] if lines else "no output")
        if "bad_alloc" in proc.stderr or proc.returncode in (-6, -9, 134, 137):
            first = f"it needed more than {NETCONVERT_MEMORY / 2**30:g} GiB of memory"
        raise ScenarioFileError(road, None, f"netconvert cannot convert this OpenDRIVE file: {first}")
    try:
        _parse(tmp)
    except ScenarioFileError:
        tmp.unlink(missing_ok=True)
        raise
    exact_lane_shapes(data, tmp)  # lanes beside one that opens or closes: on the road's own widths
    if not _edges(tmp):
        tmp.unlink(missing_ok=True)
        raise ScenarioFileError(
            road, None, "netconvert made no drivable lane of this OpenDRIVE file (no lane of type driving?)"
        )
    if lht:
        try:
            left_hand(road, tmp, lht)
        except ScenarioFileError:
            tmp.unlink(missing_ok=True)
            raise
    os.replace(tmp, out)
    return out


#: m: a reference line's chord longer than this is a straight (its heading holds along it)
LONG_CHORD = 5.0

#: a lane wider than this is no lane (docs/reliability.md, "Limits")
MAX_LANE_WIDTH = 50.0
_LANE = re.compile(rb"<lane\b([^>]*?)(/>|>(.*?)</lane>)", re.S)
_WIDTH = re.compile(rb"<width\b[^>]*>")
_ATTR = re.compile(rb"""\b(type|a|b|c|d)\s*=\s*(["'])(.*?)\2""")


def check_lane_widths(road: Path, data: bytes) -> None:
    """Every lane width record of an OpenDRIVE file: its width at the record's start (``a``)
    a number from 0 to :data:`MAX_LANE_WIDTH` m, and a driving lane's record not zero
    everywhere (netconvert would make a lane no car fits or fail far from the cause).
    ScenarioFileError naming the line."""
    for lane in _LANE.finditer(data):
        kind = dict((k, v) for k, _, v in _ATTR.findall(lane.group(1))).get(b"type", b"")
        for w in _WIDTH.finditer(lane.group(3) or b""):
            attrs = {k.decode(): v.decode(errors="replace") for k, _, v in _ATTR.findall(w.group(0))}
            line = data.count(b"\n", 0, lane.start(3) + w.start()) + 1
            try:
                coef = [float(attrs.get(k, "0")) for k in "abcd"]
            except ValueError:
                raise ScenarioFileError(road, line, f"bad lane width a={attrs.get('a')!r}: not a number") from None
            a = coef[0]
            if not (0.0 <= a <= MAX_LANE_WIDTH) or not all(math.isfinite(c) for c in coef):
                raise ScenarioFileError(
                    road, line, f"bad lane width a={a:g} m (allowed: 0 to {MAX_LANE_WIDTH:g} m, finite coefficients)"
                )
            if kind == b"driving" and not any(coef):
                raise ScenarioFileError(
                    road, line, "bad lane width 0 m everywhere for a driving lane (allowed: more than 0 m)"
                )


_ROAD_TAG = re.compile(rb"<road\b[^>]*>")
_RULE = re.compile(rb"""\srule\s*=\s*(["'])(.*?)\1""")
_ROAD_ID = re.compile(rb"""\sid\s*=\s*(["'])(.*?)\1""")


def left_hand_roads(road: Path, data: bytes) -> frozenset[str]:
    """The ids of the roads of left-hand traffic (OpenDRIVE's ``rule="LHT"``; default ``RHT``:
    lanes ``+k`` driven along the reference line). Another rule is refused: ScenarioFileError
    naming its road's line."""
    out = set()
    for tag in _ROAD_TAG.finditer(data):
        rule = _RULE.search(tag.group(0))
        value = rule.group(2).strip().upper() if rule else b"RHT"
        if value == b"LHT":
            rid = _ROAD_ID.search(tag.group(0))
            out.add(rid.group(2).decode(errors="replace") if rid else "")
        elif value != b"RHT":
            line = data.count(b"\n", 0, tag.start()) + 1
            raise ScenarioFileError(
                road,
                line,
                f'<road rule="{rule.group(2).decode(errors="replace")}"> is not a traffic rule '  # type: ignore[union-attr]
                "(allowed: RHT, LHT)",
            )
    return frozenset(out)


def road_of_edge(edge: str) -> str:
    """The OpenDRIVE road of a converted edge (``-r``, ``r``, ``-r.S``, ``r#1`` ...)."""
    return edge.removeprefix("-").partition("#")[0].partition(".")[0]


#: the edge parameter marking an edge turned round for left-hand traffic (:func:`left_hand`)
LEFT_HAND = "ego.lefthand"


def left_hand(road: Path, net: Path, roads: frozenset[str]) -> None:
    """Turn round in ``net`` (netconvert's right-hand conversion of ``road``) every edge of the
    ``roads`` driven left-hand: netconvert reads every road right-hand (its ``--lefthand`` only
    mirrors the lanes about the edge's shape, off the road's left lanes), so its edge ``-r``
    (lanes -k) runs along the reference line and ``r`` (lanes +k) against it; left-hand traffic
    drives them the other way. Each such edge gets its ends swapped, its shape and its lanes'
    shapes reversed and its lanes renumbered so that index 0 is again the rightmost lane in its
    driving direction (the lane next to the centre line): SUMO's right-hand conventions (index
    + 1 is the lane to the left, a lateral offset + to the left) hold on the turned edges as on
    any, so ego's lane model reads them unchanged. Lane geometry, lane ids (``origId``) and
    widths stay netconvert's. Such a road joined to another at a junction is refused
    (ScenarioFileError): its connections would have to be turned round too."""
    tree = ET.parse(net)
    root = tree.getroot()
    turned = {}
    for e in root.iter("edge"):
        eid = e.get("id", "")
        if e.get("function") == "internal" or road_of_edge(eid) not in roads:
            continue
        turned[eid] = e
    for c in root.iter("connection"):
        for end in ("from", "to"):
            if c.get(end, "") in turned:
                name = road_of_edge(c.get(end, ""))
                raise ScenarioFileError(
                    road,
                    None,
                    f'road {name!r} is left-hand traffic (rule="LHT" or turned by its ego\'s heading) and joined to '
                    "another road at a junction: not supported by ego (left-hand roads without junctions only)",
                )

    def rev(shape: str | None) -> str | None:
        return None if shape is None else " ".join(reversed(shape.split()))

    for eid, e in turned.items():
        a, b = e.get("from", ""), e.get("to", "")
        e.set("from", b)
        e.set("to", a)
        if e.get("shape") is not None:
            e.set("shape", rev(e.get("shape")) or "")
        lanes = e.findall("lane")
        for child in lanes:
            e.remove(child)
        for i, ln in enumerate(reversed(lanes)):
            ln.set("id", f"{eid}_{i}")
            ln.set("index", str(i))
            if ln.get("shape") is not None:
                ln.set("shape", rev(ln.get("shape")) or "")
        for i, ln in enumerate(reversed(lanes)):
            e.insert(i, ln)
        ET.SubElement(e, "param", key=LEFT_HAND, value="true")
    ends: dict[str, list[str]] = {}
    for e in root.iter("edge"):
        if e.get("function") != "internal":
            ends.setdefault(e.get("to", ""), []).extend(ln.get("id", "") for ln in e.findall("lane"))
    for j in root.iter("junction"):
        if any(e.get("from") == j.get("id") or e.get("to") == j.get("id") for e in turned.values()):
            j.set("incLanes", " ".join(ends.get(j.get("id", ""), [])))
    tree.write(net, encoding="UTF-8", xml_declaration=True)


def for_netconvert(road: Path, data: bytes) -> bytes | None:
    """The copy of an OpenDRIVE file that netconvert converts (None: the file as it is):
    signals' empty types filled in (:func:`_signal_types`), roadside objects and the elevation
    profile left out (:data:`_OBJECTS`, :data:`_ELEVATION`) and direct junctions written as
    common ones (:func:`_direct_junctions`)."""
    out = _signal_types(data) or data
    out = _OBJECTS.sub(b"<objects/>", out)
    out = _ELEVATION.sub(b"", out)
    if _DIRECT.search(out):
        out = _direct_junctions(road, out)
    return None if out == data else out


#: a road's roadside objects (trees, fences, buildings): ego uses none, netconvert makes
#: polygons of them only for ``--polygon-output`` (not asked) and yet works through every one:
#: esmini's crest-curve.xodr repeats a fence with ``distance="0"`` and took netconvert past
#: 4 GiB; without its objects the same lanes convert in 0.5 s (tests/openscenario/test_xosc_roads.py)
_OBJECTS = re.compile(rb"<objects\b[^>]*?(?<!/)>.*?</objects\s*>", re.S)
#: a road's elevation profile: ego's roads are planar, and OpenDRIVE's ``s`` is measured in the
#: plane (a road's length is its plan view's); netconvert would make each lane's length the
#: length in space, so that SUMO's positions and speeds run along the slope (crest-curve.xodr:
#: lane -1 395.834 m long for a plan-view line of 395.208 m)
_ELEVATION = re.compile(rb"<elevationProfile\b[^>]*?/>|<elevationProfile\b.*?</elevationProfile\s*>", re.S)
_DIRECT = re.compile(rb"""<junction\b[^>]*\btype\s*=\s*["']direct["']""")
#: m: the length of the connecting road written for each connection of a direct junction
DIRECT_CONNECTOR = 0.01


def _direct_junctions(road: Path, data: bytes) -> bytes:
    """``data`` with each direct junction (OpenDRIVE 1.7: an incoming road's lanes run on
    into a linked road's, no connecting road between, a motorway's on- or off-ramp) written
    as a common junction that netconvert reads: each connection gets a connecting road of
    :data:`DIRECT_CONNECTOR` m on the linked road's start (its lanes, widths and lane offset
    there), linked lane by lane as the junction's ``laneLink``s say. The roads themselves,
    their ids and lanes are unchanged; netconvert joins them at one node as at any junction.
    A direct junction joining a road at its end (not its start) is refused: ScenarioFileError."""
    try:
        root = ET.fromstring(data)
    except ET.ParseError as e:
        raise ScenarioFileError(road, e.position[0], f"malformed XML: {e}") from None
    roads = {r.get("id"): r for r in root.iterfind("road")}
    for j in root.iterfind("junction"):
        if j.get("type") != "direct":
            continue
        jid = j.get("id", "")
        del j.attrib["type"]
        for i, c in enumerate(j.findall("connection")):
            incoming, linked = roads.get(c.get("incomingRoad")), roads.get(c.get("linkedRoad"))
            if incoming is None or linked is None or c.get("contactPoint", "start") != "start":
                raise ScenarioFileError(
                    road,
                    None,
                    f"direct junction {jid}: connection {c.get('id')} (incomingRoad {c.get('incomingRoad')!r}, "
                    f"linkedRoad {c.get('linkedRoad')!r}, contactPoint {c.get('contactPoint')!r}) is not supported "
                    "(ego reads direct junctions whose linked road starts at the junction)",
                )
            ends = {"successor": "end", "predecessor": "start"}
            at = next(
                (
                    ends[k]
                    for k in ends
                    if any(e.get("elementId") == jid for e in incoming.iterfind(f"link/{k}[@elementType='junction']"))
                ),
                "end",
            )
            cid = f"{jid}.direct{i}"
            to_from = {ll.get("to"): ll.get("from") for ll in c.iterfind("laneLink")}
            root.append(_connector(cid, jid, incoming.get("id", ""), at, linked, to_from))
            c.attrib.clear()
            c.attrib.update(id=str(i), incomingRoad=incoming.get("id", ""), connectingRoad=cid, contactPoint="start")
    return ET.tostring(root, encoding="utf-8", xml_declaration=True)


def _connector(cid: str, jid: str, incoming: str, at: str, linked: ET.Element, to_from: dict) -> ET.Element:
    """A connecting road of :data:`DIRECT_CONNECTOR` m on ``linked``'s start: its lanes carry
    the linked road's ids, types and widths there, each linked to the incoming lane ``to_from``
    names."""
    length = repr(DIRECT_CONNECTOR)
    new = ET.Element("road", name="", length=length, id=cid, junction=jid)
    link = ET.SubElement(new, "link")
    ET.SubElement(link, "predecessor", elementType="road", elementId=incoming, contactPoint=at)
    ET.SubElement(link, "successor", elementType="road", elementId=linked.get("id", ""), contactPoint="start")
    g0 = linked.find("planView/geometry")
    pose = {k: g0.get(k, "0") if g0 is not None else "0" for k in ("x", "y", "hdg")}
    ET.SubElement(ET.SubElement(new, "planView"), "geometry", s="0", length=length, **pose).append(ET.Element("line"))
    lanes = ET.SubElement(new, "lanes")
    offset = linked.find("lanes/laneOffset")
    if offset is not None:
        ET.SubElement(lanes, "laneOffset", s="0", a=offset.get("a", "0"), b="0", c="0", d="0")
    first, section = linked.find("lanes/laneSection"), ET.SubElement(lanes, "laneSection", s="0")
    for side in ("left", "center", "right"):
        src = first.find(side) if first is not None else None
        if src is None:
            continue
        dst = ET.SubElement(section, side)
        for lane in src.iterfind("lane"):
            lid = lane.get("id", "0")
            new_lane = ET.SubElement(dst, "lane", id=lid, type=lane.get("type", "none"), level="false")
            lane_link = ET.SubElement(new_lane, "link")
            if lid in to_from and lid != "0":
                ET.SubElement(lane_link, "predecessor", id=to_from[lid])
                ET.SubElement(lane_link, "successor", id=lid)
            width = lane.find("width")
            if width is not None:
                ET.SubElement(new_lane, "width", sOffset="0", a=width.get("a", "0"), b="0", c="0", d="0")
    return new


_EMPTY_TYPE = re.compile(rb"""(\s(?:sub)?type\s*=\s*)(["'])\2""")
_SIGNAL = re.compile(rb"<signal\b[^>]*>")


def _signal_types(data: bytes) -> bytes | None:
    """``data`` with every road signal's empty ``type``/``subtype`` written ``-1`` (OpenDRIVE's
    "none"; netconvert refuses the whole file over an empty one, and ego uses no signal), or
    None when there is none to fill in."""
    if b"<signal" not in data:
        return None
    fixed = _SIGNAL.sub(lambda m: _EMPTY_TYPE.sub(rb'\1"-1"', m.group(0)), data)
    return None if fixed == data else fixed


@dataclass(frozen=True)
class Lane:
    id: str  #: SUMO lane id
    edge: str
    index: int  #: SUMO index, 0 = rightmost
    length: float
    width: float
    shape: tuple[tuple[float, float], ...]
    orig: str  #: OpenDRIVE origin (road_section_lane) when converted, else ""
    kind: str = ""  #: the OpenDRIVE lane type netconvert records (driving, stop, border...), if any


@dataclass(frozen=True)
class Edge:
    id: str
    lanes: tuple[Lane, ...]  #: by SUMO index
    successors: tuple[str, ...]
    #: the edge's reference line in its driving direction: SUMO's edge shape (on a converted
    #: road OpenDRIVE's reference line; on ego's motorways the road's centre line), or, where a
    #: network writes none, the border of its lane next to the centre line (the left border of
    #: its leftmost lane; on an edge turned round for left-hand traffic the right border of lane 0)
    shape: tuple[tuple[float, float], ...] = ()
    #: turned round for left-hand traffic (:func:`left_hand`): driven the other way than
    #: netconvert's edge of that name, its lane index 0 next to the centre line
    left_hand: bool = False


def _parse(net: Path) -> ET.Element:
    try:
        return ET.parse(net).getroot()
    except ET.ParseError as exc:
        raise ScenarioFileError(net, exc.position[0], f"malformed SUMO network: {exc}") from None


@lru_cache(maxsize=8)
def _edges_cached(net: str, mtime: float) -> dict[str, Edge]:
    root = _parse(Path(net))
    succ: dict[str, list[str]] = {}
    for c in root.iter("connection"):
        f, t = c.get("from", ""), c.get("to", "")
        if not f.startswith(":") and not t.startswith(":") and t not in succ.setdefault(f, []):
            succ[f].append(t)
    edges: dict[str, Edge] = {}
    for e in root.iter("edge"):
        if e.get("function") == "internal":
            continue
        eid = e.get("id", "")
        lanes = []
        # netconvert's edge type: the lanes' OpenDRIVE types by index ("a|b|c"), or one for all
        kinds = e.get("type", "").split("|")
        if len(kinds) == 1:
            kinds *= len(e.findall("lane"))
        for ln in e.iter("lane"):
            pts = tuple((float(p.split(",")[0]), float(p.split(",")[1])) for p in ln.get("shape", "").split())
            orig = next((p.get("value", "") for p in ln.iter("param") if p.get("key") == "origId"), "")
            lanes.append(
                Lane(
                    ln.get("id", ""),
                    eid,
                    int(ln.get("index", "0")),
                    float(ln.get("length", "0")),
                    float(ln.get("width", "3.2")),
                    pts,
                    orig,
                    kinds[int(ln.get("index", "0"))] if len(kinds) == len(e.findall("lane")) else "",
                )
            )
        lanes.sort(key=lambda lane: lane.index)
        shape = tuple((float(p.split(",")[0]), float(p.split(",")[1])) for p in e.get("shape", "").split())
        lht = any(p.get("key") == LEFT_HAND and p.get("value") == "true" for p in e.findall("param"))
        inner = lanes[0] if lht else lanes[-1] if lanes else None  # the lane next to the centre line
        if len(shape) < 2 and inner is not None and len(inner.shape) >= 2:
            from ego.lane_frame import LanePolyline

            side = LanePolyline(inner.shape)
            at = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(np.asarray(side.points), axis=0).T))))
            half = -0.5 * inner.width if lht else 0.5 * inner.width
            shape = tuple(side.offset_point(float(s), half) for s in at)
        edges[eid] = Edge(eid, tuple(lanes), tuple(succ.get(eid, ())), shape, lht)
    return edges


def _edges(net: Path) -> dict[str, Edge]:
    return _edges_cached(str(net), net.stat().st_mtime)


@dataclass(frozen=True)
class Link:
    """One lane's connection to a lane of the next edge: SUMO's ``<connection>``."""

    to: str  #: the next edge
    to_lane: int  #: its lane's index
    via: tuple[str, ...]  #: the internal lanes through the junction, in driving order


@lru_cache(maxsize=8)
def _links_cached(net: str, mtime: float) -> tuple[dict[tuple[str, int], tuple[Link, ...]], dict[str, tuple]]:
    """(edge, lane index) -> its connections to the next edges' lanes (through the internal
    lanes of the junction between), and the internal lanes' shapes (lane id -> points)."""
    root = _parse(Path(net))
    inner: dict[str, tuple] = {}
    for e in root.iter("edge"):
        if e.get("function") == "internal":
            for ln in e.iter("lane"):
                inner[ln.get("id", "")] = tuple(
                    (float(p.split(",")[0]), float(p.split(",")[1])) for p in ln.get("shape", "").split()
                )
    onward: dict[tuple[str, int], tuple[str, str, int]] = {}  # internal lane -> its next (via, edge, lane)
    raw = []
    for c in root.iter("connection"):
        f, t, via = c.get("from", ""), c.get("to", ""), c.get("via", "")
        fl, tl = int(c.get("fromLane", "0")), int(c.get("toLane", "0"))
        if f.startswith(":"):
            onward[(f, fl)] = (via, t, tl)
        elif not t.startswith(":"):
            raw.append((f, fl, t, tl, via))
    links: dict[tuple[str, int], list[Link]] = {}
    for f, fl, t, tl, via in raw:
        chain: list[str] = []
        while via and via not in chain and via in inner:
            chain.append(via)
            edge, _, index = via.rpartition("_")
            via = onward.get((edge, int(index)), ("", t, tl))[0]
        links.setdefault((f, fl), []).append(Link(t, tl, tuple(chain)))
    return {k: tuple(v) for k, v in links.items()}, inner


@lru_cache(maxsize=8)
def _connecting_roads(source: str) -> dict[tuple[str, str], float]:
    """(predecessor road, successor road) -> length of each connecting road (a road of a
    junction) of the OpenDRIVE file ``source``."""
    out: dict[tuple[str, str], float] = {}
    for r in ET.parse(source).getroot().iter("road"):
        link = r.find("link")
        if r.get("junction", "-1") == "-1" or link is None:
            continue
        ends = [link.find(k) for k in ("predecessor", "successor")]
        if all(e is not None and e.get("elementType") == "road" for e in ends):
            key = (ends[0].get("elementId", ""), ends[1].get("elementId", ""))  # type: ignore[union-attr]
            out[key] = min(out.get(key, math.inf), float(r.get("length", "0")))
    return out


class RoadMap:
    """OpenDRIVE lane positions on a SUMO network (a converted ``.xodr`` or a ``.net.xml``).

    On a converted road, OpenDRIVE road ``r``'s right-hand lanes are the SUMO edge ``-r``
    (``-r.S`` for a later lane section starting at S), its left-hand lanes the edge ``r``;
    lane -1 (next to the reference line) is SUMO's leftmost lane of ``-r``. On a road of
    left-hand traffic (:func:`left_hand`) ``r`` runs along the reference line and ``-r``
    against it, and lane +1 is SUMO's rightmost lane of ``r``. On a SUMO network the road id
    is the edge id and lane -k is the k-th lane from the left.
    """

    def __init__(
        self,
        net: Path,
        converted: bool,
        source: Path | None = None,
        every_lane: bool = False,
        by_heading: frozenset[str] = frozenset(),
    ) -> None:
        self.net, self.converted = net, converted
        #: the OpenDRIVE file ``net`` was converted from (where a lane netconvert drops is found)
        self.source = source
        #: whether ``net`` has every OpenDRIVE lane (:data:`ALL_LANES`)
        self.every_lane = every_lane
        self._every: RoadMap | None = None
        #: the right-hand roads read as left-hand traffic for the ego's heading (:func:`left_hand`)
        self.by_heading = by_heading
        self.edges = _edges(net)
        self.links, self.inner = _links_cached(str(net), net.stat().st_mtime)
        self._refs: dict[str, object] = {}
        self._tables: dict[str, tuple[np.ndarray, np.ndarray, float]] = {}
        self._deltas: dict[str, tuple[np.ndarray, np.ndarray]] = {}  #: lane -> (g - u, u - g) at the knots
        self._of_edge: dict[str, tuple[str, float, bool]] = {}

    # -- road s and lane positions -----------------------------------------------------------
    # OpenDRIVE's s runs along the road's reference line; a lane's point at road s is where
    # the reference line's normal at s crosses the lane (the lanes are parallel to it). SUMO
    # measures a lane by its ``length`` attribute, which netconvert makes the same for every
    # lane of an edge (the mean of their shapes' lengths, docs: Simulation/Distances), so
    # SUMO's position p on a lane is the point ``p * shape length / length`` along its shape.

    def reference(self, edge: str):
        """The reference line of ``edge`` (its driving direction) as a LanePolyline."""
        from ego.lane_frame import LanePolyline

        ref = self._refs.get(edge)
        if ref is None:
            e = self.edges[edge]
            ref = self._refs[edge] = LanePolyline(e.shape if len(e.shape) >= 2 else e.lanes[-1].shape)
        return ref

    def _table(self, lane: Lane) -> tuple[np.ndarray, np.ndarray, float]:
        """(u, g, shape length) of ``lane``: knots u along the edge's reference line and g
        along the lane's shape of the same road s (increasing), to interpolate between.

        Two parallel curves at lateral offset t advance as dg = du - t dtheta (theta the
        reference line's heading), so g is the lane's start (its first point projected onto the
        reference line) plus u less the integral of t dtheta from there. The reference line is
        netconvert's polyline: its heading is taken exact at each short chord's middle (a chord
        of a circle points along the tangent there) and along a long chord (a straight), linear
        between; t is the lane's offset from the reference line where its points project. A
        projection alone would move a point on the normal of the chord, not of the curve:
        8.75 m beside a 0.5 m chord of R = 195 m that is 1.1 cm along the road."""
        hit = self._tables.get(lane.id)
        if hit is None:
            pts = np.asarray(lane.shape, dtype=float)
            g_len = float(np.hypot(*np.diff(pts, axis=0).T).sum())
            ref = self.reference(lane.edge)
            proj = np.array([ref.project(float(x), float(y))[:2] for x, y in pts])
            lane_u, lane_t = np.maximum.accumulate(proj[:, 0]), proj[:, 1]
            rp = np.asarray(ref.points, dtype=float)
            chord = np.hypot(*np.diff(rp, axis=0).T)
            at = np.concatenate(([0.0], np.cumsum(chord)))
            angle = np.unwrap(np.arctan2(*np.diff(rp, axis=0).T[::-1]))
            knots: list[tuple[float, float]] = []
            for i, c in enumerate(chord):
                if c > LONG_CHORD:
                    knots += [(at[i], angle[i]), (at[i + 1], angle[i])]
                else:
                    knots.append((at[i] + 0.5 * c, angle[i]))
            ku = np.array([k[0] for k in knots])
            kh = np.array([k[1] for k in knots])
            u0, u1 = lane_u[0], lane_u[0] + g_len + abs(lane_t).max() * (abs(np.diff(kh)).sum() + 1.0)
            inside = (ku > u0) & (ku < u1)
            us = np.concatenate(([u0], ku[inside], [u1]))
            theta = np.interp(us, ku, kh)
            tt = np.interp(us, lane_u, lane_t)
            turn = np.concatenate(([0.0], np.cumsum(0.5 * (tt[1:] + tt[:-1]) * np.diff(theta))))
            gs = us - u0 - turn
            keep = np.concatenate(([True], np.diff(gs) > 1e-12))  # increasing for the inverse
            hit = self._tables[lane.id] = (us[keep], gs[keep], g_len)
        return hit

    def _delta(self, lane: Lane) -> tuple[np.ndarray, np.ndarray]:
        hit = self._deltas.get(lane.id)
        if hit is None:
            us, gs, _ = self._table(lane)
            hit = self._deltas[lane.id] = (gs - us, us - gs)
        return hit

    def shape_length(self, lane: Lane) -> float:
        """The geometric length (m) of ``lane``'s shape."""
        return self._table(lane)[2]

    def to_sumo(self, lane: Lane, g: float) -> float:
        """SUMO's lane position of the point ``g`` m along ``lane``'s shape."""
        geom = self.shape_length(lane)
        return g if abs(lane.length - geom) <= 1e-9 * geom else g * lane.length / geom

    def from_sumo(self, lane: Lane, pos: float) -> float:
        """The arc length (m) along ``lane``'s shape of SUMO's lane position ``pos``."""
        geom = self.shape_length(lane)
        return pos if abs(lane.length - geom) <= 1e-9 * geom else pos * geom / lane.length

    def _along_shape(self, lane: Lane, u: float, clamp: bool = True) -> float:
        """g along ``lane``'s shape where the reference line's normal at ``u`` crosses it
        (within the shape unless ``clamp`` is false)."""
        us, gs, geom = self._table(lane)
        if u <= us[0]:
            g = float(gs[0] + (u - us[0]))
        elif u >= us[-1]:
            g = float(gs[-1] + (u - us[-1]))
        else:
            g = u + float(np.interp(u, us, self._delta(lane)[0]))
        return min(max(g, 0.0), geom) if clamp else g

    def shape_s(self, lane: Lane, u: float) -> float:
        """The inverse of :meth:`reference_s` (not clamped to the shape)."""
        return self._along_shape(lane, u, clamp=False)

    def is_parallel_copy(self, lane: Lane) -> bool:
        """Whether ``lane``'s shape advances exactly as its reference line (a straight lane
        starting beside the reference line's start): :meth:`reference_s` is then g itself."""
        us, gs, _ = self._table(lane)
        return bool(np.array_equal(us, gs))

    def reference_s(self, lane: Lane, g: float) -> float:
        """The arc length u along its edge's reference line (in the edge's driving
        direction) of the point ``g`` m along ``lane``'s shape: road s less the edge's start,
        or, on a lane driven against s, from the edge's start the other way."""
        return self._along_reference(lane, g)

    def _along_reference(self, lane: Lane, g: float) -> float:
        """u along the edge's reference line of the point ``g`` along ``lane``'s shape."""
        us, gs, _ = self._table(lane)
        if g <= gs[0]:
            return float(us[0] + (g - gs[0]))
        if g >= gs[-1]:
            return float(us[-1] + (g - gs[-1]))
        return g + float(np.interp(g, gs, self._delta(lane)[1]))

    def road_s(self, lane: Lane, g: float) -> float:
        """OpenDRIVE's road s (m, along the reference line) of the point ``g`` m along
        ``lane``'s shape (the inverse of :meth:`lane_s`)."""
        _, start, right = self._section(lane.edge)
        u = self._along_reference(lane, g)
        return start + u if right else start + self.reference(lane.edge).length - u

    def moved(self, lane: Lane, g: float, ds: float = 0.0, to: Lane | None = None) -> float:
        """The arc length along ``to``'s shape (default ``lane``, a lane of the same edge) of
        the point ``ds`` m of road s (along the reference line, in the edge's driving
        direction) on from the point ``g`` along ``lane``'s shape."""
        return self._along_shape(to or lane, self._along_reference(lane, g) + ds)

    def from_centre(self, edge: str) -> list[Lane]:
        """The lanes of ``edge`` from the road's centre line outwards."""
        e = self.edges[edge]
        return list(e.lanes) if e.left_hand else list(reversed(e.lanes))

    def _section(self, edge: str) -> tuple[str, float, bool]:
        """(road, start s, driven along s) of ``edge``."""
        hit = self._of_edge.get(edge)
        if hit is None:
            if self.converted:
                name = edge.removeprefix("-").partition("#")[0].partition(".")[0]
                names = [name]
            else:
                parts = edge.split(".")
                names = [".".join(parts[:k]) for k in range(len(parts), 0, -1)]
            for name in names:
                for start, e, right in self.sections(name):
                    self._of_edge.setdefault(e.id, (name, start, right))
            hit = self._of_edge.get(edge, (edge, 0.0, True))
        return hit

    def sections(self, road: str) -> list[tuple[float, Edge, bool]]:
        """(start s, edge, driven along s) of the road's edges, by start."""
        if not self.converted:
            # a road cut into edges road, road.1, road.2, ... (ego's curved motorways,
            # sumo_nets/motorway_arcs.py): each starts where the one before ends
            out, s0 = [], 0.0
            e = self.edges.get(road)
            while e is not None:
                out.append((s0, e, True))
                s0 += self.reference(e.id).length if e.lanes else 0.0
                e = self.edges.get(f"{road}.{len(out)}")
            return out
        # netconvert splits some roads (a road that loops onto itself: ``-1#0``, ``-1#1``):
        # the pieces of one lane section follow each other in driving order, so a piece
        # starts where the ones before it end (on the side driven against s, the other way)
        pieces: dict[tuple[float, bool], list[tuple[int, Edge]]] = {}
        for eid, e in self.edges.items():
            right = eid.startswith("-")
            base, _, piece = (eid[1:] if right else eid).partition("#")
            name, _, start = base.partition(".")
            if name == road and e.lanes:
                try:
                    key = (float(start) if start else 0.0, right)
                    pieces.setdefault(key, []).append((int(piece) if piece else 0, e))
                except ValueError:
                    continue
        out = []
        for (start, right), parts in pieces.items():
            parts.sort(key=lambda x: x[0])
            if not right:
                parts.reverse()  # netconvert's edge against s: the last piece starts the section
            s0 = start
            for _, e in parts:
                out.append((s0, e, right != e.left_hand))
                s0 += self.reference(e.id).length
        return sorted(out, key=lambda x: x[0])

    def lane_position(self, road: str, lane: int, s: float) -> tuple[Lane, float]:
        """The SUMO lane and SUMO's position along it of OpenDRIVE (road, lane, s) (of a lane
        netconvert drops: the nearest lane of the network there, :meth:`lane_s_offset`)."""
        sumo_lane, g, _ = self.lane_s_offset(road, lane, s)
        return sumo_lane, self.to_sumo(sumo_lane, g)

    def every_lane_map(self) -> RoadMap | None:
        """The same road converted with every OpenDRIVE lane (:data:`ALL_LANES`; converted
        and cached when first asked), or None for a SUMO network."""
        if self._every is None and self.converted and self.source is not None and not self.every_lane:
            self._every = RoadMap(
                network_file(self.source, self.by_heading, all_lanes=True),
                True,
                self.source,
                every_lane=True,
                by_heading=self.by_heading,
            )
        return self._every

    def dropped_lane(self, road: str, lane: int, s: float) -> Lane | None:
        """The lane (of :meth:`every_lane_map`) of OpenDRIVE (road, lane, s) when netconvert
        drops it from the network (a border, shoulder, sidewalk... lane), else None. A lane the
        OpenDRIVE file does not have either is the ValueError naming the lanes it has."""
        try:
            self.lane_s(road, lane, s)
            return None
        except ValueError:
            every = self.every_lane_map()
            if every is None or lane == 0:
                raise
        return every.lane_s(road, lane, s)[0]

    def lane_s_offset(self, road: str, lane: int, s: float) -> tuple[Lane, float, float]:
        """(SUMO lane, arc length along its shape, offset) of OpenDRIVE (road, lane, s): the
        lane's point at road s is ``offset`` m left of that lane's centre there. For a lane of
        the network (:meth:`lane_s`) the offset is 0; a lane netconvert drops (a border,
        shoulder, sidewalk... lane, which no SUMO driver may drive) is the lane of the network
        nearest to it on its side (by lane id: -7 of a road whose outermost is -5 is -5) with the
        dropped lane's centre as the offset, from the road converted with every lane
        (:meth:`every_lane_map`: its lanes of the network are these, within 1e-5 m)."""
        far = self.dropped_lane(road, lane, s)
        if far is None:
            sumo_lane, g = self.lane_s(road, lane, s)
            return sumo_lane, g, 0.0
        every = self.every_lane_map()
        assert every is not None  # dropped_lane found it there
        _, gf = every.lane_s(road, lane, s)
        # the side's lanes of the network there (a side with none: the other side's)
        every_sec = self.sections(road)
        secs = [x for x in every_sec if x[2] == (lane < 0)] or every_sec
        ids = []
        for right in (True, False):
            side = [x for x in secs if x[2] == right]
            if side:
                edge = side[0][1]
                for x in side:
                    if x[0] <= s + 1e-9:
                        edge = x[1]
                ids += [self.lane_id_of(ln) for ln in edge.lanes]
        if not ids:
            raise ValueError(
                f"road {road!r} has no lane netconvert makes (lane {lane} is a{'n' if far.kind[:1] in 'aeiou' else ''} "
                f"{far.kind or 'non-driving'} lane): ego places an entity on such a lane beside a lane of the network"
            )
        near = min(ids, key=lambda k: (abs(k - lane), abs(k)))
        kept, g = self.lane_s(road, near, s)
        from ego.lane_frame import LanePolyline

        x, y = LanePolyline(far.shape, far.width, far.id).offset_point(gf, 0.0)
        _, d, _ = LanePolyline(kept.shape, kept.width, kept.id).project(x, y)
        return kept, g, d

    def lane_s(self, road: str, lane: int, s: float) -> tuple[Lane, float]:
        """The SUMO lane of OpenDRIVE (road, lane, s) and the arc length (m) along its shape
        of the lane's point at road s (where the reference line's normal at s crosses it)."""
        if lane == 0:
            raise ValueError("lane 0 is the reference line, not a lane")
        every = self.sections(road)
        # the edges of the lane's side: on a converted road ``-r`` holds lanes -k (and runs
        # along s unless the road is left-hand); a SUMO network's road holds lanes -k only
        secs = [x for x in every if (x[1].id.startswith("-") if self.converted else True) == (lane < 0)]
        if every and not secs:
            ids = sorted({self.lane_id_of(ln) for x in every for ln in x[1].lanes}, key=abs)
            raise ValueError(
                f"road {road!r} has no lanes with {'negative' if lane < 0 else 'positive'} ids "
                f"(lane ids {', '.join(map(str, ids))})"
            )
        if not secs:
            known = sorted(
                {(eid.removeprefix("-")).partition("#")[0].partition(".")[0] for eid in self.edges}
                if self.converted
                else self.edges
            )
            raise ValueError(f"unknown road {road!r} (roads: {', '.join(known)})")
        start, edge, right = secs[0]
        for x in secs:
            if x[0] <= s + 1e-9:
                start, edge, right = x
        out = self.from_centre(edge.id)
        ids = [self.lane_id_of(ln) for ln in out]  # from the reference line out
        if lane not in ids:
            raise ValueError(
                f"road {road!r} has no lane {lane} on that side at s = {s:g} "
                f"(lane ids {', '.join(map(str, ids))}"
                + (", of every type)" if self.every_lane else "; netconvert keeps driving and stop lanes)")
            )
        sumo_lane = out[ids.index(lane)]
        u = s - start if right else self.reference(edge.id).length - (s - start)
        return sumo_lane, self._along_shape(sumo_lane, u)

    def t_position(self, road: str, s: float, t: float) -> tuple[Lane, float, float]:
        """The point ``t`` m left of road ``road``'s reference line at road s (OpenDRIVE's
        RoadPosition) on SUMO's lane -1: (that lane, the arc length along its shape, the
        offset from its centre, + left in its driving direction: against s on a left-hand road)."""
        lane, g = self.lane_s(road, -1, s)
        d = t + 0.5 * lane.width
        return lane, g, d if self._section(lane.edge)[2] else -d

    def lane_id_of(self, sumo_lane: Lane) -> int:
        """The OpenDRIVE lane id of a SUMO lane: its origin's (netconvert keeps only some lane
        types: a road's border lanes next to the reference line have no SUMO lane), else by
        count (-1 = leftmost of its edge)."""
        tail = sumo_lane.orig.rpartition("_")[2] if self.converted else ""
        if tail.lstrip("-").isdigit():
            return int(tail)
        edge = self.edges[sumo_lane.edge]
        k = sumo_lane.index + 1 if edge.left_hand else len(edge.lanes) - sumo_lane.index
        return -k if (not self.converted or sumo_lane.edge.startswith("-")) else k

    def route_from(self, edge: str, limit: int = 64) -> list[str]:
        """``edge`` and its successors as long as each has one (the way straight on)."""
        route = [edge]
        while len(route) < limit:
            nxt = self.edges[route[-1]].successors
            if len(nxt) != 1 or nxt[0] in route:
                break
            route.append(nxt[0])
        return route

    def lane_route(self, edge: str, index: int, limit: int = 64) -> list[tuple[str, int, tuple[str, ...]]]:
        """The way lane ``index`` of ``edge`` drives on: (edge, lane index, the internal lanes
        from the one before) of its lane's successors, each edge once. Where the lane has
        connections to more than one edge, the straightest (the least heading change from the
        lane's end to the next lane's start: the way on, as SUMO's ``dir="s"``). A lane that
        ends with no connection (a merge lane, an on-ramp's once it has joined the motorway)
        goes on by the nearest lane beside it on its edge that has one (the left first: where a
        driver merges; :meth:`route_keys` numbers the lanes across that step); the route ends
        where no lane of the edge goes on (a dead end) or at a lane leading back onto it (a loop)."""
        route = [(edge, index, ())]
        seen = {edge}
        while len(route) < limit:
            e, i, _ = route[-1]
            n = len(self.edges[e].lanes)
            links: list[Link] = []
            for j in sorted(range(n), key=lambda j: (abs(j - i), j < i)):
                links = [k for k in self.links.get((e, j), ()) if k.to not in seen and k.to in self.edges]
                if links:
                    break
            here = self.edges[e].lanes[j].shape if links else ()
            if not links or len(here) < 2:
                break
            out = _direction(here[-2], here[-1])
            best = min(links, key=lambda k: abs(math.remainder(self._heading_in(k) - out, math.tau)))
            route.append((best.to, best.to_lane, best.via))
            seen.add(best.to)
        return route

    def route_keys(self, route: list[tuple[str, int, tuple[str, ...]]], key: int) -> list[int]:
        """The number of the route's lane on each of its edges in a numbering of lanes across the
        route that starts with ``key`` for its first lane and counts lanes from the right (SUMO's
        index): the same number on every edge for a lane that goes on, one more past a step to
        the lane on the left (:meth:`lane_route` past a lane that ends)."""
        keys = [key]
        for (e, i, _), (nxt, to_lane, _) in zip(route, route[1:]):
            step = 0
            if not any(k.to == nxt and k.to_lane == to_lane for k in self.links.get((e, i), ())):
                step = next(
                    (
                        j - i
                        for j in range(len(self.edges[e].lanes))
                        if any(k.to == nxt and k.to_lane == to_lane for k in self.links.get((e, j), ()))
                    ),
                    0,
                )
            keys.append(keys[-1] + step)
        return keys

    def _heading_in(self, link: Link) -> float:
        """The direction (rad) a connection starts in: its first internal lane's, else its lane's."""
        shape = self.inner[link.via[0]] if link.via else self.edges[link.to].lanes[link.to_lane].shape
        return _direction(shape[0], shape[1])

    def beside(
        self, route: list[tuple[str, int, tuple[str, ...]]], index: int
    ) -> list[tuple[str, int, tuple[str, ...]]]:
        """Lane ``index`` of the route's first edge along the same edges as ``route`` (a
        :meth:`lane_route`), as far as its lane connects to the next of them."""
        return self._along(route, index)

    def beside_from(
        self, route: list[tuple[str, int, tuple[str, ...]]], keys: list[int], key: int
    ) -> list[tuple[str, int, tuple[str, ...]]]:
        """Lane ``key`` of the route's lane numbering (:meth:`route_keys`: ``keys``), from the
        first of the route's edges that has it (a lane that begins after a merge: the
        motorway's lanes beside an on-ramp's), along the same edges as far as its lane connects
        to the next of them; empty when no edge of the route has it."""
        for j, ((e, i, _), r) in enumerate(zip(route, keys)):
            if 0 <= i + key - r < len(self.edges[e].lanes):
                return self._along(route[j:], i + key - r)
        return []

    def _along(
        self, route: list[tuple[str, int, tuple[str, ...]]], index: int
    ) -> list[tuple[str, int, tuple[str, ...]]]:
        out = [(route[0][0], index, ())]
        for nxt, _, _ in route[1:]:
            e, i, _ = out[-1]
            link = next((k for k in self.links.get((e, i), ()) if k.to == nxt), None)
            if link is None:
                break
            out.append((nxt, link.to_lane, link.via))
        return out

    def route_points(self, route: list[tuple[str, int, tuple[str, ...]]]) -> list[tuple[float, float]]:
        """The centre line along a :meth:`lane_route`: its lanes' and internal lanes' points in
        driving order, a point where one piece ends and the next starts taken once.

        Where the next piece starts a little behind the end of the one before (netconvert
        ends a road's lane a few mm past where the next road's starts: soderleden.xodr's ramp,
        road 1 into road 5, 6 mm), its points up to the join are left out: kept, they fold the
        line back on itself, a segment pointing backwards whose two vertices turn the lane
        by +-pi, and the frame's curvature there spikes (0.3 1/m over 0.25 m once refined)."""
        pts: list[tuple[float, float]] = []
        for e, i, via in route:
            for shape in (*(self.inner[v] for v in via), self.edges[e].lanes[i].shape):
                joined = len(pts) < 2  # past the join: the piece's points are taken as they are
                for p in shape:
                    if not pts or math.dist(pts[-1], p) > 1e-3:
                        if not joined and _behind(pts[-2], pts[-1], p):
                            continue
                        joined = True
                        pts.append(p)
        return pts

    def path(self, edges: list[str]) -> list[str] | None:
        """The shortest way (by length) from the first edge through each of the others in turn,
        every edge once where consecutive ones meet; None when one cannot be reached."""
        import heapq

        out = [edges[0]]
        for goal in edges[1:]:
            start = out[-1]
            if goal == start:
                continue
            dist, prev, heap = {start: 0.0}, {}, [(0.0, start)]
            while heap:
                d, e = heapq.heappop(heap)
                if e == goal:
                    break
                if d > dist.get(e, math.inf):
                    continue
                for nxt in self.edges[e].successors:
                    nd = d + self.edges[nxt].lanes[0].length
                    if nd < dist.get(nxt, math.inf):
                        dist[nxt], prev[nxt] = nd, e
                        heapq.heappush(heap, (nd, nxt))
            if goal not in prev:
                return None
            leg = [goal]
            while leg[-1] != start:
                leg.append(prev[leg[-1]])
            out += leg[-2::-1]
        return out

    def along_way(self, path: list[str], s0: float, s1: float, distance: float) -> tuple[str, float]:
        """(OpenDRIVE road, road s) of the point ``distance`` m along the way ``path`` (edges,
        :meth:`path`) from road s ``s0`` on its first edge to road s ``s1`` on its last, each
        edge in its driving direction and a junction by its length (:meth:`junction_length`).
        ValueError for a point inside a junction or past ``s1``."""
        left = distance
        for k, edge in enumerate(path):
            road, start, along = self._section(edge)
            length = self.reference(edge).length
            if k:
                gap = self.junction_length(path[k - 1], edge)
                if left < gap:
                    raise ValueError(
                        f"pathS {distance:g} lies {left:.2f} m into the junction between roads "
                        f"{road_of_edge(path[k - 1])!r} and {road!r} ({gap:.2f} m): ego places entities on roads"
                    )
                left -= gap
                here = start if along else start + length
            else:
                here = s0
            end = s1 if k == len(path) - 1 else start + length if along else start
            room = end - here if along else here - end
            if left <= room + 1e-9:
                return road, here + left if along else here - left
            left -= room
        raise ValueError(
            f"pathS {distance:g} is beyond the route's end (its path through its waypoints is "
            f"{distance - left:.2f} m long)"
        )

    def junction_length(self, a: str, b: str) -> float:
        """The length (m) of the way through the junction between edge ``a`` and its successor
        ``b`` (0 where they meet without one): the OpenDRIVE connecting road joining their roads
        (the shortest of several), else SUMO's internal lanes' (a SUMO network)."""
        vias = [k.via for i in range(len(self.edges[a].lanes)) for k in self.links.get((a, i), ()) if k.to == b]
        if not vias or not any(vias):
            return 0.0
        if self.converted and self.source is not None:
            ends = {road_of_edge(a), road_of_edge(b)}
            found = [n for (p, q), n in _connecting_roads(str(self.source)).items() if {p, q} == ends]
            if found:
                return min(found)
        from ego.lane_frame import LanePolyline

        return min(sum(LanePolyline(self.inner[v]).length for v in via) for via in vias if via)

    def nearest_lane(self, x: float, y: float) -> tuple[Lane, float, float]:
        """The lane whose centre line is nearest to (x, y): (lane, s along its shape, d + left)."""
        from ego.lane_frame import LanePolyline

        best = None
        for e in self.edges.values():
            for ln in e.lanes:
                if len(ln.shape) < 2:
                    continue
                s, d, _ = LanePolyline(ln.shape, ln.width, ln.id).project(x, y)
                # the distance to the lane's centre line itself, not to its extension beyond
                # an end (a point past the end of a road is nearer the road that goes on)
                length = self.shape_length(ln)
                dist = math.hypot(max(-s, s - length, 0.0), d)
                s = min(max(s, 0.0), length)
                if best is None or dist < best[3]:
                    best = (ln, s, d, dist)
        if best is None:
            raise ValueError("the road has no lanes")
        return best[0], best[1], best[2]


#: m: how far a piece may start behind the end of the one before for its points there to be
#: left out (:meth:`RoadMap.route_points`); netconvert's overlaps are millimetres
OVERLAP = 0.5


def _behind(a: tuple[float, float], b: tuple[float, float], p: tuple[float, float]) -> bool:
    """Whether ``p`` lies within :data:`OVERLAP` of ``b`` and not ahead of it along ``a`` -> ``b``."""
    dx, dy = p[0] - b[0], p[1] - b[1]
    return dx * dx + dy * dy <= OVERLAP * OVERLAP and dx * (b[0] - a[0]) + dy * (b[1] - a[1]) <= 0.0


def _direction(a: tuple[float, float], b: tuple[float, float]) -> float:
    return math.atan2(b[1] - a[1], b[0] - a[0])


def curvature_error(shape, analytic) -> float:
    """Largest |curvature - analytic(s)| of ego's lane frame over a lane shape (1/m), ``analytic``
    a function of the arc length (a test's and the docs' check of a converted road)."""
    from ego.lane_frame import LanePolyline

    lane = LanePolyline(shape)
    worst = 0.0
    n = max(2, int(lane.length / 0.25))
    for i in range(1, n):
        s = lane.length * i / n
        worst = max(worst, abs(lane.curvature_at(s) - analytic(s)))
    return worst


def refine_shape(points, step: float = 0.25, ratio: float = 3.0, longest: float = 5.0) -> list[tuple[float, float]]:
    """A lane shape whose curved runs are resampled every ``step`` (m) along a cubic spline
    through their points.

    netconvert samples an OpenDRIVE curve with a step that changes along it (a clothoid:
    2 m, then 1 m, then 0.5 m as its curvature grows), and ego's lane frame reads curvature
    from the heading change between segments: where the step changes, unequal neighbours
    bias the heading at their shared vertex and the curvature spikes. A run is a stretch of
    segments shorter than ``longest`` whose neighbours' lengths differ by at most ``ratio``
    (netconvert's samples of one curve); its points are on the curve (within 0.1 mm), so a
    not-a-knot cubic spline through them (parametrised by chord length) and resampled evenly
    gives the lane frame even steps. Long segments (straights) and their ends stay as they
    are."""
    from scipy.interpolate import CubicSpline

    pts = np.asarray(points, dtype=float)
    n = len(pts)
    if n < 4:
        return [(float(x), float(y)) for x, y in pts]
    lengths = np.hypot(*np.diff(pts, axis=0).T)
    out = [(float(pts[0, 0]), float(pts[0, 1]))]
    i = 0
    while i < n - 1:
        j = i
        while (
            j + 1 < n - 1
            and lengths[j] < longest
            and lengths[j + 1] < longest
            and 1.0 / ratio <= lengths[j + 1] / lengths[j] <= ratio
        ):
            j += 1
        if j - i >= 2:  # segments i..j: points i..j+1
            u = np.concatenate(([0.0], np.cumsum(lengths[i : j + 1])))
            spline = CubicSpline(u, pts[i : j + 2], axis=0, bc_type="not-a-knot")
            m = max(1, math.ceil(u[-1] / step))
            out.extend((float(x), float(y)) for x, y in spline(np.linspace(0.0, u[-1], m + 1)[1:]))
        else:
            out.extend((float(x), float(y)) for x, y in pts[i + 1 : j + 2])
        i = j + 1
    return out
