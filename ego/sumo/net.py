"""SUMO networks shipped with ego: where they are and how they are built.

Each network lives in ``sumo_nets/<name>/`` as plain XML sources (``<name>.nod.xml``,
``<name>.edg.xml``, ...) plus a netconvert configuration ``<name>.netccfg``; the built
``<name>.net.xml`` is committed next to them and rebuilt with ``python sumo_nets/build.py``.
An installed ego (a wheel) carries the folder as its package ``ego.sumo_nets``.
"""

from __future__ import annotations

import os
import re
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

from ego.params import ConfigError, did_you_mean

#: ``--set road=`` of the motorway scenarios (emergency-brake, fast-follower, cut-in) -> the
#: network it drives on: the straight motorway, or it bent into an arc of the middle lane's
#: radius 250 m or 1000 m, left or right, after 350 m of straight, or the road of changing
#: curvature (clothoids between arcs of 500, 250 and 1000 m, after the same straight)
#: (``sumo_nets/motorway_arcs.py`` writes their sources)
MOTORWAY_ROADS = {
    "straight": "highway",
    "left-250": "highway_left_250",
    "right-250": "highway_right_250",
    "left-1000": "highway_left_1000",
    "right-1000": "highway_right_1000",
    "clothoid": "highway_clothoid",
}

_HEADER = re.compile(r"^<\?xml[^>]*>\s*(<!--.*?-->\s*)?", re.S)


def sumo_home() -> Path:
    """SUMO_HOME of the ``eclipse-sumo`` wheel."""
    import sumo

    return Path(sumo.SUMO_HOME)


def sumo_binary(name: str = "sumo") -> Path:
    """Path of a SUMO executable (``sumo``, ``netconvert``...) from the wheel."""
    exe = sumo_home() / "bin" / name
    if not exe.exists():
        raise FileNotFoundError(f"{exe} not found: is the eclipse-sumo wheel installed?")
    return exe


def nets_dir() -> Path:
    """The networks folder: $EGO_SUMO_NETS; else the package ``ego.sumo_nets`` of an
    installed ego (a wheel carries the checkout's ``sumo_nets/`` under that name); else
    ``sumo_nets/`` beside the ``ego`` package of a checkout."""
    env = os.environ.get("EGO_SUMO_NETS")
    if env:
        path = Path(env)
    else:
        path = _installed_nets() or Path(__file__).resolve().parents[2] / "sumo_nets"
    if not path.is_dir():
        raise ConfigError(
            f"SUMO networks folder {path} not found (reinstall ego, or set EGO_SUMO_NETS to a folder of networks)"
        )
    return path


def _installed_nets() -> Path | None:
    from importlib.resources import files

    try:
        # an installed wheel unpacks into real files (ego has a C extension, it is never zipped)
        return Path(str(files("ego.sumo_nets")))
    except ModuleNotFoundError:  # ego imported from a checkout (PYTHONPATH): no such package
        return None


def available_networks() -> list[str]:
    return sorted(p.parent.name for p in nets_dir().glob("*/*.netccfg"))


def net_file(name: str) -> Path:
    """The built ``.net.xml`` of network ``name``."""
    path = nets_dir() / name / f"{name}.net.xml"
    if not path.exists():
        known = available_networks()
        if name in known:  # its sources are there, the built file is not
            raise ConfigError(
                f"network {name!r} is not built ({path} is missing); build it with python sumo_nets/build.py"
            )
        raise ConfigError(f"unknown network {name!r} (known: {', '.join(known)}){did_you_mean(name, known)}")
    check_network(path)
    return path


def lane_length(name: str, lane: str) -> float:
    """The length (m) of lane ``lane`` in the built network ``name``, read from its XML (no
    SUMO started)."""
    path = net_file(name)
    for _, elem in ET.iterparse(path, events=("start",)):
        if elem.tag == "lane" and elem.get("id") == lane:
            return float(elem.get("length"))
    raise ConfigError(f"the SUMO network {path} has no lane {lane!r}; rebuild it: python sumo_nets/build.py")


#: networks found whole, by (path, modification time, size): a sweep resolves thousands of
#: runs on one network and parses it once; a file changed since is parsed again
_CHECKED: set[tuple[str, int, int]] = set()


def check_network(path: Path) -> None:
    """A built network must be whole XML with a ``<net>`` root and edges: a truncated or
    garbled file is a ConfigError naming it here, before libsumo reads it (libsumo would
    fail deep inside SUMO, or worse, load half a road). Parsed once per version of the
    file in a process."""
    try:
        stat = path.stat()
    except OSError as exc:
        raise ConfigError(f"cannot read the SUMO network {path}: {exc.strerror or exc}") from None
    key = (str(path), stat.st_mtime_ns, stat.st_size)
    if key in _CHECKED:
        return
    _check_network(path)
    _CHECKED.add(key)


def _check_network(path: Path) -> None:
    edges = 0
    root = None
    lanes: dict[str, int] = {}  # edge id -> its lanes (internal edges, ":...", left out)
    edge = None
    try:
        for _event, elem in ET.iterparse(path, events=("start",)):
            if root is None:
                root = elem.tag
            if elem.tag == "edge":
                edges += 1
                edge = elem.get("id", "")
                if not edge.startswith(":"):
                    lanes[edge] = 0
            elif elem.tag == "lane":
                _check_lane(path, elem)
                if edge in lanes:
                    lanes[edge] += 1
    except ET.ParseError as exc:
        raise ConfigError(
            f"the SUMO network {path} is not valid XML ({exc}); rebuild it: python sumo_nets/build.py"
        ) from None
    except OSError as exc:
        raise ConfigError(f"cannot read the SUMO network {path}: {exc.strerror or exc}") from None
    if root != "net" or not edges:
        raise ConfigError(
            f"the SUMO network {path} is not a SUMO network (expected a <net> with edges); "
            "rebuild it: python sumo_nets/build.py"
        )
    _check_sources(path, lanes)


def _check_lane(path: Path, elem) -> None:
    """A lane needs a finite positive ``length`` (the scenarios read it before SUMO starts)."""
    import math

    text = elem.get("length")
    try:
        length = float(text)
    except (TypeError, ValueError):
        length = math.nan
    if not (math.isfinite(length) and length > 0):
        raise ConfigError(
            f"the SUMO network {path} has a lane ({elem.get('id')!r}) without a valid length "
            f"({text!r}); rebuild it: python sumo_nets/build.py"
        )


def _check_sources(path: Path, lanes: dict[str, int]) -> None:
    """The built network must be the one its folder's sources (``<name>.edg.xml``) describe:
    every edge there, with its number of lanes - another network copied under this name
    (another scenario's) is refused here, not found out inside SUMO."""
    name = path.name.removesuffix(".net.xml")
    source = path.with_name(f"{name}.edg.xml")
    if not source.is_file():
        return
    try:
        declared = {e.get("id"): e.get("numLanes") for e in ET.parse(source).getroot().iter("edge")}
    except (ET.ParseError, OSError):
        return  # the sources are netconvert's input, not read by a run
    for edge, count in declared.items():
        if edge not in lanes:
            raise ConfigError(
                f"the SUMO network {path} is not the {name} network: it has no edge {edge!r} "
                f"(its edges: {', '.join(sorted(lanes)) or 'none'}); rebuild it: "
                "python sumo_nets/build.py"
            )
        if count is not None and count.isdigit() and int(count) != lanes[edge]:
            raise ConfigError(
                f"the SUMO network {path} is not the {name} network: edge {edge!r} has "
                f"{lanes[edge]} lanes, its sources say {count}; rebuild it: "
                "python sumo_nets/build.py"
            )


def build_network(name: str, output: Path | None = None) -> Path:
    """Run netconvert on ``sumo_nets/<name>/<name>.netccfg``; returns the written file.

    ``output`` overrides the configured output (used by tests to rebuild elsewhere).
    """
    folder = nets_dir() / name
    cfg = folder / f"{name}.netccfg"
    if not cfg.exists():
        raise ConfigError(f"no netconvert configuration {cfg}")
    out = Path(output) if output is not None else folder / f"{name}.net.xml"
    env = dict(os.environ, SUMO_HOME=str(sumo_home()))
    subprocess.run(
        [str(sumo_binary("netconvert")), "-c", cfg.name, "-o", str(out.resolve())],
        cwd=folder,
        env=env,
        check=True,
        capture_output=True,
        text=True,
    )
    return out


def network_body(path: Path) -> str:
    """A built network without netconvert's header comment (timestamp, paths)."""
    return _HEADER.sub("", Path(path).read_text(encoding="utf-8"), count=1)
