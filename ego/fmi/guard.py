"""FMU calls under a watchdog: a hanging, crashing or interrupted FMU never takes ego down.

Every FMI function ego calls (instantiate, set up, initialise, the step's set/doStep/get,
terminate, reset, free) goes through the C extension ``ego._fmu_guard``. It leaves the FMU's
code (``siglongjmp`` back to the call) when

* a call runs longer than the step limit: ``EGO_FMU_STEP_LIMIT`` seconds (default 30, from
  0.01 to 86400): :class:`FmuTimeout`, the run ends with status ``error`` (exit 1), the
  trace so far written, one line naming the FMU, the simulated time and the limit;
* SIGINT (Ctrl-C) or SIGTERM arrives during a call: :class:`FmuInterrupted`, the run ends
  ``interrupted`` (exit 130) as between steps;
* the FMU crashes (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT - ``abort()``) in a call:
  :class:`FmuCrash`, one line naming the signal, the FMU and the simulated time (exit 1).

The FMU instance is then abandoned - never called, freed or unloaded again (its state is
whatever the jump left) - and its extracted folder removed. A watchdog thread checks the
calls in progress (every limit/20, 1 ms to 100 ms), so a step costs no system call: see
``benchmarks/bench_fmu.py`` for the figure. Without the extension (not built) FMUs are
called through ctypes, unguarded.
"""

from __future__ import annotations

import glob
import os
import shutil
import signal
import tempfile

from ego.control.base import ControllerError
from ego.params import ConfigError

try:
    from ego import _fmu_guard as native  # type: ignore[attr-defined]
except ImportError:  # not built: unguarded ctypes calls
    native = None

ENV = "EGO_FMU_STEP_LIMIT"
DEFAULT_LIMIT = 30.0
LIMIT_RANGE = (0.01, 86400.0)


def step_limit() -> float:
    """Seconds one FMU call may take (``EGO_FMU_STEP_LIMIT``); ConfigError (one line) when
    the variable is not a number in range."""
    text = os.environ.get(ENV, "").strip()
    if not text:
        return DEFAULT_LIMIT
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    lo, hi = LIMIT_RANGE
    if not lo <= value <= hi:
        raise ConfigError(
            f"bad {ENV} {text[:40]!r}: the time limit of one FMU call, in seconds, from {lo:g} to {hi:g} "
            f"(default {DEFAULT_LIMIT:g})"
        )
    return value


class FmuAbort(ControllerError):
    """The FMU was left in the middle of a call: hung, crashed or interrupted."""


class FmuTimeout(FmuAbort):
    """A call ran past the step limit."""


class FmuCrash(FmuAbort):
    """The FMU crashed in a call (a fatal signal)."""


class FmuInterrupted(FmuAbort):
    """SIGINT or SIGTERM arrived while the FMU was in a call: the run ends ``interrupted``."""

    interrupted = True


def signal_name(signo: int) -> str:
    try:
        return signal.Signals(signo).name
    except ValueError:
        return f"signal {signo}"


WHY = {"SIGSEGV": "segmentation fault", "SIGBUS": "bus error", "SIGFPE": "arithmetic error", "SIGABRT": "abort"}


def abort_error(args: tuple, fmu: str, what: str, t: float | None) -> FmuAbort:
    """The exception for ``_fmu_guard.Aborted(signo, timed_out, seconds)`` in call ``what``
    of FMU ``fmu`` at simulated time ``t`` (None: before the run)."""
    signo, timed_out, seconds = args
    at = f" at t = {t:.3f} s" if t is not None else " before the run"
    if timed_out:
        return FmuTimeout(
            f"FMU {fmu!r} hung: {what}{at} did not return within the step limit of "
            f"{native.get_limit():g} s ({ENV}); the run was stopped there"
        )
    name = signal_name(signo)
    if signo in (signal.SIGINT, signal.SIGTERM):
        return FmuInterrupted(f"interrupted ({name}) while FMU {fmu!r} was in {what}{at}")
    why = WHY.get(name, "")
    return FmuCrash(f"FMU {fmu!r} crashed with {name}{f' ({why})' if why else ''} in {what}{at}")


def arm() -> None:
    """Before an FMU's first call in a run: the limit read, the signal handlers (re)installed
    (Python's signal.signal may have replaced them since)."""
    if native is not None:
        native.set_limit(step_limit())
        native.install()


def extraction_dir(name: str) -> str:
    """A new folder to extract FMU ``name`` into: ``ego-fmu-<pid>-<name>-*`` in the temporary
    folder, so the parent of a worker that died can name the FMU and remove what it left."""
    safe = "".join(c if c.isalnum() or c in "_." else "_" for c in name)[:40] or "fmu"
    remove_orphans()
    return tempfile.mkdtemp(prefix=f"ego-fmu-{os.getpid()}-{safe}-")


def remove_orphans() -> None:
    """Remove the folders of processes that no longer exist (killed with SIGKILL mid-run)."""
    for path in glob.glob(os.path.join(tempfile.gettempdir(), "ego-fmu-*-*")):
        pid = os.path.basename(path).split("-")[2]
        if not pid.isdigit():
            continue
        try:
            os.kill(int(pid), 0)
        except ProcessLookupError:
            shutil.rmtree(path, ignore_errors=True)
        except OSError:  # another user's process: alive
            pass


def left_by(pid: int) -> list[str]:
    """Remove the extraction folders a dead process ``pid`` left; the FMU names they held."""
    names = []
    for path in glob.glob(os.path.join(tempfile.gettempdir(), f"ego-fmu-{pid}-*")):
        base = os.path.basename(path)[len(f"ego-fmu-{pid}-") :]
        names.append(base.rsplit("-", 1)[0])
        shutil.rmtree(path, ignore_errors=True)
    return sorted(set(names))
