"""Calling a user's code: whatever it raises or however it tries to leave is one message.

A controller class named by reference (``file.py:Class``, ``module:Class``, an
``ego.controllers`` plugin) is user code: ego calls its ``__init__``, ``reset``, ``step`` and
``signals`` through :class:`GuardedController`, so that

* an exception is one line naming the class, the method, the exception and the innermost
  line of the user's own file (``ctl.py:12``; ego's frames are left out);
* a ``SystemExit`` (``sys.exit(0)``) or an ``os._exit(0)`` is reported as such, never
  taken for the command's own end (a success with nothing written);
* a ``KeyboardInterrupt`` the code raises itself is reported as user code's, not as the
  user's Ctrl-C: ego's signal handlers raise :class:`SignalInterrupt`, a subclass, so a
  plain one comes from the code;
* a ``step`` that returns anything but two numbers, or a ``signals`` that returns anything
  but a mapping of names to numbers, is named with what it returned.

Failures in ``__init__`` (and at import) happen before the run: :class:`UserCodeError`
there is a ConfigError (exit status 2). During the run it is a ControllerError: the run ends
with status ``error`` and the message, the trace so far written (``ego run`` exit status 1;
``ego compare``/``sweep``: that run's row is ``error``).

This module imports only the standard library (``ego._entry`` uses it before anything else).
"""

from __future__ import annotations

import os
import threading
import traceback
from collections.abc import Callable, Mapping
from typing import Any

_EGO_DIR = os.path.dirname(os.path.abspath(__file__))


class SignalInterrupt(KeyboardInterrupt):
    """The KeyboardInterrupt ego's own SIGINT/SIGTERM handlers raise: a real Ctrl-C or
    SIGTERM, told apart from a KeyboardInterrupt user code raises."""


class UserExit(SystemExit):
    """``os._exit(status)`` called by user code while ego runs it (raised instead)."""


_state = threading.local()
_real_exit = os._exit


def _guarded_exit(status: int) -> None:
    """``os._exit`` while ego's process runs: inside user code it raises :class:`UserExit`
    (reported like ``sys.exit``); elsewhere it is the real one."""
    if getattr(_state, "depth", 0) > 0:
        raise UserExit(status)
    _real_exit(status)


def _install_exit_guard() -> None:
    if os._exit is not _guarded_exit:
        os._exit = _guarded_exit  # type: ignore[assignment]


def user_location(tb: Any, user_file: str | None = None) -> str:
    """``file.py:LINE`` of the innermost frame of ``tb`` in the user's code: in
    ``user_file`` if given and present, else outside ego's package; '' if none."""
    frames = traceback.extract_tb(tb)
    if user_file:
        target = os.path.abspath(user_file)
        mine = [f for f in frames if os.path.abspath(f.filename) == target]
        if mine:
            return f"{os.path.basename(mine[-1].filename)}:{mine[-1].lineno}"
    outside = [f for f in frames if not os.path.abspath(f.filename).startswith(_EGO_DIR + os.sep)]
    if outside:
        return f"{os.path.basename(outside[-1].filename)}:{outside[-1].lineno}"
    return ""


def describe(exc: BaseException, what: str, user_file: str | None = None) -> str:
    """One line: ``what`` raised ``exc`` (with the user's line)."""
    where = user_location(exc.__traceback__, user_file)
    at = f" at {where}" if where else ""
    if isinstance(exc, UserExit):
        return f"{what} called os._exit({exc.code}){at} (user code may not end ego)"
    if isinstance(exc, SystemExit):
        return f"{what} called sys.exit({exc.code!r}){at} (user code may not end ego)"
    if isinstance(exc, KeyboardInterrupt):
        return f"{what} raised KeyboardInterrupt{at} (raised by the code, not a Ctrl-C)"
    text = str(exc).splitlines()[0] if str(exc) else ""
    return f"{what} raised {type(exc).__name__}{at}" + (f": {text}" if text else "")


class UserCodeError(RuntimeError):
    """User code failed; the message is the one line to show."""


def call_user(fn: Callable[..., Any], what: str, user_file: str | None, error: type, *args: Any, **kw: Any) -> Any:
    """``fn(*args, **kw)``; any exception, exit or self-raised KeyboardInterrupt becomes
    ``error`` (a class taking the message) naming ``what``. A real Ctrl-C/SIGTERM passes."""
    _install_exit_guard()
    _state.depth = getattr(_state, "depth", 0) + 1
    try:
        return fn(*args, **kw)
    except SignalInterrupt:
        raise
    except (Exception, SystemExit, KeyboardInterrupt) as exc:
        raise error(describe(exc, what, user_file)) from None
    finally:
        _state.depth -= 1


def source_file(obj: Any) -> str | None:
    """The file ``obj`` (a class) was defined in, or None."""
    import inspect

    try:
        return inspect.getsourcefile(obj)
    except (TypeError, OSError):
        return None


class GuardedController:
    """A user's controller, every call through :func:`call_user`; its results checked.
    Other attributes (``signal_units``, ``close``, ...) pass through."""

    def __init__(self, inner: Any, name: str, user_file: str | None, error: type) -> None:
        self._inner = inner
        self._name = name
        self._file = user_file
        self._error = error

    def __getattr__(self, attr: str) -> Any:
        return getattr(self._inner, attr)

    def reset(self, *, seed: int | None = None) -> None:
        call_user(self._inner.reset, f"controller {self._name}.reset", self._file, self._error, seed=seed)

    def step(self, obs: Any) -> tuple[float, float]:
        what = f"controller {self._name}.step"
        action = call_user(self._inner.step, what, self._file, self._error, obs)
        try:
            a, b = action
            out = (float(a), float(b))
        except (TypeError, ValueError):
            raise self._error(
                f"{what} returned {_show(action)} (expected two numbers: the longitudinal command and the steer angle)"
            ) from None
        return out

    def signals(self) -> Mapping[str, float]:
        what = f"controller {self._name}.signals"
        got = call_user(self._inner.signals, what, self._file, self._error)
        if not isinstance(got, Mapping) or not all(isinstance(k, str) for k in got):
            raise self._error(f"{what} returned {_show(got)} (expected a mapping of signal names to numbers)")
        return got


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def guarded_build(cls: type, build: Callable[..., Any], error: type) -> Callable[[Any, float], Any]:
    """``build`` (params, dt -> an instance of ``cls``) with ``__init__`` failures as a
    ConfigError and the instance a :class:`GuardedController` raising ``error`` (the
    controllers' UserControllerError) for failures during the run."""
    from ego.params import ConfigError

    name = getattr(cls, "__name__", str(cls))
    user_file = source_file(cls)

    def build_guarded(params: Any, dt: float) -> GuardedController:
        inner = call_user(build, f"controller {name}.__init__", user_file, ConfigError, params, dt)
        return GuardedController(inner, name, user_file, error)

    return build_guarded
