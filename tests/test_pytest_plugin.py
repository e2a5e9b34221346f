"""ego's pytest plugin on a user's project: scenarios/pytest_example copied to a fresh
temporary folder and run by pytest in a subprocess, two workers (pytest-xdist), JUnit XML.

The plugin is loaded with ``-p ego.pytest_plugin``: the pytest11 entry point registers it
where ego is installed from its wheel, and the venv's editable install here may be another
checkout's (the entry point takes the same name, so both together load it once)."""

import json
import os
import shlex
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

pytestmark = pytest.mark.sumo

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "scenarios" / "pytest_example"
PLANTED = "test_planted_failure_keeps_50_m[seed0]"
#: the two rows of scenarios/cut_in_variation.xosc, an item each
ROWS = ("row0-CutInGap=10.0-seed0", "row1-CutInGap=20.0-seed0")


def test_the_example_project_fails_exactly_its_planted_item_and_reports_metrics(tmp_path):
    project = tmp_path / "project"
    shutil.copytree(EXAMPLE, project)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    env.pop("PYTEST_ADDOPTS", None)
    env.pop("PYTEST_XDIST_WORKER", None)
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "pytest",
            "-p",
            "ego.pytest_plugin",
            "-n",
            "2",
            "--junitxml=r.xml",
            "--ego-record",
            "failed",
            "--ego-record-dir",
            "rec",
            "-p",
            "no:cacheprovider",
        ],
        cwd=project,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 1, proc.stdout[-3000:] + proc.stderr[-3000:]
    cases = {c.get("name"): c for c in ET.parse(project / "r.xml").getroot().iter("testcase")}
    assert set(cases) == {"seed0", *ROWS, "test_emergency_brake_keeps_its_distance[seed0]", PLANTED}
    failed = {n for n, c in cases.items() if c.find("failure") is not None or c.find("error") is not None}
    assert failed == {PLANTED}
    message = cases[PLANTED].find("failure").get("message") + cases[PLANTED].find("failure").text
    # the violated requirement, its robustness, its first violation and the reproducer
    assert "requirement keep_50m violated: robustness -43.2094, first violation at 0.00 s" in message
    reproduce = "ego run emergency-brake -c pid --seed 0 --set traffic_density=0 --require 'keep_50m: always (gap_front >= 50 m)'"
    assert f"reproduce: {reproduce}" in message
    for name, case in cases.items():
        props = {p.get("name"): p.get("value") for p in case.iter("property")}
        assert props["ego.status"] == "completed", name
        assert props["ego.collision"] == "False", name
        assert "ego.requirements.no_collision" in props and "ego.max_decel" in props, name
        assert props["ego.command"].startswith("ego run "), name
    planted = {p.get("name"): p.get("value") for p in cases[PLANTED].iter("property")}
    # --ego-record failed: a recording of the failing item alone
    assert [p.name for p in (project / "rec").iterdir()] == ["test_planted_failure_keeps_50_m_seed0_.rrd"]
    assert planted["ego.recording"].endswith("test_planted_failure_keeps_50_m_seed0_.rrd")
    assert (project / "rec" / "test_planted_failure_keeps_50_m_seed0_.rrd").stat().st_size > 0
    assert float(planted["ego.requirements.keep_50m"]) == pytest.approx(-43.2094, abs=1e-4)
    assert float(planted["ego.first_violation.keep_50m"]) == 0.0  # every sample: the first one
    # a variation row's reproducer carries the row's values
    row = {p.get("name"): p.get("value") for p in cases[ROWS[1]].iter("property")}
    assert "--set CutInGap=20.0" in row["ego.command"] and "cut_in.xosc" in row["ego.command"], row["ego.command"]
    passing = {p.get("name") for p in cases["seed0"].iter("property")}
    assert not any(k.startswith("ego.first_violation.") for k in passing)  # a passing item: none
    # the reproducer gives the same verdict
    argv = shlex.split(reproduce)
    rerun = subprocess.run(
        [sys.executable, "-m", *argv, "--json"], cwd=project, env=env, capture_output=True, text=True, timeout=300
    )
    assert json.loads(rerun.stdout)["requirements"]["keep_50m"] == pytest.approx(-43.2094, abs=1e-4), rerun.stderr


@pytest.mark.long
def test_the_example_project_with_ego_installed_from_its_wheel(tmp_path):
    """As a user has it: ego built into a wheel and installed (``pip install --target``, the
    dependencies from this environment), the plugin found through its ``pytest11`` entry
    point - no ``-p`` - in a copy of scenarios/pytest_example, two workers, JUnit XML."""
    sys.path.insert(0, str(ROOT / "tests"))
    from test_wheel import install_wheel

    site = install_wheel(tmp_path)
    project = tmp_path / "project"
    shutil.copytree(EXAMPLE, project)
    env = {**os.environ, "PYTHONPATH": str(site)}
    for var in ("PYTEST_ADDOPTS", "PYTEST_XDIST_WORKER", "EGO_SUMO_NETS"):
        env.pop(var, None)
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-n", "2", "--junitxml=r.xml", "-p", "no:cacheprovider"],
        cwd=project,
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert proc.returncode == 1, proc.stdout[-3000:] + proc.stderr[-3000:]
    cases = {c.get("name"): c for c in ET.parse(project / "r.xml").getroot().iter("testcase")}
    failed = {n for n, c in cases.items() if c.find("failure") is not None or c.find("error") is not None}
    assert failed == {PLANTED}, proc.stdout[-3000:]
    for name, case in cases.items():
        props = {p.get("name"): p.get("value") for p in case.iter("property")}
        assert props["ego.status"] == "completed" and props["ego.command"].startswith("ego run "), name
    where = subprocess.run(
        [sys.executable, "-c", "import ego.pytest_plugin as p; print(p.__file__)"],
        cwd=project,
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert where.stdout.startswith(str(site)), where.stdout + where.stderr  # the wheel's plugin, not the checkout's
