"""Recordings are read back from the .rrd and checked against the run's own metrics."""

import os
import subprocess
import sys

import numpy as np
import pyarrow as pa
import pytest
from rerun.chunk import RrdReader

from ego.runner import RunSpec, run

pytestmark = pytest.mark.sumo


def _series(path, entity):
    """(time s, values) of a scalar entity, concatenated over its chunks in time order."""
    times, values = [], []
    for chunk in RrdReader(path).stream():
        if chunk.entity_path != entity:
            continue
        rb = chunk.to_record_batch()
        if "sim_time" not in rb.schema.names:
            continue
        times.append(rb.column("sim_time").cast(pa.int64()).to_numpy() / 1e9)
        values.append(np.array([v[0] for v in rb.column("Scalars:scalars").to_pylist()], dtype=float))
    t = np.concatenate(times)
    order = np.argsort(t, kind="stable")
    return t[order], np.concatenate(values)[order]


@pytest.fixture(scope="module")
def recorded(tmp_path_factory, fuzzy_ready):
    path = tmp_path_factory.mktemp("rec") / "eb.rrd"
    result = run(RunSpec("emergency-brake", "fuzzy", 0, record=str(path)))
    return path, result


def test_file_has_a_recording_and_an_embedded_blueprint(recorded):
    path, _ = recorded
    reader = RrdReader(path)
    assert len(reader.recordings()) == 1 and len(reader.blueprints()) == 1


def test_series_have_one_sample_per_step_and_match_the_metrics(recorded):
    path, result = recorded
    m = result.metrics
    t, d = _series(path, "/plots/lateral_error/ego")
    assert len(t) == m["steps"] == len(result.trace)
    np.testing.assert_allclose(t, result.column("t"), atol=1e-9)
    np.testing.assert_allclose(d, result.column("d"))
    _, ttc = _series(path, "/plots/ttc/front")
    assert np.nanmin(ttc) == pytest.approx(m["min_ttc_front"], abs=1e-4)  # inf recorded as gap (NaN)
    _, ay = _series(path, "/plots/lateral_accel/ego")
    assert np.max(np.abs(ay)) == pytest.approx(m["max_abs_lateral_accel"], abs=1e-4)
    for entity in (
        "/plots/speed/ego",
        "/plots/speed/reference",
        "/plots/Fx/Fx",
        "/plots/delta/delta",
        "/plots/ttc/rear",
        "/plots/ttc/trigger",
        "/plots/controller/1/fuzzy_u_lat",
    ):
        assert len(_series(path, entity)[0]) == m["steps"], entity


def test_vehicles_are_labelled_oriented_outlines(recorded):
    path, result = recorded
    rows = []
    for chunk in RrdReader(path).stream():
        if chunk.entity_path == "/world/map/vehicles":
            rb = chunk.to_record_batch()
            rows += list(
                zip(
                    rb.column("sim_time").cast(pa.int64()).to_numpy() / 1e9,
                    rb.column("LineStrips2D:labels").to_pylist(),
                    rb.column("LineStrips2D:strips").to_pylist(),
                )
            )
    assert len(rows) == result.metrics["steps"] // 10 + 1  # every SUMO step and t = 0
    _, labels, strips = rows[-1]
    assert {"ego", "lead"} <= set(labels)
    ego = np.array(strips[labels.index("ego")])
    assert ego.shape == (5, 2) and np.allclose(ego[0], ego[-1])  # closed outline
    sides = np.linalg.norm(np.diff(ego, axis=0), axis=1)
    assert sorted(sides) == pytest.approx([1.8, 1.8, 4.5, 4.5], abs=1e-3)  # width, length


def test_events_are_in_the_recording(recorded):
    path, result = recorded
    texts = []
    for chunk in RrdReader(path).stream():
        if chunk.entity_path == "/events":
            texts += chunk.to_record_batch().column("TextLog:text").to_pylist()
    flat = " ".join(t if isinstance(t, str) else t[0] for t in texts)
    assert "[trigger] front TTC" in flat and "[lane] change to the" in flat
    assert len(texts) == len(result.events)


def test_rerun_cli_verifies_the_file(recorded, tmp_path):
    path, _ = recorded
    env = dict(os.environ, XDG_CONFIG_HOME=str(tmp_path), XDG_DATA_HOME=str(tmp_path))
    rerun = os.path.join(os.path.dirname(sys.executable), "rerun")
    out = subprocess.run([rerun, "rrd", "verify", str(path)], capture_output=True, text=True, env=env)
    assert out.returncode == 0, out.stderr


def test_a_script_without_a_main_guard_runs_once_with_recording(tmp_path):
    # The writer process must not re-run the user's script (multiprocessing would import it).
    script = tmp_path / "my_run.py"
    rrd = tmp_path / "mine.rrd"
    script.write_text(
        "from ego.runner import RunSpec, run\n"
        "print('SCRIPT BODY')\n"
        f"r = run(RunSpec('emergency-brake', 'pid', 0, {{'duration': '3'}}, record={str(rrd)!r}))\n"
        "print('STATUS', r.status)\n"
    )
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert out.stdout.count("SCRIPT BODY") == 1 and "STATUS completed" in out.stdout
    assert RrdReader(rrd).recordings()


def test_in_process_writer_gives_the_same_file_content(tmp_path, fuzzy_ready):
    from ego.record import RerunRecorder
    from ego.runner import build

    spec = RunSpec("emergency-brake", "fuzzy", 0, {"duration": "4"})
    sc = build(spec)
    sc.recorder = RerunRecorder(tmp_path / "inproc.rrd", background=False)
    result = sc.run()
    t, d = _series(tmp_path / "inproc.rrd", "/plots/lateral_error/ego")
    assert len(t) == result.metrics["steps"]
    np.testing.assert_allclose(d, result.column("d"))


def test_a_curve_run_records_its_errors_and_the_ego_round_the_arc(tmp_path):
    path = tmp_path / "curve.rrd"
    result = run(RunSpec("curve", "narma-l2", 0, {"lead": 15.0}, record=str(path)))
    m = result.metrics
    assert m["status"] == "completed"
    t, ed = _series(path, "/plots/e_d/ego")
    assert len(t) == m["steps"]
    np.testing.assert_allclose(ed, result.column("e_d"))
    assert np.max(np.abs(ed[result.column("in_arc") > 0])) == pytest.approx(m["max_abs_ed"], abs=1e-6)
    for entity in (
        "/plots/e_a/ego",
        "/plots/a_x/applied",
        "/plots/a_x/plan",
        "/plots/gap/lead",
        "/plots/controller/m_per_rad/narma_g",
    ):
        assert len(_series(path, entity)[0]) == m["steps"], entity
    # the ego's outline turns with the road: heading +x at the start, +y at the end
    outlines = []
    for chunk in RrdReader(path).stream():
        if chunk.entity_path == "/world/map/vehicles":
            rb = chunk.to_record_batch()
            outlines += list(
                zip(rb.column("LineStrips2D:labels").to_pylist(), rb.column("LineStrips2D:strips").to_pylist())
            )
    first, last = (np.array(s[lab.index("ego")]) for lab, s in (outlines[0], outlines[-1]))
    assert {"ego", "lead"} <= set(outlines[-1][0])

    def long_side(box):
        sides = np.diff(box, axis=0)
        return sides[np.argmax(np.linalg.norm(sides, axis=1))]

    assert abs(long_side(first)[1]) < 0.05 * abs(long_side(first)[0])  # along x
    assert abs(long_side(last)[0]) < 0.2 * abs(long_side(last)[1])  # along y, nearly


def test_platoon_recording_has_every_follower(tmp_path):
    path = tmp_path / "platoon.rrd"
    result = run(RunSpec("platoon", "bp-pid-acc", 0, {"duration": "30"}, record=str(path)))
    steps = result.metrics["steps"]
    for vid in ("f1", "f2", "f3"):
        t, e = _series(path, f"/plots/spacing_error/{vid}")
        assert len(t) == steps
        np.testing.assert_allclose(e, result.column(f"e_{vid}"))
        _, kp = _series(path, f"/plots/kp/{vid}")
        np.testing.assert_allclose(kp, result.column(f"kp_{vid}"))
        for panel in ("gap", "speed", "accel", "command"):
            assert len(_series(path, f"/plots/{panel}/{vid}")[0]) == steps
    _, lead = _series(path, "/plots/speed/leader")
    np.testing.assert_allclose(lead, result.column("lead_speed"))
    labels = set()
    for chunk in RrdReader(path).stream():
        if chunk.entity_path == "/world/map/vehicles":
            for row in chunk.to_record_batch().column("LineStrips2D:labels").to_pylist():
                labels |= set(row)
    assert labels == {"leader", "f1", "f2", "f3"}
    assert RrdReader(path).blueprints()
