"""Two runs recording to one path at once: both succeed and the file is one whole recording
(the last to finish), never a mix; no temporary file is left."""

import json
import os
import subprocess
import sys

import pytest
from rerun.chunk import RrdReader
from test_interrupt import _rows, _verify

pytestmark = pytest.mark.sumo


def test_two_writers_to_one_recording_leave_a_valid_file(tmp_path):
    rrd = tmp_path / "same.rrd"
    env = dict(os.environ, XDG_CONFIG_HOME=str(tmp_path), XDG_DATA_HOME=str(tmp_path))
    procs = [
        subprocess.Popen(
            [
                sys.executable,
                "-m",
                "ego",
                "run",
                "emergency-brake",
                "-c",
                "pid",
                "--seed",
                str(seed),
                "--set",
                "duration=20",
                "--record",
                str(rrd),
                "--json",
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        for seed in (1, 2)
    ]
    steps = {}
    for seed, p in zip((1, 2), procs):
        out, err = p.communicate(timeout=300)
        assert p.returncode == 0, err
        steps[seed] = json.loads(out)["steps"]
    _verify(rrd, tmp_path)
    (recording,) = RrdReader(rrd).recordings()  # one run's recording, whole
    winner = int(recording.recording_id.rsplit("-", 1)[1])
    assert _rows(rrd) == steps[winner]
    assert [p.name for p in tmp_path.glob("same.rrd*")] == ["same.rrd"]
