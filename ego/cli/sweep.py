"""``ego sweep``: a spec's runs on an engine into a resumable results file (:mod:`ego.sweep`)."""

from __future__ import annotations

import sys
from typing import Any

from ego.checks import MAX_JOBS, check_count, check_output_dir
from ego.cli.common import EXIT_INTERRUPTED, EXIT_NOT_COMPLETED, EXIT_OK, choice
from ego.params import ConfigError


def command(args: Any) -> int:
    from ego.parallel.executor import ENGINES
    from ego.results.progress import Progress
    from ego.sweep import spec as sweep_spec
    from ego.sweep.runner import RECORD, parse_plot, sweep

    spec = _load(args, sweep_spec)
    if args.require:
        import dataclasses

        from ego.requirements import defaults, from_options

        base = spec.requirements if spec.requirements is not None else defaults(spec.scenario)
        reqs = {**base, **from_options(args.require)}
        sweep_spec.check_requirements(next(spec.runs()), reqs, ConfigError)
        spec = dataclasses.replace(spec, requirements=reqs)
    if args.preventable:
        import dataclasses

        spec = dataclasses.replace(spec, preventable=True)
    choice(args.engine, ENGINES, "--engine")
    check_count(args.jobs, "--jobs", 1, MAX_JOBS)
    if args.address is not None and args.engine != "ray":
        raise ConfigError("--address needs --engine ray")
    if args.address is not None:  # nothing listening there: one line in seconds, nothing written
        from ego.cluster import check_address

        check_address(args.address)
    choice(args.record, RECORD, "--record")
    for p in args.plot:
        parse_plot(p, spec)
    out = check_output_dir(args.out, "--out")  # sweep() checks the names inside it, then makes it
    report = sweep(
        spec,
        out,
        engine=args.engine,
        jobs=args.jobs,
        address=args.address,
        record=args.record,
        plots=args.plot,
        progress=Progress,
    )
    statuses = ", ".join(f"{n} {s}" for s, n in sorted(report.by_status.items())) or "none"
    print(
        f"{report.total} runs in the spec: {report.already} were already in "
        f"{out / 'results.parquet'}, {report.ran} ran now ({statuses}) in {report.seconds:.1f} s"
    )
    if report.interrupted:
        left = report.total - report.already - report.ran
        print(f"interrupted: {left} runs remain; the same command resumes", file=sys.stderr)
        return EXIT_INTERRUPTED
    print(
        f"wrote {out / 'results.parquet'}, {out / 'summary.md'}"
        + "".join(f", {out / name}" for name in plot_names(args.plot, spec))
    )
    if report.by_status.get("error"):
        print(
            f"ego: {report.by_status['error']} of {report.ran} runs ended in an error (see summary.md)", file=sys.stderr
        )
        return EXIT_NOT_COMPLETED
    return EXIT_OK


def _load(args: Any, sweep_spec: Any) -> Any:
    """A TOML spec, or a ParameterValueDistribution file (its counts printed)."""
    xosc = str(args.spec).lower().endswith(".xosc")
    if not xosc:
        for opt, value in (("-c", args.controllers), ("--sample", args.sample)):
            if value is not None:
                raise ConfigError(
                    f"{opt} is for a ParameterValueDistribution file (FILE.xosc); a TOML spec names its own"
                )
        return sweep_spec.load(args.spec)
    from ego.sweep import xosc as sweep_xosc

    if not args.controllers:
        raise ConfigError("ego sweep FILE.xosc needs -c CONTROLLER (comma-separated for several)")
    controllers = [c.strip() for c in args.controllers.split(",") if c.strip()]
    var = sweep_xosc.load(args.spec, controllers, args.sample, args.seed)
    print(
        f"{args.spec}: {var.total:,} combinations, {var.discarded:,} discarded by the value constraints of "
        f"{var.spec.scenario}, {var.remaining:,} remain"
        + (f"; running a sample of {var.spec.points():,} (seed {args.seed})" if args.sample is not None else "")
    )
    return var.spec


def plot_names(plots, spec) -> list[str]:
    from ego.sweep.runner import parse_plot

    names = []
    for p in plots:
        x, y, metric = parse_plot(p, spec)
        names.append(f"envelope_{x}_{y}" + (f"_{metric}" if metric else "") + ".png")
    return names
