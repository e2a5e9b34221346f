"""``ego export-fmu MODEL --out FILE.fmu``: ego's vehicle models as FMI 2.0 co-simulation FMUs.

* ``nonlinear-bicycle`` - report 000's nonlinear bicycle (Pacejka lateral tyres, rear friction
  circle), built from the RK4 kernel ego's native twin runs (``ego/_bicycle.h``);
* ``linear-bicycle`` - report 002's linear dynamic bicycle, its right-hand side and RK4
  written term for term as :class:`ego.models.DynamicBicycle` computes them.

Each FMU holds its binary for this platform and its C sources (``sources/``, with the FMI
headers), so it compiles for another. Inputs are the model's commands, outputs its state
(X, u, Y, v, psi, r) and the lateral acceleration; parameters are the model's constants
(with ego's values as start values), the initial state and the RK4 steps per communication
step. Stepped with the same commands, the FMU and ego's model agree to rounding (the tests
hold them to 1e-9).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

from ego.fmi.build import FRAME_DIR, ModelSpec, Var, build_fmu
from ego.params import ConfigError, ParamInfo, check_value, parse_value

EGO_DIR = Path(__file__).resolve().parent.parent
STATE = (
    ("X", "m", "world X of the centre of gravity"),
    ("u", "m/s", "body longitudinal speed"),
    ("Y", "m", "world Y of the centre of gravity"),
    ("v", "m/s", "body lateral speed (+ left)"),
    ("psi", "rad", "yaw, counter-clockwise from world X"),
    ("r", "rad/s", "yaw rate"),
)


#: what ``--set`` allows each parameter of either model: name -> (type, min, max, min
#: exclusive); as ``ego run --set`` holds ``substeps`` and ``abs`` (TimingConfig,
#: HighwayConfig), the constants positive where the model divides by them or needs them so
LIMITS: dict[str, tuple[type, float | None, float | None, bool]] = {
    "X0": (float, -1e7, 1e7, False),
    "u0": (float, 0.0, 100.0, False),
    "Y0": (float, -1e7, 1e7, False),
    "v0": (float, -50.0, 50.0, False),
    "psi0": (float, -math.pi, math.pi, False),
    "r0": (float, -10.0, 10.0, False),
    "substeps": (int, 1, 100, False),
    "Nw": (int, 1, 4, False),
    "rolling": (float, 0.0, 1e5, False),
    "m": (float, 0.0, 1e5, True),
    "Iz": (float, 0.0, 1e6, True),
    "a": (float, 0.0, 10.0, True),
    "b": (float, 0.0, 10.0, True),
    "lf": (float, 0.0, 10.0, True),
    "lr": (float, 0.0, 10.0, True),
    "DFzf": (float, 0.0, 1e6, True),
    "DFzr": (float, 0.0, 1e6, True),
    "F_max": (float, 0.0, 1e6, True),
    "By": (float, 0.0, 100.0, True),
    "Cy": (float, 0.0, 10.0, True),
    "Ey": (float, -10.0, 1.0, False),
    "Shy": (float, -90.0, 90.0, False),
    "Svy": (float, -1e5, 1e5, False),
    "Cf": (float, -1e6, 0.0, False),
    "Cr": (float, -1e6, 0.0, False),
    "slip_speed_floor": (float, 0.0, 50.0, False),
    "abs": (bool, None, None, False),
}


def start_value(var: Var, text: str) -> float:
    """``--set name=text`` of parameter ``var`` as its start value, or ConfigError naming the
    value and what :data:`LIMITS` allows (checked as ``ego run --set`` checks its values)."""
    kind, lo, hi, above = LIMITS[var.name]
    info = ParamInfo(var.name, kind, var.start, var.unit, var.description, lo, hi, None, above)
    value = parse_value(info, text)
    check_value(info, value)
    return float(value)


def _state_vars(x0) -> tuple[Var, ...]:
    outs = tuple(Var(n, "output", float(x), u, d) for (n, u, d), x in zip(STATE, x0))
    starts = tuple(Var(f"{n}0", "parameter", float(x), u, f"initial {d}", "fixed") for (n, u, d), x in zip(STATE, x0))
    return (
        *outs,
        Var("lateral_accel", "output", 0.0, "m/s2", "dv/dt + u r at the start of the last step"),
        *starts,
        Var("substeps", "parameter", 1.0, "", "RK4 steps per communication step (whole number)", "fixed"),
    )


def nonlinear_bicycle_spec(model=None) -> ModelSpec:
    """Report 000's bicycle (``model``: a :class:`ego.models.NonlinearBicycle`, default ego's)."""
    from ego.models.nonlinear_bicycle import NonlinearBicycle

    model = model if model is not None else NonlinearBicycle()
    names = (
        ("Nw", "", "driven wheels sharing Fx"),
        ("rolling", "N", "rolling resistance f m g"),
        ("m", "kg", "mass"),
        ("Iz", "kg.m2", "yaw moment of inertia"),
        ("a", "m", "CG to front axle"),
        ("b", "m", "CG to rear axle"),
        ("DFzf", "N", "front peak lateral force Dy Fzf"),
        ("DFzr", "N", "rear peak lateral force Dy Fzr"),
        ("F_max", "N", "rear friction circle mu m g"),
        ("By", "", "magic formula stiffness factor (per degree of slip)"),
        ("Cy", "", "shape factor"),
        ("Ey", "", "curvature factor"),
        ("Shy", "", "horizontal shift (deg)"),
        ("Svy", "N", "vertical shift"),
    )
    params = tuple(Var(n, "parameter", float(v), u, d, "fixed") for (n, u, d), v in zip(names, model._c))
    params += (
        Var(
            "slip_speed_floor", "parameter", float(model._floor), "m/s", "slip angles use at least this speed", "fixed"
        ),
        Var("abs", "parameter", float(model._abs), "", "1: friction-aware drive and brake (ABS)", "fixed"),
    )
    return ModelSpec(
        "nonlinear_bicycle",
        "ego: report 000's nonlinear bicycle (Pacejka tyres, rear friction circle)",
        (
            Var("Fx", "input", 0.0, "N", "longitudinal force per driven wheel"),
            Var("delta", "input", 0.0, "rad", "front steer angle (+ left)"),
            *_state_vars(model.x0),
            *params,
        ),
        (FRAME_DIR / "nonlinear_bicycle.c",),
        extra_headers=(EGO_DIR / "_bicycle.h",),
    )


def linear_bicycle_spec(model=None) -> ModelSpec:
    """Report 002's linear dynamic bicycle (``model``: a :class:`ego.models.DynamicBicycle`)."""
    from ego.models.dynamic_bicycle import DynamicBicycle

    model = model if model is not None else DynamicBicycle()
    p = model.params
    params = (
        Var("m", "parameter", p.m, "kg", "mass", "fixed"),
        Var("Iz", "parameter", p.Iz, "kg.m2", "yaw moment of inertia", "fixed"),
        Var("lf", "parameter", p.lf, "m", "CG to front axle", "fixed"),
        Var("lr", "parameter", p.lr, "m", "CG to rear axle", "fixed"),
        Var("Cf", "parameter", p.Cf, "N/rad", "front cornering stiffness per tyre (negative)", "fixed"),
        Var("Cr", "parameter", p.Cr, "N/rad", "rear cornering stiffness per tyre (negative)", "fixed"),
        Var("slip_speed_floor", "parameter", p.slip_speed_floor, "m/s", "slip angles use at least this speed", "fixed"),
    )
    return ModelSpec(
        "linear_bicycle",
        "ego: report 002's linear dynamic bicycle",
        (
            Var("a_x", "input", 0.0, "m/s2", "axial acceleration"),
            Var("delta", "input", 0.0, "rad", "front steer angle (+ left)"),
            *_state_vars(model.x0),
            *params,
        ),
        (FRAME_DIR / "linear_bicycle.c",),
    )


MODELS = {
    "nonlinear-bicycle": (nonlinear_bicycle_spec, "report 000's nonlinear bicycle (Fx, delta)"),
    "linear-bicycle": (linear_bicycle_spec, "report 002's linear dynamic bicycle (a_x, delta)"),
}


def export_fmu(model: str, out: str | os.PathLike, starts: dict[str, str] | None = None) -> Path:
    """Write ``model`` (a name of :data:`MODELS`) as an FMI 2.0 co-simulation FMU to ``out``;
    ``starts`` sets parameters' start values (``{"abs": "1", "slip_speed_floor": "1"}``: the
    motorway scenarios' settings)."""
    import dataclasses

    from ego.checks import check_output_file
    from ego.params import did_you_mean

    if model not in MODELS:
        raise ConfigError(f"unknown model {model!r} (known: {', '.join(MODELS)}){did_you_mean(model, MODELS)}")
    path = check_output_file(os.fspath(out), "--out", ".fmu")
    spec = MODELS[model][0]()
    params = {v.name: v for v in spec.variables if v.causality == "parameter"}
    changed = dict(params)
    for key, text in (starts or {}).items():
        if key not in params:
            raise ConfigError(
                f"unknown parameter {key!r} of {model}{did_you_mean(key, params)} (known: {', '.join(params)})"
            )
        changed[key] = dataclasses.replace(params[key], start=start_value(params[key], text))
    spec = dataclasses.replace(
        spec, variables=tuple(changed.get(v.name, v) if v.causality == "parameter" else v for v in spec.variables)
    )
    return build_fmu(spec, path)
