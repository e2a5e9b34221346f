"""Bring your own controller: anything with reset/step/signals drives the ego.

    python scenarios/custom_controller.py

The controller sees an :class:`ego.control.Observation` every control period (road-frame
references and measurements, SI units, errors = reference - actual) and returns
(Fx per driven wheel in N, front steer angle in rad). This one is a plain state-feedback
law with gain scheduling on speed, compared against report 000's fuzzy controller.
"""

from ego.control import FuzzyController, FuzzyParams, Observation
from ego.scenarios import EmergencyBrake, EmergencyBrakeConfig


class ScheduledStateFeedback:
    """Fx from position/speed errors; delta from lateral errors scaled by 1/u^2 (the
    lateral acceleration per radian of steer grows with u^2 / wheelbase)."""

    def __init__(self, k_s=1500.0, k_v=2500.0, w_lat=0.9, zeta=0.9, wheelbase=2.8):
        self.k_s, self.k_v, self.w, self.zeta, self.L = k_s, k_v, w_lat, zeta, wheelbase
        self._delta = 0.0

    def reset(self, *, seed=None):
        self._delta = 0.0

    def step(self, obs: Observation):
        fx = self.k_s * (obs.s_ref - obs.s) + self.k_v * (obs.ds_ref - obs.ds)
        a_y = self.w**2 * (obs.d_ref - obs.d) + 2 * self.zeta * self.w * (obs.dd_ref - obs.dd)
        self._delta = a_y * self.L / max(obs.speed, 5.0) ** 2
        return fx, self._delta

    def signals(self):
        return {"delta_cmd": self._delta}


config = EmergencyBrakeConfig()
for name, controller in [
    ("state feedback", ScheduledStateFeedback()),
    ("report 000 fuzzy", FuzzyController(FuzzyParams(), config.dt)),
]:
    m = EmergencyBrake(config, controller, seed=0, controller_name=name).run().metrics
    print(
        f"{name:16s} {m['status']:10s} lane change {m['lane_change_duration']} s, "
        f"overshoot {m['max_overshoot']} m, min gap {m['min_gap_front']} m"
    )
