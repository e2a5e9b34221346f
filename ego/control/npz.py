"""Checks of an ``.npz`` file made before numpy reads it.

``np.load`` trusts a member's header: a member that is not npy data fails with an
AttributeError deep inside numpy, and a header that claims 10^12 elements makes it try to
allocate them (MemoryError, or the machine's memory). Here every member is read only as far
as its header, and its claimed size is compared with the bytes the archive holds for it.
"""

from __future__ import annotations

import math
import os
import zipfile

from ego.params import ConfigError

#: a member claiming more than this is not one of ego's models
MAX_MEMBER_BYTES = 256 * 1024 * 1024


def check_npz_members(path: str | os.PathLike[str]) -> None:
    """ConfigError (naming the member) unless every member of the archive at ``path`` is
    npy data whose header fits the member's size."""
    import numpy as np

    try:
        archive = zipfile.ZipFile(path)
    except (zipfile.BadZipFile, OSError, ValueError) as exc:
        raise ConfigError(f"not a readable .npz file ({type(exc).__name__})") from None
    with archive:
        for info in archive.infolist():
            if not info.filename.endswith(".npy"):
                raise ConfigError(f"its member {info.filename!r} is not npy data")
            try:
                with archive.open(info) as f:
                    version = np.lib.format.read_magic(f)
                    if version == (1, 0):
                        shape, _, dtype = np.lib.format.read_array_header_1_0(f)
                    elif version == (2, 0):
                        shape, _, dtype = np.lib.format.read_array_header_2_0(f)
                    else:
                        raise ValueError(f"npy version {version}")
                    header = f.tell()
            except Exception as exc:  # noqa: BLE001 - any header numpy cannot read
                raise ConfigError(f"its member {info.filename!r} is not npy data ({type(exc).__name__})") from None
            claimed = math.prod(shape) * dtype.itemsize
            if claimed > MAX_MEMBER_BYTES or header + claimed > info.file_size:
                raise ConfigError(
                    f"its member {info.filename!r} claims {math.prod(shape):,} values "
                    f"({claimed:,} bytes) but holds {info.file_size - header:,} bytes"
                )
