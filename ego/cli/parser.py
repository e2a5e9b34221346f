"""The ``ego`` command line's argument parser: every command and option, with help."""

from __future__ import annotations

import argparse

from ego import __version__
from ego.checks import whole_number
from ego.cli.common import (
    Parser,
    add_address,
    add_engine,
    add_jobs,
    add_out,
    add_preventable,
    add_require,
    add_requirement_period,
    add_set,
)
from ego.sim.registry import DEFAULT_BACKEND, backend_names


def controllers_help() -> str:
    from ego.cli.references import load_plugins
    from ego.control import CONTROLLERS
    from ego.scenarios import SCENARIOS

    load_plugins()
    parts = []
    for task, specs in CONTROLLERS.items():
        scen = [n for n, c in SCENARIOS.items() if c.task == task]
        parts.append(f"{', '.join(specs)} (for {', '.join(scen)})")
    return "; ".join(parts)


def parser() -> argparse.ArgumentParser:
    """The whole command line: built anew on each call, so the scenario, controller and
    backend names in choices and help are the registries' as they are now (plugins included)."""
    ap = Parser(
        prog="ego",
        description="Run an ego vehicle's own model and controller inside real SUMO traffic.",
        epilog="Examples:\n" + "".join(f"  {line}\n" for line in EXAMPLES).rstrip("\n"),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument("--version", action="version", version=f"ego {__version__}")
    sub = ap.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    backends = backend_names()  # the registry as it is now, plugins included
    add_run(sub, backends)
    add_compare(sub, backends)
    add_sweep(sub)
    from ego.cli.concrete import add_parser as add_concrete
    from ego.cli.falsify import add_parser as add_falsify
    from ego.cli.report import add_parser as add_report

    add_falsify(sub)
    add_report(sub)
    add_concrete(sub)
    add_list(sub)
    add_export_fmu(sub)
    add_train(sub)
    add_tune(sub)
    return ap


#: ``ego --help``'s examples, one command each
EXAMPLES = (
    "ego list",
    "ego run emergency-brake --controller fuzzy --record runs/eb.rrd",
    "ego run emergency-brake --controller pid --set block_left=true --json",
    "ego run emergency-brake --controller pid --backend highway-env --video runs/eb.gif",
    "ego compare fast-follower --controllers pid,fuzzy,rbf-smc --seeds 3 --out runs/ff",
    "ego run curve --controller narma-l2 --set entry_speed=40",
    "ego compare curve --controllers pid,fuzzy-curve,narma-l2 --out runs/curve",
    "ego train narma-l2 --seed 1 --out runs/narma_s1.npz",
    "ego run curve --controller narma-l2 --set model=runs/narma_s1.npz",
    "ego run lane-centering --controller cascade-pid --set speed=25",
    "ego tune lane-centering --quick",
    "ego run platoon --controller bp-pid-acc --set followers=5 --record runs/platoon.rrd",
    "ego compare platoon --controllers pid,bp-pid-acc --seeds 3 --out runs/platoon",
    "rerun runs/eb.rrd   # review the recording",
)

REFERENCE_HELP = "package.module:Class, path/to/file.py:Class or path/to/controller.fmu (docs/fmi.md)"


def add_scenario(p: argparse.ArgumentParser) -> None:
    """``SCENARIO`` (a registered name or an .xosc file) and ``--ego ENTITY``: ego run and
    ego compare."""
    from ego.scenarios import SCENARIOS

    p.add_argument(
        "scenario", metavar="SCENARIO", help=f"one of: {', '.join(SCENARIOS)}; or an OpenSCENARIO file (.xosc)"
    )
    p.add_argument("--ego", metavar="ENTITY", help="with an .xosc file: the entity ego drives (default Ego)")


def add_backend(p: argparse.ArgumentParser, backends: tuple[str, ...], help: str) -> None:
    """``--backend``: a registered traffic simulator (choices: the registry when built)."""
    p.add_argument("--backend", default=DEFAULT_BACKEND, choices=backends, help=help)


def add_seed(p: argparse.ArgumentParser, help: str) -> None:
    """``--seed N``: a whole number, default 0."""
    p.add_argument("--seed", type=whole_number("--seed"), default=0, metavar="N", help=help)


def add_run(sub, backends: tuple[str, ...]) -> None:
    run = sub.add_parser(
        "run",
        help="run one scenario with one controller",
        description="Run one scenario with one controller and print its metrics.",
        epilog="Exit status: 0 completed or ended (the duration ran out first, not a failure); "
        "1 collision, diverged or timeout; 2 bad input; 130 interrupted (Ctrl-C or SIGTERM: "
        "the metrics so far printed, the recording closed).\n"
        "Every parameter, its unit and default: ego list",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_scenario(run)
    run.add_argument(
        "--controller",
        "-c",
        required=True,
        metavar="NAME",
        help=f"one of: {controllers_help()}; or a reference: {REFERENCE_HELP}",
    )
    run.add_argument("--record", metavar="PATH", help="write a Rerun recording (.rrd) here")
    add_seed(run, "seed of the traffic and of SUMO (default 0)")
    add_set(run, "override a scenario or controller parameter (repeatable)")
    run.add_argument(
        "--trace",
        metavar="PATH",
        help="write every trace column with its unit, and the traffic near the ego, to "
        "PATH: .csv, .parquet or .mat (MATLAB); see docs/traces.md",
    )
    run.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    add_backend(
        run,
        backends,
        "traffic simulator (default sumo); a scenario runs on those with the capabilities it needs (ego list shows both)",
    )
    run.add_argument(
        "--video", metavar="PATH", help="with --backend highway-env: a video of the run (.gif, or .mp4 with ffmpeg)"
    )
    add_require(run)
    add_requirement_period(run)
    run.add_argument(
        "--preventable",
        action="store_true",
        help="report collision_preventable even without a collision: run UN R157's careful "
        "driver on the same scenario too (it is reported after every collision anyway; "
        "docs/requirements.md)",
    )


def add_compare(sub, backends: tuple[str, ...]) -> None:
    cmp_ = sub.add_parser(
        "compare",
        help="every controller x seed of one scenario, in parallel processes",
        description="Run every combination of controllers and seeds of one scenario in parallel "
        "processes (one SUMO each) and write metrics.csv, metrics.md, PNG plots and "
        "one .rrd per run into --out.",
        epilog="Example: ego compare emergency-brake --controllers pid,fuzzy,rbf-smc --seeds 3 "
        "--out runs/cmp\nA --set key applies to the scenario and to every controller "
        "that has it.\nVariants of one controller side by side, named as given in every "
        "table, plot and file:\n  ego compare emergency-brake --controllers "
        "pid,pid@kp_lat=0.02@kd_lat=0.05 --out runs/pid-gains\n"
        "Exit status: 0 every run gave a result; 1 some run ended in an error; "
        "130 interrupted (finished runs written); 2 bad input or --out in use.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_scenario(cmp_)
    cmp_.add_argument(
        "--controllers",
        required=True,
        metavar="A,B,...",
        help="comma-separated; a name, or a variant with its own parameters "
        f"NAME@key=value[@key=value...] (pid@kp_lat=0.02), from: {controllers_help()}",
    )
    cmp_.add_argument("--seeds", type=whole_number("--seeds"), default=1, metavar="N", help="seeds 0..N-1 (default 1)")
    add_set(cmp_, "override a parameter (repeatable)")
    add_out(cmp_, "output folder")
    add_jobs(cmp_, "parallel processes (default: the number of CPUs)", metavar="J")
    add_backend(cmp_, backends, "traffic simulator (default sumo)")
    cmp_.add_argument(
        "--traces",
        default=None,
        metavar="FORMAT",
        help="also write every run's trace to traces/<label>-seed<N>.FORMAT: csv, parquet or mat (see docs/traces.md)",
    )
    add_require(cmp_)
    add_requirement_period(cmp_)
    add_preventable(cmp_)


SWEEP_EPILOG = (
    "Spec format (see scenarios/sweeps/*.toml):\n"
    '  scenario = "emergency-brake"\n  controllers = ["pid", "fuzzy"]\n'
    "  seeds = 2                 # or a list [0, 7, 9]\n"
    "  [set]                     # fixed for every run\n  traffic_density = 5\n"
    "  [grid]                    # full factorial\n  ego_speed = [20, 25, 30]\n"
    "  [sample]                  # n points over ranges: random | lhs | sobol\n"
    '  method = "sobol"\n  n = 256\n  lead_gap = [20, 60]\n\n'
    "Example: ego sweep scenarios/sweeps/envelope.toml --out runs/envelope "
    "--plot ego_speed,lead_decel:min_gap_front\n"
    "Exit status: 0 every run gave a result; 1 some run ended in an error; 130 "
    "interrupted (the same command resumes); 2 bad input or --out in use."
)


def add_sweep(sub) -> None:
    swp = sub.add_parser(
        "sweep",
        help="many runs over a parameter space (a TOML spec), resumable Parquet results",
        description="Run every run of a sweep spec (scenario, controllers, seeds, fixed values, a "
        "grid and/or a sample over ranges) on a process pool or a Ray cluster. Results "
        "go to DIR/results.parquet as runs finish; the same command again resumes. "
        "DIR/summary.md sums them up per controller.",
        epilog=SWEEP_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    swp.add_argument(
        "spec",
        metavar="SPEC.toml",
        help="the sweep specification, or an OpenSCENARIO ParameterValueDistribution file (FILE.xosc, "
        "with -c; docs/openscenario.md)",
    )
    swp.add_argument(
        "-c",
        "--controllers",
        default=None,
        metavar="NAMES",
        help="with FILE.xosc: the controller(s) to run, comma-separated",
    )
    swp.add_argument(
        "--sample",
        type=int,
        default=None,
        metavar="N",
        help="with FILE.xosc: run a seeded subsample of N of the combinations that meet the value constraints",
    )
    swp.add_argument("--seed", type=int, default=0, metavar="S", help="with --sample: its seed (default 0)")
    add_out(swp, "output folder (resumed if it holds results)")
    add_engine(swp, "process (default: a pool of worker processes) or ray")
    add_jobs(swp, "parallel runs (default: the number of CPUs)")
    add_address(swp, "with --engine ray: join this Ray cluster (e.g. auto or ray://host:10001)")
    swp.add_argument(
        "--record",
        default="failed",
        metavar="WHICH",
        help="recordings: none, failed (default: runs that did not complete or end by their duration) or all",
    )
    swp.add_argument(
        "--plot",
        action="append",
        default=[],
        metavar="X,Y[:METRIC]",
        help="an envelope plot over two swept parameters (repeatable)",
    )
    add_require(
        swp,
        "a requirement on top of the spec's [requirements] (or the scenario's defaults); "
        "repeatable, see docs/requirements.md",
    )
    add_preventable(swp)


def add_list(sub) -> None:
    lst = sub.add_parser(
        "list",
        help="scenarios, controllers and every parameter",
        description="List scenarios, controllers and every parameter with its default and unit.",
    )
    lst.add_argument(
        "reference",
        nargs="?",
        metavar="CONTROLLER|FILE.xosc",
        help="a controller reference (path/to/controller.fmu, module:Class, file.py:Class): "
        "its variables, the tasks it drives and its parameters; or an OpenSCENARIO "
        "file: its parameters, entities, the ego and every element (supported or not)",
    )
    lst.add_argument("--ego", metavar="ENTITY", help="with FILE.xosc: the entity ego drives (default Ego)")
    lst.add_argument("--json", action="store_true", help="print JSON instead of text")
    lst.add_argument(
        "--markdown",
        action="store_true",
        help="print every parameter's default, unit and allowed values as Markdown tables "
        "(the reference in docs/inputs.md)",
    )


def add_export_fmu(sub) -> None:
    exf = sub.add_parser(
        "export-fmu",
        help="write one of ego's vehicle models as an FMI 2.0 co-simulation FMU",
        description="Write ego's vehicle model as an FMI 2.0 co-simulation FMU with its C sources "
        "(compiled here with the system C compiler; see docs/fmi.md).",
        epilog="Example: ego export-fmu nonlinear-bicycle --out runs/bicycle.fmu",
    )
    exf.add_argument("model", metavar="MODEL", help="nonlinear-bicycle (report 000) or linear-bicycle (report 002)")
    add_out(exf, "the FMU to write", metavar="FILE.fmu")
    add_set(exf, "a parameter's start value in the FMU (repeatable), e.g. abs=1")


def add_install(p: argparse.ArgumentParser, out_help: str, install_help: str) -> None:
    """``--out PATH`` (optional) and ``--install``: where ``ego train``/``ego tune`` write."""
    add_out(p, out_help, metavar="PATH", required=False)
    p.add_argument("--install", action="store_true", help=install_help)


def add_train(sub) -> None:
    trn = sub.add_parser(
        "train",
        help="train a learned controller (narma-l2)",
        description="Generate identification data from the ego's model and train a learned "
        "controller's networks (torch, CPU, seeded: the same seed gives the same "
        "weights). Writes the weights (.npz) and their training metadata (.json).",
        epilog="Example: ego train narma-l2 --seed 0   (writes runs/narma_l2.npz; use it with "
        "--set model=runs/narma_l2.npz, or replace the model shipped with ego: --install)\n"
        "The report's setting (100 samples at one operating point): ego train narma-l2 "
        "--samples 100 --speeds 30,30 --accels 0.3,0.3 --radii 15,15 --out runs/narma_report.npz; "
        "use it with --set model=runs/narma_report.npz",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    trn.add_argument("what", metavar="MODEL", choices=["narma-l2"], help="narma-l2")
    add_seed(trn, "seed of data and training (default 0)")
    trn.add_argument(
        "--samples",
        type=whole_number("--samples"),
        default=20000,
        metavar="N",
        help="identification samples (default 20000)",
    )
    trn.add_argument(
        "--epochs", type=whole_number("--epochs"), default=150, metavar="N", help="training epochs (default 150)"
    )
    trn.add_argument("--speeds", default="20,40", metavar="LO,HI", help="entry speed range in km/h (default 20,40)")
    trn.add_argument(
        "--accels",
        default="0,0.6",
        metavar="LO,HI",
        help="axial acceleration range in m/s^2 (default 0,0.6); one starting with - is written --accels=-1,0",
    )
    trn.add_argument("--radii", default="12,60", metavar="LO,HI", help="curve radius range in m (default 12,60)")
    add_install(
        trn,
        "weights file (.npz; default: runs/narma_l2.npz)",
        "replace the model shipped in the package (what ego run uses by default)",
    )


def add_tune(sub) -> None:
    tun = sub.add_parser(
        "tune",
        help="tune a controller's gains (lane-centering: differential evolution)",
        description="Tune report 003's cascade PID by differential evolution with the report's "
        "settings (population 15 x 12 gains, at most 100 generations, its cost), each "
        "generation simulated as one vectorised batch over the whole road. Writes the "
        "gains and how they were found to a preset file (.json) that the "
        "lane-centering scenario loads with --set gains_file=PATH (with --install: the "
        "shipped preset it loads by default).",
        epilog="Example: ego tune lane-centering   (about two minutes; writes runs/cascade_pid_tuned.json, "
        "--install replaces the shipped preset)\n"
        "         ego tune lane-centering --quick --out runs/quick.json   (seconds)\n"
        "Use a preset with: ego run lane-centering -c cascade-pid --set gains_file=PATH",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    tun.add_argument("what", metavar="TASK", choices=["lane-centering"], help="lane-centering")
    tun.add_argument(
        "--quick", action="store_true", help="4 generations of a population of 4 x 12: a check, not a tuning"
    )
    tun.add_argument(
        "--workers",
        type=whole_number("--workers"),
        default=1,
        metavar="N",
        help="processes sharing each generation (default 1)",
    )
    add_seed(tun, "seed of the evolution (default 0)")
    tun.add_argument(
        "--drives",
        default="8,25:1",
        metavar="V[:OFF],...",
        help="drives whose costs are summed: speed in m/s, optionally the initial "
        "offset in m (default 8,25:1; report 003: 8)",
    )
    tun.add_argument(
        "--cost",
        default="model",
        metavar="KIND",
        help="model (default: the lateral-error model, the whole population in one numpy "
        "simulation) or sumo (each member's cost from SUMO runs of lane-centering on "
        "the dynamic bicycle, through --engine)",
    )
    add_engine(tun, "with --cost sumo: process (default) or ray; --workers runs at once")
    add_address(tun, "with --engine ray: join this cluster")
    tun.add_argument(
        "--duration",
        type=float,
        default=None,
        metavar="S",
        help="with --cost sumo: simulated seconds of each run (default: the whole road)",
    )
    add_install(
        tun,
        "preset file (.json; default: runs/cascade_pid_tuned.json)",
        "replace the tuned preset shipped in the package (cascade-pid's default)",
    )
