"""FMUs under the watchdog (ego/fmi/guard.py, ego/_fmu_guard.c): real FMUs, compiled here from
tests/fmi/c/misbehave.c, that hang in doStep, segfault in doStep, abort in fmi2Instantiate or
kill themselves. Each case: one line naming the FMU, the exit status, no traceback, the trace
so far written, no ``ego-fmu-*`` folder left in TMPDIR."""

from __future__ import annotations

import atexit
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import fmu_zoo
import pytest

pytest.importorskip("ego._fmu_guard")


@pytest.fixture(scope="module")
def bad_fmus(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bad_fmus")
    return {k: str(fmu_zoo.build(fmu_zoo.misbehave(k), folder)) for k in fmu_zoo.MISBEHAVE}


def env_with(tmp: Path, **extra: str) -> dict:
    env = dict(os.environ, TMPDIR=str(tmp), **extra)
    return env


_SHORT: dict[Path, Path] = {}


def short_tmp(tmp: Path) -> Path:
    """The TMPDIR of a test's ego processes: a short folder of its own (multiprocessing's
    AF_UNIX socket paths must stay under 108 bytes, which a pytest tmp_path can exceed),
    removed at exit."""
    if tmp not in _SHORT:
        _SHORT[tmp] = Path(tempfile.mkdtemp(prefix="ewd-"))
        atexit.register(shutil.rmtree, _SHORT[tmp], True)
    return _SHORT[tmp]


def ego(args, tmp: Path, timeout: float = 120, **extra: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "ego", *args],
        cwd=tmp,
        env=env_with(short_tmp(tmp), **extra),
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def lines_with(text: str, word: str) -> list[str]:
    return [line for line in text.splitlines() if word in line]


def one_message(text: str, word: str) -> str:
    """The one-line message with ``word`` (ego run prints it in its headline and its events)."""
    found = lines_with(text, word)
    assert found, text
    tail = found[0][found[0].index("FMU ") if "FMU " in found[0] else 0 :]
    assert all(line.endswith(tail) for line in found), found
    return found[0]


def assert_clean(proc, tmp: Path) -> None:
    assert "Traceback" not in proc.stdout + proc.stderr
    assert not list((short_tmp(tmp)).glob("ego-fmu-*"))


def test_a_hanging_do_step_ends_the_run_at_the_limit(bad_fmus, tmp_path):
    t0 = time.monotonic()
    proc = ego(
        ["run", "emergency-brake", "-c", bad_fmus["hang"], "--trace", "t.csv"], tmp_path, EGO_FMU_STEP_LIMIT="0.5"
    )
    assert proc.returncode == 1, proc.stdout + proc.stderr
    line = one_message(proc.stdout + proc.stderr, "hung")
    assert "FMU 'hang_fmu'" in line and "t = 0.200 s" in line and "0.5 s (EGO_FMU_STEP_LIMIT)" in line
    assert (tmp_path / "t.csv").read_text().count("\n") > 10  # the trace so far
    assert time.monotonic() - t0 < 60
    assert_clean(proc, tmp_path)


def test_a_segfault_in_do_step_is_one_line(bad_fmus, tmp_path):
    proc = ego(["run", "emergency-brake", "-c", bad_fmus["segv"], "--trace", "t.csv"], tmp_path)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    line = one_message(proc.stdout + proc.stderr, "crashed")
    assert "FMU 'segv_fmu' crashed with SIGSEGV" in line and "doStep at t = 0.200 s" in line
    assert (tmp_path / "t.csv").exists()
    assert_clean(proc, tmp_path)


def test_an_abort_in_instantiate_is_one_line(bad_fmus, tmp_path):
    proc = ego(["run", "emergency-brake", "-c", bad_fmus["abort"]], tmp_path)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    line = one_message(proc.stdout + proc.stderr, "crashed")
    assert "FMU 'abort_fmu' crashed with SIGABRT (abort) in fmi2Instantiate before the run" in line
    assert_clean(proc, tmp_path)


def test_sigterm_while_an_fmu_hangs_interrupts_the_run(bad_fmus, tmp_path):
    proc = subprocess.Popen(
        [sys.executable, "-m", "ego", "run", "emergency-brake", "-c", bad_fmus["hang"], "--trace", "t.csv"],
        cwd=tmp_path,
        env=env_with(short_tmp(tmp_path), EGO_FMU_STEP_LIMIT="600"),
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        deadline = time.monotonic() + 60
        while not list((short_tmp(tmp_path)).glob("ego-fmu-*")) and time.monotonic() < deadline:
            time.sleep(0.1)
        time.sleep(1.5)  # in the hang: step 20 is 0.2 s of simulated time after the start
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130, out
    line = one_message(out, "interrupted (SIGTERM)")
    assert "FMU 'hang_fmu' was in doStep at t = 0.200 s" in line
    assert (tmp_path / "t.csv").exists()
    assert "Traceback" not in out and not list((short_tmp(tmp_path)).glob("ego-fmu-*"))


@pytest.mark.long
def test_compare_in_workers_names_the_fmu_in_each_row(bad_fmus, tmp_path):
    ctrls = ",".join(bad_fmus[k] for k in ("hang", "segv", "abort", "kill")) + ",pid"
    proc = ego(
        ["compare", "emergency-brake", "--controllers", ctrls, "--jobs", "2", "--out", "cmp"],
        tmp_path,
        timeout=300,
        EGO_FMU_STEP_LIMIT="0.5",
    )
    out = proc.stdout + proc.stderr
    assert proc.returncode == 1, out
    assert len(lines_with(out, "FMU 'hang_fmu' hung: doStep at t = 0.200 s")) == 1
    assert len(lines_with(out, "FMU 'segv_fmu' crashed with SIGSEGV")) == 1
    assert len(lines_with(out, "FMU 'abort_fmu' crashed with SIGABRT")) == 1
    assert len(lines_with(out, "died 2 times running it (killed by SIGKILL; FMU 'kill_fmu' loaded)")) == 1
    assert "4 of 5 runs ended in an error" in out
    assert_clean(proc, tmp_path)


@pytest.mark.parametrize("value", ["0", "abc", "1e9", "nan"])
def test_a_bad_step_limit_is_one_line(bad_fmus, tmp_path, value):
    proc = ego(["run", "emergency-brake", "-c", bad_fmus["hang"]], tmp_path, EGO_FMU_STEP_LIMIT=value)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert proc.stdout == ""
    assert proc.stderr.count("\n") == 1 and "EGO_FMU_STEP_LIMIT" in proc.stderr and "0.01 to 86400" in proc.stderr
    assert_clean(proc, tmp_path)
