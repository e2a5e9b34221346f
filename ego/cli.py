"""The ``ego`` command line.

    ego run SCENARIO --controller NAME [--record PATH] [--trace PATH] [--seed N] [--set key=value ...]
            [--json] [--backend sumo|highway-env] [--video PATH.gif|PATH.mp4]
    ego compare SCENARIO --controllers A,B@key=value,... [--seeds N] [--set key=value ...] --out DIR
                [--traces csv|parquet|mat] [--backend sumo|highway-env]
    ego sweep SPEC.toml --out DIR [--engine process|ray] [--jobs N] [--address ADDR]
              [--record none|failed|all] [--plot X,Y[:METRIC] ...]
    ego list [--json]
    ego train narma-l2 [--seed N] [--samples N] [--epochs N] [--out PATH]
    ego tune lane-centering [--quick] [--workers N] [--seed N] [--drives V[:OFF],...] [--out PATH]
                            [--cost model|sumo] [--engine process|ray] [--address ADDR] [--duration S]

Units come from the scenario's declarations: ``ego run`` prints each numeric metric
followed by its unit, and ``--json`` adds a top-level ``"units"`` object (flattened metric
name, e.g. ``settle_times.brake@10s``, -> unit; ``-`` for a pure number, a code or text,
``""`` where the scenario declares none) beside the metrics and ``"events"``. ``ego list
--json`` gives per scenario its ``parameters``, ``metrics`` (name, unit, description,
headline; a name ending in ``.`` stands for every metric under it) and trace ``columns``
(name, unit, description), and per controller its ``parameters``.

Exit status of ``ego run``: 0 the run completed, or ``ended`` (the ``duration`` ran out
before the scenario's end, in a scenario whose end the controller does not decide: a
shortened run, not a failure); 1 it ended in a collision, diverged or timed out (the
duration ran out during a manoeuvre; the metrics are still printed); 130 interrupted by
Ctrl-C or SIGTERM (status ``interrupted``, the metrics so far printed, the recording
closed); 2 bad input (unknown name, bad value), with one line on stderr naming it and what
is allowed. ``ego compare`` and ``ego sweep``: 0 every run gave a result (a collision is a
result); 1 some run ended in ``error`` (ego could not run it); 130 interrupted (what
finished is written); 2 bad input, or ``--out`` held by another ego process.
docs/reliability.md has the details.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from collections.abc import Sequence

from ego import __version__
from ego.checks import MAX_JOBS, check_count, check_number, check_output_dir, check_output_file, check_seed
from ego.highway_env import BACKENDS
from ego.params import ConfigError, describe, did_you_mean, parse_overrides

EXIT_OK, EXIT_NOT_COMPLETED, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 130


def _choice(value: str, allowed, what: str) -> str:
    """``value`` if it is one of ``allowed``, else ConfigError (with the closest name)."""
    if value not in allowed:
        raise ConfigError(f"bad {what} {value!r} (allowed: {', '.join(allowed)}){did_you_mean(value, allowed)}")
    return value


def _terminate(signum, frame) -> None:
    """SIGTERM ends a run like Ctrl-C: status interrupted, metrics so far, recording closed."""
    raise KeyboardInterrupt


class _Parser(argparse.ArgumentParser):
    """argparse that reports bad usage in one line and exits with 2."""

    def error(self, message: str) -> None:  # pragma: no cover - exercised through main()
        choice = re.search(r"invalid choice: '([^']*)' \(choose from (.*)\)", message)
        if choice:  # a misspelt command or choice: name the closest
            message += did_you_mean(choice.group(1), re.findall(r"'([^']*)'", choice.group(2)))
        raise ConfigError(message)


def _controllers_help() -> str:
    from ego.control import CONTROLLERS
    from ego.scenarios import SCENARIOS

    parts = []
    for task, specs in CONTROLLERS.items():
        scen = [n for n, c in SCENARIOS.items() if c.task == task]
        parts.append(f"{', '.join(specs)} (for {', '.join(scen)})")
    return "; ".join(parts)


def _parser() -> argparse.ArgumentParser:
    from ego.scenarios import SCENARIOS

    ap = _Parser(
        prog="ego",
        description="Run an ego vehicle's own model and controller inside real SUMO traffic.",
        epilog="Examples:\n"
               "  ego list\n"
               "  ego run emergency-brake --controller fuzzy --record runs/eb.rrd\n"
               "  ego run emergency-brake --controller pid --set block_left=true --json\n"
               "  ego run emergency-brake --controller pid --backend highway-env --video runs/eb.gif\n"
               "  ego compare fast-follower --controllers pid,fuzzy,rbf-smc --seeds 3 --out runs/ff\n"
               "  ego run curve --controller narma-l2 --set entry_speed=40\n"
               "  ego compare curve --controllers pid,fuzzy-curve,narma-l2 --out runs/curve\n"
               "  ego train narma-l2 --seed 0\n"
               "  ego run lane-centering --controller cascade-pid --set speed=25\n"
               "  ego tune lane-centering --quick\n"
               "  ego run platoon --controller bp-pid-acc --set followers=5 --record runs/platoon.rrd\n"
               "  ego compare platoon --controllers pid,bp-pid-acc --seeds 3 --out runs/platoon\n"
               "  rerun runs/eb.rrd   # review the recording",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument("--version", action="version", version=f"ego {__version__}")
    sub = ap.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    run = sub.add_parser(
        "run", help="run one scenario with one controller",
        description="Run one scenario with one controller and print its metrics.",
        epilog="Exit status: 0 completed or ended (the duration ran out first, not a failure); "
               "1 collision, diverged or timeout; 2 bad input.\n"
               "Every parameter, its unit and default: ego list",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    run.add_argument("scenario", metavar="SCENARIO", help=f"one of: {', '.join(SCENARIOS)}")
    run.add_argument("--controller", "-c", required=True, metavar="NAME",
                     help=f"one of: {_controllers_help()}")
    run.add_argument("--record", metavar="PATH", help="write a Rerun recording (.rrd) here")
    run.add_argument("--seed", type=int, default=0, metavar="N",
                     help="seed of the traffic and of SUMO (default 0)")
    run.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                     help="override a scenario or controller parameter (repeatable)")
    run.add_argument("--trace", metavar="PATH",
                     help="write every trace column with its unit, and the traffic near the ego, to "
                          "PATH: .csv, .parquet or .mat (MATLAB); see docs/traces.md")
    run.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    run.add_argument("--backend", default="sumo", choices=BACKENDS,
                     help="traffic simulator (default sumo; highway-env runs emergency-brake, "
                          "fast-follower and cut-in)")
    run.add_argument("--video", metavar="PATH",
                     help="with --backend highway-env: a video of the run (.gif, or .mp4 with ffmpeg)")
    run.add_argument("--require", action="append", default=[], metavar="\"NAME: FORMULA\"",
                     help="a requirement in signal temporal logic over the trace's signals, on top of the scenario's defaults (repeatable; docs/requirements.md), e.g. \"keep_gap: always (gap_front >= 2 m)\"")

    cmp_ = sub.add_parser(
        "compare", help="every controller x seed of one scenario, in parallel processes",
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
    cmp_.add_argument("scenario", metavar="SCENARIO", help=f"one of: {', '.join(SCENARIOS)}")
    cmp_.add_argument("--controllers", required=True, metavar="A,B,...",
                      help="comma-separated; a name, or a variant with its own parameters "
                           f"NAME@key=value[@key=value...] (pid@kp_lat=0.02), from: {_controllers_help()}")
    cmp_.add_argument("--seeds", type=int, default=1, metavar="N", help="seeds 0..N-1 (default 1)")
    cmp_.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                      help="override a parameter (repeatable)")
    cmp_.add_argument("--out", required=True, metavar="DIR", help="output folder")
    cmp_.add_argument("--jobs", type=int, default=None, metavar="J",
                      help="parallel processes (default: the number of CPUs)")
    cmp_.add_argument("--backend", default="sumo", choices=BACKENDS,
                      help="traffic simulator (default sumo)")
    cmp_.add_argument("--traces", default=None, metavar="FORMAT",
                      help="also write every run's trace to traces/<label>-seed<N>.FORMAT: csv, parquet "
                           "or mat (see docs/traces.md)")
    cmp_.add_argument("--require", action="append", default=[], metavar="\"NAME: FORMULA\"",
                      help="a requirement in signal temporal logic over the trace's signals, on top of the scenario's defaults (repeatable; docs/requirements.md), e.g. \"keep_gap: always (gap_front >= 2 m)\"")

    swp = sub.add_parser(
        "sweep", help="many runs over a parameter space (a TOML spec), resumable Parquet results",
        description="Run every run of a sweep spec (scenario, controllers, seeds, fixed values, a "
                    "grid and/or a sample over ranges) on a process pool or a Ray cluster. Results "
                    "go to DIR/results.parquet as runs finish; the same command again resumes. "
                    "DIR/summary.md sums them up per controller.",
        epilog=("Spec format (see scenarios/sweeps/*.toml):\n"
                "  scenario = \"emergency-brake\"\n  controllers = [\"pid\", \"fuzzy\"]\n"
                "  seeds = 2                 # or a list [0, 7, 9]\n"
                "  [set]                     # fixed for every run\n  traffic_density = 5\n"
                "  [grid]                    # full factorial\n  ego_speed = [20, 25, 30]\n"
                "  [sample]                  # n points over ranges: random | lhs | sobol\n"
                "  method = \"sobol\"\n  n = 256\n  lead_gap = [20, 60]\n\n"
                "Example: ego sweep scenarios/sweeps/envelope.toml --out runs/envelope "
                "--plot ego_speed,lead_decel:min_gap_front\n"
                "Exit status: 0 every run gave a result; 1 some run ended in an error; 130 "
                "interrupted (the same command resumes); 2 bad input or --out in use."),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    swp.add_argument("spec", metavar="SPEC.toml", help="the sweep specification")
    swp.add_argument("--out", required=True, metavar="DIR", help="output folder (resumed if it holds results)")
    swp.add_argument("--engine", default="process", metavar="ENGINE",
                     help="process (default: a pool of worker processes) or ray")
    swp.add_argument("--jobs", type=int, default=None, metavar="N",
                     help="parallel runs (default: the number of CPUs)")
    swp.add_argument("--address", default=None, metavar="ADDR",
                     help="with --engine ray: join this Ray cluster (e.g. auto or ray://host:10001)")
    swp.add_argument("--record", default="failed", metavar="WHICH",
                     help="recordings: none, failed (default: runs that did not complete or end by "
                          "their duration) or all")
    swp.add_argument("--plot", action="append", default=[], metavar="X,Y[:METRIC]",
                     help="an envelope plot over two swept parameters (repeatable)")
    swp.add_argument("--require", action="append", default=[], metavar="\"NAME: FORMULA\"",
                     help="a requirement on top of the spec's [requirements] (or the scenario's defaults); "
                          "repeatable, see docs/requirements.md")
    from ego.falsify.cli import add_parser as _add_falsify

    _add_falsify(sub)

    lst = sub.add_parser("list", help="scenarios, controllers and every parameter",
                         description="List scenarios, controllers and every parameter with "
                                     "its default and unit.")
    lst.add_argument("--json", action="store_true", help="print JSON instead of text")
    lst.add_argument("--markdown", action="store_true",
                     help="print every parameter's default, unit and allowed values as Markdown tables "
                          "(the reference in docs/inputs.md)")

    trn = sub.add_parser(
        "train", help="train a learned controller (narma-l2)",
        description="Generate identification data from the ego's model and train a learned "
                    "controller's networks (torch, CPU, seeded: the same seed gives the same "
                    "weights). Writes the weights (.npz) and their training metadata (.json).",
        epilog="Example: ego train narma-l2 --seed 0   (rewrites the model shipped with ego)\n"
               "The report's setting (100 samples at one operating point): ego train narma-l2 "
               "--samples 100 --speeds 30,30 --accels 0.3,0.3 --radii 15,15 --out runs/narma_report.npz; "
               "use it with --set model=runs/narma_report.npz",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    trn.add_argument("what", metavar="MODEL", choices=["narma-l2"], help="narma-l2")
    trn.add_argument("--seed", type=int, default=0, metavar="N", help="seed of data and training (default 0)")
    trn.add_argument("--samples", type=int, default=20000, metavar="N",
                     help="identification samples (default 20000)")
    trn.add_argument("--epochs", type=int, default=150, metavar="N", help="training epochs (default 150)")
    trn.add_argument("--speeds", default="20,40", metavar="LO,HI",
                     help="entry speed range in km/h (default 20,40)")
    trn.add_argument("--accels", default="0,0.6", metavar="LO,HI",
                     help="axial acceleration range in m/s^2 (default 0,0.6)")
    trn.add_argument("--radii", default="12,60", metavar="LO,HI",
                     help="curve radius range in m (default 12,60)")
    trn.add_argument("--out", default=None, metavar="PATH",
                     help="weights file (.npz; default: runs/narma_l2.npz)")
    trn.add_argument("--install", action="store_true",
                     help="replace the model shipped in the package (what ego run uses by default)")

    tun = sub.add_parser(
        "tune", help="tune a controller's gains (lane-centering: differential evolution)",
        description="Tune report 003's cascade PID by differential evolution with the report's "
                    "settings (population 15 x 12 gains, at most 100 generations, its cost), each "
                    "generation simulated as one vectorised batch over the whole road. Writes the "
                    "gains and how they were found to a preset file (.json) that the "
                    "lane-centering scenario loads by default.",
        epilog="Example: ego tune lane-centering   (about two minutes; rewrites the shipped preset)\n"
               "         ego tune lane-centering --quick --out runs/quick.json   (seconds)\n"
               "Use a preset with: ego run lane-centering -c cascade-pid --set gains_file=PATH",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    tun.add_argument("what", metavar="TASK", choices=["lane-centering"], help="lane-centering")
    tun.add_argument("--quick", action="store_true",
                     help="4 generations of a population of 4 x 12: a check, not a tuning")
    tun.add_argument("--workers", type=int, default=1, metavar="N",
                     help="processes sharing each generation (default 1)")
    tun.add_argument("--seed", type=int, default=0, metavar="N", help="seed of the evolution (default 0)")
    tun.add_argument("--drives", default="8,25:1", metavar="V[:OFF],...",
                     help="drives whose costs are summed: speed in m/s, optionally the initial "
                          "offset in m (default 8,25:1; report 003: 8)")
    tun.add_argument("--cost", default="model", metavar="KIND",
                     help="model (default: the lateral-error model, the whole population in one numpy "
                          "simulation) or sumo (each member's cost from SUMO runs of lane-centering on "
                          "the dynamic bicycle, through --engine)")
    tun.add_argument("--engine", default="process", metavar="ENGINE",
                     help="with --cost sumo: process (default) or ray; --workers runs at once")
    tun.add_argument("--address", default=None, metavar="ADDR", help="with --engine ray: join this cluster")
    tun.add_argument("--duration", type=float, default=None, metavar="S",
                     help="with --cost sumo: simulated seconds of each run (default: the whole road)")
    tun.add_argument("--out", default=None, metavar="PATH",
                     help="preset file (.json; default: runs/cascade_pid_tuned.json)")
    tun.add_argument("--install", action="store_true",
                     help="replace the tuned preset shipped in the package (cascade-pid's default)")
    return ap


def _catalogue() -> dict:
    """Everything ``ego list`` shows. Per scenario: its parameters, every metric a run
    reports (with its unit, and whether ``ego compare``'s table shows it) and its trace
    columns for the default configuration (the controller's signals follow, unitless)."""
    from ego.control import CONTROLLERS, TASKS
    from ego.runner import declared_columns
    from ego.scenarios import SCENARIOS
    from ego.scenarios.base import COMMON_METRICS, COMMON_TAIL_METRICS

    def params(cls) -> list[dict]:
        return [
            {"name": i.name, "default": i.default, "unit": i.unit, "allowed": i.allowed(),
             "description": i.doc}
            for i in describe(cls)
        ]

    def scenario(name: str, cls) -> dict:
        config = cls.default_config({})
        return {
            "name": name, "task": cls.task, "summary": cls.summary, "backends": list(cls.backends),
            "parameters": params(cls.config_cls),
            "metrics": [{"name": m.name, "unit": m.unit, "description": m.description, "headline": m.headline}
                        for m in cls.metrics_declared(config)],
            "columns": [{"name": c.name, "unit": c.unit, "description": c.description}
                        for c in declared_columns(cls, config)],
        }

    return {
        "scenarios": [scenario(n, c) for n, c in SCENARIOS.items()],
        "common_metrics": [m.name for m in COMMON_METRICS + COMMON_TAIL_METRICS],
        "tasks": [TASKS[t].as_dict() for t in CONTROLLERS],
        "controllers": [{"name": n, "task": t, "summary": s.summary, "parameters": params(s.params)}
                        for t, specs in CONTROLLERS.items() for n, s in specs.items()],
    }


def parameters_markdown(cat: dict) -> str:
    """Every scenario's and controller's parameters as Markdown tables (``ego list --markdown``):
    name, default, unit, what is allowed, description."""
    def table(title: str, rows: list[dict]) -> list[str]:
        lines = [f"### {title}", ""]
        if not rows:
            return lines + ["(no parameters)", ""]
        lines += ["| parameter | default | unit | allowed | description |", "|---|---|---|---|---|"]
        for r in rows:
            cells = (f"`{r['name']}`", f"`{json.dumps(r['default'])}`", r["unit"], r["allowed"], r["description"])
            lines.append("| " + " | ".join(str(c).replace("|", "\\|") for c in cells) + " |")
        return lines + [""]

    lines = ["## Scenario parameters", ""]
    for s in cat["scenarios"]:
        lines += table(f"{s['name']} ({s['task']} task)", s["parameters"])
    lines += ["## Controller parameters", ""]
    for c in cat["controllers"]:
        lines += table(f"{c['name']} ({c['task']} task)", c["parameters"])
    return "\n".join(lines)


def _print_catalogue(cat: dict) -> None:
    from ego.scenarios.metrics import with_unit

    def table(rows: list[dict]) -> None:
        if not rows:
            print("    (no parameters)")
            return
        w = max(len(r["name"]) for r in rows)
        defaults = [_default(r["default"], r["unit"]) for r in rows]
        wd = min(max(map(len, defaults)), 24)  # a long text default overflows rather than widen all
        for r, default in zip(rows, defaults):
            print(f"    {r['name']:<{w}}  {default:<{wd}}  {r['description']}")

    def metrics(rows: list[dict]) -> None:
        own = [r for r in rows if r["name"] not in common]
        if not own:
            return
        print("    metrics (* in ego compare's table):")
        # a prefix ("settle_times.") stands for every metric under it
        labels = [with_unit(r["name"] + ("*" if r["name"].endswith(".") else ""), r["unit"])
                  + (" *" if r["headline"] else "") for r in own]
        w = max(map(len, labels))
        for label, r in zip(labels, own):
            print(f"      {label:<{w}}  {r['description']}".rstrip())

    common = set(cat["common_metrics"])
    every = {m["name"]: m for s in cat["scenarios"] for m in s["metrics"] if m["name"] in common}
    print("Scenarios (ego run SCENARIO ...; parameters with --set key=value):")
    if every:
        print("Every run reports " + ", ".join(with_unit(n, every[n]["unit"]) for n in cat["common_metrics"]
                                             if n in every) + " and the scenario's metrics below.")
    for s in cat["scenarios"]:
        on = "" if s["backends"] == ["sumo"] else f"; --backend {' or '.join(s['backends'])}"
        print(f"\n  {s['name']} [{s['task']} task{on}]: {s['summary']}")
        table(s["parameters"])
        metrics(s["metrics"])
    for task in cat["tasks"]:
        print(f"\nControllers of the {task['name']} task ({task['summary']}; --controller NAME, "
              "parameters with --set key=value):")
        print(f"  they observe ({task['observation'].split(':')[1]}): "
              + ", ".join(with_unit(x["name"], x["unit"]) for x in task["observes"]))
        print("  and return (" + ", ".join(with_unit(x["name"], x["unit"]) for x in task["returns"]) + ")")
        for c in cat["controllers"]:
            if c["task"] == task["name"]:
                print(f"\n  {c['name']}: {c['summary']}")
                table(c["parameters"])


def _default(value, unit: str) -> str:
    """A parameter's default for ``ego list``: a number to 6 significant digits with its
    unit, an angle also in degrees (``0.436332 rad (25 deg)``), text quoted."""
    from ego.params import _fmt as number

    if isinstance(value, str):
        return json.dumps(value)
    text = number(value) + ("" if unit in ("", "-") else f" {unit}")
    if unit == "rad" and isinstance(value, float):
        text += f" ({math.degrees(value):.3g} deg)"
    return text


def _fmt(value) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.3f}"
    return str(value)


def _print_result(result, units: dict[str, str]) -> None:
    """The run's metrics as text, each number followed by its unit (``units``: flattened
    metric -> unit)."""
    from ego.scenarios.metrics import flatten

    m = flatten(result.metrics)
    print(f"{m['scenario']} with {m['controller']} (seed {m['seed']}): {m['status'].upper()}"
          f" - {m['status_detail']}")
    skip = {"scenario", "controller", "seed", "status", "status_detail", "lane_choice"}
    width = max(len(k) for k in m)
    for key, value in m.items():
        if key not in skip:
            unit = units.get(key, "")
            number = isinstance(value, (int, float)) and not isinstance(value, bool)
            suffix = f" {unit}" if number and unit not in ("", "-") else ""
            print(f"  {key:<{width}}  {_fmt(value)}{suffix}")
    if result.events:
        print("events:")
        for e in result.events:
            print(f"  t={e.t:7.2f} s  [{e.kind}] {e.text}")


def _run(args) -> int:
    from ego.requirements import with_defaults
    from ego.runner import RunSpec, declared_metrics, run
    from ego.scenarios.base import NOT_FAILED
    from ego.scenarios.metrics import flatten, metric_units

    from ego.export import trace_files

    spec = RunSpec(args.scenario, args.controller, seed=check_seed(args.seed, "--seed"),
                   overrides=parse_overrides(args.overrides), record=args.record, trace=args.trace,
                   backend=args.backend, video=args.video,
                   requirements=with_defaults(args.scenario, args.require))
    result = run(spec)  # checks the --trace path before anything runs
    written = [str(p) for p in trace_files(args.trace, result.traffic is not None)] if args.trace else []
    units = metric_units(declared_metrics(spec), flatten(result.metrics))
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
    if result.status == "interrupted":
        return EXIT_INTERRUPTED
    return EXIT_OK if result.status in NOT_FAILED else EXIT_NOT_COMPLETED


def _compare(args) -> int:
    from ego.compare import MAX_SEEDS, UNITS_FILE, compare

    if args.seeds > MAX_SEEDS:
        raise ConfigError(f"bad value for --seeds: {args.seeds} (expected at most {MAX_SEEDS}; use ego sweep "
                          "for more)")
    check_count(args.seeds, "--seeds", 1, MAX_SEEDS)
    check_count(args.jobs, "--jobs", 1, MAX_JOBS)
    labels = [n.strip() for n in args.controllers.split(",") if n.strip()]
    out = check_output_dir(args.out, "--out")
    from ego.requirements import with_defaults

    rows = compare(args.scenario, labels, args.seeds, parse_overrides(args.overrides), out, args.jobs,
                   traces=args.traces, backend=args.backend,
                   requirements=with_defaults(args.scenario, args.require))
    print((out / "metrics.md").read_text(), end="")
    files = ["metrics.csv", UNITS_FILE, "metrics.md"] + sorted(p.name for p in out.glob("*.png"))
    recorded = sum(1 for r in rows if r.recording)
    traces = f" and their traces ({args.traces}) in traces/" if args.traces else ""
    print(f"\nwrote into {out}/: {', '.join(files)} and {recorded} of {len(rows)} recordings in "
          f"runs/{traces}")
    return _compare_status([r.status for r in rows])


def _compare_status(statuses: Sequence[str]) -> int:
    """``ego compare``'s exit status: 130 when interrupted (the finished runs are written),
    1 when a run ended in ``error`` (ego could not run it: an exception, a dead worker),
    else 0 - a collision or a diverging controller is a result of the comparison."""
    if "interrupted" in statuses:
        unfinished = statuses.count("interrupted")
        print(f"ego: interrupted: {unfinished} of {len(statuses)} runs did not finish "
              "(rows with status interrupted)", file=sys.stderr)
        return EXIT_INTERRUPTED
    if "error" in statuses:
        print(f"ego: {statuses.count('error')} of {len(statuses)} runs ended in an error "
              "(see metrics.md)", file=sys.stderr)
        return EXIT_NOT_COMPLETED
    return EXIT_OK


def _range(text: str, what: str, declared) -> tuple[float, float]:
    """``LO,HI`` within the bounds ``declared`` (a parameter's ``ParamInfo``) gives."""
    try:
        lo, hi = (float(x) for x in text.split(","))
    except ValueError:
        raise ConfigError(f"bad value for {what}: {text!r} (expected LO,HI, e.g. 20,40)") from None
    if not (math.isfinite(lo) and math.isfinite(hi)) or lo > hi:
        raise ConfigError(f"bad value for {what}: {text!r} (expected finite LO <= HI)")
    if lo < declared.min or hi > declared.max:
        raise ConfigError(f"bad value for {what}: {text!r} (expected {declared.unit} within "
                          f"{declared.min:g}..{declared.max:g})")
    return lo, hi


def _declared(cls, name: str):
    """The declaration (``ParamInfo``) of parameter ``name`` of ``cls``."""
    return next(i for i in describe(cls) if i.name == name)


def _sweep(args) -> int:
    from ego.sweep import spec as sweep_spec
    from ego.sweep.executor import ENGINES
    from ego.sweep.runner import RECORD, parse_plot, print_progress, sweep

    spec = sweep_spec.load(args.spec)
    if args.require:
        import dataclasses

        from ego.requirements import defaults, split

        base = spec.requirements if spec.requirements is not None else defaults(spec.scenario)
        reqs = {**base, **dict(split(t) for t in args.require)}
        sweep_spec.check_requirements(next(spec.runs()), reqs, ConfigError)
        spec = dataclasses.replace(spec, requirements=reqs)
    _choice(args.engine, ENGINES, "--engine")
    check_count(args.jobs, "--jobs", 1, MAX_JOBS)
    if args.address is not None and args.engine != "ray":
        raise ConfigError("--address needs --engine ray")
    _choice(args.record, RECORD, "--record")
    for p in args.plot:
        parse_plot(p, spec)
    out = check_output_dir(args.out, "--out")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"cannot create --out folder {args.out!r}: {exc.strerror}") from None
    report = sweep(spec, out, engine=args.engine, jobs=args.jobs, address=args.address,
                   record=args.record, plots=args.plot, progress=print_progress)
    statuses = ", ".join(f"{n} {s}" for s, n in sorted(report.by_status.items())) or "none"
    print(f"{report.total} runs in the spec: {report.already} were already in "
          f"{out / 'results.parquet'}, {report.ran} ran now ({statuses}) in {report.seconds:.1f} s")
    if report.interrupted:
        left = report.total - report.already - report.ran
        print(f"interrupted: {left} runs remain; the same command resumes", file=sys.stderr)
        return EXIT_INTERRUPTED
    print(f"wrote {out / 'results.parquet'}, {out / 'summary.md'}"
          + "".join(f", {out / name}" for name in _plot_names(args.plot, spec)))
    if report.by_status.get("error"):
        print(f"ego: {report.by_status['error']} of {report.ran} runs ended in an error "
              "(see summary.md)", file=sys.stderr)
        return EXIT_NOT_COMPLETED
    return EXIT_OK


def _plot_names(plots, spec) -> list[str]:
    from ego.sweep.runner import parse_plot

    names = []
    for p in plots:
        x, y, metric = parse_plot(p, spec)
        names.append(f"envelope_{x}_{y}" + (f"_{metric}" if metric else "") + ".png")
    return names


def _model_out(args, shipped, default: str, suffix: str):
    """Where ``ego train``/``ego tune`` write: --out, the shipped file with --install (and
    only then), else ``default`` in the working directory."""
    from pathlib import Path

    if args.install and args.out:
        raise ConfigError("give --out or --install, not both")
    if args.install:
        return Path(shipped)
    return check_output_file(args.out or default, "--out path", suffix)


def _train(args) -> int:
    from ego.control.narma import DEFAULT_MODEL
    from ego.train.narma_l2 import DataSpec, TrainSpec, train

    for value, what, cls, name in ((args.samples, "--samples", DataSpec, "samples"),
                                   (args.epochs, "--epochs", TrainSpec, "epochs")):
        declared = _declared(cls, name)
        check_count(value, what, int(declared.min), int(declared.max))
    v_lo, v_hi = _range(args.speeds, "--speeds", _declared(DataSpec, "speed_min"))
    a_lo, a_hi = _range(args.accels, "--accels", _declared(DataSpec, "accel_min"))
    r_lo, r_hi = _range(args.radii, "--radii", _declared(DataSpec, "radius_min"))
    check_seed(args.seed, "--seed")
    out = _model_out(args, DEFAULT_MODEL, "runs/narma_l2.npz", ".npz")
    data = DataSpec(samples=args.samples, speed_min=v_lo, speed_max=v_hi, accel_min=a_lo,
                    accel_max=a_hi, radius_min=r_lo, radius_max=r_hi)
    train(TrainSpec(seed=args.seed, epochs=args.epochs, data=data), out)
    return EXIT_OK


def _tune(args) -> int:
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
        raise ConfigError(f"bad value for --drives: {args.drives!r} (expected speeds in m/s with "
                          "optional offsets in m, e.g. 8,25:1)") from None
    check_drives(drives, "--drives", repr(args.drives))
    check_seed(args.seed, "--seed")
    out = _model_out(args, TUNED_PRESET, "runs/cascade_pid_tuned.json", ".json")
    from ego.sweep.executor import ENGINES

    _choice(args.cost, ("model", "sumo"), "--cost")
    _choice(args.engine, ENGINES, "--engine")
    if args.cost == "model" and (args.engine != "process" or args.address or args.duration is not None):
        raise ConfigError("--engine, --address and --duration go with --cost sumo")
    if args.address is not None and args.engine != "ray":
        raise ConfigError("--address needs --engine ray")
    check_number(args.duration, "--duration", 1.0, MAX_DURATION, "s")
    spec = TuneSpec.quick(args.seed, args.workers) if args.quick else TuneSpec(seed=args.seed, workers=args.workers)
    tune(TuneSpec(**{**spec.__dict__, "drives": drives, "cost": args.cost, "engine": args.engine,
                     "address": args.address, "duration": args.duration}), out)
    return EXIT_OK


def main(argv: Sequence[str] | None = None) -> int:
    from ego.sumo.bridge import SumoError

    import signal

    if argv is None:  # the command itself, not a call from Python code
        signal.signal(signal.SIGTERM, _terminate)
    try:
        args = _parser().parse_args(argv)
        if args.command == "run":
            return _run(args)
        if args.command == "compare":
            return _compare(args)
        if args.command == "sweep":
            return _sweep(args)
        if args.command == "falsify":
            from ego.falsify.cli import main as falsify_main

            return falsify_main(args)
        if args.command == "train":
            return _train(args)
        if args.command == "tune":
            return _tune(args)
        if args.command == "list":
            cat = _catalogue()
            if args.json:
                print(json.dumps(cat, indent=2))
            elif args.markdown:
                print(parameters_markdown(cat), end="")
            else:
                _print_catalogue(cat)
            return EXIT_OK
        _parser().print_help()
        return EXIT_USAGE
    except (ConfigError, SumoError) as exc:
        print(f"ego: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("ego: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # e.g. piped into head: stop quietly
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
