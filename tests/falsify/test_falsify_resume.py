"""``ego falsify`` keeps every finished row within 2 s and resumes only the same search
(issue 41, items 10 and 11)."""

import signal
import subprocess
import sys
import time

import pyarrow.parquet as pq
import pytest

from ego.cli import main

SPEC = """scenario = "emergency-brake"
controller = "pid"
requirement = "far"
seed = 3
[requirements]
far = "always (gap_front >= 25 m)"
[search]
ego_speed = [15, 30]
lead_gap = [20, 60]
"""

ARGS = ["--budget", "4", "--optimizer", "random", "--no-verify", "--jobs", "1"]


@pytest.mark.sumo
@pytest.mark.parametrize(
    "old, new, what",
    [
        ("lead_gap = [20, 60]", "lead_gap = [20, 50]", "ranges changed"),
        ('far = "always (gap_front >= 25 m)"', 'far = "always (gap_front >= 5 m)"', "requirements changed"),
    ],
)
def test_a_resume_whose_search_changed_is_refused_in_one_line(old, new, what, tmp_path, capsys):
    first, second = tmp_path / "a.toml", tmp_path / "b.toml"
    first.write_text(SPEC)
    second.write_text(SPEC.replace(old, new))
    out = tmp_path / "out"
    assert main(["falsify", str(first), "--out", str(out), *ARGS]) == 1
    before = {p.name: p.stat().st_mtime_ns for p in out.iterdir()}
    capsys.readouterr()
    assert main(["falsify", str(second), "--out", str(out), *ARGS]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and what in err and "another --out" in err, err
    assert {p.name: p.stat().st_mtime_ns for p in out.iterdir()} == before  # nothing written
    # the same search resumes (a larger budget: more runs of it), another optimiser does not
    assert main(["falsify", str(first), "--out", str(out), *ARGS[:1], "6", *ARGS[2:]]) == 1
    assert "2 runs ran now" in capsys.readouterr().out
    assert main(["falsify", str(first), "--out", str(out), *ARGS[:3], "lhs", *ARGS[4:]]) == 2
    assert "optimizer changed" in capsys.readouterr().err


@pytest.mark.sumo
def test_a_killed_search_keeps_every_run_reported_2_s_before_and_resumes_without_redoing_them(tmp_path):
    import psutil

    spec = tmp_path / "f.toml"
    spec.write_text(SPEC)
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "ego", "falsify", str(spec), "--out", str(out), *ARGS[:1], "8", *ARGS[2:]]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    reported = 0
    deadline = time.time() + 120
    while reported < 4 and time.time() < deadline:
        line = proc.stderr.readline()
        if line.startswith("pid: "):
            reported = int(line.split()[1].split("/")[0])
    assert reported >= 4, "the search did not report 4 runs"
    time.sleep(2.3)  # the rows of the runs reported have been on disk for 2 s
    children = psutil.Process(proc.pid).children(recursive=True)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    proc.stderr.close()
    kept = pq.read_table(out / "results.parquet").num_rows
    assert kept >= reported
    gone, alive = psutil.wait_procs(children, timeout=15)
    assert not alive, [p.cmdline() for p in alive]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert p.returncode in (0, 1), p.stderr
    assert f"{8 - kept} runs ran now" in p.stdout, p.stdout
    ids = pq.read_table(out / "results.parquet").column("run_id").to_pylist()
    assert len(ids) == len(set(ids))
