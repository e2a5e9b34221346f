"""An FMI co-simulation FMU as an ego controller.

``ego run emergency-brake -c path/to/controller.fmu`` (or in ``ego compare``, a sweep spec,
``ControllerPolicy``) builds a :class:`FmuController`: every control period it copies the
mapped observation signals (converted to the FMU's units) into the FMU's inputs, calls
``doStep(t, dt)`` and returns the mapped outputs (converted to SI) as the action. The other
real outputs are recorded as the controller's signals.

Parameters: ``fmu_map`` (a TOML mapping file, :mod:`ego.fmi.mapping`) and one
``fmu.<name>`` per real parameter of the FMU (its start value the default), set with
``--set fmu.<name>=value``, in ``@fmu.<name>=value`` compare variants and swept like any
parameter; ``ego list path.fmu`` lists them.
"""

from __future__ import annotations

import dataclasses
import math
import operator
from functools import lru_cache
from math import isfinite
from typing import Any

from ego.fmi.cosim import CoSim, FmuError
from ego.fmi.mapping import Mapping, build_mapping
from ego.fmi.model import FmuInfo, check_step, inspect_fmu
from ego.params import ConfigError, Params, param

#: observation signals that are objects, not numbers: never FMU inputs
NOT_SIGNALS = ("lane", "policy", "surround")
#: error properties of the road-frame observation an FMU may take besides its fields
DERIVED = {"e_lon": "m", "e_lat": "m"}


def observes(task: str) -> dict[str, str]:
    """Observation signal -> SI unit for ``task`` (what FMU inputs connect to)."""
    from ego.control.tasks import TASKS

    t = TASKS[task]
    out = {s.name: s.unit for s in t.observes if s.name not in NOT_SIGNALS}
    if t.observation.endswith(":Observation"):
        out.update(DERIVED)
    return out


def actions(task: str) -> dict[str, str]:
    from ego.control.tasks import TASKS

    return {s.name: s.unit for s in TASKS[task].returns}


@lru_cache(maxsize=64)
def _mapping(info: FmuInfo, task: str, map_file: str, map_digest: str, name: str) -> Mapping:
    return build_mapping(info, observes(task), actions(task), name, map_file)


def mapping_for(info: FmuInfo, task: str, map_file: str, name: str) -> Mapping:
    """The checked mapping (cached by the map file's content)."""
    from ego.plugins import file_digest

    digest = ""
    if map_file:
        try:
            digest = file_digest(map_file)
        except OSError:
            digest = "missing"
    return _mapping(info, task, map_file, digest, name)


# -- parameters -------------------------------------------------------------------------------


class FmuParams(Params):
    """Base of the parameter classes made per FMU: ``fmu_map`` and ``fmu.<name>`` fields.
    Field names with a dot are not Python identifiers, so the class is a dataclass by its
    ``__dataclass_fields__`` (what :func:`dataclasses.fields` and :func:`dataclasses.replace`
    read) with a keyword constructor, frozen, hashable and picklable (by reference)."""

    _ref: tuple[str, str] = ("", "")  #: (FMU reference, task): how a worker finds the class again

    def __init__(self, **values: Any) -> None:
        fields = dataclasses.fields(self)
        names = {f.name for f in fields}
        for key in values:
            if key not in names:
                raise TypeError(f"unknown parameter {key!r}")
        for f in fields:
            object.__setattr__(self, f.name, values.get(f.name, f.default))
        self.__post_init__()
        if self.fmu_map:  # a mapping file is checked against the FMU with the parameters
            self.check()

    def check(self) -> None:
        """The connections these parameters make (the mapping file, or names) are valid for
        the FMU: ConfigError otherwise. ``ego.runner.configure`` calls it on the resolved
        parameters, before anything runs."""
        ref, task = type(self)._ref
        mapping_for(type(self)._info, task, self.fmu_map, ref)  # type: ignore[attr-defined]

    def __setattr__(self, name: str, value: Any) -> None:
        raise dataclasses.FrozenInstanceError(f"cannot assign to field {name!r}")

    def values(self) -> dict[str, Any]:
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}

    def __eq__(self, other: object) -> bool:
        return type(other) is type(self) and other.values() == self.values()  # type: ignore[attr-defined]

    def __hash__(self) -> int:
        return hash(tuple(self.values().items()))

    def __repr__(self) -> str:
        return f"{type(self).__name__}({', '.join(f'{k}={v!r}' for k, v in self.values().items())})"

    def __reduce__(self):
        return _rebuild_params, (*type(self)._ref, self.values())


def _rebuild_params(ref: str, task: str, values: dict) -> FmuParams:
    return fmu_controller_spec(ref, task).params(**values)


def _params_class(info: FmuInfo, ref: str, task: str) -> type:
    fields = {}

    def add(name: str, typ: type, f: dataclasses.Field) -> None:
        f.name, f.type = name, typ
        f._field_type = dataclasses._FIELD  # type: ignore[attr-defined]  # what fields() lists
        fields[name] = f

    add(
        "fmu_map",
        str,
        param("", "-", "TOML file mapping FMU variables to the task's signals (default: by name; see docs/fmi.md)"),
    )
    for v in info.tunable:
        start = v.start if v.start is not None and math.isfinite(v.start) else 0.0
        doc = v.description or f"FMU parameter {v.name}"
        add(f"fmu.{v.name}", float, param(float(start), v.unit or "-", doc))
    cls = type(
        f"FmuParams_{info.model_identifier}",
        (FmuParams,),
        {
            "__dataclass_fields__": fields,
            "__doc__": f"Parameters of the FMU {info.model_name}.",
            "_ref": (ref, task),
            "_info": info,
            "__module__": __name__,
        },
    )
    return cls


# -- the controller ---------------------------------------------------------------------------


class FmuController:
    """A co-simulation FMU stepping at the control period (see the module)."""

    def __init__(self, info: FmuInfo, params: FmuParams, dt: float, task: str, name: str) -> None:
        check_step(info, dt, name)
        m = mapping_for(info, task, params.fmu_map, name)
        self.info, self.mapping, self.name, self.dt = info, m, name, dt
        signals = [link.signal for link in m.inputs]
        self._get_obs = operator.attrgetter(*signals) if signals else None
        self._single = len(signals) == 1
        #: inputs needing a conversion: (index, 1/factor, offset) with fmu = (task - offset) / factor
        self._in_conv = tuple(
            (i, 1.0 / link.factor, link.offset) for i, link in enumerate(m.inputs) if not link.identity
        )
        self._out_conv = tuple((link.factor, link.offset) for link in m.outputs)
        self._n_actions = len(m.outputs)
        self._extras = tuple((link.fmu_name, len(m.outputs) + i) for i, link in enumerate(m.extras))
        self.signal_units = {e.fmu_name: (u or "-") for e, u in zip(m.extras, m.extra_units)}
        values = params.values()
        self._parameters = {v.vr: float(values[f"fmu.{v.name}"]) for v in info.tunable if f"fmu.{v.name}" in values}
        self._event = None
        self.cosim = CoSim(
            info,
            [link.vr for link in m.inputs],
            [link.vr for link in (*m.outputs, *m.extras)],
            on_log=self._on_log,
            instance_name=info.model_identifier,
        )
        self._k = 0
        self._out: tuple[float, ...] = ()

    def bind_events(self, event) -> None:
        """Route the FMU's log messages to ``event(kind, text, level)`` (the run's events and
        recording); the scenario calls it when it resets."""
        self._event = event

    def _on_log(self, level: str, category: str, message: str) -> None:
        text = f"{self.info.model_name}: {message}" + (f" ({category})" if category else "")
        if self._event is not None:
            self._event("fmu", text, level)
        else:
            import logging

            logging.getLogger("ego.fmi").log({"INFO": 20, "WARN": 30}.get(level, 40), "%s", text)

    def reset(self, *, seed: int | None = None) -> None:
        try:
            self.cosim.start(self._parameters, 0.0)
        except FmuError as exc:  # it refused its parameters or failed to start: before the run
            self.close()
            raise ConfigError(str(exc)) from None
        self._k = 0

    def step(self, obs) -> tuple[float, ...]:
        get = self._get_obs
        values = () if get is None else ((get(obs),) if self._single else get(obs))
        if self._in_conv:
            values = list(values)
            for i, inv, off in self._in_conv:
                values[i] = (values[i] - off) * inv
        k = self._k
        out = self._out = self.cosim.exchange(values, k * self.dt, self.dt)
        self._k = k + 1
        if self._n_actions == 2:
            (f0, o0), (f1, o1) = self._out_conv
            a, b = out[0] * f0 + o0, out[1] * f1 + o1
            if not (isfinite(a) and isfinite(b)):
                self._not_finite(obs, (a, b))
            return a, b
        action = tuple(out[i] * f + o for i, (f, o) in enumerate(self._out_conv))
        if not all(isfinite(x) for x in action):
            self._not_finite(obs, action)
        return action

    def _not_finite(self, obs, action) -> None:
        link, x = next((link, x) for link, x in zip(self.mapping.outputs, action) if not math.isfinite(x))
        t = (self._k - 1) * self.dt
        raise FmuError(
            f"FMU {self.info.model_name}: output {link.fmu_name!r} ({link.signal}) is {x} "
            f"at t = {t:.3f} s (step {self._k - 1})"
            + (f"; its last message: {self.cosim.last_message}" if self.cosim.last_message else "")
        )

    def signals(self) -> dict[str, float]:
        out = self._out
        return {name: out[i] if i < len(out) else 0.0 for name, i in self._extras}

    def close(self) -> None:
        """Terminate and free the FMU instance (the next reset instantiates it again)."""
        self.cosim.close()
        self.cosim = CoSim(
            self.info,
            [link.vr for link in self.mapping.inputs],
            [link.vr for link in (*self.mapping.outputs, *self.mapping.extras)],
            on_log=self._on_log,
            instance_name=self.info.model_identifier,
        )


_specs: dict[tuple[str, str, str], Any] = {}


def fmu_controller_spec(ref: str, task: str):
    """The :class:`ego.control.ControllerSpec` of the FMU at ``ref`` for ``task`` (checked:
    ConfigError before anything runs). Cached per file content."""
    from ego.control.base import ControllerSpec

    info = inspect_fmu(ref)
    key = (ref, task, info.digest)
    spec = _specs.get(key)
    if spec is None:
        params_cls = _params_class(info, ref, task)
        summary = f"FMI {info.fmi_version} co-simulation FMU {info.model_name}" + (
            f": {info.description}" if info.description else ""
        )

        def build(params, dt: float, _info=info) -> FmuController:
            return FmuController(_info, params, dt, task, ref)

        spec = ControllerSpec(ref, summary, params_cls, build)
        _specs[key] = spec
    return spec
