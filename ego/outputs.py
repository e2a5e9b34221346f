"""Writing outputs safely: whole files or none, and one writer per output folder.

* :func:`atomic_path` / :func:`write_text` - a file is written under a temporary name in
  its own folder and renamed into place (``os.replace``) only once complete, so a reader
  (or a second writer of the same file) never sees half of it, and a process killed while
  writing leaves the previous file as it was.
* :class:`FolderLock` - ``ego compare`` and ``ego sweep`` hold their ``--out`` folder for as
  long as they run; a second process pointed at it is refused with one line naming the
  holder. The lock is an ``fcntl.flock`` on ``DIR/.ego.lock``: the kernel releases it when
  its holder exits, however it dies, so a stale lock never needs cleaning up.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from ego.params import ConfigError

LOCK_FILE = ".ego.lock"
#: how an unfinished file is named: ``<name>.<pid>.partial`` beside where it will go
PARTIAL_SUFFIX = ".partial"


class OutputError(RuntimeError):
    """A write that failed after every check passed (the disk filled during the run, the
    folder vanished): one line naming the file and the errno. ``result``: the run's result
    when the failure came after a run (its metrics are still worth printing). The CLI
    reports it in one line and exits 1."""

    def __init__(self, message: str, result=None) -> None:
        super().__init__(message)
        self.result = result


def output_error(path: str | Path, exc: BaseException, result=None) -> OutputError:
    """The :class:`OutputError` for ``exc`` raised while writing ``path``."""
    if isinstance(exc, OutputError):
        return exc
    if isinstance(exc, OSError) and exc.errno is not None:
        import errno as _errno

        why = f"[Errno {exc.errno} {_errno.errorcode.get(exc.errno, '?')}] {exc.strerror}"
    else:
        why = f"{type(exc).__name__}: {exc}"
    return OutputError(f"cannot write {path}: {why}", result)


def final_path(path: str | Path) -> Path:
    """The file a write to ``path`` replaces: ``path``, or where it links to (a symlink is
    written through, as the checks before the run follow it; the link stays)."""
    path = Path(path)
    return Path(os.path.realpath(path)) if path.is_symlink() else path


def partial_path(path: str | Path, pid: int | None = None) -> Path:
    """The temporary name of ``path`` while process ``pid`` (default: this one) writes it.
    The pid keeps two writers of one file apart; the suffix says what the file is if its
    writer died before renaming it."""
    path = Path(path)
    return path.with_name(f"{path.name}.{os.getpid() if pid is None else pid}{PARTIAL_SUFFIX}")


def remove_partials(folder: str | Path) -> None:
    """Remove the unfinished files in ``folder``: call it only while holding the folder
    (:class:`FolderLock`), when every writer of them is known to be gone."""
    for partial in Path(folder).glob(f"*{PARTIAL_SUFFIX}"):
        partial.unlink(missing_ok=True)


@contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path to write; it replaces ``path`` when the block ends normally
    and is removed when the block raises."""
    path = final_path(path)
    tmp = partial_path(path)
    try:
        yield tmp
        os.replace(tmp, path)
    except OSError as exc:  # a disk that filled, a folder that vanished: one line, no partial
        _unlink_quietly(tmp)
        raise output_error(path, exc) from None
    except BaseException:
        _unlink_quietly(tmp)
        raise


def _unlink_quietly(path: Path) -> None:
    try:
        path.unlink(missing_ok=True)
    except OSError:
        pass


def write_text(path: str | Path, text: str) -> None:
    """``path``'s new content, all of it or (if this process dies) none of it."""
    with atomic_path(path) as tmp:
        tmp.write_text(text)


def write_generated(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` (checked by :func:`ego.checks.check_generated`) atomically,
    making its folder."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"bad --out {str(path)!r}: cannot create its folder ({exc.strerror})") from None
    write_text(path, text)


class FolderLock:
    """This process's hold on an output folder (see the module docstring).

    ``what`` names the folder in the refusal (``--out``). Use as a context manager or call
    :meth:`acquire` / :meth:`release`.
    """

    def __init__(self, folder: str | Path, what: str = "--out") -> None:
        self.folder = Path(folder)
        self.what = what
        self._fd: int | None = None

    def acquire(self) -> FolderLock:
        import fcntl

        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise ConfigError(f"cannot create {self.what} folder {str(self.folder)!r}: {exc.strerror}") from None
        fd = os.open(self.folder / LOCK_FILE, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            holder = os.pread(fd, 64, 0).decode(errors="replace").strip() or "unknown"
            os.close(fd)
            raise ConfigError(
                f"bad {self.what} {str(self.folder)!r}: another ego process "
                f"(pid {holder}) is writing into it; wait for it or choose another "
                "folder"
            ) from None
        try:
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        except OSError as exc:  # a full disk: one line, before anything runs
            os.close(fd)
            raise output_error(self.folder / LOCK_FILE, exc) from None
        self._fd = fd
        return self

    def release(self) -> None:
        if self._fd is not None:
            fd, self._fd = self._fd, None
            os.close(fd)  # closing the descriptor drops the flock

    def __enter__(self) -> FolderLock:
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()
