"""Ctrl-C or SIGTERM during a recorded run: status interrupted, metrics so far, exit 130,
and a recording that verifies and holds every step simulated."""

import os
import signal
import subprocess
import sys
import time

import pytest
from process_group import survivors, wait_for

pytestmark = pytest.mark.sumo


def _rows(path, entity="/plots/speed/ego"):
    from rerun.chunk import RrdReader

    n = 0
    for chunk in RrdReader(path).stream():
        if chunk.entity_path == entity:
            rb = chunk.to_record_batch()
            if "sim_time" in rb.schema.names:
                n += rb.num_rows
    return n


def _start_recorded_run(tmp_path, controller):
    """``ego run emergency-brake`` recording to tmp_path/run.rrd, in a session of its own,
    returned once the recording has begun (its partial file exists): past its imports."""
    env = dict(os.environ, XDG_CONFIG_HOME=str(tmp_path), XDG_DATA_HOME=str(tmp_path))
    p = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "ego",
            "run",
            "emergency-brake",
            "-c",
            controller,
            "--record",
            str(tmp_path / "run.rrd"),
            "--set",
            "duration=3600",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        env=env,
    )
    wait_for(lambda: list(tmp_path.glob("run.rrd.*.partial")), p, "the recording begin")
    return p


def _verify(path, tmp_path):
    rerun = os.path.join(os.path.dirname(sys.executable), "rerun")
    env = dict(os.environ, XDG_CONFIG_HOME=str(tmp_path), XDG_DATA_HOME=str(tmp_path))
    check = subprocess.run([rerun, "rrd", "verify", str(path)], capture_output=True, text=True, env=env)
    assert check.returncode == 0, check.stderr


# Repeated at several moments: where the signal lands (start-up, a step, a recorder batch)
# used to decide whether the recording survived. One of each signal runs by default, every
# moment with ``-m long``.
@pytest.mark.parametrize(
    "sig, after",
    [
        pytest.param(sig, after, id=f"{sig.lower()}-{after:g}s", marks=() if keep else pytest.mark.long)
        for sig, after, keep in [
            ("SIGINT", 0.0, False),
            ("SIGINT", 0.4, False),
            ("SIGINT", 1.0, True),
            ("SIGINT", 1.7, False),
            ("SIGTERM", 0.2, True),
            ("SIGTERM", 1.0, False),
        ]
    ],
)
def test_an_interrupted_recorded_run_keeps_everything_it_simulated(sig, after, tmp_path):
    rrd = tmp_path / "run.rrd"
    p = _start_recorded_run(tmp_path, "fuzzy")
    time.sleep(after)
    os.killpg(p.pid, getattr(signal, sig))  # the whole process group, as a terminal does
    out, err = p.communicate(timeout=120)
    assert p.returncode == 130, err
    assert "INTERRUPTED" in out and "Traceback" not in err
    steps = int(next(line for line in out.splitlines() if line.strip().startswith("steps")).split()[1])
    _verify(rrd, tmp_path)
    assert _rows(rrd) == steps  # one row per control step, the last one included
    assert sorted(p.name for p in tmp_path.glob("run.rrd*")) == ["run.rrd"]  # no partial file left
    assert not survivors(p.pid)  # the recording's writer process is gone too


def test_a_killed_recorded_run_leaves_a_partial_file_named_so_and_no_writer(tmp_path):
    p = _start_recorded_run(tmp_path, "pid")
    time.sleep(0.5)
    p.kill()  # the simulation process only, no chance to close anything
    p.communicate(timeout=60)
    # the writer sees its input end, closes the file with what it received and exits
    assert not survivors(p.pid)
    assert not (tmp_path / "run.rrd").exists()  # never the finished recording's name
    (partial,) = tmp_path.glob("run.rrd.*.partial")
    _verify(partial, tmp_path)
