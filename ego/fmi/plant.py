"""An FMI co-simulation FMU as the ego's vehicle model: ``--set plant=vehicle.fmu``.

The FMU replaces the scenario's own bicycle (report 000's in the motorway scenarios, report
002's in the curve) for the ego vehicle. The scenario builds its plant as usual; the FMU
takes its place with the same geometry, actuator limits and initial state, and its outputs
feed SUMO, the surround sensor, the recording and the metrics exactly as the built-in plant's
do.

Connections, by name unless ``plant_map`` (a TOML mapping file, :mod:`ego.fmi.mapping`)
says otherwise:

* inputs: the plant's commands after the actuator limits - ``Fx`` (N per driven wheel) or
  ``a_x`` (m/s^2), and ``delta`` (rad);
* outputs: the world state ``X``, ``u``, ``Y``, ``v``, ``psi``, ``r`` (m, m/s, m, m/s, rad,
  rad/s) and, if it has one, ``lateral_accel`` (m/s^2; else dv/dt + u r from the states);
* parameters ``X0``, ``u0``, ``Y0``, ``v0``, ``psi0``, ``r0``: the initial state, set by ego
  to where the scenario starts the ego (an FMU made by ``ego export-fmu`` has them).

Units are converted as for controllers. The FMU integrates on its own: ego's plants hold a
car that stopped braking at standstill, an FMU plant's model decides that itself.
"""

from __future__ import annotations

import math
from typing import Any

from ego.fmi.cosim import CoSim, FmuError
from ego.fmi.mapping import build_mapping
from ego.fmi.model import check_step, inspect_fmu
from ego.fmi.units import conversion
from ego.params import ConfigError

STATE = {"X": "m", "u": "m/s", "Y": "m", "v": "m/s", "psi": "rad", "r": "rad/s"}
COMMANDS = {"Fx": "N", "a_x": "m/s^2", "delta": "rad"}


def check_plant_fmu(path: str, map_file: str = "") -> None:
    """What can be checked of a plant FMU without the scenario: the file, its outputs and
    start parameters, the mapping (ConfigError, one line)."""
    info = inspect_fmu(path)
    _mapping(info, tuple(COMMANDS), path, map_file, partial_inputs=True)
    _start_vrs(info, path)


def _mapping(info, commands, name, map_file, partial_inputs=False):
    observes = {c: COMMANDS[c] for c in commands}
    mapping = build_mapping(
        info,
        observes if not partial_inputs else COMMANDS,
        STATE,
        name,
        map_file,
        outputs_word="plant output",
        key="plant_map",
    )
    if not partial_inputs and {link.signal for link in mapping.inputs} != set(observes):
        raise ConfigError(
            f"plant FMU {name!r}: its inputs must take the commands {', '.join(observes)} (it takes "
            f"{', '.join(link.signal for link in mapping.inputs) or 'none'})"
        )
    return mapping


def _start_vrs(info, name):
    out = []
    for s, unit in STATE.items():
        v = info.var(f"{s}0")
        if v is None or v.causality != "parameter":
            raise ConfigError(
                f"plant FMU {name!r}: no parameter {s}0 for the initial {s} (a plant FMU takes its "
                "start state as parameters X0, u0, Y0, v0, psi0, r0; ego export-fmu writes them)"
            )
        f, o = conversion(v.unit, info.units, unit, f"plant FMU {name!r} parameter {s}0")
        out.append((v.vr, f, o))
    return out


class FmuPlant:
    """The ego's plant stepped as a co-simulation FMU (the :class:`ego.models.plant.Plant`
    interface of the plant it replaces)."""

    is_fmu = True

    def __init__(self, path: str, map_file: str, base, dt: float, on_log=None, substeps: int = 1) -> None:
        info = inspect_fmu(path)
        check_step(info, dt, path)
        self.geometry, self.limits, self.dt = base.geometry, base.limits, dt
        #: the model the FMU stands in for: its parameters still give the friction limit the
        #: safety layer and the braking criterion assume
        self.model = getattr(base, "model", None)
        self.state, self.state_names = tuple(base.state), tuple(base.state_names)
        self.input_names, self.input_units = tuple(base.input_names), tuple(base.input_units)
        self.applied = (0.0, 0.0)
        self.lateral_accel = 0.0
        self._apply = base.limits.apply
        m = _mapping(info, self.input_names, path, map_file)
        order = {link.signal: link for link in m.inputs}
        self._in = tuple(order[n] for n in self.input_names)
        lat = info.var("lateral_accel")
        self._lat = None
        outs = [link.vr for link in m.outputs]
        if lat is not None and lat.causality == "output":
            self._lat = conversion(lat.unit, info.units, "m/s^2", f"plant FMU {path!r} output lateral_accel")
            outs.append(lat.vr)
        self._out = tuple((link.factor, link.offset) for link in m.outputs)
        start = {}
        for (vr, f, o), x in zip(_start_vrs(info, path), self.state):
            start[vr] = (x - o) / f
        sub = info.var("substeps")  # the scenario's RK4 sub-steps, to an FMU that takes them (ego's)
        if sub is not None and sub.causality == "parameter":
            start[sub.vr] = float(substeps)
        self.info, self.name = info, path
        self.cosim = CoSim(info, [link.vr for link in self._in], outs, on_log=on_log, instance_name="ego_plant")
        try:
            self.cosim.start(start, 0.0)
        except FmuError as exc:
            self.cosim.close()
            raise ConfigError(str(exc)) from None
        self._k = 0

    @property
    def speed(self) -> float:
        return self.state[1]

    def pose(self) -> tuple[float, float, float]:
        x = self.state
        return x[0], x[2], x[4]

    def step(self, action) -> None:
        x = self.state
        command, delta = self._apply(action[0], action[1], x[1], self.applied[1], self.dt)
        self.applied = (command, delta)
        (l0, l1) = self._in
        out = self.cosim.exchange(
            ((command - l0.offset) / l0.factor, (delta - l1.offset) / l1.factor), self._k * self.dt, self.dt
        )
        self._k += 1
        state = tuple(out[i] * f + o for i, (f, o) in enumerate(self._out))
        if not all(math.isfinite(s) for s in state):
            raise FmuError(
                f"plant FMU {self.info.model_name}: its state is not finite at t = {self._k * self.dt:.3f} s"
            )
        if self._lat is not None:
            self.lateral_accel = out[6] * self._lat[0] + self._lat[1]
        else:  # dv/dt + u r over the step
            self.lateral_accel = (state[3] - x[3]) / self.dt + x[1] * x[5]
        self.state = state

    def close(self) -> None:
        self.cosim.close()


def fmu_plant(scenario: Any, base: Any) -> Any:
    """The FMU of ``scenario.config.plant`` in place of ``base``, the plant the scenario built
    for its ego (its initial state and geometry)."""
    c = scenario.config
    if base is None or tuple(getattr(base, "state_names", ())) != ("X", "U", "Y", "V", "PSI", "R"):
        raise ConfigError(
            f"--set plant= replaces a bicycle plant; the {scenario.name} scenario has none "
            "(motorway and curve scenarios have)"
        )
    return FmuPlant(
        c.plant,
        c.plant_map,
        base,
        c.dt,
        substeps=getattr(c, "substeps", 1),
        on_log=lambda level, cat, msg: scenario.event("fmu", f"plant: {msg}", level),
    )
