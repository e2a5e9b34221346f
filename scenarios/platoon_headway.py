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

With the defaults this is the headway table of docs/results/report-004.md (``python -m
ego.docs results --table headway`` rewrites it there); the rows are built by ego.docs.
"""

import argparse

from ego.docs import DELAY, HEADWAYS, LAG, PID_GAINS, Table, headway_header, headway_row, markdown, run_jobs
from ego.scenarios import string_stability as ss


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--jobs", type=int, default=None)
    ap.add_argument("--omega", type=float, default=0.5, help="leader oscillation (rad/s)")
    args = ap.parse_args()

    rows = tuple(headway_row(h, args.seeds, args.omega) for h in HEADWAYS)
    table = Table("headway", "report-004", (), headway_header(args.omega), rows)
    print(markdown(table, run_jobs((j for r in rows for j in r.jobs), args.jobs)))
    print(
        f"\ntheory: report 004's PID (kp, ki, kd {PID_GAINS}), lag {LAG} s, delay {DELAY} s; string stable "
        f"for lambda >= {ss.min_stable_headway(*PID_GAINS, LAG, DELAY):.2f} s "
        f"(without lag and delay: sqrt(2/kp) = {ss.min_stable_headway(*PID_GAINS):.2f} s)"
    )


if __name__ == "__main__":
    main()
