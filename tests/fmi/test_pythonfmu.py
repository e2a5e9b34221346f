"""An FMU built with pythonfmu (a Python class inside an FMI 2.0 co-simulation FMU, as a
Python user would export one) drives ego like the same law written as a file's class."""

import subprocess
import sys

import pytest

from ego.runner import RunSpec, run

pytestmark = pytest.mark.sumo

LAW = '''
def law(p, s_ref, ds_ref, s, ds, d_ref, dd_ref, d, dd):
    """PD on both channels."""
    return (p["kp_lon"] * (s_ref - s) + p["kd_lon"] * (ds_ref - ds),
            p["kp_lat"] * (d_ref - d) + p["kd_lat"] * (dd_ref - dd))


GAINS = {"kp_lon": 800.0, "kd_lon": 1500.0, "kp_lat": 0.01, "kd_lat": 0.02}
'''

SLAVE = (
    LAW
    + '''
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real

INPUTS = ("s_ref", "ds_ref", "s", "ds", "d_ref", "dd_ref", "d", "dd")


class PdFmu(Fmi2Slave):
    """PD on both channels, in Python."""

    author = "ego tests"
    description = "PD on both channels (pythonfmu)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        for name in INPUTS:
            setattr(self, name, 0.0)
            self.register_variable(Real(name, causality=Fmi2Causality.input))
        for name, value in GAINS.items():
            setattr(self, name, value)
            self.register_variable(Real(name, causality=Fmi2Causality.parameter,
                                        variability=Fmi2Variability.tunable))
        self.Fx = self.delta = 0.0
        self.register_variable(Real("Fx", causality=Fmi2Causality.output))
        self.register_variable(Real("delta", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        p = {name: getattr(self, name) for name in GAINS}
        self.Fx, self.delta = law(p, *(getattr(self, name) for name in INPUTS))
        return True
'''
)

CLASS = (
    LAW
    + '''
from ego.control.base import Observation


class Pd:
    """PD on both channels, as a file's class."""

    task = "tracking"

    def __init__(self, dt):
        pass

    def reset(self, *, seed=None):
        pass

    def step(self, o: Observation):
        return law(GAINS, o.s_ref, o.ds_ref, o.s, o.ds, o.d_ref, o.dd_ref, o.d, o.dd)

    def signals(self):
        return {}
'''
)


def test_a_pythonfmu_fmu_drives_like_the_same_law_as_a_class(tmp_path):
    (tmp_path / "pd_fmu.py").write_text(SLAVE)
    (tmp_path / "pd.py").write_text(CLASS)
    proc = subprocess.run(
        [sys.executable, "-m", "pythonfmu", "build", "-f", str(tmp_path / "pd_fmu.py"), "--dest", str(tmp_path)],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stderr
    fmu = tmp_path / "PdFmu.fmu"
    over = {"duration": 6.0}
    mine = run(RunSpec("emergency-brake", str(fmu), overrides=over)).metrics
    ref = run(RunSpec("emergency-brake", f"{tmp_path / 'pd.py'}:Pd", overrides=over)).metrics
    drop = ("wall_time", "controller", "real_time_factor")
    assert mine["status"] == ref["status"] and mine["steps"] == 600
    assert {k: v for k, v in mine.items() if k not in drop} == {k: v for k, v in ref.items() if k not in drop}
