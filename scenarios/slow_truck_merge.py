"""A traffic situation of your own, composed from ego's scenario kit without touching the
package: a slow truck ahead in the ego's lane, and a car merging in from the right between
the two. Copy this file and change the traffic.

    python scenarios/slow_truck_merge.py [--controller fuzzy] [--out runs/truck]

What the kit gives (see docs/architecture.md, "Writing a scenario from the kit"):

* ``EvasiveLaneChange`` / ``EvasiveConfig``: the motorway, the ego on its plant (report
  000's car with ABS), the surround sensor (gaps and TTC from the vehicles' outlines), the
  front/rear TTC trigger, gap acceptance, the AEB and the metrics, all declared with units;
* scripted SUMO actors (``ego.sumo.traffic``): ``PacedVehicle`` holds a speed,
  ``CutInVehicle`` overtakes and merges, ``BrakingLeader`` brakes, ``RecklessFollower``
  never brakes; ``VehicleType`` and ``VehicleSpec`` put them on the road;
* ``RerunRecorder``: the recording with its layout (``rerun FILE.rrd`` to review it).

A scenario says which vehicles exist (``_actors``), what the ego does when nothing is free
(``_in_lane_reference``) and when that is settled (``_in_lane_settled``); everything else
is inherited.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

from ego.control import controller_spec
from ego.params import param
from ego.record import RerunRecorder
from ego.results.trace import Metric
from ego.scenarios.evasive import EvasiveConfig, EvasiveLaneChange
from ego.scenarios.highway import ROUTE
from ego.sumo.bridge import VehicleSpec, VehicleType
from ego.sumo.traffic import CutInVehicle, PacedVehicle

TRUCK = VehicleType("truck", length=12.0, width=2.5, sigma=0.0, accel=1.0, decel=4.0,
                    color=(120, 90, 60))
MERGER = VehicleType("merger", length=4.5, width=1.8, sigma=0.0, max_speed=50.0, accel=4.0,
                     decel=8.0, color=(255, 80, 160))


@dataclass(frozen=True)
class TruckMergeConfig(EvasiveConfig):
    duration: float = param(30.0, "s", "simulated time", min=1.0, max=600.0)
    ego_speed: float = param(27.0, "m/s", "ego's cruise speed", min=5.0, max=40.0)
    truck_gap: float = param(120.0, "m", "truck's rear ahead of the ego's front at t = 0", min=20.0,
                             max=500.0)
    truck_speed: float = param(22.0, "m/s", "the truck's speed", min=1.0, max=30.0)
    merge_gap: float = param(30.0, "m", "the merging car's rear ahead of the ego when it merges",
                             min=5.0, max=100.0)
    merge_speed: float = param(3.0, "m/s", "how much slower than the ego it merges", min=0.0,
                               max=20.0)


class TruckMerge(EvasiveLaneChange):
    name = "truck-merge"
    summary = "slow truck ahead, a car merges from the right; front TTC triggers braking or a lane change"
    config_cls = TruckMergeConfig
    trigger_on = "front"
    in_lane_action = "brake"
    metric_specs = EvasiveLaneChange.metric_specs + (
        Metric("merge_time", "s", "when the merging car started across"),
    )

    def _actors(self):
        c = self.config
        for vtype in (TRUCK, MERGER):
            self.bridge.add_type(vtype)
        truck_front = c.ego_start + c.truck_gap + TRUCK.length
        self.merger = CutInVehicle("merger", "ego", c.ego_lane - 1, c.ego_lane, c.ego_speed + 4.0,
                                   c.ego_speed - c.merge_speed, c.merge_gap, 2.5, 3.5, c.sumo_step)
        self.actors += [PacedVehicle("truck", c.truck_speed), self.merger]
        self.colors.update(truck=TRUCK.color, merger=MERGER.color)
        return [VehicleSpec("truck", TRUCK.id, ROUTE, c.ego_lane, truck_front, c.truck_speed),
                VehicleSpec("merger", MERGER.id, ROUTE, c.ego_lane - 1, c.ego_start - 30.0, c.ego_speed)
                ], ["truck", "merger"]

    def background(self, rng, keep_clear=()):
        # the right lane belongs to the merging car (it drives blind, as scripted)
        return super().background(rng, keep_clear=(*keep_clear, (self.config.ego_lane - 1, 0.0, 1e9)))

    def _in_lane_reference(self):
        # nowhere to go: follow whoever is ahead at the follow distance
        c = self.config
        return self.behind_front(self._s0 + c.ego_speed * self.t, c.ego_speed)

    def _in_lane_settled(self) -> bool:
        return self.ds <= self.sensor.front.speed + 0.2

    def _metrics(self, trace, columns):
        out = super()._metrics(trace, columns)
        out["merge_time"] = self.merger.cut_in_time
        return out


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
    result = TruckMerge(config, controller, seed=args.seed, recorder=recorder,
                        controller_name=args.controller).run()
    units = {m.name: m.unit for m in TruckMerge.metrics_declared(config)}
    for name, value in result.metrics.items():
        unit = units.get(name, "-")
        print(f"{name:24s} {value}{'' if unit in ('-', '') or value is None else ' ' + unit}")
    print(f"recording: {rrd}")


if __name__ == "__main__":
    main()
