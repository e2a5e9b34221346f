"""The user scenario script: a traffic situation built from the kit outside the package."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.sumo
def test_slow_truck_merge_runs_headless_with_a_recording(tmp_path):
    from rerun.chunk import RrdReader

    p = subprocess.run(
        [sys.executable, str(ROOT / "scenarios" / "slow_truck_merge.py"), "-c", "pid", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode == 0, p.stderr
    lines = dict(line.split(None, 1) for line in p.stdout.splitlines() if " " in line.strip())
    assert lines["status"].strip() == "completed" and lines["collision"].strip() == "False"
    assert lines["min_gap_front"].strip().endswith(" m")  # units from the kit's declarations
    assert lines["merge_time"].strip() != "None"  # the merging car did merge
    rrd = tmp_path / "pid-seed0.rrd"
    assert rrd.is_file() and RrdReader(rrd).recordings()
    # the package was not touched: the scenario is not registered there
    from ego.scenarios import SCENARIOS

    assert "truck-merge" not in SCENARIOS
