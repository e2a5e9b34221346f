"""``ego tune lane-centering``: tune report 003's cascade PID (:mod:`ego.train.lane_centering`)."""

from __future__ import annotations

import math
from typing import Any

from ego.checks import MAX_JOBS, check_count, check_number, check_seed
from ego.cli.common import EXIT_OK, choice, model_out
from ego.params import ConfigError


def command(args: Any) -> int:
    from ego.control.cascade import TUNED_PRESET
    from ego.train.lane_centering import MAX_DURATION, TuneSpec, check_drives, tune

    check_count(args.workers, "--workers", 1, MAX_JOBS)
    try:
        parts = [d.split(":") for d in args.drives.split(",")]
        if any(len(p) > 2 for p in parts):
            raise ValueError
        drives = tuple((float(p[0]), float(p[1]) if len(p) == 2 else 0.0) for p in parts)
        if not all(math.isfinite(x) for d in drives for x in d):
            raise ValueError
    except ValueError:
        raise ConfigError(
            f"bad value for --drives: {args.drives!r} (expected speeds in m/s with optional offsets in m, e.g. 8,25:1)"
        ) from None
    check_drives(drives, "--drives", args.drives)
    check_seed(args.seed, "--seed")
    out = model_out(args, TUNED_PRESET, "runs/cascade_pid_tuned.json", ".json")
    from ego.parallel.executor import ENGINES

    choice(args.cost, ("model", "sumo"), "--cost")
    choice(args.engine, ENGINES, "--engine")
    if args.cost == "model" and (args.engine != "process" or args.address or args.duration is not None):
        raise ConfigError("--engine, --address and --duration go with --cost sumo")
    if args.address is not None and args.engine != "ray":
        raise ConfigError("--address needs --engine ray")
    if args.address is not None:
        from ego.cluster import check_address

        check_address(args.address)
    check_number(args.duration, "--duration", 1.0, MAX_DURATION, "s")
    spec = TuneSpec.quick(args.seed, args.workers) if args.quick else TuneSpec(seed=args.seed, workers=args.workers)
    tune(
        TuneSpec(
            **{
                **spec.__dict__,
                "drives": drives,
                "cost": args.cost,
                "engine": args.engine,
                "address": args.address,
                "duration": args.duration,
            }
        ),
        out,
    )
    return EXIT_OK
