"""Vector envs of the ego ids: what ``gym.make_vec(id, n)`` builds by default.

libsumo runs one SUMO simulation per process, so ``n > 1`` envs in one process cannot all
run through it. The ids' ``vector_entry_point`` (:func:`make_vector`) therefore gives an
:class:`EgoVectorEnv`: each env in its own worker process (one libsumo each, the cores used
in parallel). ``n == 1`` stays in this process (:class:`gymnasium.vector.SyncVectorEnv`).

:class:`EgoVectorEnv` keeps what crosses between the processes per step to the minimum an
env step of 50-150 us can afford: the actions, observations, rewards, terminations and
truncations live in shared memory; a step is one byte down each worker's pipe and one byte
back; an ``info`` crosses (pickled) only where it carries something - a reset's, and an
episode's end with its ``metrics`` (``info="all"``: every step's, as Gymnasium's own vector
envs merge them). Otherwise Gymnasium 1.x's semantics: ``AutoresetMode.NEXT_STEP``, seeds
``seed + i``, ``call`` / ``get_attr`` / ``set_attr``, ``close`` reaps the workers, a worker's
exception is raised in the parent with its message. A worker exits when the parent goes
(its pipe's end of file: Ctrl-C, a kill) and ignores SIGINT itself, so no orphan is left.

Several envs in one process (SB3's ``DummyVecEnv``, ``vectorization_mode="sync"``) need
``config={"multi_instance": True}``: the second and later run SUMO through TraCI (see
docs/gym.md for its cost). ``gymnasium.vector.AsyncVectorEnv`` and SB3's ``SubprocVecEnv``
of ``gym.make(id)`` work as well.
"""

from __future__ import annotations

import ctypes
import multiprocessing as mp
import os
import pickle
import signal
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
_STEP, _RESET, _CALL, _SETATTR, _CLOSE = b"s", b"r", b"c", b"a", b"q"
_DONE, _INFO, _ERROR = b"d", b"i", b"e"


def env_id_of(scenario: str) -> str:
    from ego.gym import ENV_IDS

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
    scenario: str = "emergency-brake",
    config: Mapping[str, Any] | None = None,
    render_mode: str | None = None,
    info: str = "episode",
    **kwargs: Any,
):
    """``num_envs`` envs of ``scenario``'s id, each in its own process when more than one
    (:class:`EgoVectorEnv`; ``info`` as there).

    Workers start by ``fork`` when no SUMO runs in this process, else by ``forkserver``
    (a fork of a process whose libsumo runs would inherit its simulation)."""
    if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
        raise ConfigError(f"bad value for num_envs: {num_envs!r} (expected a whole number >= 1)")
    make = _Maker(env_id_of(scenario), {"config": dict(config or {}), "render_mode": render_mode, **kwargs})
    if num_envs == 1:
        return SyncVectorEnv([make])
    return EgoVectorEnv([make] * num_envs, info=info)


class EgoVectorEnv(VectorEnv):
    """``len(env_fns)`` envs, each stepped in its own worker process, the per-step data in
    shared memory (see the module docstring). ``env_fns``: picklable callables making the
    envs (each a Box observation space; all alike). ``info``: ``"episode"`` (default) - the
    infos of resets and of steps that end an episode or carry ``metrics``; ``"all"`` - every
    step's (as ``gymnasium.vector.AsyncVectorEnv``, at its cost). ``context``: the start
    method (default ``fork`` when no SUMO runs in this process, else ``forkserver``)."""

    def __init__(self, env_fns, info: str = "episode", context: str | None = None) -> None:
        if info not in ("episode", "all"):
            raise ConfigError(f"bad value for info: {info!r} (expected episode or all)")
        env_fns = list(env_fns)
        if len(env_fns) < 1:
            raise ConfigError("bad value for env_fns: empty (expected at least one env maker)")
        # the spaces from an env built here (a bad configuration fails now, before any
        # process starts); an EgoEnv starts no SUMO before its reset
        dummy = env_fns[0]()
        try:
            self.single_observation_space = dummy.observation_space
            self.single_action_space = dummy.action_space
            self.metadata = {**dummy.metadata, "autoreset_mode": AutoresetMode.NEXT_STEP}
            self.render_mode = dummy.render_mode
            self.spec = dummy.spec
        finally:
            dummy.close()
        obs_space = self.single_observation_space
        if not isinstance(obs_space, spaces.Box):
            raise ConfigError(f"bad observation space for EgoVectorEnv: {obs_space} (expected a Box)")
        self.num_envs = n = len(env_fns)
        self.observation_space = batch_space(obs_space, n)
        self.action_space = batch_space(self.single_action_space, n)
        self.autoreset_mode = AutoresetMode.NEXT_STEP
        self._info_all = info == "all"

        act_space = self.single_action_space
        act_shape = act_space.shape if act_space.shape is not None else ()
        act_dtype = np.dtype(act_space.dtype if act_space.dtype is not None else np.int64)
        layout = [
            ("obs", (n, *obs_space.shape), np.dtype(obs_space.dtype)),
            ("action", (n, *act_shape), act_dtype),
            ("reward", (n,), np.dtype(np.float64)),
            ("terminated", (n,), np.dtype(np.bool_)),
            ("truncated", (n,), np.dtype(np.bool_)),
        ]
        if context is None:
            context = "forkserver" if exclusive_running() else "fork"
        ctx = mp.get_context(context)
        self._buffers = {
            name: ctx.RawArray(ctypes.c_char, max(1, int(np.prod(shape)) * dt.itemsize)) for name, shape, dt in layout
        }
        self._layout = layout
        views = _views(self._buffers, layout)
        self._obs, self._actions = views["obs"], views["action"]
        self._rewards, self._terminated, self._truncated = views["reward"], views["terminated"], views["truncated"]

        self._conns: list = []
        self._fds: list[int] = []
        self._processes: list = []
        self.closed = False
        self._broken = False
        try:
            for index, fn in enumerate(env_fns):
                parent, child = ctx.Pipe(duplex=True)
                # a forked worker closes the parents' ends it inherits (else a worker would
                # hold another's pipe open and miss the parent's end of file)
                inherited = [*self._conns, parent] if context == "fork" else []
                proc = ctx.Process(
                    target=_worker,
                    args=(index, fn, child, inherited, self._buffers, layout, self._info_all),
                    name=f"EgoVectorEnv-{index}",
                    daemon=True,
                )
                proc.start()
                child.close()
                self._conns.append(parent)
                self._fds.append(parent.fileno())
                self._processes.append(proc)
            for index in range(n):  # each worker reports its env built (or its error)
                self._receive(index)
        except BaseException:
            self._reap(timeout=1.0)
            raise
        # the workers go with the vector env, however it is dropped
        self._finalizer = weakref.finalize(self, _reap, self._conns, self._processes, 1.0)

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
        indices = [i for i in range(n) if mask is None or mask[i]]
        for i in indices:
            self._send(i, _RESET, (seeds[i], options))
        infos: dict = {}
        for i in indices:
            info = self._receive(i)
            infos = self._add_info(infos, info, i)
        if mask is None:
            self._terminated[:] = False
            self._truncated[:] = False
        else:
            self._terminated[mask] = False
            self._truncated[mask] = False
        return self._obs.copy(), infos

    def step(self, actions):
        self._check_open()
        actions = np.asarray(actions)
        if actions.shape != self._actions.shape:
            raise ValueError(f"bad actions: expected shape {self._actions.shape}, got {actions.shape}")
        self._actions[...] = actions
        write, read, fds = os.write, os.read, self._fds
        try:
            for fd in fds:
                write(fd, _STEP)
            infos: dict = {}
            for i, fd in enumerate(fds):
                reply = read(fd, 1)
                if reply != _DONE:
                    info = self._reply(i, reply)
                    infos = self._add_info(infos, info, i)
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
        for i in range(self.num_envs):
            self._send(i, _CALL, (name, args, kwargs))
        return tuple(self._receive(i) for i in range(self.num_envs))

    def get_attr(self, name: str) -> tuple[Any, ...]:
        return self.call(name)

    def set_attr(self, name: str, values: Any) -> None:
        self._check_open()
        if not isinstance(values, (list, tuple)):
            values = [values] * self.num_envs
        if len(values) != self.num_envs:
            raise ValueError(f"values must be a list of length {self.num_envs}, got {len(values)}")
        for i, value in enumerate(values):
            self._send(i, _SETATTR, (name, value))
        for i in range(self.num_envs):
            self._receive(i)

    def close_extras(self, timeout: float = 5.0, terminate: bool = False) -> None:
        self._reap(timeout=0.0 if terminate else timeout)

    # -- the pipes ----------------------------------------------------------------------------
    def _check_open(self) -> None:
        if self.closed or self._broken:
            raise RuntimeError("this EgoVectorEnv is closed" if self.closed else "this EgoVectorEnv's workers are gone")

    def _send(self, i: int, kind: bytes, payload: Any) -> None:
        try:
            os.write(self._fds[i], kind)
            self._conns[i].send(payload)
        except OSError as exc:
            self._fail(f"worker {i} of EgoVectorEnv is gone ({exc})")

    def _receive(self, i: int):
        try:
            reply = os.read(self._fds[i], 1)
        except OSError as exc:
            self._fail(f"worker {i} of EgoVectorEnv is gone ({exc})")
        return self._reply(i, reply)

    def _reply(self, i: int, reply: bytes):
        if reply == _DONE:
            return {}
        if reply == _INFO:
            return self._conns[i].recv()
        if reply == _ERROR:
            exc, trace = self._conns[i].recv()
            self._fail(None)
            exc.add_note(f"(raised in worker {i} of EgoVectorEnv)\n{trace}")
            raise exc
        proc = self._processes[i]
        proc.join(1.0)
        self._fail(f"worker {i} of EgoVectorEnv ended unexpectedly (exit code {proc.exitcode})")

    def _fail(self, message: str | None):
        """The workers reaped; ``message``: raised as a RuntimeError."""
        self._broken = True
        self._reap(timeout=1.0)
        if message is not None:
            raise RuntimeError(message)

    def _reap(self, timeout: float) -> None:
        _reap(self._conns, self._processes, timeout)
        self._fds = []


def _views(buffers: dict, layout) -> dict[str, np.ndarray]:
    return {
        name: np.frombuffer(buffers[name], dtype=dt, count=int(np.prod(shape))).reshape(shape)
        for name, shape, dt in layout
    }


def _reap(conns: list, processes: list, timeout: float) -> None:
    """Ask the workers to close their envs, wait ``timeout`` s, then terminate (and kill)
    the ones left; close the pipes. Safe to call twice."""
    for conn in conns:
        try:
            os.write(conn.fileno(), _CLOSE)
        except (OSError, ValueError):
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


def _worker(index: int, make, conn, inherited: list, buffers: dict, layout, info_all: bool) -> None:
    """One env stepped on the parent's byte (see the module docstring)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's; it closes us
    for other in inherited:  # a forked worker's copies of the parent's ends
        other.close()
    fd = conn.fileno()
    write, read = os.write, os.read
    env = None
    try:
        views = _views(buffers, layout)
        obs_row, action_row = views["obs"][index], views["action"][index]
        rewards, terminated, truncated = views["reward"], views["terminated"], views["truncated"]
        env = make()
        write(fd, _DONE)
        autoreset = False
        copy = action_row.ndim > 0
        step, reset = env.step, env.reset
        while True:
            kind = read(fd, 1)
            if kind == _STEP:
                if autoreset:
                    obs, info = reset()
                    rewards[index] = 0.0
                    terminated[index] = truncated[index] = autoreset = False
                    obs_row[...] = obs
                    write(fd, _INFO)
                    conn.send(info)
                    continue
                obs, reward, term, trunc, info = step(action_row.copy() if copy else action_row[()])
                obs_row[...] = obs
                rewards[index] = reward
                terminated[index] = term
                truncated[index] = trunc
                autoreset = term or trunc
                if info_all or autoreset or "metrics" in info:
                    write(fd, _INFO)
                    conn.send(info)
                else:
                    write(fd, _DONE)
            elif kind == _RESET:
                seed, options = conn.recv()
                obs, info = reset(seed=seed, options=options)
                obs_row[...] = obs
                autoreset = False
                write(fd, _INFO)
                conn.send(info)
            elif kind == _CALL:
                name, args, kwargs = conn.recv()
                value = env.get_wrapper_attr(name)
                write(fd, _INFO)
                conn.send(value(*args, **kwargs) if callable(value) else value)
            elif kind == _SETATTR:
                name, value = conn.recv()
                env.set_wrapper_attr(name, value)
                write(fd, _DONE)
            else:  # _CLOSE, or the parent's end of file: it is gone
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
