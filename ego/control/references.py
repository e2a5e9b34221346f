"""Controller references and ``ego.controllers`` entry points (:mod:`ego.plugins` has the
forms a reference takes)."""

from __future__ import annotations

import inspect
import sys
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from ego.control.base import UserControllerError
from ego.params import ConfigError
from ego.plugins import CONTROLLER_GROUP, entry_points, file_resolver, load_object
from ego.usercode import guarded_build

if TYPE_CHECKING:
    from ego.control.base import ControllerSpec


def _builder(cls: type, has_params: bool) -> Callable[..., Any]:
    """How to build ``cls``: (params, dt), (dt) or () as its constructor takes them."""
    if has_params:
        return cls
    try:
        sig = inspect.signature(cls)
        sig.bind(0.01)
        return lambda params, dt: cls(dt)
    except (TypeError, ValueError):
        return lambda params, dt: cls()


def controller_spec_of(obj: Any, name: str, task: str, where: str) -> ControllerSpec:
    """A :class:`ControllerSpec` named ``name`` from a spec or a controller class."""
    from ego.control.base import ControllerSpec

    if isinstance(obj, ControllerSpec):
        spec = replace(obj, name=name, build=guarded_build(type(obj), obj.build, UserControllerError))
        obj_task = getattr(obj, "task", None)
    elif inspect.isclass(obj):
        missing = [m for m in ("reset", "step", "signals") if not callable(getattr(obj, m, None))]
        if missing:
            raise ConfigError(
                f"bad controller {where}: class {obj.__name__} has no {', '.join(missing)} "
                "(a controller has reset, step and signals)"
            )
        params = getattr(obj, "Params", None)
        from ego.control.base import NoParams
        from ego.params import Params

        if params is not None and not (inspect.isclass(params) and issubclass(params, Params)):
            raise ConfigError(f"bad controller {where}: {obj.__name__}.Params is not an ego.params.Params dataclass")
        doc = (inspect.getdoc(obj) or obj.__name__).strip().splitlines()[0]
        spec = ControllerSpec(
            name, doc, params or NoParams, guarded_build(obj, _builder(obj, params is not None), UserControllerError)
        )
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


def resolve_controller(ref: str, task: str) -> ControllerSpec:
    """The :class:`ControllerSpec` of a reference (``module:Name``, ``file.py:Name``, ``*.fmu``)
    for ``task``; its name is the reference as given. ConfigError on anything wrong."""
    resolver = file_resolver(ref)  # an FMU (ego.fmi), looked up by name
    if resolver is not None:
        spec: ControllerSpec = resolver(ref, task)
        return spec
    return controller_spec_of(load_object(ref, "controller"), ref, task, repr(ref))


def load_controller_plugins(registry: dict[str, dict[str, Any]]) -> None:
    """Register the ``ego.controllers`` entry points into ``registry`` (task -> name -> spec),
    once per process. A plugin that fails to load is skipped with a warning on stderr (one
    broken package does not break ego)."""
    for ep in entry_points(CONTROLLER_GROUP):
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
