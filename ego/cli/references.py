"""``ego list REFERENCE`` and the plugins every command sees: what a controller reference
(an FMU, a class) offers."""

from __future__ import annotations

from ego.params import ConfigError


def load_plugins() -> None:
    """Register every installed plugin (both groups) into ego's registries."""
    from ego.control import CONTROLLERS
    from ego.control.references import load_controller_plugins
    from ego.scenarios import SCENARIOS
    from ego.scenarios.references import load_scenario_plugins

    load_controller_plugins(CONTROLLERS)
    load_scenario_plugins(SCENARIOS)


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

    out: dict = {"reference": ref}
    fits, errors = [], {}
    spec = None
    for task in TASKS:
        try:
            spec = controller_spec(ref, task)
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
    if spec is not None:
        out["summary"] = spec.summary
        out["parameters"] = params(spec.params)
    if not fits:
        out["why_not"] = errors
    return out


def print_reference(d: dict) -> None:
    """``ego list REF`` as text."""
    print(f"{d['reference']}: {d.get('summary', '')}")
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
            f"  drives the {', '.join(d['tasks'])} task{'s' if len(d['tasks']) > 1 else ''} "
            "(connected by name, or by --set fmu_map=map.toml)"
        )
    else:
        print("  connects to no task as it is:")
        for task, why in d.get("why_not", {}).items():
            print(f"    {task}: {why}")
    if d.get("parameters"):
        w = max(len(p["name"]) for p in d["parameters"])
        print("  parameters (--set key=value):")
        for p in d["parameters"]:
            default = repr(p["default"]) if isinstance(p["default"], str) else f"{p['default']:g}"
            unit = "" if p["unit"] in ("", "-") else f" {p['unit']}"
            print(f"    {p['name']:<{w}}  {default}{unit}  {p['description']}")
