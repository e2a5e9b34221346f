"""The test FMUs, built once per session (and cached between sessions by their sources' hash)."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

import fmu_zoo  # noqa: E402


@pytest.fixture(scope="session")
def fmus(tmp_path_factory):
    """name -> path of every test FMU (FMI 2.0 unless named ...3)."""
    folder = tmp_path_factory.mktemp("fmus")
    specs = {
        "pid": fmu_zoo.pid_tracking(),
        "pid_curve": fmu_zoo.pid_curve(),
        "pid_units": fmu_zoo.pid_units(),
        "error": fmu_zoo.faulty(),
        "nan": fmu_zoo.faulty(nan=True),
        "fixed": fmu_zoo.fixed_step(),
        "renamed": fmu_zoo.renamed(),
        "pid3": fmu_zoo.pid_tracking("3.0"),
        "error3": fmu_zoo.faulty(version="3.0"),
    }
    return {name: str(fmu_zoo.build(spec, folder)) for name, spec in specs.items()}
