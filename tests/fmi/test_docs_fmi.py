"""docs/fmi.md's worked example runs as written: its files are written, its commands run (ego as
``python -m ego``) in an empty folder, each one succeeding."""

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.sumo

DOC = Path(__file__).resolve().parents[2] / "docs" / "fmi.md"


@pytest.mark.long
def test_the_worked_example_runs(tmp_path):
    text = DOC.read_text()
    files = re.findall(r"<!-- file: (\S+) -->\n```\w+\n(.*?)```", text, re.S)
    assert [name for name, _ in files] == ["pd_controller.py", "map.toml"]
    for name, body in files:
        (tmp_path / name).write_text(body)
    block = re.search(r"<!-- example: fmi -->\n```console\n(.*?)```", text, re.S).group(1)
    commands = [line[2:] for line in block.splitlines() if line.startswith("$ ")]
    assert len(commands) == 6
    outputs = []
    for command in commands:
        args = shlex.split(command)
        program = {"ego": [sys.executable, "-m", "ego"], "pythonfmu": [sys.executable, "-m", "pythonfmu"]}[args[0]]
        proc = subprocess.run(program + args[1:], cwd=tmp_path, capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, (command, proc.stderr)
        outputs.append(proc.stdout)
    assert "drives the tracking task" not in outputs[1]  # it needs its mapping file
    assert "fmu.kd_lat" in outputs[1]
    assert "COMPLETED" in outputs[2] and "COMPLETED" in outputs[5]
    assert (tmp_path / "cmp" / "metrics.csv").read_text().count("PdController.fmu") == 2
