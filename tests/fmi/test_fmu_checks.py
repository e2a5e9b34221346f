"""What is wrong with an FMU (or its mapping) is said in one line before anything runs, exit 2."""

import re
import subprocess
import sys
import zipfile

import pytest


def rewrite(src: str, dst, edit) -> str:
    """A copy of the zip ``src`` with each (name, bytes) passed through ``edit`` (None drops it)."""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w") as zout:
        for item in zin.infolist():
            out = edit(item.filename, zin.read(item.filename))
            if out is not None:
                zout.writestr(out[0], out[1])
    return str(dst)


def md_edit(f):
    return lambda name, data: (name, f(data.decode()).encode()) if name == "modelDescription.xml" else (name, data)


def ego_error(*args) -> str:
    proc = subprocess.run(
        [sys.executable, "-m", "ego", "run", "emergency-brake", *args], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("ego: error: "), proc.stderr
    assert proc.stdout == ""
    return lines[0]


def test_not_a_zip(tmp_path):
    bad = tmp_path / "c.fmu"
    bad.write_text("not an archive")
    assert "not a zip file" in ego_error("-c", str(bad))


def test_missing_file():
    assert "bad FMU 'nowhere/c.fmu': no such file" in ego_error("-c", "nowhere/c.fmu")


def test_no_model_description(fmus, tmp_path):
    bad = rewrite(fmus["pid"], tmp_path / "c.fmu", lambda n, d: None if n == "modelDescription.xml" else (n, d))
    assert "no modelDescription.xml in the archive" in ego_error("-c", bad)


def test_invalid_model_description(fmus, tmp_path):
    bad = rewrite(fmus["pid"], tmp_path / "c.fmu", md_edit(lambda t: t.replace("<ModelVariables>", "<ModelVariables")))
    assert "invalid modelDescription.xml" in ego_error("-c", bad)


def test_fmi_1(fmus, tmp_path):
    bad = rewrite(fmus["pid"], tmp_path / "c.fmu", md_edit(lambda t: t.replace('fmiVersion="2.0"', 'fmiVersion="1.0"')))
    assert "FMI 1.0 is not supported (FMI 2.0 or 3.0 co-simulation)" in ego_error("-c", bad)


def test_model_exchange_only(fmus, tmp_path):
    def me(text):
        return re.sub(
            r"<CoSimulation.*?</CoSimulation>", '<ModelExchange modelIdentifier="pid_tracking"/>', text, flags=re.S
        )

    bad = rewrite(fmus["pid"], tmp_path / "c.fmu", md_edit(me))
    assert "model exchange interface only; ego steps co-simulation FMUs" in ego_error("-c", bad)


def test_windows_only(fmus, tmp_path):
    def win(name, data):
        if name.startswith("binaries/"):
            return "binaries/win64/pid_tracking.dll", data
        return None if name.startswith("sources/") else (name, data)

    bad = rewrite(fmus["pid"], tmp_path / "c.fmu", win)
    assert "no binary for this platform (linux64); it has binaries for win64" in ego_error("-c", bad)


def test_missing_output_names_the_outputs(fmus):
    msg = ego_error("-c", fmus["renamed"])
    assert "no output for the action 'Fx' (N); its outputs: force, steer; name it in a mapping file" in msg


@pytest.mark.parametrize(
    "mapping,expected",
    [
        ('[outputs]\nhold_fx = "Fx"\n', "FMU variable 'hold_fx' is a parameter, not an output"),
        ('[outputs]\nforce = "Fz"\n', "unknown action 'Fz' for 'force' (known: Fx, delta)"),
        ('[outputs]\nforcee = "Fx"\n', "the FMU has no variable 'forcee'; did you mean 'force'?"),
        ('[outputs]\nforce = "delta"\nsteer = "Fx"\n', "unit 'deg' cannot be converted to 'N' (different dimensions)"),
        ("[links]\n", "unknown table 'links' (expected [inputs] and [outputs])"),
    ],
)
def test_bad_mappings(fmus, tmp_path, mapping, expected):
    path = tmp_path / "map.toml"
    path.write_text(mapping)
    assert expected in ego_error("-c", fmus["renamed"], "--set", f"fmu_map={path}")


def test_unknown_input_signal(fmus, tmp_path):
    path = tmp_path / "map.toml"
    path.write_text('[inputs]\ns = "position"\n')
    assert "unknown observation signal 'position' for 's'" in ego_error("-c", fmus["pid"], "--set", f"fmu_map={path}")


def test_a_step_the_fmu_cannot_take(fmus):
    msg = ego_error("-c", fmus["fixed"])
    assert "cannot take a communication step of dt = 0.01 s (it takes only 0.02 s steps" in msg
    assert msg.rstrip().endswith("set --set dt=0.02)")


def test_the_suggested_steps_are_ones_ego_takes():
    """The suggestion for a fixed-step FMU is a dt and, where 0.1 s is no whole number of
    its steps, a SUMO step that is (the configuration accepts both)."""
    from ego.fmi.model import _workable_step
    from ego.params import apply_overrides
    from ego.scenarios.emergency_brake import EmergencyBrakeConfig

    for step, expected in ((0.02, "--set dt=0.02"), (0.003, "--set dt=0.003 --set sumo_step=0.102")):
        suggestion = _workable_step(step)
        assert suggestion == expected
        values = dict(part.split("=") for part in suggestion.replace("--set ", "").split())
        apply_overrides(EmergencyBrakeConfig(), {k: float(v) for k, v in values.items()})


def test_unknown_and_bad_parameters(fmus):
    assert "unknown parameter 'fmu.kp_la'; did you mean 'fmu.kp_lat'?" in ego_error(
        "-c", fmus["pid"], "--set", "fmu.kp_la=1"
    )
    assert "bad value for fmu.kp_lat: 'x' (expected a number" in ego_error("-c", fmus["pid"], "--set", "fmu.kp_lat=x")


def test_wrong_task(fmus):
    proc = subprocess.run(
        [sys.executable, "-m", "ego", "run", "curve", "-c", fmus["pid"]], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 2
    assert "input 's_ref' is connected to no observation signal" not in proc.stderr  # s_ref is a curve signal too
    assert "no output for the action 'a_x'" in proc.stderr
