"""``ego run``: one scenario with one controller, its metrics printed (text or JSON)."""

from __future__ import annotations

import json
import sys
from typing import Any

from ego.checks import check_seed
from ego.cli.common import EXIT_INTERRUPTED, EXIT_NOT_COMPLETED, EXIT_OK, ego_entity
from ego.params import parse_overrides


def command(args: Any) -> int:
    from ego.requirements import check_period, with_defaults
    from ego.results.export import trace_files
    from ego.results.metrics import flatten, metric_units
    from ego.runner import RunSpec, resolve, run
    from ego.scenarios.base import NOT_FAILED

    spec = RunSpec(
        args.scenario,
        args.controller,
        seed=check_seed(args.seed, "--seed"),
        overrides=ego_entity(args, parse_overrides(args.overrides)),
        record=args.record,
        trace=args.trace,
        backend=args.backend,
        video=args.video,
        requirements=with_defaults(args.scenario, args.require),
        preventable=True if args.preventable else None,
        requirement_period=check_period(args.requirement_period),
    )
    resolved = resolve(spec)  # every name, value and path checked before anything runs
    from ego.outputs import OutputError

    failure = None
    try:
        result = run(resolved)
    except OutputError as exc:  # a write failed after the run: its metrics are still printed
        if exc.result is None:
            raise
        result, failure = exc.result, exc
        args.record = args.trace = args.video = None  # not written
    written = [str(p) for p in trace_files(args.trace, result.traffic is not None)] if args.trace else []
    units = metric_units(resolved.metrics_declared(), flatten(result.metrics))
    if args.json:
        out = dict(result.metrics)
        out["events"] = [e.as_dict() for e in result.events]
        out["units"] = units
        if args.record:
            out["record"] = args.record
        if args.video:
            out["video"] = args.video
        if written:
            out["trace"] = written
        print(json.dumps(out))
    else:
        _print_result(result, units)
        if args.record:
            print(f"recording: {args.record}  (review with: rerun {args.record})")
        if args.video:
            print(f"video: {args.video}")
        if written:
            print(f"trace: {', '.join(written)}")
    if failure is not None:
        sys.stdout.flush()
        print(f"ego: error: {failure}", file=sys.stderr)
        return EXIT_NOT_COMPLETED
    if result.status == "interrupted":
        return EXIT_INTERRUPTED
    return EXIT_OK if result.status in NOT_FAILED else EXIT_NOT_COMPLETED


def _fmt(value) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.3f}"
    return str(value)


def _print_result(result, units: dict[str, str]) -> None:
    """The run's metrics as text, each number followed by its unit (``units``: flattened
    metric -> unit)."""
    from ego.results.metrics import flatten

    m = flatten(result.metrics)
    print(f"{m['scenario']} with {m['controller']} (seed {m['seed']}): {m['status'].upper()} - {m['status_detail']}")
    skip = {"scenario", "controller", "seed", "status", "status_detail", "lane_choice"}
    width = max(len(k) for k in m)
    for key, value in m.items():
        if key.startswith("first_violation.") and value is None:
            continue  # a requirement that holds: no time (its events list the violations)
        if key not in skip:
            unit = units.get(key, "")
            number = isinstance(value, (int, float)) and not isinstance(value, bool)
            suffix = f" {unit}" if number and unit not in ("", "-") else ""
            print(f"  {key:<{width}}  {_fmt(value)}{suffix}")
    if result.events:
        print("events:")
        for e in result.events:
            print(f"  t={e.t:7.2f} s  [{e.kind}] {e.text}")
