"""Trace export: every format written and read back with its units (pandas, pyarrow,
scipy.io.loadmat), the traffic log, bad paths, atomic writes, RunResult.to_pandas."""

import csv
import dataclasses
import math
import subprocess
import sys

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
from scipy.io import loadmat

from ego.params import ConfigError
from ego.results.export import check_trace_path, write_trace
from ego.results.traffic_log import UNITS as TRAFFIC_UNITS
from ego.results.traffic_log import TrafficLog
from ego.runner import RunSpec, run


@pytest.fixture(scope="module")
def result():
    """A real SUMO run, short: the emergency brake's first 3 s (its TTC column is infinite
    at the start: infinities must survive every format), without a traffic log: the traffic
    part is tested on a constructed one."""
    return dataclasses.replace(run(RunSpec("emergency-brake", "pid", 0, {"duration": 3.0})), traffic=None)


def traffic_log() -> TrafficLog:
    """Two vehicles over three SUMO steps; the second appears at the second step."""
    f = np.array
    return TrafficLog(
        ids=("left_3", "flow.0"),
        t=f([0.1, 0.2, 0.2, 0.3, 0.3]),
        vehicle=f([0, 0, 1, 0, 1], dtype=np.int32),
        x=f([10.0, 12.5, -20.0, 15.0, -18.25]),
        y=f([3.2, 3.2, -3.2, 3.2, -3.2]),
        heading=f([0.0, 0.01, math.pi, 0.02, math.pi]),
        speed=f([25.0, 25.0, 20.0, 25.5, 20.0]),
        length=f([4.5, 4.5, 12.0, 4.5, 12.0]),
        width=f([1.8, 1.8, 2.5, 1.8, 2.5]),
    )


@pytest.mark.sumo
def test_a_real_run_has_its_trace_with_units(result):
    assert result.columns[0] == "t" and result.units["t"] == "s"
    assert np.isinf(result.column("ttc_rear")).any()


@pytest.mark.sumo
def test_csv_holds_every_column_and_a_units_sidecar(result, tmp_path):
    files = write_trace(result, tmp_path / "eb.csv")
    assert files == [tmp_path / "eb.csv", tmp_path / "eb.units.csv"]  # no traffic log: no traffic file
    df = pd.read_csv(tmp_path / "eb.csv")
    assert tuple(df.columns) == result.columns
    np.testing.assert_array_equal(df.to_numpy(), result.trace)  # exact, infinities included
    with open(tmp_path / "eb.units.csv", newline="") as f:
        rows = list(csv.reader(f))
    assert rows[0] == ["table", "column", "unit"]
    assert [r[1] for r in rows[1:]] == list(result.columns)
    assert {r[1]: r[2] for r in rows[1:]} == {c: result.units[c] for c in result.columns}
    assert {r[0] for r in rows[1:]} == {"trace"}


@pytest.mark.sumo
def test_parquet_keeps_units_in_the_field_metadata(result, tmp_path):
    write_trace(result, tmp_path / "eb.parquet")
    table = pq.read_table(tmp_path / "eb.parquet")
    assert tuple(table.column_names) == result.columns
    units = {f.name: f.metadata[b"unit"].decode() for f in table.schema}
    assert units == {c: result.units[c] for c in result.columns}
    assert units["speed"] == "m/s" and units["ttc_front"] == "s"
    meta = table.schema.metadata
    assert meta[b"scenario"] == b"emergency-brake" and meta[b"controller"] == b"pid" and meta[b"seed"] == b"0"
    np.testing.assert_array_equal(table.to_pandas().to_numpy(), result.trace)


@pytest.mark.sumo
def test_mat_reads_back_with_loadmat(result, tmp_path):
    write_trace(result, tmp_path / "eb.mat")
    mat = loadmat(tmp_path / "eb.mat", squeeze_me=True, simplify_cells=True)
    assert set(mat["trace"]) == set(result.columns)
    for i, c in enumerate(result.columns):
        np.testing.assert_array_equal(mat["trace"][c], result.trace[:, i])
        unit = mat["units"][c]  # '' reads back as an empty array
        assert (unit if isinstance(unit, str) else "") == result.units[c]
    assert mat["run"]["scenario"] == "emergency-brake" and mat["run"]["seed"] == 0
    assert "traffic" not in mat


@pytest.mark.sumo
def test_every_format_holds_the_traffic_log_with_units(result, tmp_path):
    log = traffic_log()
    with_traffic = dataclasses.replace(result, traffic=log)
    ids = [log.ids[i] for i in log.vehicle]

    files = write_trace(with_traffic, tmp_path / "run.csv")
    assert files[-1] == tmp_path / "run.traffic.csv"
    df = pd.read_csv(files[-1])
    assert list(df.columns) == list(TRAFFIC_UNITS)
    assert list(df["vehicle"]) == ids
    np.testing.assert_array_equal(df["x"], log.x)
    np.testing.assert_array_equal(df["heading"], log.heading)
    with open(tmp_path / "run.units.csv", newline="") as f:
        traffic_units = {r[1]: r[2] for r in csv.reader(f) if r[0] == "traffic"}
    assert traffic_units == TRAFFIC_UNITS

    files = write_trace(with_traffic, tmp_path / "run.parquet")
    assert files == [tmp_path / "run.parquet", tmp_path / "run.traffic.parquet"]
    table = pq.read_table(files[1])
    assert table.column("vehicle").to_pylist() == ids
    assert {f.name: f.metadata[b"unit"].decode() for f in table.schema} == TRAFFIC_UNITS
    np.testing.assert_array_equal(table.column("speed").to_numpy(), log.speed)

    write_trace(with_traffic, tmp_path / "run.mat")
    mat = loadmat(tmp_path / "run.mat", squeeze_me=True, simplify_cells=True)
    traffic = mat["traffic"]
    assert list(traffic["ids"]) == list(log.ids)
    # 1-based, as MATLAB indexes: traffic.ids{traffic.vehicle(k)}
    assert [traffic["ids"][k - 1] for k in traffic["vehicle"]] == ids
    np.testing.assert_array_equal(traffic["y"], log.y)
    assert mat["traffic_units"]["x"] == "m" and mat["traffic_units"]["heading"] == "rad"


@pytest.mark.sumo
def test_a_real_runs_traffic_log_reaches_the_file_as_simulated(tmp_path):
    """The traffic log of a real run (the emergency brake's lead is within 50 m from the
    start) survives the Parquet file row for row."""
    real = run(RunSpec("emergency-brake", "pid", 0, {"duration": 2.0}))
    log = real.traffic
    assert log is not None and len(log) > 0
    files = write_trace(real, tmp_path / "run.parquet")
    table = pq.read_table(files[1])
    assert table.num_rows == len(log)
    assert table.column("vehicle").to_pylist() == [log.ids[i] for i in log.vehicle]
    for name in ("t", "x", "y", "heading", "speed", "length", "width"):
        np.testing.assert_array_equal(table.column(name).to_numpy(), getattr(log, name))
    # every row within the log's 50 m of the ego's centre of gravity at that time
    ego = real.to_pandas().set_index("t")
    gaps = np.hypot(
        table.column("x").to_numpy() - ego["x"].reindex(log.t, method="nearest").to_numpy(),
        table.column("y").to_numpy() - ego["y"].reindex(log.t, method="nearest").to_numpy(),
    )
    assert gaps.max() <= 50.0 + 2.0  # the ego moves < 2 m between a SUMO step and the nearest row


@pytest.mark.sumo
def test_to_pandas_gives_the_trace_and_the_traffic_with_units(result):
    df = result.to_pandas()
    assert tuple(df.columns) == result.columns and len(df) == len(result.trace)
    assert df.attrs["units"]["speed"] == "m/s" and df.attrs["units"]["t"] == "s"
    assert df.attrs["status"] == result.status and df.attrs["controller"] == "pid"
    assert result.to_pandas(traffic=True) is None  # this run has no traffic log
    traffic = dataclasses.replace(result, traffic=traffic_log()).to_pandas(traffic=True)
    assert list(traffic["vehicle"]) == ["left_3", "left_3", "flow.0", "left_3", "flow.0"]
    assert traffic.attrs["units"] == TRAFFIC_UNITS


def test_pandas_is_imported_only_when_asked():
    code = "import sys; import ego.runner, ego.results.export, ego.scenarios; print('pandas' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


@pytest.mark.parametrize(
    "name, suffix",
    [("run.txt", "'.txt'"), ("run", "'(none)'"), ("run.CSV", "'.CSV'"), ("run.mat.gz", "'.gz'")],
    ids=str,
)
def test_an_unknown_suffix_names_it_and_the_allowed_ones(name, suffix, tmp_path):
    with pytest.raises(ConfigError) as err:
        check_trace_path(str(tmp_path / name))
    msg = str(err.value)
    assert "\n" not in msg and f"unknown suffix {suffix} (allowed: .csv, .parquet, .mat)" in msg


def test_a_folder_is_no_trace_file(tmp_path):
    (tmp_path / "x.csv").mkdir()
    with pytest.raises(ConfigError, match="it is a folder"):
        check_trace_path(str(tmp_path / "x.csv"))


class Unwritable:
    def __str__(self):
        raise RuntimeError("cannot be written")


@pytest.mark.sumo
def test_a_failed_write_leaves_the_old_file_and_no_temporary(result, tmp_path):
    path = tmp_path / "eb.traffic.csv"
    path.write_text("old")
    # the writer fails in the middle of the traffic file: its header is out, its first id is not
    broken = dataclasses.replace(result, traffic=dataclasses.replace(traffic_log(), ids=(Unwritable(), "b")))
    with pytest.raises(RuntimeError, match="cannot be written"):
        write_trace(broken, tmp_path / "eb.csv")
    assert path.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["eb.csv", "eb.traffic.csv"]


@pytest.mark.sumo
def test_ego_run_trace_checks_the_path_first_and_writes_the_file(tmp_path):
    ego = [sys.executable, "-m", "ego", "run", "emergency-brake", "-c", "pid", "--set", "duration=2"]
    bad = subprocess.run(
        [*ego, "--trace", str(tmp_path / "t.xlsx"), "--record", str(tmp_path / "r.rrd")],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "'.xlsx'" in bad.stderr
    assert list(tmp_path.iterdir()) == []  # nothing ran, nothing written
    good = subprocess.run([*ego, "--trace", str(tmp_path / "t.parquet")], capture_output=True, text=True, timeout=300)
    assert f"trace: {tmp_path / 't.parquet'}" in good.stdout
    assert pq.read_table(tmp_path / "t.parquet").num_rows == 200


def test_recordings_of_different_runs_have_different_ids_and_say_their_simulator():
    """Recordings opened together merge by id: the id tells the backend and the parameters
    apart, the seed last; the trace's metadata names the simulator where there are two."""
    from ego.results.export import run_info
    from ego.results.run import RunResult
    from ego.runner import RunSpec, recording_id

    ids = {
        recording_id(RunSpec("emergency-brake", "pid", 0)),
        recording_id(RunSpec("emergency-brake", "pid", 0, backend="highway-env")),
        recording_id(RunSpec("emergency-brake", "pid", 0, {"ego_speed": "25"})),
        recording_id(RunSpec("emergency-brake", "pid", 0, {"ego_speed": "26"})),
    }
    assert len(ids) == 4 and all(i.rsplit("-", 1)[1] == "0" for i in ids)
    assert recording_id(RunSpec("emergency-brake", "pid", 3)) == "emergency-brake-pid-3"
    result = RunResult("cut-in", "pid", 0, "completed", {"backend": "highway-env"}, [], ("t",), None)
    assert run_info(result)["backend"] == "highway-env"
