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

EXIT_NOT_COMPLETED, EXIT_INTERRUPTED = 1, 130


def _terminate(signum, frame) -> None:
    """SIGTERM ends the command like Ctrl-C."""
    raise KeyboardInterrupt


def _exit_now(signum, frame) -> None:  # pragma: no cover - a signal during interpreter exit
    os._exit(EXIT_INTERRUPTED)


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


def main(argv=None) -> int:
    if argv is None:
        signal.signal(signal.SIGTERM, _terminate)
        signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        try:
            from ego.cli import main as cli_main

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
            _stdout_gone()
            _say(f"ego: error: {_describe(exc)}")
            return EXIT_NOT_COMPLETED
        try:
            sys.stdout.flush()
        except BrokenPipeError:
            _stdout_gone()
        except OSError as exc:
            _stdout_gone()
            _say(f"ego: error: {_describe(exc)}")
            return EXIT_NOT_COMPLETED
        return status
    except KeyboardInterrupt:  # a second signal while the first was being reported
        _say("ego: interrupted")
        return EXIT_INTERRUPTED
    finally:
        if argv is None:  # the interpreter's exit (atexit handlers) is not interrupted with a traceback
            signal.signal(signal.SIGINT, _exit_now)
            signal.signal(signal.SIGTERM, _exit_now)


def run() -> None:
    """``python -m ego`` and the console script."""
    sys.exit(main())
