"""ego.outputs: a file appears whole or not at all, and an output folder has one holder."""

import os

import pytest

from ego.outputs import FolderLock, atomic_path, remove_partials, write_text
from ego.params import ConfigError


def test_a_file_written_atomically_replaces_the_old_one_only_when_whole(tmp_path):
    path = tmp_path / "metrics.md"
    write_text(path, "old\n")
    with pytest.raises(RuntimeError):
        with atomic_path(path) as tmp:
            tmp.write_text("half")
            assert tmp.name == f"metrics.md.{os.getpid()}.partial" and tmp.parent == tmp_path
            raise RuntimeError("the writer failed")
    assert path.read_text() == "old\n"  # untouched, and no temporary file left
    assert [p.name for p in tmp_path.iterdir()] == ["metrics.md"]
    write_text(path, "new\n")
    assert path.read_text() == "new\n" and len(list(tmp_path.iterdir())) == 1


def test_an_output_folder_has_one_holder_at_a_time(tmp_path):
    out = tmp_path / "cmp"
    with FolderLock(out):
        assert (out / ".ego.lock").read_text() == f"{os.getpid()}\n"
        with pytest.raises(
            ConfigError,
            match=rf"^bad --out '{out}': another ego process \(pid {os.getpid()}\) "
            "is writing into it; wait for it or choose another folder$",
        ):
            FolderLock(out).acquire()
    with FolderLock(out):  # released: free again
        pass


def test_a_folder_that_cannot_be_made_is_one_line(tmp_path):
    """The lock makes its folder (the commands no longer do it before their checks)."""
    (tmp_path / "file").write_text("x")
    with pytest.raises(ConfigError, match=r"^cannot create --out folder '.*/file/out': Not a directory$"):
        FolderLock(tmp_path / "file" / "out").acquire()


def test_partial_files_are_removed_and_nothing_else(tmp_path):
    for name in ("a.rrd", "a.rrd.123.partial", "b.rrd.9.partial", "notes.txt"):
        (tmp_path / name).write_text("x")
    remove_partials(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.rrd", "notes.txt"]
