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

Installed packages register under names through entry points, groups ``ego.controllers``
and ``ego.scenarios``::

    [project.entry-points."ego.controllers"]
    my-pid = "my_package.control:MyPID"       # a class (its ``task`` attribute) or a spec

A reference is a plain string, so it travels to process and Ray workers as it is and each
worker resolves it again itself (imports the module, extracts the FMU).
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import inspect
import os
import sys
import threading
from dataclasses import replace
from pathlib import Path
from typing import Any

from ego.params import ConfigError

CONTROLLER_GROUP = "ego.controllers"
SCENARIO_GROUP = "ego.scenarios"

_lock = threading.Lock()
_loaded_groups: set[str] = set()
#: (absolute path, sha256 of the content) -> the module imported from it
_file_modules: dict[tuple[str, str], Any] = {}


def is_reference(name: str) -> bool:
    """True for ``module:Name``, ``file.py:Name`` and ``*.fmu``; False for a plain name."""
    return isinstance(name, str) and (":" in name or name.lower().endswith(".fmu"))


def file_digest(path: str | os.PathLike) -> str:
    """sha256 of a file's content (hex)."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
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
        try:
            spec.loader.exec_module(module)
        except Exception as exc:  # noqa: BLE001 - the user's file is at fault: say which and why
            sys.modules.pop(mod_name, None)
            raise ConfigError(f"bad {what} reference: importing {path!r} failed: {type(exc).__name__}: {exc}") from None
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


def _builder(cls: type, has_params: bool):
    """How to build ``cls``: (params, dt), (dt) or () as its constructor takes them."""
    if has_params:
        return cls
    try:
        sig = inspect.signature(cls)
        sig.bind(0.01)
        return lambda params, dt: cls(dt)
    except (TypeError, ValueError):
        return lambda params, dt: cls()


def controller_spec_of(obj: Any, name: str, task: str, where: str):
    """A :class:`ControllerSpec` named ``name`` from a spec or a controller class."""
    from ego.control.base import ControllerSpec

    if isinstance(obj, ControllerSpec):
        spec = replace(obj, name=name)
        obj_task = getattr(obj, "task", None)
    elif inspect.isclass(obj):
        missing = [m for m in ("reset", "step", "signals") if not callable(getattr(obj, m, None))]
        if missing:
            raise ConfigError(
                f"bad controller {where}: class {obj.__name__} has no {', '.join(missing)} "
                "(a controller has reset, step and signals)"
            )
        params = getattr(obj, "Params", None)
        from ego.control import NoParams
        from ego.params import Params

        if params is not None and not (inspect.isclass(params) and issubclass(params, Params)):
            raise ConfigError(f"bad controller {where}: {obj.__name__}.Params is not an ego.params.Params dataclass")
        doc = (inspect.getdoc(obj) or obj.__name__).strip().splitlines()[0]
        spec = ControllerSpec(name, doc, params or NoParams, _builder(obj, params is not None))
        obj_task = getattr(obj, "task", None)
    else:
        raise ConfigError(
            f"bad controller {where}: {type(obj).__name__} is neither a controller class nor "
            "an ego.control.ControllerSpec"
        )
    if obj_task is not None:
        tasks = (obj_task,) if isinstance(obj_task, str) else tuple(obj_task)
        if task not in tasks:
            raise ConfigError(f"controller {name!r} drives the {', '.join(tasks)} task, not {task}")
    return spec


def resolve_controller(ref: str, task: str):
    """The :class:`ControllerSpec` of a reference (``module:Name``, ``file.py:Name``, ``*.fmu``)
    for ``task``; its name is the reference as given. ConfigError on anything wrong."""
    if ref.lower().endswith(".fmu"):
        from ego.fmi.controller import fmu_controller_spec

        return fmu_controller_spec(ref, task)
    return controller_spec_of(load_object(ref, "controller"), ref, task, repr(ref))


def resolve_scenario(ref: str):
    """The scenario class a ``module:Name`` or ``file.py:Name`` reference names."""
    from ego.scenarios.base import Scenario

    obj = load_object(ref, "scenario")
    if not (inspect.isclass(obj) and issubclass(obj, Scenario)):
        raise ConfigError(f"bad scenario reference {ref!r}: not an ego Scenario subclass")
    return obj


def _entry_points(group: str):
    from importlib.metadata import entry_points

    return entry_points(group=group)


def load_controller_plugins(registry: dict[str, dict[str, Any]]) -> None:
    """Register the ``ego.controllers`` entry points into ``registry`` (task -> name -> spec),
    once per process. A plugin that fails to load is skipped with a warning on stderr (one
    broken package does not break ego)."""
    if CONTROLLER_GROUP in _loaded_groups:
        return
    with _lock:
        if CONTROLLER_GROUP in _loaded_groups:
            return
        _loaded_groups.add(CONTROLLER_GROUP)
        eps = list(_entry_points(CONTROLLER_GROUP))
    for ep in eps:
        try:
            obj = ep.load()
            tasks = getattr(obj, "task", None) or "tracking"
            for task in (tasks,) if isinstance(tasks, str) else tuple(tasks):
                if task in registry and ep.name not in registry[task]:
                    registry[task][ep.name] = controller_spec_of(obj, ep.name, task, f"plugin {ep.name!r}")
        except Exception as exc:  # noqa: BLE001
            print(
                f"ego: warning: controller plugin {ep.name!r} ({ep.value}) not loaded: {type(exc).__name__}: {exc}",
                file=sys.stderr,
            )


def load_scenario_plugins(registry: dict[str, Any]) -> None:
    """Register the ``ego.scenarios`` entry points into ``registry`` (name -> class), once."""
    if SCENARIO_GROUP in _loaded_groups:
        return
    with _lock:
        if SCENARIO_GROUP in _loaded_groups:
            return
        _loaded_groups.add(SCENARIO_GROUP)
        eps = list(_entry_points(SCENARIO_GROUP))
    from ego.scenarios.base import Scenario

    for ep in eps:
        try:
            obj = ep.load()
            if not (inspect.isclass(obj) and issubclass(obj, Scenario)):
                raise TypeError("not an ego Scenario subclass")
            registry.setdefault(ep.name, obj)
        except Exception as exc:  # noqa: BLE001
            print(
                f"ego: warning: scenario plugin {ep.name!r} ({ep.value}) not loaded: {type(exc).__name__}: {exc}",
                file=sys.stderr,
            )


def load_plugins() -> None:
    """Register every installed plugin (both groups) into ego's registries."""
    from ego.control import CONTROLLERS
    from ego.scenarios import SCENARIOS

    load_controller_plugins(CONTROLLERS)
    load_scenario_plugins(SCENARIOS)


def describe_reference(ref: str) -> dict:
    """What ``ego list REF`` shows for a controller reference: for an FMU its FMI version,
    variables with units and causality, the tasks whose signals its inputs and outputs
    connect to by name, and its parameters (``fmu.<name>``); for a class its parameters."""
    from ego.control import TASKS, controller_spec
    from ego.params import describe

    def params(cls) -> list[dict]:
        return [
            {"name": i.name, "default": i.default, "unit": i.unit, "allowed": i.allowed(), "description": i.doc}
            for i in describe(cls)
        ]

    out: dict = {"reference": ref}
    fits, errors = [], {}
    spec = None
    for task in TASKS:
        try:
            spec = controller_spec(ref, task)
            if ref.lower().endswith(".fmu"):  # connects by name to this task's signals?
                from ego.fmi.controller import mapping_for

                mapping_for(spec.params._info, task, "", ref)
            fits.append(task)
        except ConfigError as exc:
            errors[task] = str(exc)
    if ref.lower().endswith(".fmu"):
        from ego.fmi.model import inspect_fmu

        info = inspect_fmu(ref)  # the FMU's own problems are raised here, before the tasks'
        out.update(
            kind="fmu",
            fmi_version=info.fmi_version,
            model_name=info.model_name,
            description=info.description,
            generation_tool=info.generation_tool,
            variable_step=info.variable_step,
            default_step=info.default_step,
            variables=[
                {
                    "name": v.name,
                    "causality": v.causality,
                    "type": v.type,
                    "unit": v.unit,
                    "start": v.start,
                    "description": v.description,
                }
                for v in info.variables
                if v.causality in ("input", "output", "parameter")
            ],
        )
    else:
        out["kind"] = "class"
    out["tasks"] = fits
    if spec is not None:
        out["summary"] = spec.summary
        out["parameters"] = params(spec.params)
    if not fits:
        out["why_not"] = errors
    return out


def print_reference(d: dict) -> None:
    """``ego list REF`` as text."""
    print(f"{d['reference']}: {d.get('summary', '')}")
    if d["kind"] == "fmu":
        step = "any communication step" if d["variable_step"] else f"fixed step {d['default_step']} s"
        print(
            f"  FMI {d['fmi_version']} co-simulation, {step}"
            + (f", made by {d['generation_tool']}" if d["generation_tool"] else "")
        )
        for causality in ("input", "output", "parameter"):
            vs = [v for v in d["variables"] if v["causality"] == causality]
            if vs:
                print(
                    f"  {causality}s: "
                    + ", ".join(
                        v["name"]
                        + (f" [{v['unit']}]" if v["unit"] else "")
                        + ("" if v["type"] in ("Real", "Float64") else f" ({v['type']})")
                        for v in vs
                    )
                )
    if d["tasks"]:
        print(
            f"  drives the {', '.join(d['tasks'])} task{'s' if len(d['tasks']) > 1 else ''} "
            "(connected by name, or by --set fmu_map=map.toml)"
        )
    else:
        print("  connects to no task as it is:")
        for task, why in d.get("why_not", {}).items():
            print(f"    {task}: {why}")
    if d.get("parameters"):
        w = max(len(p["name"]) for p in d["parameters"])
        print("  parameters (--set key=value):")
        for p in d["parameters"]:
            default = repr(p["default"]) if isinstance(p["default"], str) else f"{p['default']:g}"
            unit = "" if p["unit"] in ("", "-") else f" {p['unit']}"
            print(f"    {p['name']:<{w}}  {default}{unit}  {p['description']}")
