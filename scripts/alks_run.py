"""Run the public UN R157 ALKS scenarios (asam-oss/OSC-ALKS-scenarios) as a new user would: every
template with ``ego run`` and every variation file with ``ego sweep``, and print "N of 30 run"::

    python scripts/alks_run.py OSC-ALKS-scenarios -c pid --sample 4 --seed 1 --jobs 2 \
        --out /tmp/alks-sweeps

The copy keeps the repository's layout: ``Scenarios/ALKS_Scenario_4.*_TEMPLATE.xosc`` (the
reference player's ``*_esmini`` copies left out) with their roads beside them and
``Catalogs/``; ``LogicalScenarios/ALKS_Scenario_4.*_Variation*.xosc`` naming their templates in
``LogicalScenarios/ConcreteScenarios/``. Each template runs from its folder; each variation file
is swept (a seeded ``--sample`` of the combinations its template's value constraints leave, the
whole of it when it has no more than that) with ``--path COPY --path COPY/Scenarios``, so a
catalog or road the ``ConcreteScenarios`` folder lacks (a copy holding only some of the
repository's files) is found in the repository's own ``Catalogs/`` and ``Scenarios/``.

A file **ran** when ``ego`` exits 0 or 1 with no traceback (``scripts/corpus_run.py``'s rule: a
collision or a broken requirement is a run that ended, not a refusal). Prints a table per kind
(for a variation: its combinations, how many the value constraints discard, how many remain,
and the sample's statuses and smallest front gap from ``results.parquet``) and
the count. ``--json OUT`` also writes the rows.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import corpus_run  # noqa: E402  (the sibling script: one rule for ran / refused / crashed)


def templates(root: Path) -> list[Path]:
    """The concrete templates of a copy: ``Scenarios/ALKS_Scenario_4.*_TEMPLATE.xosc``."""
    return sorted(p for p in (root / "Scenarios").glob("ALKS_Scenario_4.*_TEMPLATE.xosc"))


def variations(root: Path) -> list[Path]:
    """The variation files of a copy: ``LogicalScenarios/ALKS_Scenario_4.*_Variation*.xosc``."""
    return sorted((root / "LogicalScenarios").glob("ALKS_Scenario_4.*_Variation*.xosc"))


def sample_summary(folder: Path) -> str:
    """The sweep's runs as the results file has them: statuses and the smallest front gap (negative:
    bodies overlapping, a collision)."""
    import pandas as pd

    table = folder / "results.parquet"
    if not table.is_file():
        return "-"
    rows = pd.read_parquet(table)
    statuses = ", ".join(f"{n} {s}" for s, n in Counter(rows["status"]).most_common())
    gap = rows["min_gap_front"].dropna()
    return statuses + (f"; min front gap {gap.min():.1f} m" if len(gap) else "")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("root", help="the copy of asam-oss/OSC-ALKS-scenarios (its top folder)")
    ap.add_argument("-c", "--controller", default="pid")
    ap.add_argument("--sample", type=int, default=4, help="runs per variation file (default 4)")
    ap.add_argument("--seed", type=int, default=1, help="the sample's seed (default 1)")
    ap.add_argument("--jobs", type=int, default=2, help="parallel runs of a sweep (default 2)")
    ap.add_argument("--out", required=True, help="folder for the sweeps' results (one folder per file)")
    ap.add_argument("--timeout", type=float, default=900.0, help="seconds per file (default 900)")
    ap.add_argument("--json", help="also write the rows to this file")
    args = ap.parse_args(argv)
    root = Path(args.root).resolve()
    runs, swept = templates(root), variations(root)
    if not runs and not swept:
        print(f"alks_run: no ALKS templates or variation files under {root}", file=sys.stderr)
        return 2
    rows: list[dict] = []
    print("| template (ego run) | exit | s | sim s | stop s | how it ends |")
    print("|---|---|---|---|---|---|")
    for f in runs:
        r = corpus_run.run_one(f, args.controller, args.timeout)
        rows.append(r)
        corpus_run._print_row(r, times=True)
    print("\n| variation file (ego sweep) | exit | s | combinations | discarded | remain | the sample |")
    print("|---|---|---|---|---|---|---|")
    search = (str(root), str(root / "Scenarios"))
    sample = ("--jobs", str(args.jobs), "--sample", str(args.sample), "--seed", str(args.seed))
    for f in swept:
        out = Path(args.out) / f.stem
        r = corpus_run.run_one(f, args.controller, args.timeout, search, sweep_out=str(out), sweep_args=sample)
        r["sample"] = sample_summary(out) if r["verdict"] == "ran" else r["first"]
        rows.append(r)
        total, dropped, remain = r["combinations"] or ("-", "-", "-")
        print(
            f"| {f.name} | {r['exit']} | {r['seconds']:.1f} | {total} | {dropped} | {remain} | {r['sample']} |",
            flush=True,
        )
    verdicts = Counter(r["verdict"] for r in rows)
    print(
        f"\n{verdicts['ran']} of {len(rows)} run ({len(runs)} templates with ego run, {len(swept)} variation "
        f"files with ego sweep); {verdicts['refused']} refused, {verdicts['crashed']} crashed"
    )
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0 if verdicts["ran"] == len(rows) else 1


if __name__ == "__main__":
    sys.exit(main())
