"""``ego list``: every scenario, controller and parameter, as text, JSON or markdown."""

from __future__ import annotations

import json
import math
from dataclasses import asdict
from typing import Any

from ego.cli.common import EXIT_OK
from ego.params import ConfigError, describe


def command(args: Any) -> int:
    from ego.cli.common import check_ego_name
    from ego.openscenario import is_scenario_file

    check_ego_name(args.ego)
    if args.ego and not (args.reference and is_scenario_file(args.reference)):
        raise ConfigError("--ego goes with a scenario file: ego list FILE.xosc --ego ENTITY")
    if args.reference and is_scenario_file(args.reference):
        from ego.openscenario.distribution import root_of

        if root_of(args.reference) is not None:
            return _distribution(args.reference, args.json)
        from ego.openscenario.scenario import file_listing, print_listing

        listing = file_listing(args.reference, args.ego or "")
        print(json.dumps(listing, indent=2) if args.json else print_listing(listing), end="" if not args.json else "\n")
        return EXIT_OK
    if args.reference:
        from ego.cli.references import describe_reference, print_reference

        ref = describe_reference(args.reference)
        print(json.dumps(ref, indent=2)) if args.json else print_reference(ref)
        return EXIT_OK
    cat = catalogue()
    if args.json:
        print(json.dumps(cat, indent=2))
    elif args.markdown:
        print(parameters_markdown(cat), end="")
    else:
        print_catalogue(cat)
    return EXIT_OK


def _distribution(path: str, as_json: bool) -> int:
    """``ego list`` of a ParameterValueDistribution file: its scenario file, the parameters
    it distributes, how many combinations (and how many the scenario's value constraints
    discard), and the command that runs it; checked as ``ego sweep`` checks it."""
    from ego.sweep.xosc import load

    var = load(path, ["pid"])
    listing = {
        "distribution": path,
        "scenario": var.spec.scenario,
        "parameters": list(var.spec.listed[0]) if var.spec.listed else [],
        "combinations": var.total,
        "discarded": var.discarded,
        "remaining": var.remaining,
        "run": f"ego sweep {path} --out DIR -c CONTROLLER",
    }
    if as_json:
        print(json.dumps(listing, indent=2))
        return EXIT_OK
    print(f"{path}: a ParameterValueDistribution of {listing['scenario']}")
    print(f"  parameters    {', '.join(listing['parameters'])}")
    print(
        f"  combinations  {var.total:,} ({var.discarded:,} outside the scenario's value constraints, "
        f"{var.remaining:,} to run)"
    )
    print(f"  run it with   {listing['run']}")
    return EXIT_OK


def catalogue() -> dict:
    """Everything ``ego list`` shows. Per scenario: its parameters, every metric a run
    reports (with its unit, and whether ``ego compare``'s table shows it) and its trace
    columns for the default configuration (the controller's signals follow, unitless)."""
    from ego.cli.references import load_plugins
    from ego.control import CONTROLLERS, TASKS
    from ego.runner import declared_columns
    from ego.scenarios import SCENARIOS
    from ego.scenarios.base import COMMON_METRICS, COMMON_TAIL_METRICS, backends_for

    load_plugins()
    from ego.sim.registry import backend, backend_names

    def params(cls) -> list[dict]:
        return [
            {"name": i.name, "default": i.default, "unit": i.unit, "allowed": i.allowed(), "description": i.doc}
            for i in describe(cls)
        ]

    def scenario(name: str, cls) -> dict:
        config = cls.default_config({})
        return {
            "name": name,
            "task": cls.task,
            "summary": cls.summary,
            "backends": list(backends_for(cls)),
            "needs": list(cls.needs),
            "parameters": params(cls.config_cls),
            "metrics": [
                {"name": m.name, "unit": m.unit, "description": m.description, "headline": m.headline}
                for m in cls.metrics_declared(config)
            ],
            "columns": [
                {"name": c.name, "unit": c.unit, "description": c.description} for c in declared_columns(cls, config)
            ],
        }

    return {
        "scenarios": [scenario(n, c) for n, c in SCENARIOS.items()],
        "common_metrics": [m.name for m in COMMON_METRICS + COMMON_TAIL_METRICS],
        "backends": [
            {
                "name": name,
                "capabilities": [k for k, v in asdict(b.capabilities).items() if v],
                "options": list(b.options),
            }
            for name, b in ((n, backend(n)) for n in backend_names())
        ],
        "tasks": [TASKS[t].as_dict() for t in CONTROLLERS],
        "controllers": [
            {"name": n, "task": t, "summary": s.summary, "parameters": params(s.params)}
            for t, specs in CONTROLLERS.items()
            for n, s in specs.items()
        ],
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


def print_catalogue(cat: dict) -> None:
    from ego.results.metrics import with_unit

    def table(rows: list[dict]) -> None:
        if not rows:
            print("    (no parameters)")
            return
        w = max(len(r["name"]) for r in rows)
        defaults = [default_text(r["default"], r["unit"]) for r in rows]
        wd = min(max(map(len, defaults)), 24)  # a long text default overflows rather than widen all
        for r, default in zip(rows, defaults):
            print(f"    {r['name']:<{w}}  {default:<{wd}}  {r['description']}")

    def metrics(rows: list[dict]) -> None:
        own = [r for r in rows if r["name"] not in common]
        if not own:
            return
        print("    metrics (* in ego compare's table):")
        # a prefix ("settle_times.") stands for every metric under it
        labels = [
            with_unit(r["name"] + ("*" if r["name"].endswith(".") else ""), r["unit"]) + (" *" if r["headline"] else "")
            for r in own
        ]
        w = max(map(len, labels))
        for label, r in zip(labels, own):
            print(f"      {label:<{w}}  {r['description']}".rstrip())

    common = set(cat["common_metrics"])
    every = {m["name"]: m for s in cat["scenarios"] for m in s["metrics"] if m["name"] in common}
    print("Scenarios (ego run SCENARIO ...; parameters with --set key=value):")
    if every:
        print(
            "Every run reports "
            + ", ".join(with_unit(n, every[n]["unit"]) for n in cat["common_metrics"] if n in every)
            + " and the scenario's metrics below."
        )
    for s in cat["scenarios"]:
        if not s["backends"]:
            on = "; no traffic simulator"
        else:
            on = "" if s["backends"] == ["sumo"] else f"; --backend {' or '.join(s['backends'])}"
        on += f"; needs {', '.join(s['needs'])}" if s["needs"] else ""
        print(f"\n  {s['name']} [{s['task']} task{on}]: {s['summary']}")
        table(s["parameters"])
        metrics(s["metrics"])
    print("\nTraffic simulators (--backend NAME; a scenario runs on every one with the capabilities it needs):")
    for b in cat["backends"]:
        options = f" (options: {', '.join('--' + o for o in b['options'])})" if b["options"] else ""
        print(f"  {b['name']}: {', '.join(b['capabilities']) or 'no capabilities'}{options}")
    for task in cat["tasks"]:
        print(
            f"\nControllers of the {task['name']} task ({task['summary']}; --controller NAME, "
            "parameters with --set key=value):"
        )
        print(
            f"  they observe ({task['observation'].split(':')[1]}): "
            + ", ".join(with_unit(x["name"], x["unit"]) for x in task["observes"])
        )
        print("  and return (" + ", ".join(with_unit(x["name"], x["unit"]) for x in task["returns"]) + ")")
        for c in cat["controllers"]:
            if c["task"] == task["name"]:
                print(f"\n  {c['name']}: {c['summary']}")
                table(c["parameters"])


def default_text(value, unit: str) -> str:
    """A parameter's default for ``ego list``: a number to 6 significant digits with its
    unit, an angle also in degrees (``0.436332 rad (25 deg)``), text quoted."""
    from ego.params import _fmt as number

    if isinstance(value, str):
        return json.dumps(value)
    text = number(value) + ("" if unit in ("", "-") else f" {unit}")
    if unit == "rad" and isinstance(value, float):
        text += f" ({math.degrees(value):.3g} deg)"
    return text
