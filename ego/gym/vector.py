"""Vector envs of the ego ids: what ``gym.make_vec(id, n)`` builds by default.

libsumo runs one SUMO simulation per process, so ``n > 1`` envs in one process cannot all
run through it. The ids' ``vector_entry_point`` (:func:`make_vector`) therefore gives an
:class:`EgoVectorEnv`: the first env in this process (its libsumo, while this process runs no
other SUMO) and each other env in a worker process of its own, the cores used in parallel.
``n == 1`` stays in this process (:class:`gymnasium.vector.SyncVectorEnv`).

:class:`EgoVectorEnv` keeps what a step costs beyond the envs' own work to the minimum an env
step of 30-150 us can afford: the actions, observations, rewards, terminations and
truncations live in shared memory; while this process steps its own env the workers step
theirs. Where the processes fit the cores (``n`` <= the cores, this process counted; x86-64,
whose memory order makes a counter in shared memory a safe signal) a step is a counter in
shared memory each way: a worker watches for its next step for ``SPIN_S`` after each one
(then sleeps on its pipe, woken by a byte), this process watches for the workers' replies;
otherwise it is one byte down each worker's pipe and one byte back. An ``info`` crosses
(pickled) only where it carries something - a reset's, and an episode's end with its
``metrics`` (``info="all"``: every step's, as Gymnasium's own vector envs merge them).
Otherwise Gymnasium 1.x's semantics: ``AutoresetMode.NEXT_STEP``, seeds ``seed + i``,
``call`` / ``get_attr`` / ``set_attr``, ``close`` reaps the workers, an env's exception is
raised in the parent with its message (a worker's traceback as a note). A worker exits when
the parent goes (its pipe's end of file: Ctrl-C, a kill) and ignores SIGINT itself, so no
orphan is left.

The env stepped here holds this process's libsumo while the vector env is open: another ego
env started here meanwhile runs its SUMO through TraCI (slower; a warning says so).
``host=False`` keeps every env in a worker (then a step is the pipes' round trip). Several
envs in one process (SB3's ``DummyVecEnv``, ``vectorization_mode="sync"``) work with the
default config: the second and later run SUMO through TraCI (see docs/gym.md for its cost). ``gymnasium.vector.AsyncVectorEnv`` and SB3's ``SubprocVecEnv``
of ``gym.make(id)`` work as well.
"""

from __future__ import annotations

import ctypes
import multiprocessing as mp
import os
import pickle
import platform
import select
import signal
import time
import traceback
import weakref
from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, SyncVectorEnv, VectorEnv
from gymnasium.vector.utils import batch_space

from ego.params import ConfigError
from ego.sim import exclusive_running

# one byte per message on a worker's pipe; the larger messages that follow are pickled
_STEP, _RESET, _CALL, _SETATTR, _CLOSE, _WAKE = b"s", b"r", b"c", b"a", b"q", b"w"
_DONE, _INFO, _ERROR = b"d", b"i", b"e"
#: a step's reply in shared memory (its ``kind`` slot): the same three
_REPLIES = (_DONE, _INFO, _ERROR)
#: a worker's control slots in shared memory: the step asked, the step done, the reply's
#: kind, asleep (on its pipe)
_CMD, _DONE_AT, _KIND, _ASLEEP, _SLOTS = 0, 1, 2, 3, 4
#: how long (s) a worker watches shared memory for its next step before it sleeps on its pipe
SPIN_S = 0.002
#: how many times a process reads a counter before it yields its core at each further read
#: (~30 us: a reply that comes at once costs no system call; one that does not leaves the
#: core to any process waiting for one, e.g. on a busy machine)
_PURE_SPINS = 300
#: how long (ms) a sleeping worker waits on its pipe before it looks at shared memory again
#: (a byte wakes it; this bounds the rare wake-up lost between its look and its sleep)
SLEEP_MS = 20
#: machines whose memory order (total store order) makes plain loads and stores of shared
#: memory a safe signal: a reader that sees a counter change sees what was written before it
_TSO_MACHINES = ("x86_64", "amd64", "i386", "i686", "x86")


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def env_id_of(scenario: str | None) -> str:
    """The id of ``scenario``'s env; None: ``ego/Scenario-v0`` (its config names the scenario)."""
    from ego.gym import ENV_IDS, SCENARIO_ENV_ID

    if scenario is None:
        return SCENARIO_ENV_ID

    for env_id, name in ENV_IDS.items():
        if name == scenario:
            return env_id
    raise ConfigError(f"bad value for scenario: {scenario!r} (expected one of {', '.join(ENV_IDS.values())})")


class _Maker:
    """A picklable ``gym.make(env_id, **kwargs)`` (the spec's TimeLimit included)."""

    def __init__(self, env_id: str, kwargs: dict) -> None:
        self.env_id, self.kwargs = env_id, kwargs

    def __call__(self):
        import ego.gym  # noqa: F401 - registers the ids in a fresh worker

        return gym.make(self.env_id, **self.kwargs)


def make_vector(
    num_envs: int = 1,
    scenario: str | None = "emergency-brake",
    config: Mapping[str, Any] | None = None,
    render_mode: str | None = None,
    info: str = "episode",
    host: bool | None = None,
    **kwargs: Any,
):
    """``num_envs`` envs of ``scenario``'s id (None: ``ego/Scenario-v0``, the scenario in
    ``config``): when more than one, an :class:`EgoVectorEnv`
    (``info`` and ``host`` as there).

    Workers start by ``fork`` when no SUMO runs in this process, else by ``forkserver``
    (a fork of a process whose libsumo runs would inherit its simulation)."""
    if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
        raise ConfigError(f"bad value for num_envs: {num_envs!r} (expected a whole number >= 1)")
    make = _Maker(env_id_of(scenario), {"config": dict(config or {}), "render_mode": render_mode, **kwargs})
    if num_envs == 1:
        return SyncVectorEnv([make])
    return EgoVectorEnv([make] * num_envs, info=info, host=host)


def _brief(space) -> str:
    """A space in a line: a Box by its shape and dtype (its bounds are arrays)."""
    if isinstance(space, spaces.Box):
        return f"Box{space.shape} {space.dtype}"
    return str(space)


class EgoVectorEnv(VectorEnv):
    """``len(env_fns)`` envs stepped in parallel: the first in this process (``host``), the
    others each in a worker process, the per-step data in shared memory (see the module
    docstring). ``env_fns``: picklable callables making the envs (each a Box observation
    space; all alike). ``info``: ``"episode"`` (default) - the infos of resets and of steps
    that end an episode or carry ``metrics``; ``"all"`` - every step's (as
    ``gymnasium.vector.AsyncVectorEnv``, at its cost). ``host``: step the first env in this
    process (default: when this process runs no SUMO now); False puts every env in a worker.
    ``context``: the workers' start method (default ``fork`` when no SUMO runs in this
    process, else ``forkserver``)."""

    def __init__(self, env_fns, info: str = "episode", context: str | None = None, host: bool | None = None) -> None:
        if info not in ("episode", "all"):
            raise ConfigError(f"bad value for info: {info!r} (expected episode or all)")
        if host is not None and not isinstance(host, bool):
            raise ConfigError(f"bad value for host: {host!r} (expected true, false or None)")
        env_fns = list(env_fns)
        if len(env_fns) < 1:
            raise ConfigError("bad value for env_fns: empty (expected at least one env maker)")
        if host is None:
            host = not exclusive_running()
        # the spaces from an env built here (a bad configuration fails now, before any
        # process starts); an EgoEnv starts no SUMO before its reset. Hosted, it stays.
        self._make_first = env_fns[0]
        self._configured: dict = {}  # what reset(options={"config": ...}) has set since
        first = env_fns[0]()
        try:
            self.single_observation_space = first.observation_space
            self.single_action_space = first.action_space
            self.metadata = {**first.metadata, "autoreset_mode": AutoresetMode.NEXT_STEP}
            self.render_mode = first.render_mode
            self.spec = first.spec
            obs_space = self.single_observation_space
            if not isinstance(obs_space, spaces.Box):
                raise ConfigError(f"bad observation space for EgoVectorEnv: {obs_space} (expected a Box)")
        except BaseException:
            first.close()
            raise
        if not host:
            first.close()
        elif hasattr(first.unwrapped, "_hosted"):  # an ego env: never evicted by another here
            first.unwrapped._hosted = True
        self.num_envs = n = len(env_fns)
        self.observation_space = batch_space(obs_space, n)
        self.action_space = batch_space(self.single_action_space, n)
        self.autoreset_mode = AutoresetMode.NEXT_STEP
        self._info_all = info == "all"
        #: the env indices stepped by workers (the first is this process's when hosted)
        self._indices = list(range(1 if host else 0, n))
        #: steps are signalled through shared memory (else through the pipes)
        self.spinning = host and platform.machine().lower() in _TSO_MACHINES and n <= _cores()

        layout = _layout(obs_space, self.single_action_space, n)
        if context is None:
            context = "forkserver" if exclusive_running() else "fork"
        self._context = context
        ctx = mp.get_context(context)
        self._buffers = {
            name: ctx.RawArray(ctypes.c_char, max(1, int(np.prod(shape)) * dt.itemsize)) for name, shape, dt in layout
        }
        self._ctrl = ctx.RawArray(ctypes.c_int64, _SLOTS * n)
        self._seq = 0
        self._layout = layout
        views = _views(self._buffers, layout)
        self._obs, self._actions = views["obs"], views["action"]
        self._rewards, self._terminated, self._truncated = views["reward"], views["terminated"], views["truncated"]
        self._here = _Stepper(first, 0, views, self._info_all) if host else None
        #: the envs closed with the vector env, however it is dropped (the hosted one)
        self._hosted: list = [first] if host else []

        self._conns: list = []
        self._fds: list[int] = []
        self._processes: list = []
        self.closed = False
        self._broken = False
        try:
            self._start_workers(env_fns, ctx, context, layout)
        except BaseException:
            self._reap(timeout=1.0)
            raise
        # the workers (and the hosted env) go with the vector env, however it is dropped
        self._finalizer = weakref.finalize(self, _reap, self._conns, self._processes, 1.0, self._hosted)

    def _start_workers(self, env_fns: list, ctx, context: str, layout: list) -> None:
        """A worker process per env index it steps (the hosted one excepted), each reporting
        its env built (or its error) before this returns."""
        for index in self._indices:
            parent, child = ctx.Pipe(duplex=True)
            # a forked worker closes the parents' ends it inherits (else a worker would
            # hold another's pipe open and miss the parent's end of file)
            inherited = [*self._conns, parent] if context == "fork" else []
            proc = ctx.Process(
                target=_worker,
                args=(index, env_fns[index], child, inherited, self._buffers, layout, self._ctrl, self._info_all),
                kwargs={"spinning": self.spinning},
                name=f"EgoVectorEnv-{index}",
                daemon=True,
            )
            proc.start()
            child.close()
            self._conns.append(parent)
            self._fds.append(parent.fileno())
            self._processes.append(proc)
        for k in range(len(self._indices)):
            self._receive(k)

    # -- the Gymnasium vector interface ---------------------------------------------------
    def reset(self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None):
        self._check_open()
        n = self.num_envs
        if seed is None:
            seeds: list = [None] * n
        elif isinstance(seed, (int, np.integer)):
            seeds = [int(seed) + i for i in range(n)]
        else:
            seeds = list(seed)
        if len(seeds) != n:
            raise ValueError(
                f"If seeds are passed as a list the length must match num_envs={n} but got length={len(seeds)}."
            )
        mask = None
        if options is not None and "reset_mask" in options:
            options = dict(options)
            mask = options.pop("reset_mask")
            if not isinstance(mask, np.ndarray) or mask.shape != (n,) or mask.dtype != np.bool_ or not mask.any():
                raise ValueError(
                    f"`options['reset_mask']` must be a numpy bool array of shape ({n},) with a True value, got {mask!r}"
                )
        if options is not None and "config" in options:
            self._check_config(options["config"])
        asked = [k for k, i in enumerate(self._indices) if mask is None or mask[i]]
        for k in asked:
            self._send(k, _RESET, (seeds[self._indices[k]], options))
        infos: dict = {}
        if self._here is not None and (mask is None or mask[0]):
            infos = self._add_info(infos, self._hosted_call(self._here.reset, seeds[0], options), 0)
        for k in asked:
            infos = self._add_info(infos, self._receive(k), self._indices[k])
        if mask is None:
            self._terminated[:] = False
            self._truncated[:] = False
        else:
            self._terminated[mask] = False
            self._truncated[mask] = False
        return self._obs.copy(), infos

    def _check_config(self, config) -> None:
        """A reset's new configuration, checked on an env built here (no SUMO starts) before any
        env takes it: valid, and keeping the spaces the shared buffers were made for."""
        probe = self._make_first()
        try:
            env = probe.unwrapped
            if not hasattr(env, "configure"):
                return
            env.configure({**self._configured, **config})
            if env._config_changed():
                env._rebuild()
            for what, old, new in (
                ("observation", self.single_observation_space, env.observation_space),
                ("action", self.single_action_space, env.action_space),
            ):
                if old != new:
                    raise ConfigError(
                        f"bad options['config'] for a vector env: it changes the {what} space "
                        f"({_brief(old)} -> {_brief(new)}), and the vector env's shared buffers hold the one it was made with; "
                        "make a new vector env (gym.make_vec) with that configuration"
                    )
        finally:
            probe.close()
        self._configured.update(config)

    def step(self, actions):
        self._check_open()
        actions = np.asarray(actions)
        if actions.shape != self._actions.shape:
            raise ValueError(f"bad actions: expected shape {self._actions.shape}, got {actions.shape}")
        self._actions[...] = actions
        infos: dict = {}
        try:
            if self.spinning:
                seq = self._seq = self._seq + 1
                ctrl = self._ctrl
                for k, i in enumerate(self._indices):  # the actions are written: go
                    base = _SLOTS * i
                    ctrl[base + _CMD] = seq
                    if ctrl[base + _ASLEEP]:
                        os.write(self._fds[k], _WAKE)
            else:
                write = os.write
                for fd in self._fds:
                    write(fd, _STEP)
            if self._here is not None:
                info = self._hosted_call(self._here.step)
                if info is not None:
                    infos = self._add_info(infos, info, 0)
            for k, i in enumerate(self._indices):
                reply = self._await(k, i) if self.spinning else os.read(self._fds[k], 1)
                if reply != _DONE:
                    infos = self._add_info(infos, self._reply(k, reply), i)
        except OSError as exc:
            self._fail(f"a worker of EgoVectorEnv is gone ({exc})")
        except KeyboardInterrupt:  # mid-step: the workers' replies would be out of step
            self._fail(None)
            raise
        return self._obs.copy(), self._rewards.copy(), self._terminated.copy(), self._truncated.copy(), infos

    def render(self):
        return self.call("render")

    def call(self, name: str, *args: Any, **kwargs: Any) -> tuple[Any, ...]:
        """``name(*args, **kwargs)`` of every env (or its value if not callable)."""
        self._check_open()
        for k in range(len(self._indices)):
            self._send(k, _CALL, (name, args, kwargs))
        here = (self._hosted_call(_call, self._hosted[0], name, args, kwargs),) if self._here is not None else ()
        return here + tuple(self._receive(k) for k in range(len(self._indices)))

    def get_attr(self, name: str) -> tuple[Any, ...]:
        return self.call(name)

    def set_attr(self, name: str, values: Any) -> None:
        self._check_open()
        if not isinstance(values, (list, tuple)):
            values = [values] * self.num_envs
        if len(values) != self.num_envs:
            raise ValueError(f"values must be a list of length {self.num_envs}, got {len(values)}")
        for k, i in enumerate(self._indices):
            self._send(k, _SETATTR, (name, values[i]))
        if self._here is not None:
            self._hosted_call(self._hosted[0].set_wrapper_attr, name, values[0])
        for k in range(len(self._indices)):
            self._receive(k)

    def close_extras(self, timeout: float = 5.0, terminate: bool = False) -> None:
        self._reap(timeout=0.0 if terminate else timeout)

    # -- the pipes and the shared counters -------------------------------------------------------
    def _check_open(self) -> None:
        if self.closed or self._broken:
            raise RuntimeError("this EgoVectorEnv is closed" if self.closed else "this EgoVectorEnv's workers are gone")

    def _hosted_call(self, fn, *args):
        """``fn(*args)`` on the env stepped here; its exception ends the vector env (the
        workers' replies to the same command would be out of step), raised as it is."""
        try:
            return fn(*args)
        except BaseException:
            self._fail(None)
            raise

    def _await(self, k: int, i: int) -> bytes:
        """The reply to step ``self._seq`` of worker ``k`` (env ``i``), watched in shared memory."""
        ctrl, seq = self._ctrl, self._seq
        done = _SLOTS * i + _DONE_AT
        spins = 0
        yield_ = os.sched_yield
        while ctrl[done] != seq:
            spins += 1
            if spins > _PURE_SPINS:  # a while already: let a process waiting for a core run
                yield_()
                if not spins & 0xFF and not self._processes[k].is_alive():
                    return b""  # gone: _reply says how
        return _REPLIES[ctrl[_SLOTS * i + _KIND]]

    def _send(self, k: int, kind: bytes, payload: Any) -> None:
        try:
            os.write(self._fds[k], kind)
            self._conns[k].send(payload)
        except OSError as exc:
            self._fail(f"worker {self._indices[k]} of EgoVectorEnv is gone ({exc})")

    def _receive(self, k: int):
        try:
            reply = os.read(self._fds[k], 1)
        except OSError as exc:
            self._fail(f"worker {self._indices[k]} of EgoVectorEnv is gone ({exc})")
        return self._reply(k, reply)

    def _reply(self, k: int, reply: bytes):
        i = self._indices[k]
        if reply == _DONE:
            return {}
        if reply == _INFO:
            return self._conns[k].recv()
        if reply == _ERROR:
            exc, trace = self._conns[k].recv()
            self._fail(None)
            exc.add_note(f"(raised in worker {i} of EgoVectorEnv)\n{trace}")
            raise exc
        proc = self._processes[k]
        proc.join(1.0)
        hint = ""
        if self._context != "fork":
            hint = (
                f"; its workers start by {self._context} (this process ran a SUMO when the vector env "
                "was made), which imports the main script again in each worker: put the script's "
                "code under `if __name__ == '__main__':` (Python's multiprocessing rule), or close the "
                "other ego env before gym.make_vec"
            )
        self._fail(f"worker {i} of EgoVectorEnv ended unexpectedly (exit code {proc.exitcode}){hint}")

    def _fail(self, message: str | None):
        """The workers reaped, the hosted env closed; ``message``: raised as a RuntimeError."""
        self._broken = True
        self._reap(timeout=1.0)
        if message is not None:
            raise RuntimeError(message)

    def _reap(self, timeout: float) -> None:
        _reap(self._conns, self._processes, timeout, self._hosted)
        self._fds = []
        self._here = None


def _call(env, name: str, args: tuple, kwargs: dict):
    value = env.get_wrapper_attr(name)
    return value(*args, **kwargs) if callable(value) else value


class _Stepper:
    """One env's steps with Gymnasium's NEXT_STEP autoreset, its results written into row
    ``index`` of the shared buffers: the same in a worker and in the parent."""

    def __init__(self, env, index: int, views: dict, info_all: bool) -> None:
        self.env, self.index, self.info_all = env, index, info_all
        actions = views["action"]
        # a slice, then its shape: row ``index`` as a view of the shared buffer even where an
        # action is a scalar (Discrete), whose plain index would be a copy taken once, here
        self.obs_row = views["obs"][index]
        self.action_row = actions[index : index + 1].reshape(actions.shape[1:])
        self.rewards, self.terminated, self.truncated = views["reward"], views["terminated"], views["truncated"]
        self.copy = self.action_row.ndim > 0
        self.autoreset = False

    def step(self) -> dict | None:
        """One step (a reset after an episode's end); its info where it carries something."""
        index = self.index
        if self.autoreset:
            obs, info = self.env.reset()
            self.rewards[index] = 0.0
            self.terminated[index] = self.truncated[index] = self.autoreset = False
            self.obs_row[...] = obs
            return info
        row = self.action_row
        obs, reward, term, trunc, info = self.env.step(row.copy() if self.copy else row[()])
        self.obs_row[...] = obs
        self.rewards[index] = reward
        self.terminated[index] = term
        self.truncated[index] = trunc
        self.autoreset = term or trunc
        if self.info_all or self.autoreset or "metrics" in info:
            return info
        return None

    def reset(self, seed, options) -> dict:
        obs, info = self.env.reset(seed=seed, options=options)
        self.obs_row[...] = obs
        self.autoreset = False
        return info


def _views(buffers: dict, layout) -> dict[str, np.ndarray]:
    return {
        name: np.frombuffer(buffers[name], dtype=dt, count=int(np.prod(shape))).reshape(shape)
        for name, shape, dt in layout
    }


def _reap(conns: list, processes: list, timeout: float, hosted: list) -> None:
    """Ask the workers to close their envs, wait ``timeout`` s, then terminate (and kill)
    the ones left; close the pipes and the env stepped here. Safe to call twice."""
    for conn in conns:
        try:
            os.write(conn.fileno(), _CLOSE)
        except (OSError, ValueError):
            pass
    while hosted:  # while the workers close theirs
        env = hosted.pop()
        try:
            env.close()
        except Exception:  # noqa: BLE001 - closing what is left; the workers still go
            pass
    for proc in processes:
        proc.join(timeout)
    for proc in processes:
        if proc.is_alive():
            proc.terminate()
            proc.join(1.0)
        if proc.is_alive():
            proc.kill()
            proc.join()
    for conn in conns:
        conn.close()
    conns.clear()
    processes.clear()


#: the thread pools of numerical libraries: one thread each in a worker
_POOL_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def _one_thread() -> None:
    """A worker's numerical libraries compute on one thread: an env steps on one core, and
    the vector env's processes already use every core (an idle BLAS pool's threads spin and
    take a core from another env: LaneCentering's worker stepped 1.7x slower)."""
    for name in _POOL_VARIABLES:  # libraries loaded from now on
        os.environ[name] = "1"
    from threadpoolctl import threadpool_limits  # those loaded already

    threadpool_limits(1)


def _wait_step(ctrl, base: int, seq: int, poll, clock) -> bool:
    """A worker's wait in shared memory: True when step ``seq + 1`` is asked, False when its
    pipe has something (a command, a wake-up byte, the parent's end of file). Watches for
    ``SPIN_S``, then sleeps on the pipe, looking again every ``SLEEP_MS``."""
    cmd = base + _CMD
    if ctrl[cmd] != seq:
        return True
    end = clock() + SPIN_S
    spins = 0
    yield_ = os.sched_yield
    while ctrl[cmd] == seq:
        spins += 1
        if spins > _PURE_SPINS:  # a while already: let a process waiting for a core run
            yield_()
            if not spins & 0x3F:
                if poll(0):
                    return ctrl[cmd] != seq
                if clock() > end:
                    break
    else:
        return True
    ctrl[base + _ASLEEP] = 1
    try:
        while ctrl[cmd] == seq:
            if poll(SLEEP_MS):
                return ctrl[cmd] != seq
        return True
    finally:
        ctrl[base + _ASLEEP] = 0


def _layout(obs_space, act_space, n: int) -> list:
    """The shared buffers' layout: (name, shape, dtype) of the observations, actions,
    rewards and end flags of ``n`` envs."""
    act_shape = act_space.shape if act_space.shape is not None else ()
    act_dtype = np.dtype(act_space.dtype if act_space.dtype is not None else np.int64)
    return [
        ("obs", (n, *obs_space.shape), np.dtype(obs_space.dtype)),
        ("action", (n, *act_shape), act_dtype),
        ("reward", (n,), np.dtype(np.float64)),
        ("terminated", (n,), np.dtype(np.bool_)),
        ("truncated", (n,), np.dtype(np.bool_)),
    ]


def _answer(kind: bytes, env, stepper: _Stepper, conn, fd: int) -> bool:
    """A worker's answer to a message other than a step (reset, a method call, an
    attribute set); False for _CLOSE or the parent's end of file: it is gone."""
    if kind == _RESET:
        seed, options = conn.recv()
        info = stepper.reset(seed, options)
        os.write(fd, _INFO)
        conn.send(info)
    elif kind == _CALL:
        name, args, kwargs = conn.recv()
        value = _call(env, name, args, kwargs)
        os.write(fd, _INFO)
        conn.send(value)
    elif kind == _SETATTR:
        name, value = conn.recv()
        env.set_wrapper_attr(name, value)
        os.write(fd, _DONE)
    else:
        return False
    return True


def _worker(
    index: int, make, conn, inherited: list, buffers: dict, layout, ctrl, info_all: bool, spinning: bool = False
) -> None:
    """One env stepped on the parent's counter or byte (see the module docstring)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's; it closes us
    _one_thread()
    for other in inherited:  # a forked worker's copies of the parent's ends
        other.close()
    fd = conn.fileno()
    write, read = os.write, os.read
    base = _SLOTS * index
    seq = 0
    in_step = False  # a step asked through shared memory, its reply not given yet
    env = None
    try:
        env = make()
        stepper = _Stepper(env, index, _views(buffers, layout), info_all)
        write(fd, _DONE)
        poller = select.poll()
        poller.register(fd, select.POLLIN)
        poll, clock = poller.poll, time.perf_counter
        while True:
            if spinning:
                if _wait_step(ctrl, base, seq, poll, clock):
                    kind = _STEP
                else:
                    kind = read(fd, 1)
                    if kind == _WAKE:  # a hint; the step is in shared memory
                        continue
            else:
                kind = read(fd, 1)
            if kind == _STEP:
                if spinning:
                    seq += 1
                    in_step = True
                    info = stepper.step()
                    in_step = False
                    ctrl[base + _KIND] = 0 if info is None else 1
                    ctrl[base + _DONE_AT] = seq
                    if info is not None:
                        conn.send(info)
                    continue
                info = stepper.step()
                if info is None:
                    write(fd, _DONE)
                else:
                    write(fd, _INFO)
                    conn.send(info)
            elif not _answer(kind, env, stepper, conn, fd):  # _CLOSE, or the parent's end of file
                break
    except (KeyboardInterrupt, BrokenPipeError, ConnectionResetError, EOFError):
        pass
    except BaseException as exc:  # the parent raises it with its message
        trace = traceback.format_exc()
        try:
            pickle.dumps(exc)
        except Exception:
            exc = RuntimeError(f"{type(exc).__name__}: {exc}")
        try:
            if in_step:
                ctrl[base + _KIND] = 2
                ctrl[base + _DONE_AT] = seq
            else:
                write(fd, _ERROR)
            conn.send((exc, trace))
        except OSError:
            pass
    finally:
        if env is not None:
            try:
                env.close()
            except Exception:
                pass
        conn.close()
