"""Where a scenario file's road and catalogs are: the paths as written, then search folders.

A scenario names its road (``<LogicFile filepath>``) and catalog folders (``<Directory
path>``) relative to itself, but real files are written for another working directory or
another disk: the reference player's examples name ``../resources/xodr/curve_r100.xodr``
(relative to its ``bin`` folder, which it searches) or ``C:/Users/.../highway.xodr``. ego
looks, in order (docs/openscenario.md, "Finding a scenario's files"):

1. the path as written, relative to the scenario's folder (an absolute one as it is; ``\\``
   read as ``/``);
2. in each search folder - the scenario's folder, each ``--path DIR`` of the command line,
   then each folder of ``$EGO_PATH`` (separated by ``:``; ``;`` on Windows) - the path as
   written (when relative) and then the file's name alone.

The reference player (esmini) looks the same way (the path as written, relative to the
scenario, the name in its working directory, then each ``--path`` with the path and with the
name). A file found by step 2 is used with a one-line note on stderr (``ego: warning: ...``,
once per process); one not found is a one-line error listing every place looked.
"""

from __future__ import annotations

import hashlib
import os
import re
import sys
from collections.abc import Iterable
from pathlib import Path, PurePosixPath

#: the environment variable of extra search folders (``--path`` prepends to it for the command)
SEARCH_ENV = "EGO_PATH"

#: the warnings a command printed (short digests), for the worker processes it starts: a
#: sweep's workers resolve the file again and would print each warning once more
WARNED_ENV = "EGO_WARNED"

_DRIVE = re.compile(r"^[A-Za-z]:[\\/]")


def warn(message: str) -> None:
    """``ego: warning: message`` on stderr, once per command: a file is resolved several times
    a run, and the worker processes a command starts inherit what it printed (``$EGO_WARNED``)."""
    digest = hashlib.sha1(message.encode()).hexdigest()[:12]
    printed = os.environ.get(WARNED_ENV, "").split()
    if digest not in printed:
        os.environ[WARNED_ENV] = " ".join([*printed, digest])
        print(f"ego: warning: {message}", file=sys.stderr)


def forget_warnings() -> None:
    """Print every warning again (a new command in the same process)."""
    os.environ.pop(WARNED_ENV, None)


def search_folders() -> list[Path]:
    """The folders of ``$EGO_PATH`` (``--path`` puts its folders first), in order."""
    return [Path(p) for p in os.environ.get(SEARCH_ENV, "").split(os.pathsep) if p.strip()]


def _norm(p: Path) -> Path:
    """``p`` absolute with its links resolved and ``..`` taken out as the file system does, and
    by the letter past a folder that does not exist (a search folder ``bin`` that does not
    exist still gives ``bin/../resources``, as the reference player's own bin does)."""
    return Path(os.path.realpath(p))


def _exists(p: Path, folder: bool) -> bool:
    try:
        return p.is_dir() if folder else p.is_file()
    except (OSError, ValueError):  # a name too long, a NUL byte: no such file
        return False


def written_parts(written: str) -> tuple[str, bool, str]:
    """(the path with ``/`` separators, whether it is absolute - a Windows drive path
    ``C:/...`` counts as absolute, on another machine -, its last component)."""
    posix = written.replace("\\", "/")
    absolute = posix.startswith("/") or bool(_DRIVE.match(posix))
    name = PurePosixPath(posix).name
    return posix, absolute, name


def candidates(scenario: Path, written: str) -> tuple[list[Path], list[Path]]:
    """(the place the path as written names, the other places to look in order)."""
    posix, absolute, name = written_parts(written)
    here = _norm(scenario.parent)
    first = [] if _DRIVE.match(posix) and os.name != "nt" else [_norm(Path(posix) if absolute else here / posix)]
    rest: list[Path] = []
    for folder in [here, *map(_norm, search_folders())]:
        if not absolute and folder != here:
            rest.append(_norm(folder / posix))
        if name:
            rest.append(folder / name)
    seen = set(first)
    out = []
    for c in rest:
        if c not in seen:
            seen.add(c)
            out.append(c)
    return first, out


def locate(
    scenario: Path, written: str, what: str, folder: bool = False, note: bool = True
) -> tuple[Path | None, list[Path]]:
    """(where the file or ``folder`` named ``written`` in ``scenario`` is, or None; every
    place looked, in order). A place other than the path as written is noted on stderr
    (unless ``note`` is False)."""
    first, rest = candidates(scenario, written)
    for c in first:
        if _exists(c, folder):
            return c, first
    for i, c in enumerate(rest):
        if _exists(c, folder):
            if note:
                warn(
                    f"{scenario}: {what} {written!r} is not at {_shown(first)}; found as {c} (see docs/openscenario.md)"
                )
            return c, first + rest[: i + 1]
    return None, first + rest


def _shown(paths: Iterable[Path]) -> str:
    return ", ".join(str(p) for p in paths) or "the path as written (a Windows drive)"


def looked(paths: Iterable[Path]) -> str:
    """The places looked, for an error message."""
    return f"looked for {_shown(paths)}"
