"""The ``ego`` command's entry point: signals handled from the first instant.

The console script calls :func:`main` here, a module that imports nothing heavy, so a
Ctrl-C or SIGTERM that arrives while ``ego.cli`` and its dependencies are still being
imported (the first half second) ends the command with ``ego: interrupted`` and exit 130,
not a traceback. It also makes sure the last of the output reaches stdout: a full stdout
(``ego list > /dev/full``) is one line and exit 1.
"""

from __future__ import annotations

import os
import signal
import sys

from ego.usercode import SignalInterrupt

EXIT_NOT_COMPLETED, EXIT_INTERRUPTED = 1, 130


def _describe(exc: OSError) -> str:
    import errno

    name = errno.errorcode.get(exc.errno, "?") if exc.errno is not None else "?"
    where = f" ({exc.filename})" if exc.filename else " (writing the output)"
    return f"[Errno {exc.errno} {name}] {exc.strerror or exc}{where}"


def _say(text: str) -> None:
    try:
        sys.stderr.write(text + "\n")
        sys.stderr.flush()
    except (OSError, ValueError):
        pass


def _stdout_gone() -> None:
    """Point stdout at /dev/null so the interpreter's last flush has nowhere to fail."""
    try:
        fd = os.open(os.devnull, os.O_WRONLY)
        os.dup2(fd, sys.stdout.fileno())
        os.close(fd)
    except (OSError, ValueError, AttributeError):
        pass


_received: list[int] = []


def _stop(signum, frame) -> None:
    """SIGINT and SIGTERM: noted (an import they break may raise something else), then a
    KeyboardInterrupt, which the command answers with ``ego: interrupted`` and exit 130."""
    _received.append(signum)
    raise SignalInterrupt


def _unraisable(hook=sys.unraisablehook):
    """``sys.unraisablehook`` for the command: a Ctrl-C or SIGTERM whose KeyboardInterrupt
    lands in a weakref callback or a finaliser (an import's module lock, a file's ``__del__``)
    cannot propagate, and Python would print it as "Exception ignored in ..." with its
    traceback. It is dropped quietly instead: the stop it asks for is on record (a run's
    handler has set its stop, so it ends at its next step; a signal during the imports is in
    ``_received``, checked once they are done); anything else goes to the default hook."""

    def unraisable(info) -> None:
        if isinstance(info.exc_value, KeyboardInterrupt):
            return
        hook(info)

    return unraisable


def main(argv=None) -> int:
    if argv is None:
        signal.signal(signal.SIGINT, _stop)
        signal.signal(signal.SIGTERM, _stop)
        sys.unraisablehook = _unraisable()
        argv = sys.argv[1:]
    try:
        try:
            from ego.cli import main as cli_main

            if _received:  # a signal whose KeyboardInterrupt an import swallowed
                raise KeyboardInterrupt
            status = cli_main(argv)
        except KeyboardInterrupt:
            _say("ego: interrupted")
            status = EXIT_INTERRUPTED
        except SystemExit as exc:  # --help, --version: their text must reach stdout too
            status = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
        except BrokenPipeError:
            _stdout_gone()
            return 0
        except OSError as exc:  # a write the checks could not foresee (stdout on a full disk)
            if _received:
                _say("ego: interrupted")
                return EXIT_INTERRUPTED
            _stdout_gone()
            _say(f"ego: error: {_describe(exc)}")
            return EXIT_NOT_COMPLETED
        except Exception:
            if _received:  # an import broken by the signal (numpy turns it into an ImportError)
                _say("ego: interrupted")
                return EXIT_INTERRUPTED
            raise
        try:
            sys.stdout.flush()
        except BrokenPipeError:
            _stdout_gone()
        except OSError as exc:
            _stdout_gone()
            _say(f"ego: error: {_describe(exc)}")
            return EXIT_NOT_COMPLETED
        return status
    except KeyboardInterrupt:  # a second signal while the first was being answered
        return EXIT_INTERRUPTED
    finally:
        # the answer is given: a signal during the interpreter's exit (where Python restores the
        # default action, which would end the process by the signal) changes nothing
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)


def run() -> None:
    """``python -m ego`` and the console script."""
    try:
        status = main()
    except KeyboardInterrupt:  # in the instant between an answer and the signals set aside
        status = EXIT_INTERRUPTED
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    # Python's own exit can still turn a Ctrl-C that came during the run into "killed by
    # SIGINT" (exit -2) after everything is done; the answer is given, so the exit handlers
    # run and the process ends with it
    import atexit

    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(status if isinstance(status, int) else 1)
