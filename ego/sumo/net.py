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
            f"SUMO networks folder {path} not found (reinstall ego, or set EGO_SUMO_NETS to a "
            "folder of networks)"
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
            raise ConfigError(f"network {name!r} is not built ({path} is missing); build it with "
                              "python sumo_nets/build.py")
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
    try:
        for _event, elem in ET.iterparse(path, events=("start",)):
            if root is None:
                root = elem.tag
            edges += elem.tag == "edge"
    except ET.ParseError as exc:
        raise ConfigError(f"the SUMO network {path} is not valid XML ({exc}); rebuild it: "
                          "python sumo_nets/build.py") from None
    except OSError as exc:
        raise ConfigError(f"cannot read the SUMO network {path}: {exc.strerror or exc}") from None
    if root != "net" or not edges:
        raise ConfigError(f"the SUMO network {path} is not a SUMO network (expected a <net> with edges); "
                          "rebuild it: python sumo_nets/build.py")


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
        cwd=folder, env=env, check=True, capture_output=True, text=True,
    )
    return out


def network_body(path: Path) -> str:
    """A built network without netconvert's header comment (timestamp, paths)."""
    return _HEADER.sub("", Path(path).read_text(encoding="utf-8"), count=1)
