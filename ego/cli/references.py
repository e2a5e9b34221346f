"""``ego list REFERENCE`` and the plugins every command sees: what a controller reference
(an FMU, a class) offers."""

from __future__ import annotations

from ego.params import ConfigError, did_you_mean


def load_plugins() -> None:
    """Register every installed plugin (controllers, scenarios, metrics, backends) into
    ego's registries."""
    from ego.control import CONTROLLERS
    from ego.control.references import load_controller_plugins
    from ego.results.metrics import load_metric_plugins
    from ego.scenarios import SCENARIOS
    from ego.scenarios.references import load_scenario_plugins
    from ego.sim.registry import load_backend_plugins

    load_controller_plugins(CONTROLLERS)
    load_scenario_plugins(SCENARIOS)
    load_metric_plugins()
    load_backend_plugins()


def describe_reference(ref: str) -> dict:
    """What ``ego list REF`` shows for a controller reference: for an FMU its FMI version,
    variables with units and causality, the tasks whose signals its inputs and outputs
    connect to by name, and its parameters (``fmu.<name>``); for a class its parameters."""
    from ego.control import TASKS, controller_spec
    from ego.params import describe

    def params(cls) -> list[dict]:
        return [
            {"name": i.name, "default": i.default, "unit": i.unit, "allowed": i.allowed(), "description": i.doc}
            for i in describe(cls)
        ]

    check_reference(ref)
    out: dict = {"reference": ref}
    fits, errors = [], {}
    spec = None
    variants = {}  # task -> what the reference is there: a name may stand for another controller per task
    for task in TASKS:
        try:
            spec = controller_spec(ref, task)
            variants[task] = {"summary": spec.summary, "parameters": params(spec.params)}
            if ref.lower().endswith(".fmu"):  # connects by name to this task's signals?
                from ego.fmi.controller import mapping_for

                mapping_for(spec.params._info, task, "", ref)
            fits.append(task)
        except ConfigError as exc:
            errors[task] = str(exc)
    if ref.lower().endswith(".fmu"):
        from ego.fmi.model import inspect_fmu

        info = inspect_fmu(ref)  # the FMU's own problems are raised here, before the tasks'
        out.update(
            kind="fmu",
            fmi_version=info.fmi_version,
            model_name=info.model_name,
            description=info.description,
            generation_tool=info.generation_tool,
            variable_step=info.variable_step,
            default_step=info.default_step,
            variables=[
                {
                    "name": v.name,
                    "causality": v.causality,
                    "type": v.type,
                    "unit": v.unit,
                    "start": v.start,
                    "description": v.description,
                }
                for v in info.variables
                if v.causality in ("input", "output", "parameter")
            ],
        )
    else:
        out["kind"] = "class"
    out["tasks"] = fits
    shown = [variants[t] for t in fits] or list(variants.values())[-1:]
    if shown and all(v == shown[0] for v in shown):
        out.update(shown[0])
    elif shown:  # pid: a controller of its own in each task, with parameters of its own
        out["per_task"] = {t: variants[t] for t in fits}
    if not fits:
        out["why_not"] = errors
    return out


def check_reference(ref: str) -> None:
    """ConfigError unless ``ref`` names something to describe: a registered controller, a
    class (or spec) that imports, or an FMU (whose own checks follow); a reference that fits
    no task is still described, with why not."""
    from ego.control import controller_names
    from ego.plugins import file_resolver, is_reference, load_object

    if not is_reference(ref):
        known = controller_names()
        if ref not in known:
            raise ConfigError(
                f"unknown controller {ref!r}{did_you_mean(ref, known)} (known: {', '.join(known)}; or a reference: "
                "package.module:Class, path/to/file.py:Class or path/to/controller.fmu)"
            )
    elif file_resolver(ref) is None:  # a missing file, module or name, or one that does not import
        load_object(ref, "controller")


def print_reference(d: dict) -> None:
    """``ego list REF`` as text."""
    from ego.scenarios import SCENARIOS

    load_plugins()
    print(f"{d['reference']}: {d.get('summary', 'a controller of its own in each task' if 'per_task' in d else '')}")
    if d["kind"] == "fmu":
        step = "any communication step" if d["variable_step"] else f"fixed step {d['default_step']} s"
        print(
            f"  FMI {d['fmi_version']} co-simulation, {step}"
            + (f", made by {d['generation_tool']}" if d["generation_tool"] else "")
        )
        for causality in ("input", "output", "parameter"):
            vs = [v for v in d["variables"] if v["causality"] == causality]
            if vs:
                print(
                    f"  {causality}s: "
                    + ", ".join(
                        v["name"]
                        + (f" [{v['unit']}]" if v["unit"] else "")
                        + ("" if v["type"] in ("Real", "Float64") else f" ({v['type']})")
                        for v in vs
                    )
                )
    if d["tasks"]:
        print(
            f"  drives the {', '.join(d['tasks'])} task{'s' if len(d['tasks']) > 1 else ''}"
            + (" (connected by name, or by --set fmu_map=map.toml)" if d["kind"] == "fmu" else "")
        )
    else:
        print("  connects to no task as it is:")
        for task, why in d.get("why_not", {}).items():
            print(f"    {task}: {why}")
    print_parameters(d.get("parameters"), "  ")
    for task, variant in d.get("per_task", {}).items():
        scenarios = ", ".join(n for n, c in SCENARIOS.items() if c.task == task)
        print(f"  in the {task} task ({scenarios}): {variant['summary']}")
        print_parameters(variant["parameters"], "    ")


def print_parameters(rows: list[dict] | None, indent: str) -> None:
    """A reference's parameters, one a line: name, default with unit, description."""
    if rows:
        w = max(len(p["name"]) for p in rows)
        print(f"{indent}parameters (--set key=value):")
        for p in rows:
            default = repr(p["default"]) if isinstance(p["default"], str) else f"{p['default']:g}"
            unit = "" if p["unit"] in ("", "-") else f" {p['unit']}"
            print(f"{indent}  {p['name']:<{w}}  {default}{unit}  {p['description']}")
