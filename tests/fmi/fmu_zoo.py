"""The test FMUs: C sources in tests/fmi/c/, built with ego.fmi.build (the system C compiler
against fmpy's FMI headers) and cached by the hash of their inputs under
$EGO_TEST_FMU_CACHE (default ~/.cache/ego/test-fmus)."""

from __future__ import annotations

import math
import os
import tempfile
from pathlib import Path

from ego.fmi.build import ModelSpec, Var, build_fmu

C = Path(__file__).parent / "c"
CACHE = Path(os.environ.get("EGO_TEST_FMU_CACHE", Path.home() / ".cache" / "ego" / "test-fmus"))

TRACKING_IN = [
    Var("s_ref", "input", 0.0, "m"),
    Var("ds_ref", "input", 0.0, "m/s"),
    Var("s", "input", 0.0, "m"),
    Var("ds", "input", 0.0, "m/s"),
    Var("d_ref", "input", 0.0, "m"),
    Var("dd_ref", "input", 0.0, "m/s"),
    Var("d", "input", 0.0, "m"),
    Var("dd", "input", 0.0, "m/s"),
]
PID_PARAMS = [
    Var("kp_lon", "parameter", 800.0, "N/m", "longitudinal proportional gain"),
    Var("ki_lon", "parameter", 20.0),
    Var("kd_lon", "parameter", 1500.0),
    Var("kp_lat", "parameter", 0.01, "rad/m", "lateral proportional gain"),
    Var("ki_lat", "parameter", 0.0),
    Var("kd_lat", "parameter", 0.02),
    Var("tau_d", "parameter", 0.05, "s"),
    Var("fx_limit", "parameter", 4805.0, "N"),
    Var("steer_limit", "parameter", 0.5, "rad"),
]


def pid_tracking(version: str = "2.0") -> ModelSpec:
    """ego's tracking pid (PIDController, default gains) as an FMU."""
    return ModelSpec(
        "pid_tracking" if version == "2.0" else "pid_tracking3",
        "ego's tracking pid as an FMU",
        (
            *TRACKING_IN,
            *PID_PARAMS,
            Var("Fx", "output", 0.0, "N"),
            Var("delta", "output", 0.0, "rad"),
            Var("integral_lon", "output", 0.0, "m.s"),
            Var("integral_lat", "output", 0.0, "m.s"),
        ),
        (C / "pid_tracking.c",),
        fmi_version=version,
    )


def pid_curve() -> ModelSpec:
    """ego's curve pid (CurvePID, pedal off) as an FMU."""
    ins = [
        Var(n, "input", 0.0, u)
        for n, u in (
            ("d_ref", "m"),
            ("d", "m"),
            ("heading_error", "rad"),
            ("dd_ref", "m/s"),
            ("dd", "m/s"),
            ("yaw_rate", "rad/s"),
            ("ds", "m/s"),
            ("curvature", "1/m"),
            ("accel_ref", "m/s2"),
        )
    ]
    return ModelSpec(
        "pid_curve",
        "ego's curve pid as an FMU",
        (
            *ins,
            Var("kp", "parameter", 2.0),
            Var("ki", "parameter", 0.5),
            Var("kd", "parameter", 0.0),
            Var("steer_limit", "parameter", 0.6),
            Var("a_x", "output", 0.0, "m/s2"),
            Var("delta", "output", 0.0, "rad"),
            Var("pid_e", "output", 0.0, "m"),
        ),
        (C / "pid_curve.c",),
        units=(("m/s2", (("m", 1), ("s", -2)), 1.0, 0.0),),
    )


def pid_units() -> ModelSpec:
    """The tracking pid in km/h, kN and degrees (with their unit definitions)."""
    kmh = [Var(v.name, "input", 0.0, "km/h") if v.unit == "m/s" else v for v in TRACKING_IN]
    return ModelSpec(
        "pid_units",
        "the tracking pid in km/h, kN and degrees",
        (*kmh, *PID_PARAMS, Var("Fx", "output", 0.0, "kN"), Var("delta", "output", 0.0, "deg")),
        (C / "pid_units.c",),
        units=(
            ("km/h", (("m", 1), ("s", -1)), 1 / 3.6, 0.0),
            ("kN", (("kg", 1), ("m", 1), ("s", -2)), 1000.0, 0.0),
            ("deg", (("rad", 1),), math.pi / 180, 0.0),
        ),
    )


def faulty(nan: bool = False, version: str = "2.0") -> ModelSpec:
    """Fx = hold_fx until step fail_step, then an error (or a NaN delta)."""
    name = ("nan_output" if nan else "error_at_step") + ("3" if version != "2.0" else "")
    return ModelSpec(
        name,
        "goes wrong at a given step",
        (
            Var("fail_step", "parameter", 50.0, "", "the step it fails at"),
            Var("hold_fx", "parameter", 100.0, "N"),
            Var("Fx", "output", 0.0, "N"),
            Var("delta", "output", 0.0, "rad"),
        ),
        (C / "faulty.c",),
        defines=("FAULT_NAN",) if nan else (),
        fmi_version=version,
    )


def fixed_step(step: float = 0.02) -> ModelSpec:
    """The tracking pid declared as taking only ``step`` second steps."""
    spec = pid_tracking()
    return ModelSpec("pid_fixed", spec.description, spec.variables, spec.sources, step_size=step, fixed_step=True)


def build(spec: ModelSpec, folder: Path) -> Path:
    """``spec`` built (or taken from the cache) into ``folder``/<identifier>.fmu."""
    return build_fmu(spec, Path(folder) / f"{spec.identifier}.fmu", cache_dir=CACHE)


def renamed() -> ModelSpec:
    """The faulty model (never failing by default) with outputs named and scaled as another
    tool would: ``force`` in kN and ``steer`` in degrees (a mapping file connects them)."""
    return ModelSpec(
        "renamed",
        "outputs named force [kN] and steer [deg]",
        (
            Var("fail_step", "parameter", 1e9),
            Var("hold_fx", "parameter", 0.1, "kN"),
            Var("force", "output", 0.0, "kN"),
            Var("steer", "output", 0.0, "deg"),
        ),
        (C / "faulty.c",),
        defines=("VR_Fx=VR_force", "VR_delta=VR_steer"),
        units=(("kN", (("kg", 1), ("m", 1), ("s", -2)), 1000.0, 0.0), ("deg", (("rad", 1),), math.pi / 180, 0.0)),
    )


MISBEHAVE = {"hang": ("HANG",), "segv": ("SEGV",), "kill": ("KILL",), "abort": ("MODEL_ON_INSTANTIATE=abort()",)}


def misbehave(kind: str) -> ModelSpec:
    """A controller that hangs (``hang``) or segfaults (``segv``) in doStep at step
    ``fail_step``, kills itself with SIGKILL (``kill``), or aborts in fmi2Instantiate (``abort``): tests/fmi/c/misbehave.c."""
    return ModelSpec(
        f"{kind}_fmu",
        f"misbehaves: {kind}",
        (
            Var("fail_step", "parameter", 20.0, "", "the step it misbehaves at"),
            Var("hold_fx", "parameter", 100.0, "N"),
            Var("Fx", "output", 0.0, "N"),
            Var("delta", "output", 0.0, "rad"),
        ),
        (C / "misbehave.c",),
        defines=MISBEHAVE[kind],
    )


def fmu_folders(tmp: str | None = None) -> set[str]:
    """The FMU extraction folders (``ego-fmu-<pid>-*``) in the temporary folder."""
    tmp = tmp or tempfile.gettempdir()
    return {n for n in os.listdir(tmp) if n.startswith("ego-fmu-") and n.split("-")[2].isdigit()}


def fmu_folders_left(before: set[str]) -> set[str]:
    """FMU extraction folders made since ``before`` whose process has ended: what a run left
    behind. A test running beside this one (pytest -n) has folders of live processes, and the
    FMU builder's ``ego-fmu-build-*`` are no run's."""
    left = set()
    for name in fmu_folders() - before:
        try:
            os.kill(int(name.split("-")[2]), 0)
        except ProcessLookupError:
            left.add(name)
        except OSError:
            pass
    return left
