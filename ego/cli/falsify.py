"""``ego falsify``: search a parameter space for runs that violate a requirement (:mod:`ego.falsify`)."""

from __future__ import annotations

import argparse
import sys

from ego.checks import whole_number
from ego.cli.common import add_address, add_engine, add_jobs, add_out, add_path

#: the optimisers (psy-taliro's two where psy-taliro is installed: ego's test extra)
OPTIMIZERS = ("cma", "bo", "bo-tpe", "random", "lhs", "psytaliro-uniform", "psytaliro-annealing")
UNTIL = ("first", "budget")


def add_parser(sub) -> argparse.ArgumentParser:
    """Add the ``falsify`` subcommand to ``ego``'s subparsers."""
    fal = sub.add_parser(
        "falsify",
        help="search a parameter space for runs that violate a requirement (STL)",
        description="Search the ranges of a falsification spec for the runs that minimise a "
        "requirement's robustness (signal temporal logic over the trace, see "
        "docs/requirements.md): CMA-ES or Bayesian optimisation proposing batches "
        "sized to the workers, or random / Latin-hypercube baselines. Every run goes "
        "to DIR/results.parquet (the same command resumes); DIR/falsified.md lists "
        "each violation with the ego run command that reproduces it; "
        "DIR/convergence.png plots the best robustness against runs.",
        epilog=(
            "Spec format (see scenarios/falsify/*.toml):\n"
            '  scenario = "emergency-brake"\n  controller = "fuzzy-pid"\n'
            '  requirement = "no_avoidable_collision"   # a name from [requirements] or the defaults\n'
            "  seed = [0, 99999]          # a range searched, or one fixed seed\n"
            "  seeds_per_point = 1        # each point over its seed and the next k-1, the worst kept\n"
            "  requirement_period = 0     # requirements on every sample (or a grid of S seconds)\n"
            "  budget = 500               # runs (--budget overrides)\n"
            '  [requirements]\n  no_avoidable_collision = "always (not avoidable_collision)"\n'
            "  [set]\n  traffic_density = 5\n"
            "  [search]                   # ranges: floats, whole numbers (integer), [false, true] (categorical)\n"
            "  ego_speed = [10, 36]\n  block_left = [false, true]\n\n"
            "Exit status: 0 no violation found; 1 a violation found (see falsified.md); 130 "
            "interrupted (the same command resumes); 2 bad input or --out in use."
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    fal.add_argument(
        "spec",
        metavar="SPEC.toml",
        help="the falsification specification, or a ParameterValueDistribution FILE.xosc (its ranges searched)",
    )
    add_out(fal, "output folder (resumed if it holds results)")
    add_engine(fal, "process (default) or ray")
    add_jobs(fal, "parallel runs (default: the CPUs)")
    fal.add_argument(
        "--batch",
        type=whole_number("--batch"),
        default=None,
        metavar="N",
        help="points the optimiser proposes at a time (default 2); the search depends on it, not "
        "on --jobs: more workers than that only help with a larger batch",
    )
    add_address(fal, "with --engine ray: join this cluster")
    fal.add_argument(
        "--budget",
        type=whole_number("--budget"),
        default=None,
        metavar="N",
        help="runs at most (default: the spec's)",
    )
    fal.add_argument(
        "--optimizer",
        default="cma",
        metavar="NAME",
        help=f"one of {', '.join(OPTIMIZERS)} (default cma)",
    )
    fal.add_argument(
        "--optimizer-seed",
        type=whole_number("--optimizer-seed"),
        default=0,
        metavar="N",
        help="the optimiser's seed (default 0)",
    )
    fal.add_argument(
        "--until",
        default="budget",
        metavar="WHEN",
        help="first: stop at the first violation; budget (default): use the whole budget",
    )
    _add_distribution_options(fal)
    fal.add_argument(
        "--no-verify",
        action="store_true",
        help="do not rerun each violation to check that its ego run command reproduces it",
    )
    add_path(fal)
    return fal


def _add_distribution_options(fal: argparse.ArgumentParser) -> None:
    """The options a ParameterValueDistribution FILE.xosc needs (a TOML spec names them)."""
    fal.add_argument(
        "-c",
        "--controller",
        default=None,
        metavar="NAMES",
        help="with a ParameterValueDistribution FILE.xosc: the controllers (comma-separated)",
    )
    fal.add_argument(
        "--requirement",
        default=None,
        metavar="NAME",
        help="with FILE.xosc: the requirement to falsify (default no_collision)",
    )


def command(args) -> int:
    from ego.checks import MAX_JOBS, check_count, check_output_dir, check_seed
    from ego.falsify.search import BATCH, falsify
    from ego.falsify.spec import load
    from ego.parallel.executor import ENGINES
    from ego.params import ConfigError

    if str(args.spec).lower().endswith(".xosc"):
        from ego.falsify.spec import from_distribution

        if not args.controller:
            raise ConfigError("ego falsify FILE.xosc needs -c CONTROLLER (a TOML spec names its controllers)")
        controllers = [c.strip() for c in args.controller.split(",") if c.strip()]
        spec = from_distribution(str(args.spec), controllers, args.requirement, args.budget)
    elif args.controller is not None or args.requirement is not None:
        raise ConfigError("-c and --requirement are for a FILE.xosc distribution; a TOML spec names them")
    else:
        spec = load(args.spec)
    for value, allowed, what in (
        (args.optimizer, OPTIMIZERS, "--optimizer"),
        (args.until, UNTIL, "--until"),
        (args.engine, ENGINES, "--engine"),
    ):
        if value not in allowed:
            raise ConfigError(f"bad value for {what}: {value!r} (allowed: {', '.join(allowed)})")
    check_count(args.jobs, "--jobs", 1, MAX_JOBS)
    check_count(args.batch, "--batch", 1, 1024)
    check_count(args.budget, "--budget", 1, 10_000_000)
    check_seed(args.optimizer_seed, "--optimizer-seed")
    if args.address is not None and args.engine != "ray":
        raise ConfigError("--address needs --engine ray")
    spec.check_optimizer(args.optimizer)
    out = check_output_dir(args.out, "--out")  # falsify() checks the names inside it, then makes it
    report = falsify(
        spec,
        out,
        optimizer=args.optimizer,
        budget=args.budget,
        engine=args.engine,
        jobs=args.jobs,
        address=args.address,
        until=args.until,
        optimizer_seed=args.optimizer_seed,
        verify=not args.no_verify,
        progress=True,
        batch=args.batch or BATCH,
    )
    print(report.text())
    if report.interrupted:
        print("interrupted: the same command resumes", file=sys.stderr)
        return 130
    return 1 if report.violations else 0
