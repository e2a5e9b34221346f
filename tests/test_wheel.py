"""ego installed as a wheel (not editable) runs from anywhere: the SUMO networks and the
trained models travel inside it as package data."""

import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
from setuptools import find_packages

ROOT = Path(__file__).resolve().parents[1]


#: packages of the checkout the wheel leaves out: the docs generator needs docs/ and scenarios/
CHECKOUT_ONLY = ["ego.docs"]


def test_the_packages_listed_for_the_wheel_are_every_package_of_ego():
    listed = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"]
    found = find_packages(str(ROOT), include=["ego", "ego.*"])
    assert set(CHECKOUT_ONLY) <= set(found)
    assert sorted(listed) == sorted([p for p in found if p not in CHECKOUT_ONLY] + ["ego.sumo_nets"])


def install_wheel(tmp_path: Path) -> Path:
    """ego built as a wheel from a copy of the checkout (so the checkout gets no build/
    folder) and installed with ``pip install --target``: the folder to put on PYTHONPATH
    (the dependencies come from this environment)."""
    src = tmp_path / "src"
    ignore = shutil.ignore_patterns("__pycache__", "*.so", "*.rrd")
    for folder in ("ego", "sumo_nets"):
        shutil.copytree(ROOT / folder, src / folder, ignore=ignore)
    for name in ("pyproject.toml", "setup.py", "README.md"):
        shutil.copy(ROOT / name, src / name)
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "-q"]
    subprocess.run(
        pip + ["wheel", "--no-deps", "--no-build-isolation", "-w", str(tmp_path / "dist"), str(src)],
        check=True,
        capture_output=True,
        timeout=300,
    )
    (wheel,) = (tmp_path / "dist").glob("ego-*.whl")
    import zipfile

    names = zipfile.ZipFile(wheel).namelist()
    assert "ego/cli/__init__.py" in names and "ego/results/run.py" in names and "ego/parallel/executor.py" in names
    assert not [n for n in names if n.startswith("ego/docs/")]  # a checkout's tool, not shipped
    site = tmp_path / "site"
    subprocess.run(
        pip + ["install", "--no-deps", "--target", str(site), str(wheel)], check=True, capture_output=True, timeout=300
    )
    return site


@pytest.mark.sumo
def test_a_wheel_installed_elsewhere_runs_a_scenario(tmp_path):
    site = install_wheel(tmp_path)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    env = {k: v for k, v in os.environ.items() if k != "EGO_SUMO_NETS"}
    env["PYTHONPATH"] = str(site)  # the dependencies come from this environment
    where = subprocess.run(
        [
            sys.executable,
            "-c",
            "import ego, ego.sumo.net, ego.control.narma as n; "
            "print(ego.__file__); print(ego.sumo.net.nets_dir()); print(n.DEFAULT_MODEL)",
        ],
        cwd=elsewhere,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert where.returncode == 0, where.stderr
    for line in where.stdout.split():
        assert line.startswith(str(site / "ego")), where.stdout  # the installed copy, not the checkout
    p = subprocess.run(
        [sys.executable, "-m", "ego", "run", "emergency-brake", "-c", "pid", "--set", "duration=3"],
        cwd=elsewhere,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode in (0, 1), p.stderr  # a short run may time out; it must run
    assert "emergency-brake with pid (seed 0)" in p.stdout
    c = subprocess.run(
        [sys.executable, "-m", "ego", "run", "curve", "-c", "narma-l2", "--set", "duration=2"],
        cwd=elsewhere,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert c.returncode in (0, 1) and "curve with narma-l2" in c.stdout, c.stderr  # the trained networks
