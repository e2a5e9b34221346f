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


def test_a_symlink_is_written_through_and_stays(tmp_path):
    """The checks before a run follow a link (a link to a folder is refused as a folder); the
    write does too: the file it points to is replaced, the link stays a link."""
    target = tmp_path / "keep" / "real.txt"
    target.parent.mkdir()
    target.write_text("old")
    link = tmp_path / "link.txt"
    link.symlink_to(target)
    write_text(link, "new")
    assert link.is_symlink() and target.read_text() == "new"
    dangling = tmp_path / "dangling.txt"
    dangling.symlink_to(tmp_path / "keep" / "later.txt")
    write_text(dangling, "made")
    assert dangling.is_symlink() and (tmp_path / "keep" / "later.txt").read_text() == "made"


@pytest.mark.sumo
def test_a_run_records_and_traces_through_links(tmp_path):
    from ego.runner import RunSpec, run

    (tmp_path / "keep").mkdir()
    rrd, csv = tmp_path / "link.rrd", tmp_path / "link.csv"
    rrd.symlink_to(tmp_path / "keep" / "run.rrd")
    csv.symlink_to(tmp_path / "keep" / "run.csv")
    run(RunSpec("emergency-brake", "pid", overrides={"duration": 3.0}, record=str(rrd), trace=str(csv)))
    assert rrd.is_symlink() and csv.is_symlink()
    assert (tmp_path / "keep" / "run.rrd").stat().st_size > 0 and (tmp_path / "keep" / "run.csv").stat().st_size > 0


@pytest.mark.sumo
def test_the_trace_is_written_when_the_recording_fails(tmp_path, monkeypatch):
    """A recording that cannot be written (a full disk) is reported; the trace, whose folder
    is fine, is written all the same (docs/traces.md: whatever the run's status)."""
    from ego.outputs import OutputError
    from ego.record import rerun_recorder
    from ego.runner import RunSpec, run

    close = rerun_recorder.RerunRecorder.close

    def full_disk(self, *args, **kwargs):
        close(self, *args, **kwargs)
        raise OutputError(f"cannot write {self.path}: [Errno 28] No space left on device")

    monkeypatch.setattr(rerun_recorder.RerunRecorder, "close", full_disk)
    spec = RunSpec(
        "emergency-brake",
        "pid",
        overrides={"duration": 3.0},
        record=str(tmp_path / "r.rrd"),
        trace=str(tmp_path / "t.csv"),
    )
    with pytest.raises(OutputError, match="No space left on device") as err:
        run(spec)
    assert err.value.result.metrics["status"] and (tmp_path / "t.csv").stat().st_size > 0


def test_a_finished_row_reaches_the_file_within_the_flush_time_without_another_row(tmp_path):
    """A row waits for the file at most flush_seconds, even when no other row follows (a long
    run after it, a slow executor shutdown): a kill -9 then loses only the last moments."""
    import time

    import pyarrow.parquet as pq

    from ego.sweep.results import ResultStore

    store = ResultStore(tmp_path, flush_rows=1000, flush_seconds=0.2)
    store.add({"run_id": "a", "scenario": "x", "status": "completed"})
    deadline = time.monotonic() + 5.0
    while not (tmp_path / "results.parquet").exists():
        assert time.monotonic() < deadline, "the row never reached the file"
        time.sleep(0.05)
    assert pq.read_table(tmp_path / "results.parquet").column("run_id").to_pylist() == ["a"]
    store.add({"run_id": "b", "scenario": "x", "status": "completed"})
    store.flush()
    assert len(pq.read_table(tmp_path / "results.parquet")) == 2


def test_a_column_only_later_rows_of_a_batch_have_is_kept(tmp_path):
    """collision_preventable exists only in the rows that collided: in a batch whose first
    row has no such key, pyarrow's from_pylist would drop the column (it did: 7 of 16 verdicts
    of a 200-run R157 sweep were lost)."""
    import pyarrow.parquet as pq

    from ego.sweep.results import ResultStore

    store = ResultStore(tmp_path, flush_rows=1000)
    store.add({"run_id": "a", "scenario": "x", "status": "completed", "collision": False})
    store.add({"run_id": "b", "scenario": "x", "status": "collision", "collision": True, "collision_preventable": True})
    store.flush()
    rows = pq.read_table(tmp_path / "results.parquet").to_pylist()
    assert [r["collision_preventable"] for r in rows] == [None, True]
    store.add({"run_id": "c", "scenario": "x", "status": "completed", "collision": False, "later": 1.5})
    store.flush()
    assert pq.read_table(tmp_path / "results.parquet").column("later").to_pylist() == [None, None, 1.5]
