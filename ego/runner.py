"""One run as a pure function of a picklable description: what sweeps and the CLI call."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ego.control import controller_spec
from ego.params import ConfigError, apply_overrides, unknown_parameter, describe
from ego.record import RerunRecorder
from ego.scenarios import RunResult, scenario_class


@dataclass(frozen=True)
class RunSpec:
    """Everything that defines a run. Same spec, same metrics (``wall_time`` aside)."""

    scenario: str
    controller: str
    seed: int = 0
    overrides: Mapping[str, Any] = field(default_factory=dict)
    record: str | None = None


def build(spec: RunSpec):
    """Resolve names and overrides into a ready scenario (validates everything first)."""
    cls = scenario_class(spec.scenario)
    ctrl = controller_spec(spec.controller)
    config, rest = apply_overrides(cls.config_cls(), spec.overrides, strict=False)
    ctrl_params, rest = apply_overrides(ctrl.params(), rest, strict=False)
    if rest:
        known = [i.name for i in describe(cls.config_cls)] + [i.name for i in describe(ctrl.params)]
        raise unknown_parameter(next(iter(rest)), known)
    controller = ctrl.build(ctrl_params, config.dt)
    recorder = None
    if spec.record:
        path = Path(spec.record)
        if path.suffix != ".rrd":
            raise ConfigError(f"bad --record path {spec.record!r} (expected a file ending in .rrd)")
        recorder = RerunRecorder(path, recording_id=f"{spec.scenario}-{spec.controller}-{spec.seed}")
    return cls(config, controller, seed=spec.seed, recorder=recorder, controller_name=spec.controller)


def run(spec: RunSpec) -> RunResult:
    """Run one scenario to its end; SUMO and the recording are closed whatever happens."""
    return build(spec).run()
