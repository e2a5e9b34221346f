"""How much time headway does report 004's platoon need? The theory beside real SUMO runs.

    python scenarios/platoon_headway.py [--seeds 3] [--jobs 2] [--omega 0.5]

For each time headway lambda it prints, as a markdown table:

* theory, for report 004's PID with the scenario's actuator lag (0.2 s) and control period
  (0.1 s, modelled as a T/2 delay): the peak gain max |H(jw)| from one car's speed to the
  next one's, and |H| at ``--omega``;
* for each controller, over ``--seeds`` runs of the default drive (brake to 20 km/h,
  accelerate to 50 km/h, brake hard to a stop): how many runs collided, the smallest gap,
  how many were string stable, and the largest amplification measured between consecutive
  vehicles (L2 ratios of acceleration and spacing error);
* for each controller, one run with the leader's speed oscillating 1 km/h at ``--omega``:
  the measured gain f1 -> f2 (theory's |H| is the PID's).
"""

import argparse
import multiprocessing
from concurrent.futures import ProcessPoolExecutor

from ego.processes import main_module_hidden
from ego.runner import RunSpec, run
from ego.scenarios import string_stability as ss

HEADWAYS = (0.2, 0.5, 1.0, 1.25, 1.5, 1.75, 2.0, 2.5, 3.0)
CONTROLLERS = ("pid", "bp-pid-acc")
KP, KI, KD, LAG, DELAY = 0.85, 0.2, 0.3, 0.2, 0.05


def _worst_amplification(m: dict) -> float | None:
    ratios = [v for pair in m["amplification"].values() for k, v in pair.items()
              if k.startswith("l2_") and v is not None]
    return max(ratios) if ratios else None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--jobs", type=int, default=None)
    ap.add_argument("--omega", type=float, default=0.5, help="leader oscillation (rad/s)")
    args = ap.parse_args()

    drive = {(c, h, s): RunSpec("platoon", c, s, {"headway": h})
             for c in CONTROLLERS for h in HEADWAYS for s in range(args.seeds)}
    sine = {(c, h): RunSpec("platoon", c, 0, {"headway": h, "manoeuvres": "none", "sine_amplitude": 1.0,
                                              "sine_omega": args.omega, "duration": 150.0,
                                              "sine_transient": 60.0})
            for c in CONTROLLERS for h in HEADWAYS}
    with ProcessPoolExecutor(args.jobs, mp_context=multiprocessing.get_context("forkserver")) as pool:
        with main_module_hidden():
            # workers run ego's own function: they never import this script
            done = {k: pool.submit(run, spec) for k, spec in [*drive.items(), *sine.items()]}
        results = {k: f.result().metrics for k, f in done.items()}

    head = ["lambda [s]", "theory peak |H|", f"theory |H({args.omega:g})|"]
    for c in CONTROLLERS:
        head += [f"{c}: collisions", f"{c}: min gap [m]", f"{c}: string stable", f"{c}: worst L2 ratio",
                 f"{c}: gain f1->f2 at {args.omega:g}"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for h in HEADWAYS:
        peak, _ = ss.peak_gain(lambda w: ss.pid_transfer(w, KP, KI, KD, h, LAG, DELAY))
        at = abs(ss.pid_transfer(args.omega, KP, KI, KD, h, LAG, DELAY))
        cells = [f"{h:g}", f"{peak:.2f}", f"{at:.3f}"]
        for c in CONTROLLERS:
            runs = [results[c, h, s] for s in range(args.seeds)]
            crashed = sum(m["collision"] for m in runs)
            gaps = [m["min_gap"] for m in runs if m["min_gap"] is not None]
            stable = sum(m["string_stable"] is True for m in runs)
            worst = [w for w in map(_worst_amplification, runs) if w is not None]
            gain = (results[c, h]["frequency_gain"] or {}).get("f1->f2")
            sine_status = results[c, h]["status"]
            cells += [f"{crashed}/{len(runs)}", f"{min(gaps):.2f}" if gaps else "-", f"{stable}/{len(runs)}",
                      f"{max(worst):.2f}" if worst else "-",
                      f"{gain:.3f}" if gain is not None and sine_status == "completed" else sine_status]
        print("| " + " | ".join(cells) + " |")
    print(f"\ntheory: report 004's PID (kp {KP}, ki {KI}, kd {KD}), lag {LAG} s, delay {DELAY} s; "
          f"string stable for lambda >= {ss.min_stable_headway(KP, KI, KD, LAG, DELAY):.2f} s "
          f"(without lag and delay: sqrt(2/kp) = {ss.min_stable_headway(KP, KI, KD):.2f} s)")


if __name__ == "__main__":
    main()
