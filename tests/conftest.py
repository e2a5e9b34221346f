"""Test-wide set-up: keep Rerun's and matplotlib's config out of the user's home."""

import os
import tempfile

import pytest

_TMP = tempfile.mkdtemp(prefix="ego-tests-")
for var in ("XDG_CONFIG_HOME", "XDG_DATA_HOME", "MPLCONFIGDIR"):
    os.environ.setdefault(var, os.path.join(_TMP, var.lower()))
os.environ.setdefault("RERUN_ANALYTICS", "false")


def pytest_collection_modifyitems(config, items):
    """A highway-env simulation and a Ray instance take seconds to start: such tests are
    ``slow`` too, so ``pytest -m "not sumo and not slow"`` is the fast loop."""
    slow = pytest.mark.slow
    for item in items:
        ray = (
            "ray_executor" in getattr(item, "fixturenames", ())
            or getattr(getattr(item, "callspec", None), "params", {}).get("engine") == "ray"
        )
        if item.get_closest_marker("highway_env") is not None or ray:
            item.add_marker(slow)


@pytest.fixture(scope="session")
def fuzzy_ready():
    """Compile report 000's rule base once (scikit-fuzzy builds its graph slowly)."""
    from ego.control import fuzzy

    return fuzzy.evaluator()


@pytest.fixture
def point_mass(monkeypatch):
    """The test-only point-mass scenario (no SUMO), registered for the test's duration."""
    from point_mass import PointMass

    from ego.scenarios import SCENARIOS

    monkeypatch.setitem(SCENARIOS, PointMass.name, PointMass)
    return PointMass
