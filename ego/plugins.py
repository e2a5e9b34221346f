"""Controllers and scenarios from outside ego: references and entry-point plugins.

Wherever a controller name goes (``ego run -c``, ``ego compare --controllers``, a sweep
spec's ``controllers``, :class:`ego.gym.ControllerPolicy`) a *reference* may stand instead:

* ``package.module:Name`` - an importable module's attribute;
* ``path/to/file.py:Name`` - a Python file's attribute (the file is imported under a name
  derived from its path and content hash, so an edited file is imported afresh);
* ``path/to/controller.fmu`` - an FMI 2.0 or 3.0 co-simulation FMU (:mod:`ego.fmi`).

``Name`` is a controller class (anything with ``reset``/``step``/``signals``, built as
``Name(params, dt)`` with ``params`` an instance of its ``Params`` class attribute, a
:class:`ego.params.Params` dataclass; without one it has no parameters and is built as
``Name(dt)`` or ``Name()``) or a ready :class:`ego.control.ControllerSpec`. A class may
declare the task it drives in a ``task`` attribute (default: any task).

Scenarios are named the same way (``package.module:Name`` or ``file.py:Name``, a
:class:`ego.scenarios.Scenario` subclass).

Installed packages register under names through entry points, groups ``ego.controllers``,
``ego.scenarios``, ``ego.metrics`` and ``ego.backends``::

    [project.entry-points."ego.controllers"]
    my-pid = "my_package.control:MyPID"       # a class (its ``task`` attribute) or a spec
    [project.entry-points."ego.metrics"]
    my-metric = "my_package.metrics:METRIC"   # an ego.results.metrics.TraceMetric
    [project.entry-points."ego.backends"]
    my-sim = "my_package.sim:BACKEND"         # an ego.sim.registry.Backend

Metrics and backends load where ego first reads their registry (the metrics a run reports
or declares, a backend looked up by name or listed for ``--backend``), in the parent and in
every process or Ray worker alike.

Controller references resolve in :mod:`ego.control.references`, scenario references in
:mod:`ego.scenarios.references`; this module holds what both share (importing a reference,
content hashes, entry points) and imports neither. A reference is a plain string, so it travels to process and Ray workers as it is and each
worker resolves it again itself (imports the module, extracts the FMU).
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import os
import sys
import threading
from pathlib import Path
from typing import Any

from ego.params import ConfigError
from ego.usercode import call_user

CONTROLLER_GROUP = "ego.controllers"
SCENARIO_GROUP = "ego.scenarios"
#: a :class:`ego.results.metrics.TraceMetric` each (loaded by ego.results.metrics)
METRIC_GROUP = "ego.metrics"
#: a :class:`ego.sim.registry.Backend` each (loaded by ego.sim.registry)
BACKEND_GROUP = "ego.backends"

_lock = threading.Lock()
_loaded_groups: set[str] = set()
#: (absolute path, sha256 of the content) -> the module imported from it
_file_modules: dict[tuple[str, str], Any] = {}


def is_reference(name: str) -> bool:
    """True for ``module:Name``, ``file.py:Name`` and ``*.fmu``; False for a plain name."""
    return isinstance(name, str) and (":" in name or name.lower().endswith(".fmu"))


def file_digest(path: str | os.PathLike) -> str:
    """sha256 of a file's content (hex); OSError for anything but a regular file (a FIFO or
    a link to /dev/zero would never end)."""
    import stat

    h = hashlib.sha256()
    with open(path, "rb", opener=lambda p, flags: os.open(p, flags | getattr(os, "O_NONBLOCK", 0))) as f:
        if not stat.S_ISREG(os.fstat(f.fileno()).st_mode):
            raise OSError(f"{os.fspath(path)!r} is not a regular file")
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _import_file(path: str, what: str) -> Any:
    p = Path(path).expanduser()
    if not p.is_file():
        raise ConfigError(f"bad {what} reference: no file {path!r} (expected path/to/file.py:Name)")
    digest = file_digest(p)
    key = (str(p.resolve()), digest)
    with _lock:
        module = _file_modules.get(key)
        if module is not None:
            return module
        mod_name = f"ego_user_{p.stem}_{digest[:12]}"
        spec = importlib.util.spec_from_file_location(mod_name, p)
        if spec is None or spec.loader is None:
            raise ConfigError(f"bad {what} reference: {path!r} cannot be imported as Python")
        module = importlib.util.module_from_spec(spec)
        # registered before it runs: dataclasses and pickling look classes up by module name
        sys.modules[mod_name] = module
        try:  # an exception, sys.exit/os._exit or a self-raised KeyboardInterrupt: one line
            call_user(spec.loader.exec_module, f"importing {path!r}", str(p), ConfigError, module)
        except ConfigError as exc:
            sys.modules.pop(mod_name, None)
            raise ConfigError(f"bad {what} reference: {exc}") from None
        _file_modules[key] = module
        return module


def load_object(ref: str, what: str = "controller") -> Any:
    """The object ``ref`` (``package.module:Name`` or ``path/file.py:Name``) names."""
    target, sep, attr = ref.rpartition(":")
    if not sep or not target or not attr:
        raise ConfigError(
            f"bad {what} reference {ref!r} (expected a registered name, package.module:Name, "
            "path/to/file.py:Name or path/to/file.fmu)"
        )
    if target.endswith(".py") or "/" in target or os.sep in target:
        module = _import_file(target, what)
    else:
        try:
            module = importlib.import_module(target)
        except ImportError as exc:
            raise ConfigError(f"bad {what} reference {ref!r}: cannot import {target!r} ({exc})") from None
        except Exception as exc:  # noqa: BLE001
            raise ConfigError(
                f"bad {what} reference {ref!r}: importing {target!r} failed: {type(exc).__name__}: {exc}"
            ) from None
    obj = module
    for part in attr.split("."):
        try:
            obj = getattr(obj, part)
        except AttributeError:
            raise ConfigError(f"bad {what} reference {ref!r}: {target!r} has no {attr!r}") from None
    return obj


def entry_points(group: str) -> list[Any]:
    """The installed entry points of ``group``, the first time it is asked for in this
    process (a plugin registers once); afterwards an empty list."""
    from importlib.metadata import entry_points as installed

    if group in _loaded_groups:
        return []
    with _lock:
        if group in _loaded_groups:
            return []
        _loaded_groups.add(group)
        return list(installed(group=group))


#: file suffix -> "module:function" building a controller spec from such a file (``ref``,
#: ``task``): the kinds of reference beside ``module:Name``; looked up by name, so this
#: module (below the controllers) imports none of them
CONTROLLER_FILES = {".fmu": "ego.fmi.controller:fmu_controller_spec"}


#: file suffix -> "module:function" giving the scenario class of such a file (``ref``): a
#: scenario described as data (OpenSCENARIO), looked up by name like CONTROLLER_FILES
SCENARIO_FILES = {".xosc": "ego.openscenario.scenario:file_scenario_class"}


def file_resolver(ref: str, kinds: dict[str, str] = CONTROLLER_FILES) -> Any:
    """The function that resolves ``ref`` when its suffix is a file kind of ``kinds``
    (:data:`CONTROLLER_FILES` or :data:`SCENARIO_FILES`), else None."""
    for suffix, target in kinds.items():
        if ref.lower().endswith(suffix):
            module, _, name = target.partition(":")
            return getattr(importlib.import_module(module), name)
    return None
