"""Checks of the places ego will write, made before the first step of a run.

A write that fails after a run (or a training) has been done loses its work, so every output
location - and every name that will be created inside it, under its final and its temporary
(``<name>.<pid>.partial``) name - is checked first:

* names too long for the filesystem (``NAME_MAX`` per component, ``PATH_MAX`` in all, asked
  of the filesystem with ``os.pathconf``), the temporary suffix included;
* symlink loops, and ``/proc`` or ``/sys`` (not places for files);
* occupied names: a file where a folder is needed, a folder (or a FIFO, a socket, a device)
  where a file is needed;
* read-only filesystems and folders that cannot be written;
* free space: a filesystem with less than :data:`MIN_FREE_BYTES` free is refused.

Each problem is a :class:`ego.params.ConfigError` with one line naming the path, so the CLI
exits 2 before anything runs. A write that fails anyway (the disk fills during the run) is an
:class:`ego.outputs.OutputError` (see there).
"""

from __future__ import annotations

import errno
import os
import stat
from collections.abc import Iterable
from pathlib import Path

from ego.params import ConfigError

#: refuse a filesystem with less free space than this (a recording of a long run is a few MB)
MIN_FREE_BYTES = 8 * 1024 * 1024
#: the longest temporary suffix ego adds to a name: ``.<pid>.partial`` with the largest pid
PARTIAL_SUFFIX_LEN = len(".4194304.partial")
_NOT_FOR_FILES = ("/proc", "/sys")


def min_free_bytes() -> int:
    """:data:`MIN_FREE_BYTES`, or ``EGO_MIN_FREE_MB`` (a whole number of MiB, 0 to switch the
    check off) from the environment."""
    text = os.environ.get("EGO_MIN_FREE_MB", "")
    if text.strip().isascii() and text.strip().isdigit():
        return int(text) * 1024 * 1024
    return MIN_FREE_BYTES


def _bad(what: str, text: str, why: str) -> ConfigError:
    return ConfigError(f"bad {what} {text!r}: {why}")


def _limits(existing: Path) -> tuple[int, int]:
    """(NAME_MAX, PATH_MAX) of the filesystem holding ``existing`` (255/4096 if unknown)."""
    try:
        name_max = os.pathconf(existing, "PC_NAME_MAX")
    except (OSError, ValueError):
        name_max = 255
    try:
        path_max = os.pathconf(existing, "PC_PATH_MAX")
    except (OSError, ValueError):
        path_max = 4096
    return name_max or 255, path_max or 4096


def nearest_existing(path: Path) -> Path:
    """The nearest ancestor of ``path`` (or ``path`` itself) that exists (symlinks followed)."""
    p = Path(os.path.abspath(path))
    while True:
        try:
            os.stat(p)
            return p
        except OSError:  # missing, under a file, too long, a loop: look further up
            pass
        if p.parent == p:
            return p
        p = p.parent


def _file_ancestor(path: Path) -> Path:
    """The ancestor of ``path`` that is a file (where a folder should be)."""
    for parent in reversed(Path(os.path.abspath(path)).parents):
        if os.path.isfile(parent):
            return parent
    return path.parent


def _resolve(path: Path, what: str, text: str) -> Path:
    try:
        return Path(os.path.realpath(path, strict=False))
    except (
        OSError,
        RuntimeError,
    ) as exc:  # a symlink loop (Python < 3.13 raises RuntimeError)
        raise _bad(what, text, f"cannot resolve it ({getattr(exc, 'strerror', None) or exc})") from None


def _loop_check(path: Path, what: str, text: str) -> None:
    """A symlink loop anywhere in ``path``: os.stat says ELOOP."""
    p = Path(os.path.abspath(path))
    for part in [*reversed(p.parents), p]:
        try:
            os.stat(part)
        except OSError as exc:
            if exc.errno == errno.ELOOP:
                raise _bad(what, text, f"{part} is a symlink loop") from None
            if exc.errno in (errno.ENOENT, errno.ENOTDIR):
                return
            if exc.errno == errno.ENAMETOOLONG:
                raise _bad(what, text, "the name is too long for the filesystem") from None
            raise _bad(what, text, f"{part}: {exc.strerror}") from None


def _not_for_files(resolved: Path, what: str, text: str) -> None:
    s = str(resolved)
    if any(s == root or s.startswith(root + "/") for root in _NOT_FOR_FILES):
        raise _bad(what, text, "not a place for files")


def _lengths(path: Path, what: str, text: str, extra: int) -> None:
    """Every component of ``path`` (its last one plus ``extra`` characters) within NAME_MAX,
    the whole within PATH_MAX."""
    name_max, path_max = _limits(nearest_existing(path))
    absolute = os.path.abspath(path)
    for part in Path(absolute).parts[1:-1]:
        if len(os.fsencode(part)) > name_max:
            raise _bad(
                what,
                text,
                f"the folder name {part[:40]!r}... is longer than the filesystem allows ({name_max} bytes)",
            )
    last = len(os.fsencode(Path(absolute).name)) + extra
    if last > name_max:
        raise _bad(
            what,
            text,
            f"the name is too long for the filesystem ({last} bytes"
            + (" with ego's temporary suffix" if extra else "")
            + f"; at most {name_max})",
        )
    if len(os.fsencode(absolute)) + extra >= path_max:
        raise _bad(
            what,
            text,
            f"the path is too long for the filesystem (at most {path_max} bytes)",
        )


def _space_and_writable(path: Path, what: str, text: str) -> None:
    """The folder that will hold ``path`` (or its nearest existing ancestor) is a writable
    folder on a writable filesystem with room."""
    parent = nearest_existing(path.parent)
    try:
        st = os.stat(parent)
    except OSError as exc:
        raise _bad(what, text, f"{parent}: {exc.strerror}") from None
    if not stat.S_ISDIR(st.st_mode):
        raise _bad(what, text, f"{parent} is a file, not a folder")
    try:
        vfs = os.statvfs(parent)
    except OSError:
        return
    if vfs.f_flag & os.ST_RDONLY:
        raise _bad(what, text, f"{parent} is on a read-only filesystem")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise _bad(what, text, f"cannot write into {parent}")
    free = vfs.f_bavail * vfs.f_frsize
    need = min_free_bytes()
    if free < need:
        raise _bad(
            what,
            text,
            f"the filesystem of {parent} has {free // 1024} KiB free "
            f"(ego needs at least {need // (1024 * 1024)} MiB; EGO_MIN_FREE_MB sets it)",
        )


def check_path_names(path: str | os.PathLike, what: str, text: str | None = None, partial: bool = True) -> Path:
    """Only the name of ``path``: lengths (with the temporary suffix if ``partial``), symlink
    loops, ``/proc`` and ``/sys``. Safe to call before anything else looks at the path."""
    path = Path(path)
    text = str(path) if text is None else text
    _lengths(path, what, text, PARTIAL_SUFFIX_LEN if partial else 0)
    _loop_check(path, what, text)
    _not_for_files(_resolve(path, what, text), what, text)
    return path


def _place(path: Path, what: str, text: str, suffix_len: int) -> os.stat_result | None:
    """The checks every output place shares (name lengths with ``suffix_len`` more for a
    temporary name, symlink loops, places ego never writes) and what is there now: its
    ``os.stat`` result, or None when nothing is."""
    _lengths(path, what, text, suffix_len)
    _loop_check(path, what, text)
    _not_for_files(_resolve(path, what, text), what, text)
    try:
        return os.stat(path)
    except FileNotFoundError:
        return None
    except NotADirectoryError:
        raise _bad(what, text, f"{_file_ancestor(path)} is a file, not a folder") from None
    except OSError as exc:
        raise _bad(what, text, exc.strerror or str(exc)) from None


def check_file_target(path: str | os.PathLike, what: str, text: str | None = None, partial: bool = True) -> Path:
    """``path`` may be created (or replaced) as a regular file, written under its temporary
    name first (``partial``); see the module docstring. Returns ``path``."""
    path = Path(path)
    text = str(path) if text is None else text
    st = _place(path, what, text, PARTIAL_SUFFIX_LEN if partial else 0)
    if st is not None:
        if stat.S_ISDIR(st.st_mode):
            raise _bad(what, text, "it is a folder (expected a file)")
        if not stat.S_ISREG(st.st_mode):
            raise _bad(what, text, "it is not a regular file (a FIFO, socket or device)")
        if not os.access(path, os.W_OK):
            raise _bad(what, text, "the file cannot be written")
    _space_and_writable(path, what, text)
    return path


def check_folder_target(path: str | os.PathLike, what: str, text: str | None = None) -> Path:
    """``path`` is a folder ego may write into, or may be created as one."""
    path = Path(path)
    text = str(path) if text is None else text
    st = _place(path, what, text, 0)
    if st is not None:
        if not stat.S_ISDIR(st.st_mode):
            raise _bad(what, text, "it is a file (expected a folder)")
        try:
            vfs = os.statvfs(path)
        except OSError:
            vfs = None
        if vfs is not None and vfs.f_flag & os.ST_RDONLY:
            raise _bad(what, text, "it is on a read-only filesystem")
        if not os.access(path, os.W_OK | os.X_OK):
            raise _bad(what, text, "cannot write into it")
        _space_and_writable(path / "x", what, text)
    else:
        _space_and_writable(path, what, text)
    return path


def check_folder_contents(
    folder: str | os.PathLike,
    what: str,
    files: Iterable[str] = (),
    folders: Iterable[str] = (),
    text: str | None = None,
) -> None:
    """The names ego will create inside output folder ``folder``: each of ``files`` (relative
    paths) must be free for a file (and its temporary name), each of ``folders`` free for a
    folder. One ConfigError naming the first occupied name."""
    folder = Path(folder)
    text = str(folder) if text is None else text
    prefix = f"bad {what} {text!r}: "
    for name, check in [(n, check_folder_target) for n in folders] + [(n, check_file_target) for n in files]:
        try:
            check(folder / name, what, text)
        except ConfigError as exc:
            why = str(exc).removeprefix(prefix)
            raise ConfigError(f"{prefix}{name} inside it: {why}") from None


def trace_files(path: str | os.PathLike[str], traffic: bool = True) -> list[Path]:
    """The files :func:`ego.results.export.write_trace` writes for ``path`` (``traffic``: the run has a traffic log)."""
    path = Path(path)
    if path.suffix == ".csv":
        return [path, path.with_name(f"{path.stem}.units.csv")] + (
            [path.with_name(f"{path.stem}.traffic.csv")] if traffic else []
        )
    if path.suffix == ".parquet":
        return [path] + ([path.with_name(f"{path.stem}.traffic.parquet")] if traffic else [])
    return [path]


def check_run_outputs(spec) -> None:
    """Every file one run (a :class:`ego.runner.RunSpec`) writes - its recording, its trace
    with the sidecar files beside it (``x.units.csv`` beside ``--trace x.csv``), its video -
    free and writable, before the run starts."""
    if spec.record is not None:
        check_file_target(os.fspath(spec.record), "--record path", os.fspath(spec.record))
    if spec.trace is not None:
        for path in trace_files(spec.trace):
            text = os.fspath(spec.trace)
            try:
                check_file_target(path, "--trace path", text)
            except ConfigError as exc:
                if Path(path) == Path(text):
                    raise
                prefix = f"bad --trace path {text!r}: "
                why = str(exc).removeprefix(prefix)
                raise ConfigError(f"{prefix}{path} (written beside it): {why}") from None
    if spec.video is not None:
        check_file_target(os.fspath(spec.video), "--video path", os.fspath(spec.video))


def check_compare_outputs(out: str | os.PathLike, specs, traces: str | None) -> None:
    """Every name ``ego compare`` creates in ``out`` (its tables, the lock, runs/ and traces/)
    and every run's files, before anything runs."""
    from ego.outputs import LOCK_FILE

    out = Path(out)
    check_folder_target(out, "--out", str(out))
    folders = ["runs"] + (["traces"] if traces else [])
    files = ["metrics.csv", "metrics_units.csv", "metrics.md", "compare.json", LOCK_FILE]
    for spec in specs:
        for attr in ("record", "trace"):
            value = getattr(spec, attr)
            if value is not None:
                try:
                    files.append(str(Path(value).relative_to(out)))
                except ValueError:
                    pass
    if traces:
        for spec in specs:
            for extra in trace_files(spec.trace)[1:]:
                files.append(str(Path(extra).relative_to(out)))
    check_folder_contents(out, "--out", files=files, folders=folders, text=str(out))
