"""Small task functions for testing the executors (``ego.parallel``) and compare's faults.

Test scaffolding, not shipped: the workers import this module by name as the tests do. A
forkserver worker starts with the test process's ``sys.path`` (which holds ``tests/``); a
Ray worker gets ``tests/`` on its ``PYTHONPATH`` from the fixture that starts Ray
(:func:`ray_env`).
"""

from __future__ import annotations

import os
import signal
from pathlib import Path
from typing import Any


def square(x: float) -> float:
    return x * x


def fail(x: Any) -> None:
    raise ValueError(f"bad task {x!r}")


def die_once(marker: str) -> int:
    """SIGKILL this worker process the first time (leaving ``marker`` behind), return its
    pid the second time: one death, then a value."""
    path = Path(marker)
    if not path.exists():
        path.write_text(str(os.getpid()))
        os.kill(os.getpid(), signal.SIGKILL)
    return os.getpid()


def always_die(_: Any) -> None:
    os.kill(os.getpid(), signal.SIGKILL)


def pid(_: Any) -> int:
    return os.getpid()


def ego_location(_: Any) -> str:
    """Where the worker imported ``ego`` from (it must be the caller's own copy)."""
    import ego

    return str(Path(ego.__file__).resolve().parent)


def run_metrics(spec: tuple) -> dict:
    """One real SUMO run, not recorded: ``(scenario, controller, seed)`` or
    ``(scenario, controller, seed, overrides)`` -> its metrics without ``wall_time``."""
    from ego.runner import RunSpec, run

    scenario, controller, seed, *rest = spec
    result = run(RunSpec(scenario, controller, seed, dict(rest[0]) if rest else {}, record=None))
    metrics = dict(result.metrics)
    metrics.pop("wall_time", None)
    return metrics


def second_simulation_refused(_: Any = None) -> str:
    """Start a SUMO simulation, then try a second one in the same process: returns the
    ``SumoError`` text (and raises if the second one was allowed). Both are closed after."""
    from ego.sumo.bridge import SumoBridge, SumoConfig, SumoError
    from ego.sumo.net import net_file

    def bridge() -> SumoBridge:
        return SumoBridge(SumoConfig(net_file("highway"), seed=1))

    with bridge():
        second = bridge()
        try:
            second.start()
        except SumoError as exc:
            refused = f"{type(exc).__name__}: {exc}"
        else:
            second.close()
            raise AssertionError("a second SUMO simulation started in one process")
    if SumoBridge._running:
        raise AssertionError("the bridge's guard was left set after close")
    return refused


def run_in_worker(spec: tuple) -> tuple[int, str, bool]:
    """One real SUMO run: (this worker's pid, the run's status, whether SUMO is still marked
    running in this process afterwards - it must not be)."""
    from ego.sumo.bridge import SumoBridge

    status = run_metrics(spec)["status"]
    return os.getpid(), status, SumoBridge._running


class RaisesAt:
    """A tracking controller that drives like the ``none`` controller, then raises at its
    ``step``-th control step: a user's controller failing mid-run."""

    def __init__(self, step: int) -> None:
        self.step_at, self.steps = step, 0

    def reset(self, *, seed: int | None = None) -> None:
        self.steps = 0

    def step(self, obs) -> tuple[float, float]:
        self.steps += 1
        if self.steps == self.step_at:
            raise RuntimeError(f"controller fault injected at step {self.steps}")
        return 0.0, 0.0

    def signals(self) -> dict[str, float]:
        return {}


def compare_run_with_fault(job: tuple) -> Any:
    """``(fault, RunSpec, argument)`` -> ego compare's worker function on the spec (a row),
    with a fault in this worker for that run only: ``none``; ``controller`` (the spec's
    controller name ``raises`` is a :class:`RaisesAt` at step ``argument``); ``sumo`` (the
    networks are read from the folder ``argument``, e.g. one holding a broken network)."""
    from ego.compare import run_one
    from ego.control import CONTROLLERS, NoParams
    from ego.control.base import ControllerSpec

    fault, spec, argument = job
    saved_env = os.environ.get("EGO_SUMO_NETS")
    tracking = CONTROLLERS["tracking"]
    try:
        if fault == "controller":
            tracking["raises"] = ControllerSpec(
                "raises", "raises mid-run (tests)", NoParams, lambda params, dt: RaisesAt(int(argument))
            )
        elif fault == "sumo":
            os.environ["EGO_SUMO_NETS"] = str(argument)
        return run_one(spec)
    finally:
        tracking.pop("raises", None)
        if saved_env is None:
            os.environ.pop("EGO_SUMO_NETS", None)
        else:
            os.environ["EGO_SUMO_NETS"] = saved_env


def ray_env() -> dict[str, str]:
    """The environment a local Ray instance must start with for its workers to import this
    module (and ``point_mass``) by name: ``tests/`` on ``PYTHONPATH``."""
    here = str(Path(__file__).resolve().parent)
    path = os.environ.get("PYTHONPATH", "")
    return {"PYTHONPATH": here + (os.pathsep + path if path else "")}


def call(job: tuple[str, Any]) -> Any:
    """``(name, argument)`` -> this module's function ``name`` applied to the argument: one
    run mixing tasks that succeed, raise and kill their worker."""
    name, arg = job
    if name not in _CALLABLE:
        raise KeyError(f"no task function {name!r}")
    return _CALLABLE[name](arg)


_CALLABLE = {f.__name__: f for f in (square, fail, die_once, always_die, pid)}


def environ(key: str) -> str | None:
    """The worker's value of the environment variable ``key``."""
    return os.environ.get(key)
