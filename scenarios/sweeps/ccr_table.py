"""The Euro NCAP CCR matrices (aeb-ccr-s/m/b.toml beside this file) as markdown tables: for
every controller and case, avoided (smallest gap) or hit (impact speed, km/h).

    PYTHONPATH=. python scenarios/sweeps/ccr_table.py [--workers 4] [--set key=value ...] [aeb-ccr-s.toml ...]

``--set`` overrides the files' values for every run (e.g. ``--set ttc_threshold=1.5``: an AEB
that reacts later). ``ego sweep`` runs the same files into results.parquet; the tables with
the default trigger, 1.5 s and 1 s are in docs/results/envelope.md, written by
``python -m ego.docs results --page envelope`` (this script uses its tables).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ego.docs import ccr_table, markdown, run_jobs

HERE = Path(__file__).parent
FILES = ("aeb-ccr-s.toml", "aeb-ccr-m.toml", "aeb-ccr-b.toml")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*", default=[str(HERE / f) for f in FILES])
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    args = ap.parse_args()
    extra = dict(item.split("=", 1) for item in args.set)
    for f in args.files:
        table = ccr_table(Path(f).stem, Path(f).resolve(), extra)
        results = run_jobs((j for r in table.rows for j in r.jobs), args.workers)
        title = Path(f).name + "".join(f", {k}={v}" for k, v in extra.items())
        print(f"{title}: no (x m) = avoided, smallest gap; HIT v (r) = impact speed (relative), km/h\n")
        print(markdown(table, results) + "\n")


if __name__ == "__main__":
    main()
