"""Ctrl-C or SIGTERM during a recorded run: status interrupted, metrics so far, exit 130,
and a recording that verifies and holds every step simulated."""

import os
import signal
import subprocess
import sys
import time

import pytest

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


@pytest.mark.parametrize("sig, after", [("SIGINT", 2.5), ("SIGINT", 3.0), ("SIGINT", 3.5), ("SIGTERM", 3.0)],
                         ids=["sigint-2.5s", "sigint-3s", "sigint-3.5s", "sigterm"])
def test_an_interrupted_recorded_run_keeps_everything_it_simulated(sig, after, tmp_path):
    rrd = tmp_path / "run.rrd"
    env = dict(os.environ, XDG_CONFIG_HOME=str(tmp_path), XDG_DATA_HOME=str(tmp_path))
    p = subprocess.Popen([sys.executable, "-m", "ego", "run", "emergency-brake", "-c", "fuzzy", "--record",
                          str(rrd), "--set", "duration=3600"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True, start_new_session=True, env=env)
    time.sleep(after)
    os.killpg(p.pid, getattr(signal, sig))  # the whole process group, as a terminal does
    out, err = p.communicate(timeout=120)
    assert p.returncode == 130, err
    assert "INTERRUPTED" in out and "Traceback" not in err
    steps = int(next(line for line in out.splitlines() if line.strip().startswith("steps")).split()[1])
    assert steps > 100
    rerun = os.path.join(os.path.dirname(sys.executable), "rerun")
    check = subprocess.run([rerun, "rrd", "verify", str(rrd)], capture_output=True, text=True, env=env)
    assert check.returncode == 0, check.stderr
    assert _rows(rrd) == steps  # one row per control step, the last one included
