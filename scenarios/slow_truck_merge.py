"""A traffic situation of your own, composed from ego's scenario kit without touching the
package: a slow truck ahead in the ego's lane, and a car merging in from the right between
the two. Copy this file and change the traffic.

    python scenarios/slow_truck_merge.py [--controller fuzzy] [--out runs/truck]

What the kit gives (see docs/architecture.md, "Writing a scenario from the kit"):

* ``ego.scenarios.evasive.compose``: the parts of an evasive scenario - the motorway world,
  the ego on its plant (report 000's car with ABS), the surround view (gaps and TTC from the
  vehicles' outlines), the manoeuvre state machine (TTC trigger, gap acceptance, lane change
  or in-lane manoeuvre) and the safety layer (AEB); ``METRICS`` and ``evasive_metrics``, all
  declared with units;
* scripted actors (``ego.sim.traffic``): ``PacedVehicle`` holds a speed, ``CutInVehicle``
  overtakes and merges, ``BrakingLeader`` brakes, ``RecklessFollower`` never brakes;
  ``VehicleType`` and ``VehicleSpec`` (``ego.sim``) put them on the road;
* ``RerunRecorder``: the recording with its layout (``rerun FILE.rrd`` to review it).

A scenario says which vehicles exist (``populate``), what the ego does when no lane is free
(an in-lane behaviour: ``reference`` and ``settled``) and what it reports (``_metrics``).
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

from ego.control import controller_spec
from ego.params import param
from ego.record import RerunRecorder
from ego.results.trace import Metric
from ego.scenarios.base import Scenario
from ego.scenarios.evasive import METRICS, EvasiveConfig, compose, evasive_metrics
from ego.scenarios.motorway import COLUMNS, EDGE, PLOTS, ROUTE
from ego.sim import VehicleSpec, VehicleType
from ego.sim.traffic import CutInVehicle, PacedVehicle

TRUCK = VehicleType("truck", length=12.0, width=2.5, sigma=0.0, accel=1.0, decel=4.0, color=(120, 90, 60))
MERGER = VehicleType(
    "merger", length=4.5, width=1.8, sigma=0.0, max_speed=50.0, accel=4.0, decel=8.0, color=(255, 80, 160)
)


@dataclass(frozen=True)
class TruckMergeConfig(EvasiveConfig):
    duration: float = param(30.0, "s", "simulated time", min=1.0, max=600.0)
    ego_speed: float = param(27.0, "m/s", "ego's cruise speed", min=5.0, max=40.0)
    truck_gap: float = param(120.0, "m", "truck's rear ahead of the ego's front at t = 0", min=20.0, max=500.0)
    truck_speed: float = param(22.0, "m/s", "the truck's speed", min=1.0, max=30.0)
    merge_gap: float = param(30.0, "m", "the merging car's rear ahead of the ego when it merges", min=5.0, max=100.0)
    merge_speed: float = param(3.0, "m/s", "how much slower than the ego it merges", min=0.0, max=20.0)


class FollowAhead:
    """The in-lane manoeuvre: nowhere to go, follow whoever is ahead at the follow distance."""

    action = "brake"

    def start(self, man) -> None:
        pass

    def reference(self, man):
        c = man.config
        return man.behind_front(man.s0 + c.ego_speed * man.t, c.ego_speed)

    def settled(self, man) -> bool:
        return man.view.ds <= man.view.sensor.front.speed + 0.2


class TruckMerge(Scenario):
    name = "truck-merge"
    summary = "slow truck ahead, a car merges from the right; front TTC triggers braking or a lane change"
    config_cls = TruckMergeConfig
    network, edge, columns, plots = "highway", EDGE, COLUMNS, PLOTS
    metric_specs = METRICS + (Metric("merge_time", "s", "when the merging car started across"),)

    def compose(self):
        return compose(self, "front", FollowAhead(), self.populate)

    def populate(self, world) -> None:
        c = self.config
        truck_front = c.ego_start + c.truck_gap + TRUCK.length
        self.merger = CutInVehicle(
            "merger",
            "ego",
            c.ego_lane - 1,
            c.ego_lane,
            c.ego_speed + 4.0,
            c.ego_speed - c.merge_speed,
            c.merge_gap,
            2.5,
            3.5,
            c.sumo_step,
        )
        world.vehicle(
            VehicleSpec("truck", TRUCK.id, ROUTE, c.ego_lane, truck_front, c.truck_speed),
            TRUCK,
            PacedVehicle("truck", c.truck_speed),
        )
        world.vehicle(
            VehicleSpec("merger", MERGER.id, ROUTE, c.ego_lane - 1, c.ego_start - 30.0, c.ego_speed),
            MERGER,
            self.merger,
        )
        # the right lane belongs to the merging car (it drives blind, as scripted)
        world.keep_clear(c.ego_lane - 1)

    def _metrics(self, trace, names):
        return {**evasive_metrics(self, trace, names), "merge_time": self.merger.cut_in_time}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--controller", "-c", default="fuzzy", help="a tracking controller (ego list)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=Path("runs/truck-merge"), help="output directory")
    args = ap.parse_args()

    config = TruckMergeConfig()
    spec = controller_spec(args.controller, TruckMerge.task)
    controller = spec.build(spec.params(), config.dt)
    args.out.mkdir(parents=True, exist_ok=True)
    rrd = args.out / f"{args.controller}-seed{args.seed}.rrd"
    recorder = RerunRecorder(rrd, recording_id=f"truck-merge-{args.controller}-{args.seed}")
    result = TruckMerge(config, controller, seed=args.seed, recorder=recorder, controller_name=args.controller).run()
    units = {m.name: m.unit for m in TruckMerge.metrics_declared(config)}
    for name, value in result.metrics.items():
        unit = units.get(name, "-")
        print(f"{name:24s} {value}{'' if unit in ('-', '') or value is None else ' ' + unit}")
    print(f"recording: {rrd}")


if __name__ == "__main__":
    main()
