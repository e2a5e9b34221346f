"""ego export-fmu: report 000's and report 002's bicycles as FMI 2.0 co-simulation FMUs, stepped
with fmpy (its own FMU2Slave, not ego's co-simulation code) against ego's models: the same
numbers (1e-9; in fact bit for bit). The sources inside compile on their own."""

import random
import shutil
import subprocess
import sys
import zipfile

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from ego.models.dynamic_bicycle import DynamicBicycle
from ego.models.nonlinear_bicycle import NonlinearBicycle

OUTPUTS = ("X", "u", "Y", "v", "psi", "r", "lateral_accel")


def step_with_fmpy(path, inputs, commands, dt, substeps):
    md = read_model_description(path)
    folder = extract(path)
    try:
        vr = {v.name: v.valueReference for v in md.modelVariables}
        fmu = FMU2Slave(
            guid=md.guid, unzipDirectory=folder, modelIdentifier=md.coSimulation.modelIdentifier, instanceName="check"
        )
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.setReal([vr["substeps"]], [float(substeps)])
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        out = []
        for k, command in enumerate(commands):
            fmu.setReal([vr[n] for n in inputs], list(command))
            fmu.doStep(currentCommunicationPoint=k * dt, communicationStepSize=dt)
            out.append(fmu.getReal([vr[n] for n in OUTPUTS]))
        fmu.terminate()
        fmu.freeInstance()
        return out
    finally:
        shutil.rmtree(folder, ignore_errors=True)


@pytest.mark.parametrize("substeps", [1, 4])
@pytest.mark.parametrize(
    "name,model,inputs,scale",
    [
        ("nonlinear-bicycle", NonlinearBicycle, ("Fx", "delta"), 3000.0),
        ("linear-bicycle", DynamicBicycle, ("a_x", "delta"), 3.0),
    ],
)
def test_the_exported_fmu_steps_as_egos_model(tmp_path, name, model, inputs, scale, substeps):
    out = tmp_path / f"{name}.fmu"
    proc = subprocess.run(
        [sys.executable, "-m", "ego", "export-fmu", name, "--out", str(out)], capture_output=True, text=True
    )
    assert proc.returncode == 0, proc.stderr
    rng = random.Random(7)
    commands = [(rng.uniform(-scale, scale), rng.uniform(-0.12, 0.12)) for _ in range(400)]
    fmu = step_with_fmpy(str(out), inputs, commands, 0.01, substeps)
    step = model().stepper(0.01 / substeps, substeps)
    x = model.x0
    worst = 0.0
    for command, row in zip(commands, fmu):
        x, lateral = step(x, *command)
        worst = max(worst, max(abs(a - b) for a, b in zip((*x, lateral), row)))
    assert worst <= 1e-9
    assert abs(x[0]) > 10  # it did drive


def test_the_sources_inside_compile_on_their_own(tmp_path):
    out = tmp_path / "b.fmu"
    subprocess.run([sys.executable, "-m", "ego", "export-fmu", "nonlinear-bicycle", "--out", str(out)], check=True)
    with zipfile.ZipFile(out) as z:
        z.extractall(tmp_path / "x", [n for n in z.namelist() if n.startswith("sources/")])
        listed = read_model_description(str(out)).buildConfigurations[0].sourceFileSets[0].sourceFiles
    src = tmp_path / "x" / "sources"
    assert set(listed) <= {p.name for p in src.iterdir()}
    cc = shutil.which("cc") or shutil.which("gcc")
    proc = subprocess.run(
        [cc, "-shared", "-fPIC", "-I", str(src), "-o", str(tmp_path / "b.so"), *(str(src / n) for n in listed), "-lm"],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stderr


def test_bad_export_arguments_are_one_line(tmp_path):
    for args, expected in (
        (["bicycle", "--out", str(tmp_path / "b.fmu")], "unknown model 'bicycle'"),
        (["linear-bicycle", "--out", str(tmp_path / "b.zip")], "expected a file ending in .fmu"),
    ):
        proc = subprocess.run([sys.executable, "-m", "ego", "export-fmu", *args], capture_output=True, text=True)
        assert proc.returncode == 2 and proc.stderr.count("\n") == 1 and expected in proc.stderr
