"""A user's controller class that raises, exits or returns nonsense: one line naming the
class, the method, the exception and the user's line; never exit 0 or 130 (ego.usercode)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest

CLASS = """
import os, sys

class C:
    def __init__(self, dt):
        {init}
    def reset(self, *, seed=None):
        pass
    def step(self, obs):
        if obs.t > 0.5:
            {step}
        return (0.0, 0.0)
    def signals(self):
        {signals}
"""


def _ego(tmp_path, *args):
    env = dict(os.environ, TMPDIR=str(tmp_path))
    return subprocess.run(
        [sys.executable, "-m", "ego", *args], capture_output=True, text=True, timeout=300, env=env, cwd=tmp_path
    )


def _file(tmp_path, top="", init="pass", step="pass", signals="return {}"):
    path = tmp_path / "ctl.py"
    path.write_text(top + textwrap.dedent(CLASS).format(init=init, step=step, signals=signals))
    return f"{path}:C"


# (file parts, expected status, words the one line holds)
BEFORE = {
    "sys.exit at import": (dict(top="import sys\nsys.exit(0)\n"), ["importing", "sys.exit(0)", "ctl.py:2"]),
    "os._exit at import": (dict(top="import os\nos._exit(0)\n"), ["importing", "os._exit(0)", "ctl.py:2"]),
    "KeyboardInterrupt at import": (
        dict(top="raise KeyboardInterrupt\n"),
        ["importing", "KeyboardInterrupt", "ctl.py:1"],
    ),
    "raises in __init__": (
        dict(init="raise ValueError('bad gain')"),
        ["C.__init__", "ValueError", "ctl.py:6", "bad gain"],
    ),
    "signals not a mapping": (dict(signals="return [1, 2]"), ["C.signals", "returned [1, 2]", "mapping"]),
}


@pytest.mark.parametrize("case", sorted(BEFORE))
def test_failure_before_the_run_is_one_line_exit_2(tmp_path, case):
    parts, words = BEFORE[case]
    ref = _file(tmp_path, **parts)
    r = _ego(tmp_path, "run", "emergency-brake", "-c", ref, "--trace", str(tmp_path / "t.csv"))
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("ego: error: "), r.stderr
    for w in words:
        assert w in lines[0]
    assert "Traceback" not in r.stderr and not (tmp_path / "t.csv").exists()


DURING = {
    "returns None": ("return None", ["C.step returned None", "two numbers"]),
    "returns a string": ("return 'ab'", ["C.step returned 'ab'"]),
    "divides by zero": ("return 1 / 0", ["C.step raised ZeroDivisionError at ctl.py:11", "division by zero"]),
    "sys.exit in step": ("sys.exit(0)", ["C.step called sys.exit(0) at ctl.py:11"]),
    "os._exit in step": ("os._exit(0)", ["C.step called os._exit(0) at ctl.py:11"]),
    "KeyboardInterrupt in step": ("raise KeyboardInterrupt", ["C.step raised KeyboardInterrupt", "not a Ctrl-C"]),
}


@pytest.mark.parametrize("case", sorted(DURING))
def test_failure_during_the_run_ends_it_in_error_exit_1(tmp_path, case):
    step, words = DURING[case]
    ref = _file(tmp_path, step=step)
    r = _ego(tmp_path, "run", "emergency-brake", "-c", ref, "--trace", str(tmp_path / "t.csv"))
    assert r.returncode == 1, r.stdout + r.stderr
    head = r.stdout.splitlines()[0]
    assert ": ERROR - " in head
    for w in words:
        assert w in head
    assert "Traceback" not in r.stdout + r.stderr
    assert (tmp_path / "t.csv").exists()  # the trace so far is kept


@pytest.mark.long
def test_os_exit_in_a_compare_worker_is_an_error_row(tmp_path):
    ref = _file(tmp_path, step="os._exit(0)")
    r = _ego(tmp_path, "compare", "emergency-brake", "--controllers", f"pid,{ref}", "--jobs", "2", "--out", "o")
    assert r.returncode == 1, r.stdout + r.stderr
    assert "C.step called os._exit(0) at ctl.py:11" in r.stdout + r.stderr
    assert "1 of 2 runs ended in an error" in r.stderr
    assert "Traceback" not in r.stdout + r.stderr
