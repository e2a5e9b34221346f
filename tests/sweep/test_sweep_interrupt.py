"""Ctrl-C during ego sweep in a real process: exit 130, the finished rows stored (never an
interrupted one), no partial recording and no process left, and the same command resumes."""

import os
import signal
import subprocess
import sys

import pyarrow.parquet as pq
import pytest
from process_group import survivors, wait_for

pytestmark = pytest.mark.sumo


def test_ctrl_c_keeps_the_finished_rows_and_the_same_command_resumes(tmp_path):
    # 60 runs: far more than finish between the first stored batch and the signal
    spec = tmp_path / "spec.toml"
    spec.write_text(
        'scenario = "emergency-brake"\ncontrollers = ["none", "pid"]\nseeds = 30\n'
        "[set]\nduration = 12.0\ntraffic_density = 0\n"
    )
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "ego", "sweep", str(spec), "--out", str(out), "--jobs", "2", "--record", "all"]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    results = out / "results.parquet"
    wait_for(results.exists, p, "the first batch of results")
    os.killpg(p.pid, signal.SIGINT)
    stdout, stderr = p.communicate(timeout=120)
    assert p.returncode == 130, stderr
    assert "runs remain; the same command resumes" in stderr and "Traceback" not in stderr
    assert not survivors(p.pid)
    table = pq.read_table(results).to_pylist()
    assert 0 < len(table) < 60
    assert "interrupted" not in {r["status"] for r in table}
    # every stored run has its recording; nothing half-written is left beside them
    runs = sorted(x.name for x in (out / "runs").iterdir())
    assert not [name for name in runs if name.endswith(".partial")]
    assert {f"{r['controller']}-{r['run_id']}.rrd" for r in table} <= set(runs)
    assert (out / "summary.md").exists()
    again = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr
    assert f"{len(table)} were already in" in again.stdout and f"{60 - len(table)} ran now" in again.stdout
    assert len(pq.read_table(results)) == 60


@pytest.mark.long  # 40 s of Ray start-up; the process engine's Ctrl-C runs by default
def test_sigterm_ends_a_ray_sweep_as_ctrl_c_does(tmp_path):
    """ray.init puts in its own SIGTERM handler (exit 15, a native crash dump, no summary);
    ego's comes back, so a SIGTERM ends a Ray sweep as Ctrl-C does."""
    pytest.importorskip("ray")
    spec = tmp_path / "spec.toml"
    spec.write_text(
        'scenario = "emergency-brake"\ncontrollers = ["pid"]\nseeds = 60\n[set]\nduration = 12.0\ntraffic_density = 0\n'
    )
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "ego", "sweep", str(spec), "--out", str(out), "--jobs", "2", "--engine", "ray"]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    wait_for((out / "results.parquet").exists, p, "the first batch of results")
    os.kill(p.pid, signal.SIGTERM)
    stdout, stderr = p.communicate(timeout=120)
    assert p.returncode == 130, stderr
    assert "runs remain; the same command resumes" in stderr and "SIGTERM received" not in stderr
    assert (out / "summary.md").exists()
