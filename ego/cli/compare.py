"""``ego compare``: every controller x seed of one scenario (:mod:`ego.compare`)."""

from __future__ import annotations

import sys
import time
from collections.abc import Sequence
from typing import Any

from ego.checks import MAX_JOBS, check_count, check_output_dir
from ego.cli.common import EXIT_INTERRUPTED, EXIT_NOT_COMPLETED, EXIT_OK, ego_entity
from ego.params import ConfigError, parse_overrides


def command(args: Any) -> int:
    from ego.compare import MAX_SEEDS, SETTINGS_FILE, UNITS_FILE, compare
    from ego.requirements import check_period, with_defaults

    if args.seeds > MAX_SEEDS:
        raise ConfigError(f"bad value for --seeds: {args.seeds} (expected at most {MAX_SEEDS}; use ego sweep for more)")
    check_count(args.seeds, "--seeds", 1, MAX_SEEDS)
    check_count(args.jobs, "--jobs", 1, MAX_JOBS)
    labels = [n.strip() for n in args.controllers.split(",") if n.strip()]
    out = check_output_dir(args.out, "--out")
    started = time.time()
    rows = compare(
        args.scenario,
        labels,
        args.seeds,
        ego_entity(args, parse_overrides(args.overrides)),
        out,
        args.jobs,
        traces=args.traces,
        backend=args.backend,
        requirements=with_defaults(args.scenario, args.require),
        preventable=args.preventable,
        requirement_period=check_period(args.requirement_period),
    )
    print((out / "metrics.md").read_text(), end="")
    # the plots this command wrote (an earlier comparison's in the same --out are not these)
    plots = sorted(p.name for p in out.glob("*.png") if p.stat().st_mtime >= started - 0.01)
    files = ["metrics.csv", UNITS_FILE, "metrics.md", SETTINGS_FILE] + plots
    recorded = sum(1 for r in rows if r.recording)
    traces = f" and their traces ({args.traces}) in traces/" if args.traces else ""
    print(f"\nwrote into {out}/: {', '.join(files)} and {recorded} of {len(rows)} recordings in runs/{traces}")
    return exit_status([r.status for r in rows])


def exit_status(statuses: Sequence[str]) -> int:
    """``ego compare``'s exit status: 130 when interrupted (the finished runs are written),
    1 when a run ended in ``error`` (ego could not run it: an exception, a dead worker),
    else 0 - a collision or a diverging controller is a result of the comparison."""
    if "interrupted" in statuses:
        unfinished = statuses.count("interrupted")
        print(
            f"ego: interrupted: {unfinished} of {len(statuses)} runs did not finish (rows with status interrupted)",
            file=sys.stderr,
        )
        return EXIT_INTERRUPTED
    if "error" in statuses:
        print(
            f"ego: {statuses.count('error')} of {len(statuses)} runs ended in an error (see metrics.md)",
            file=sys.stderr,
        )
        return EXIT_NOT_COMPLETED
    return EXIT_OK
