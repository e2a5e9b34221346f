"""Checks of user input made before anything runs: seeds, output locations and the input
files a run reads (a trained model, a gains preset).

Each raises :class:`ego.params.ConfigError` with one line naming the value and what is
allowed, so the CLI exits 2 before SUMO starts or a file is written.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

from ego.params import ConfigError

#: SUMO's seeds (and every seed ego takes): 0 .. 2^31 - 1
MAX_SEED = 2**31 - 1
#: more parallel processes than this (--jobs, --workers) is a typo, not a machine
MAX_JOBS = 1024
#: a JSON input (gains, metadata) larger than this is not one
MAX_JSON_BYTES = 16 * 1024 * 1024


def check_seed(value: Any, what: str = "seed") -> int:
    """``value`` as a seed, or ConfigError: a whole number from 0 to 2^31 - 1 (an int; a
    bool, float or string is refused rather than truncated)."""
    import numbers

    if isinstance(value, numbers.Integral) and not isinstance(value, (bool, int)):
        value = int(value)  # a numpy integer
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= MAX_SEED:
        raise ConfigError(f"bad value for {what}: {value!r} (expected a whole number from 0 to {MAX_SEED})")
    return value


def whole_number(what: str):
    """An argparse ``type`` for a whole number written as ``--set`` takes one: ASCII digits
    with an optional sign (``1_0``, ``٣``, `` 3`` and ``0x10`` are refused: ConfigError)."""
    import re

    def parse(text: str) -> int:
        if not re.fullmatch(r"[+-]?[0-9]+", text):
            raise ConfigError(f"bad value for {what}: {text!r} (expected a whole number written with the digits 0-9)")
        return int(text)

    parse.__name__ = "whole number (digits 0-9)"
    return parse


def _writable_ancestor(path: Path, what: str, text: str) -> None:
    """The nearest existing ancestor of ``path`` must be a folder we may write into."""
    parent = path.parent
    while not parent.exists():
        if parent == parent.parent:
            break
        parent = parent.parent
    if not parent.is_dir():
        raise ConfigError(f"bad {what} {text!r}: {parent} is a file, not a folder")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise ConfigError(f"bad {what} {text!r}: cannot write into {parent}")


def check_count(value: Any, what: str, lo: int, hi: int) -> None:
    """A whole number from ``lo`` to ``hi`` (None: a default is used), or ConfigError."""
    if value is None:
        return
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        raise ConfigError(f"bad value for {what}: {value!r} (expected a whole number from {lo} to {hi})")


def check_number(value: Any, what: str, lo: float, hi: float, unit: str) -> None:
    """A finite number from ``lo`` to ``hi`` (None: a default is used), or ConfigError."""
    if value is not None and not (finite_number(value) and lo <= value <= hi):
        raise ConfigError(f"bad value for {what}: {value!r} (expected {lo:g} to {hi:g} {unit})")


def check_output_file(text: str | None, what: str, suffix: str) -> Path:
    """An output file: non-empty, ending in ``suffix``, not a folder, in a folder that exists
    or can be made and may be written."""
    if text is None or not str(text).strip():
        raise ConfigError(f"bad {what} {text!r} (expected a file ending in {suffix})")
    path = Path(text)
    if path.suffix != suffix:
        raise ConfigError(f"bad {what} {text!r} (expected a file ending in {suffix})")
    from ego.paths import check_path_names

    check_path_names(path, what, text)
    if path.is_dir():
        raise ConfigError(f"bad {what} {text!r}: it is a folder (expected a file ending in {suffix})")
    if path.exists() and not path.is_file():
        raise ConfigError(
            f"bad {what} {text!r}: it is not a regular file (a FIFO, socket or device; "
            f"expected a file ending in {suffix})"
        )
    if path.exists() and not os.access(path, os.W_OK):
        raise ConfigError(f"bad {what} {text!r}: the file cannot be written")
    _writable_ancestor(path, what, text)
    from ego.paths import check_file_target

    check_file_target(path, what, text)
    check_not_shipped(path, what, text)
    return path


def check_not_shipped(path: Path, what: str, text: str) -> None:
    """Files inside the installed ``ego`` package (the trained models, the tuned gains) are
    replaced only through ``--install``; any other output there is refused."""
    import ego

    package = Path(os.path.realpath(Path(ego.__file__).parent))
    try:
        target = Path(os.path.realpath(path))
    except (OSError, RuntimeError):
        return
    if target == package or package in target.parents:
        raise ConfigError(
            f"bad {what} {text!r}: it is inside the ego package ({package}); ego writes there "
            "only to replace the files it ships (train/tune --install)"
        )


def check_output_dir(text: str | None, what: str) -> Path:
    """An output folder: non-empty, not inside the ego package, a folder if it exists, else
    creatable, and writable."""
    if text is None or not str(text).strip():
        raise ConfigError(f"bad {what} {text!r} (expected a folder)")
    path = Path(text)
    from ego.paths import check_folder_target, check_path_names

    check_path_names(path, what, text, partial=False)
    check_not_shipped(path, what, text)
    if path.exists():
        if not path.is_dir():
            raise ConfigError(f"bad {what} {text!r}: it is a file (expected a folder)")
        if not os.access(path, os.W_OK | os.X_OK):
            raise ConfigError(f"bad {what} {text!r}: cannot write into it")
        return check_folder_target(path, what, text)
    _writable_ancestor(path, what, text)
    return check_folder_target(path, what, text)


def check_input_file(text: str | os.PathLike, what: str, suffix: str) -> Path:
    """An input file: ends in ``suffix``, exists and is a readable file (not a folder)."""
    path = Path(text)
    if path.suffix != suffix:
        raise ConfigError(f"bad {what} {str(text)!r} (expected a file ending in {suffix})")
    if path.is_dir():
        raise ConfigError(f"bad {what} {str(text)!r}: it is a folder (expected a file ending in {suffix})")
    if not path.is_file():
        raise ConfigError(f"bad {what} {str(text)!r}: no such file")
    if not os.access(path, os.R_OK):
        raise ConfigError(f"bad {what} {str(text)!r}: the file cannot be read")
    return path


def read_json(text: str | os.PathLike, what: str) -> Any:
    """The contents of a JSON input file, or ConfigError naming the file and what is wrong
    (missing, a folder, not text, not JSON); NaN and infinities are not JSON and are refused."""
    path = check_input_file(text, what, ".json")

    def no_constant(name: str) -> Any:
        raise ValueError(f"{name} is not a number JSON allows")

    def no_duplicates(pairs: list) -> dict:
        seen: dict = {}
        for key, value in pairs:
            if key in seen:
                raise ValueError(f"the key {key!r} is given twice")
            seen[key] = value
        return seen

    try:
        if path.stat().st_size > MAX_JSON_BYTES:
            raise ValueError(f"larger than {MAX_JSON_BYTES // (1024 * 1024)} MiB")
        return json.loads(path.read_text(encoding="utf-8"), parse_constant=no_constant, object_pairs_hook=no_duplicates)
    except RecursionError:
        raise ConfigError(f"bad {what} {str(text)!r}: nested too deeply") from None
    except UnicodeDecodeError:
        raise ConfigError(f"bad {what} {str(text)!r}: not a text file (expected JSON)") from None
    except json.JSONDecodeError as exc:
        raise ConfigError(
            f"bad {what} {str(text)!r}: not valid JSON ({exc.msg} at line {exc.lineno} column {exc.colno})"
        ) from None
    except ValueError as exc:
        raise ConfigError(f"bad {what} {str(text)!r}: {exc}") from None
    except OSError as exc:
        raise ConfigError(f"bad {what} {str(text)!r}: {exc.strerror or exc}") from None


def finite_number(value: Any) -> bool:
    """A real number (not a bool, not text) that is neither NaN nor infinite."""
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


MIB = 1024 * 1024
#: the largest input files ego reads (docs/reliability.md, "Limits"): checked before reading
MAX_XOSC_BYTES = 16 * MIB  #: an OpenSCENARIO file or catalog
MAX_ROAD_BYTES = 256 * MIB  #: an OpenDRIVE .xodr or a SUMO .net.xml
MAX_MAP_BYTES = 1 * MIB  #: an FMU mapping file (TOML)


def _size(n: int) -> str:
    return f"{n // MIB} MiB" if n >= MIB and n % MIB == 0 else f"{n // 1024} KiB"


def read_limited(path: str | os.PathLike, what: str, limit: int, fail: Any = None) -> bytes:
    """The bytes of the regular file ``path`` (a ``what``: "scenario file"), at most ``limit``
    of them. Refused in one line before anything is read: a folder, a FIFO, a device (a link
    to /dev/zero), a socket, a symlink loop, a file larger than ``limit``; and a file that
    grows past it while read. ``fail(reason)`` makes the exception (default: ConfigError
    ``cannot read the <what> '<path>': <reason>``)."""
    import stat

    shown = os.fspath(path)

    def refuse(reason: str) -> Exception:
        return fail(reason) if fail is not None else ConfigError(f"cannot read the {what} {shown!r}: {reason}")

    try:
        # O_NONBLOCK: opening a FIFO with no writer must not wait for one
        fd = os.open(shown, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise refuse("no such file") from None
    except OSError as exc:
        import errno

        if exc.errno == errno.ELOOP:
            raise refuse("a symbolic link loop") from None
        if exc.errno == errno.EISDIR:
            raise refuse("it is a folder") from None
        raise refuse(exc.strerror or str(exc)) from None
    try:
        st = os.fstat(fd)
        if stat.S_ISDIR(st.st_mode):
            raise refuse("it is a folder")
        if not stat.S_ISREG(st.st_mode):
            kind = "a FIFO" if stat.S_ISFIFO(st.st_mode) else "a device" if stat.S_ISCHR(st.st_mode) else "special"
            raise refuse(f"not a regular file ({kind}; ego reads only regular files)")
        if st.st_size > limit:
            raise refuse(f"{st.st_size / MIB:.1f} MiB, larger than the limit of {_size(limit)}")
        chunks, total = [], 0
        while True:
            chunk = os.read(fd, min(limit + 1 - total, 1 << 20))
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
            if total > limit:
                raise refuse(f"larger than the limit of {_size(limit)}")
        return b"".join(chunks)
    except OSError as exc:
        raise refuse(exc.strerror or str(exc)) from None
    finally:
        os.close(fd)


def resolved(path: Path, what: str) -> Path:
    """``path`` with its links resolved; a symlink loop is one line (ConfigError)."""
    try:
        return path.resolve()
    except (RuntimeError, OSError):
        raise ConfigError(f"bad {what} {str(path)!r}: a symbolic link loop") from None


def check_generated(out: Path, force: bool, suffix: str, marker: str, command: str, head: int = 4096) -> None:
    """``out`` (an ``--out`` file ending in ``suffix``) may be written: a new file, one whose
    first ``head`` bytes carry ``marker`` (so ``command`` wrote it), or any with ``force``."""
    check_output_file(str(out), "--out", suffix)
    if out.exists() and not force:
        with open(out, "rb") as f:
            start = f.read(head)
        if marker.encode() not in start:
            raise ConfigError(
                f"bad --out {str(out)!r}: the file exists and {command} did not write it (give --force to replace it)"
            )
