"""Emergency lane change in SUMO traffic, as a script to copy and edit.

    python scenarios/emergency_brake.py            # fuzzy controller, recording in runs/
    rerun runs/emergency_brake.rrd                 # review it

Everything here is also reachable from the command line
(``ego run emergency-brake --controller fuzzy --set lead_decel=7 ...``); a script is
the place to go further: change the rule base gains, sweep a parameter, plug in your
own controller (see custom_controller.py).
"""

from pathlib import Path

from ego.control import FuzzyController, FuzzyParams
from ego.record import RerunRecorder
from ego.scenarios import EmergencyBrake, EmergencyBrakeConfig

config = EmergencyBrakeConfig(
    ego_speed=20.0,  # m/s, report 000's initial speed
    lead_gap=30.0,  # m between the ego's front and the lead car's rear
    lead_brake_time=2.0,  # s
    lead_decel=6.0,  # m/s^2
    lead_final_speed=5.0,  # m/s
    ttc_threshold=3.0,  # s: the manoeuvre starts below this front time-to-collision
    traffic_density=10.0,  # vehicles per km in each adjacent lane
)
controller = FuzzyController(FuzzyParams(fx_gain=100.0, delta_gain=0.001), dt=config.dt)
record = Path("runs/emergency_brake.rrd")

result = EmergencyBrake(config, controller, seed=1, recorder=RerunRecorder(record), controller_name="fuzzy").run()

m = result.metrics
print(f"status {m['status']}: {m['status_detail']}")
print(f"lane chosen: {m['target_side']} ({m['lane_choice']})")
print(
    f"lane change took {m['lane_change_duration']} s, overshoot {m['max_overshoot']} m, "
    f"min front TTC {m['min_ttc_front']} s"
)
for event in result.events:
    print(f"  t={event.t:6.2f} s  {event.text}")
print(f"recording: {record} (rerun {record})")
