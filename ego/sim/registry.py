"""Traffic simulators by name: ``name -> Backend(factory, capabilities)``.

A scenario asks for a simulator with :func:`make_sim` and declares what it needs of one
(``needs``: field names of :class:`Capabilities`); :func:`check_needs` refuses a backend
that lacks one, in one line naming both, when the run is resolved (before anything
starts). Backend options (highway-env's ``video``, say) travel as data: a mapping handed to
the factory, checked by the backend's ``check_options``.

A backend module is imported only when its factory runs, so SUMO runs never load
highway-env and the registry costs nothing to import.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ego.params import ConfigError, did_you_mean
from ego.plugins import BACKEND_GROUP, entry_points
from ego.sim.protocol import TrafficSim


@dataclass(frozen=True)
class Capabilities:
    """What a simulator can do beyond the :class:`~ego.sim.protocol.TrafficSim` basics."""

    #: vehicles move sideways within a lane and change lane gradually (SUMO's sublane model)
    sublane: bool = False
    #: scripted actors (speed commands, blind driving, sideways moves) are honoured
    scripted_actors: bool = True
    #: it renders a video of the run (backend option ``video``)
    video: bool = False
    #: any network (curves, junctions); False: straight multi-lane roads only
    any_network: bool = False
    #: several project-controlled vehicles, each pushed with its acceleration, and who leads
    #: whom among them (the platoon: ego.scenarios.platoon.PlatoonSim)
    several_egos: bool = False


@dataclass(frozen=True)
class SimSetup:
    """What every simulator is started with (seconds, metres)."""

    net: Path
    step_length: float
    seed: int
    #: sublane width (m), for a backend with the sublane model
    lateral_resolution: float = 0.875
    #: the edge the scenario drives on (a straight-road backend builds only that)
    edge: str | None = None
    #: the run's simulated time (s), for a backend that renders a video
    duration: float = 0.0
    #: start every vehicle exactly where the scenario places it, refusing only a start that
    #: overlaps another vehicle (not one closer than its drivers' safe gap): a scenario file's
    #: Init (SUMO: ``--insertion-checks collision``)
    exact_starts: bool = False


@dataclass(frozen=True)
class Backend:
    """A registered simulator: ``factory`` is ``"module:function"``, the function taking
    (SimSetup, options mapping) and returning a :class:`TrafficSim`; ``options`` the option
    names it accepts; ``requires`` the Python package it needs (None: always there)."""

    name: str
    factory: str
    capabilities: Capabilities
    options: tuple[str, ...] = ()
    requires: str | None = None
    install: str = ""
    #: "module:function" checking the options before anything runs (ConfigError)
    check: str | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    def lacks(self, needs: Sequence[str]) -> list[str]:
        """The capabilities among ``needs`` (field names of :class:`Capabilities`) it lacks."""
        return [need for need in needs if not getattr(self.capabilities, need)]

    def load(self, ref: str) -> Callable[..., Any]:
        module, _, name = ref.partition(":")
        function: Callable[..., Any] = getattr(importlib.import_module(module), name)
        return function


BACKENDS: dict[str, Backend] = {}


def register(backend: Backend) -> Backend:
    """Make ``backend`` known by its name (a later one of the same name replaces it)."""
    BACKENDS[backend.name] = backend
    return backend


#: the backend a run takes unless told (``--backend``)
DEFAULT_BACKEND = "sumo"

register(
    Backend(
        DEFAULT_BACKEND,
        "ego.sumo.bridge:make_sim",
        Capabilities(sublane=True, scripted_actors=True, video=False, any_network=True, several_egos=True),
    )
)
register(
    Backend(
        "highway-env",
        "ego.highway_env.bridge:make_sim",
        Capabilities(sublane=False, scripted_actors=True, video=True, any_network=False),
        options=("video",),
        requires="highway_env",
        install="pip install 'ego[highway]'",
        check="ego.highway_env.video:check_options",
    )
)


def load_backend_plugins() -> None:
    """Register the ``ego.backends`` entry points (a :class:`Backend` each), once per process;
    a plugin that fails to load is a warning, not an error."""
    for ep in entry_points(BACKEND_GROUP):
        try:
            obj = ep.load()
            if not isinstance(obj, Backend):
                raise TypeError("not an ego.sim.registry.Backend")
            BACKENDS.setdefault(obj.name, obj)
        except Exception as exc:  # noqa: BLE001
            print(
                f"ego: warning: backend plugin {ep.name!r} ({ep.value}) not loaded: {type(exc).__name__}: {exc}",
                file=sys.stderr,
            )


def backend_names() -> tuple[str, ...]:
    """Every registered backend's name, plugins included (``--backend``'s choices)."""
    load_backend_plugins()
    return tuple(BACKENDS)


def backend(name: str) -> Backend:
    """The registered backend ``name``, or a ConfigError naming the known ones."""
    load_backend_plugins()
    try:
        return BACKENDS[name]
    except KeyError:
        raise ConfigError(
            f"bad value for --backend: {name!r} (expected one of: {', '.join(BACKENDS)}){did_you_mean(name, BACKENDS)}"
        ) from None


def check_needs(who: str, needs: Sequence[str], name: str) -> Backend:
    """Backend ``name`` if it has every capability ``who`` (a scenario: "scenario cut-in")
    ``needs``; else a one-line ConfigError naming both and what it lacks."""
    found = backend(name)
    lacking = found.lacks(needs)
    if lacking:
        raise ConfigError(
            f"bad value for --backend: {name!r} ({who} needs {', '.join(lacking)}; backend {name} "
            f"lacks {'it' if len(lacking) == 1 else 'them'})"
        )
    return found


def check_options(name: str, options: Mapping[str, Any]) -> None:
    """ConfigError unless backend ``name`` is installed and takes every option in ``options``."""
    b = backend(name)
    if b.requires is not None and importlib.util.find_spec(b.requires) is None:
        raise ConfigError(f"--backend {name} needs the {b.requires.replace('_', '-')} package: {b.install}")
    for key in options:
        if key not in b.options:
            takers = [o.name for o in BACKENDS.values() if key in o.options]
            if takers:
                raise ConfigError(
                    f"--{key} needs --backend {' or '.join(takers)} (--backend {name} "
                    f"takes {', '.join('--' + o for o in b.options) or 'no options'})"
                )
            raise ConfigError(f"bad backend option {key!r} (--backend {name} takes {', '.join(b.options) or 'none'})")
    if b.check is not None and options:
        b.load(b.check)(options)


def make_sim(name: str, setup: SimSetup, options: Mapping[str, Any] | None = None) -> TrafficSim:
    """A new (not yet started) simulation of backend ``name``."""
    b = backend(name)
    sim: TrafficSim = b.load(b.factory)(setup, dict(options or {}))
    return sim
