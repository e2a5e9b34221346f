"""A catalogue of bad and hostile inputs, as a new user would type them.

Every case over the command line (``ego run/compare/sweep/train/tune/list``) must end with
exit status 2, nothing on stdout, exactly one line on stderr starting ``ego: error:`` that
names the bad value (and, where one is close, the name meant), no traceback, no file written
and no SUMO simulation started. The CLI cases call ``ego.cli.main`` in this process (cheap);
a handful run ``python -m ego`` as a subprocess to prove the same end to end. The Python API
cases (RunSpec, resolve, parameter dataclasses, sweep specs, file loaders) must raise
:class:`ego.params.ConfigError` itself - never a TypeError, ValueError or KeyError - with a
one-line message naming the value.

Corrupt input files (NARMA-L2 models, gains presets, sweep specs, SUMO networks) are made
fresh in each test's folder by the ``files`` fixture; ``{name}`` in a case stands for the
path of file ``name``.
"""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ego.cli import main
from ego.control.narma import DEFAULT_MODEL
from ego.params import ConfigError
from ego.sumo.bridge import SumoBridge
from ego.sumo.net import nets_dir

EB = ["run", "emergency-brake", "-c", "pid"]
CURVE_NARMA = ["run", "curve", "-c", "narma-l2"]
LANE = ["run", "lane-centering", "-c", "cascade-pid"]
PLATOON = ["run", "platoon", "-c", "bp-pid-acc"]
CMP = ["compare", "emergency-brake", "--out", "{out}"]
TRAIN = ["train", "narma-l2", "--samples", "400", "--epochs", "1"]
TUNE = ["tune", "lane-centering", "--quick"]
XOSC = str(Path(__file__).resolve().parents[1] / "scenarios" / "openscenario" / "cut_in.xosc")
FMU = ["export-fmu", "nonlinear-bicycle", "--out", "{out}/e2.fmu", "--set"]
LINEAR_FMU = ["export-fmu", "linear-bicycle", "--out", "{out}/e2.fmu", "--set"]
SWEEP_OK = 'scenario = "emergency-brake"\ncontrollers = ["pid"]\n[grid]\nego_speed = [20, 25]\n'


def _sweep(name: str, *extra: str) -> list[str]:
    return ["sweep", "{" + name + "}", "--out", "{out}", *extra]


def _model(
    arrays: dict | None = None, meta: dict | str | None = None, drop: str | None = None, change: dict | None = None
):
    """A NARMA-L2 model: the shipped arrays and metadata with some changed."""

    def write(path: Path) -> None:
        with np.load(DEFAULT_MODEL) as data:
            a = {k: data[k] for k in data.files}
        a.update(change or {})
        if drop:
            del a[drop]
        np.savez(path, **(arrays if arrays is not None else a))
        m = json.loads(DEFAULT_MODEL.with_suffix(".json").read_text())
        text = meta if isinstance(meta, str) else json.dumps(m if meta is None else {**m, **meta})
        path.with_suffix(".json").write_text(text)

    return write


def _truncated_model(path: Path) -> None:
    _model()(path)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def _object_array(path: Path) -> None:
    _model()(path)
    with np.load(path) as data:
        a = {k: data[k] for k in data.files}
    a["mean"] = np.array([{"x": 1}] * 12, dtype=object)
    np.savez(path, **a)


def _gains(payload) -> callable:
    def write(path: Path) -> None:
        if isinstance(payload, bytes):
            path.write_bytes(payload)
        elif isinstance(payload, str):
            path.write_text(payload)
        else:
            path.write_text(json.dumps(payload))

    return write


GOOD_GAINS = {f"{k}_{loop}": 0.5 for loop in ("e", "psi", "vy", "r") for k in ("kp", "ki", "kd")}

#: file name -> how to write it (into the test's input folder)
FILES = {
    "model_text.npz": lambda p: (p.write_text("these are not weights\n"), p.with_suffix(".json").write_text("{}")),
    "model_empty.npz": lambda p: (p.write_bytes(b""), p.with_suffix(".json").write_text("{}")),
    "model_truncated.npz": _truncated_model,
    "model_keys.npz": _model(arrays={"weights": np.zeros(3)}),
    "model_missing_g.npz": _model(drop="g_w2"),
    "model_shape.npz": _model(change={"f_w1": np.zeros((32, 7))}),
    "model_mean_shape.npz": _model(change={"mean": np.zeros(5)}),
    "model_nan.npz": _model(change={"f_w2": np.full((32, 32), np.nan)}),
    "model_inf.npz": _model(change={"dy_scale": np.array(np.inf)}),
    "model_std0.npz": _model(change={"std": np.zeros(12)}),
    "model_strings.npz": _model(change={"g_b1": np.array(["a"] * 32)}),
    "model_object.npz": _object_array,
    "model_meta_garbled.npz": _model(meta="{not json"),
    "model_meta_list.npz": _model(meta="[1, 2, 3]"),
    "model_meta_period.npz": _model(meta={"sample_period": "fast"}),
    "model_meta_period0.npz": _model(meta={"sample_period": 0}),
    "model_meta_features.npz": _model(meta={"features": ["speed"]}),
    "model_meta_nan.npz": _model(meta='{"sample_period": NaN}'),
    "model_no_meta.npz": lambda p: (_model()(p), p.with_suffix(".json").unlink()),
    "model_dir.npz": lambda p: p.mkdir(),
    "model.txt": lambda p: p.write_text("x"),
    "gains_garbage.json": _gains("gains? what gains"),
    "gains_list.json": _gains([0.2, 0.3, 0.1] * 4),
    "gains_strings.json": _gains({"gains": {k: "high" for k in GOOD_GAINS}}),
    "gains_nan.json": _gains('{"gains": {' + ", ".join(f'"{k}": NaN' for k in GOOD_GAINS) + "}}"),
    "gains_inf.json": _gains('{"gains": {' + ", ".join(f'"{k}": Infinity' for k in GOOD_GAINS) + "}}"),
    "gains_binary.json": _gains(bytes(range(256)) * 4),
    "gains_missing.json": _gains({"gains": {k: v for k, v in GOOD_GAINS.items() if k != "kd_r"}}),
    "gains_negative.json": _gains({"gains": {**GOOD_GAINS, "kp_e": -1.0}}),
    "gains_huge.json": _gains({"gains": {**GOOD_GAINS, "ki_psi": 1e308}}),
    "gains_bool.json": _gains({"gains": {**GOOD_GAINS, "kp_vy": True}}),
    "gains_extra.json": _gains({"gains": {**GOOD_GAINS, "kp_rr": 1.0}}),
    "gains_not_object.json": _gains({"gains": [1, 2, 3]}),
    "gains_empty.json": _gains(""),
    "gains_dir.json": lambda p: p.mkdir(),
    "gains.txt": _gains({"gains": GOOD_GAINS}),
    "spec_binary.toml": lambda p: p.write_bytes(bytes(range(256))),
    "spec_dir.toml": lambda p: p.mkdir(),
    "spec_garbled.toml": lambda p: p.write_text("scenario = [unclosed\n"),
    "spec_top.toml": lambda p: p.write_text(SWEEP_OK + "[gird]\nlead_gap = [20]\n"),
    "spec_scenario.toml": lambda p: p.write_text(SWEEP_OK.replace('"emergency-brake"', '"emergency-brak"')),
    "spec_controllers.toml": lambda p: p.write_text(SWEEP_OK.replace('["pid"]', '"pid"')),
    "spec_controller.toml": lambda p: p.write_text(SWEEP_OK.replace('["pid"]', '["pdi"]')),
    "spec_axis.toml": lambda p: p.write_text(SWEEP_OK.replace("ego_speed", "ego_sped")),
    "spec_range.toml": lambda p: p.write_text(SWEEP_OK.replace("[20, 25]", "[20, 250]")),
    "spec_type.toml": lambda p: p.write_text(SWEEP_OK.replace("[20, 25]", '[20, "fast"]')),
    "spec_int.toml": lambda p: p.write_text(SWEEP_OK.replace("ego_speed = [20, 25]", "substeps = [1, 2.0]")),
    "spec_bool.toml": lambda p: p.write_text(SWEEP_OK.replace("[20, 25]", "[true]")),
    "spec_empty_grid.toml": lambda p: p.write_text(SWEEP_OK.replace("[20, 25]", "[]")),
    "spec_method.toml": lambda p: p.write_text(SWEEP_OK + '[sample]\nmethod = "sobl"\nn = 4\nlead_gap = [20, 40]\n'),
    "spec_n.toml": lambda p: p.write_text(SWEEP_OK + "[sample]\nn = 0\nlead_gap = [20, 40]\n"),
    "spec_reversed.toml": lambda p: p.write_text(SWEEP_OK + "[sample]\nn = 4\nlead_gap = [40, 20]\n"),
    "spec_sample_range.toml": lambda p: p.write_text(SWEEP_OK + "[sample]\nn = 4\nlead_gap = [20, 4000]\n"),
    "spec_sample_text.toml": lambda p: p.write_text(SWEEP_OK + "[sample]\nn = 4\nabs = [0, 1]\n"),
    "spec_seeds.toml": lambda p: p.write_text("seeds = [-1]\n" + SWEEP_OK),
    "spec_seeds0.toml": lambda p: p.write_text("seeds = 0\n" + SWEEP_OK),
    "spec_huge.toml": lambda p: p.write_text(
        SWEEP_OK + '[sample]\nmethod = "random"\nn = 100000000\nlead_gap = [20, 40]\n'
    ),
    "spec_mix.toml": lambda p: p.write_text(SWEEP_OK.replace("ego_speed = [20, 25]", "dt = [0.03]")),
    "spec_ok.toml": lambda p: p.write_text(SWEEP_OK),
    "file.txt": lambda p: p.write_text("x"),
    "folder.fmu": lambda p: p.mkdir(),
    "syntax_error.py": lambda p: p.write_text("def x(:\n"),
    "folder.rrd": lambda p: p.mkdir(),
}


def _nets(kind: str):
    """A copy of the shipped networks folder with the highway network spoilt."""

    def write(path: Path) -> None:
        shutil.copytree(nets_dir(), path, ignore=shutil.ignore_patterns("*.py", "__pycache__"))
        net = path / "highway" / "highway.net.xml"
        text = net.read_text()
        if kind == "truncated":
            net.write_text(text[: len(text) // 2])
        elif kind == "garbled":
            net.write_bytes(bytes(range(256)) * 8)
        elif kind == "not-a-net":
            net.write_text('<?xml version="1.0"?>\n<routes><vehicle id="a"/></routes>\n')
        elif kind == "empty":
            net.write_text("")

    return write


FILES.update({f"nets_{k}": _nets(k) for k in ("truncated", "garbled", "not-a-net", "empty")})


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """Every input file of the catalogue, made once (the cases only read them)."""
    folder = tmp_path_factory.mktemp("inputs")
    paths = {}
    for name, write in FILES.items():
        path = folder / name
        write(path)
        paths[name] = str(path)
    return paths


@pytest.fixture
def files(inputs, tmp_path):
    """The input files, and ``out``: where outputs would go, in this test's (empty) folder."""
    return {**inputs, "out": str(tmp_path / "out")}


def _fill(args, paths: dict) -> list[str]:
    out = []
    for a in args:
        for key, value in paths.items():
            a = a.replace("{" + key + "}", value)
        out.append(a)
    return out


def _tree(root: Path) -> list[str]:
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


def C(id: str, args: list[str], message: str, env: dict | None = None):  # noqa: N802 - a table row
    return pytest.param(args, message, env or {}, id=id)


CLI = [
    # -- names, and what was meant -------------------------------------------------------------------------
    C("run-unknown-scenario", ["run", "nowhere", "-c", "pid"], "unknown scenario 'nowhere' (known: emergency-brake"),
    C("run-misspelt-scenario", ["run", "emergency-brak", "-c", "pid"], "did you mean 'emergency-brake'?"),
    C("run-empty-scenario", ["run", "", "-c", "pid"], "unknown scenario ''"),
    C("run-unknown-controller", ["run", "emergency-brake", "-c", "magic"], "unknown controller 'magic'"),
    C("run-misspelt-controller", ["run", "emergency-brake", "-c", "fuzy"], "did you mean 'fuzzy'?"),
    C("run-controller-case", ["run", "emergency-brake", "-c", "PID"], "did you mean 'pid'?"),
    C("run-controller-of-another-task", ["run", "curve", "-c", "fuzzy"], "'fuzzy' is a tracking controller"),
    C("run-misspelt-curve-controller", ["run", "curve", "-c", "narma"], "did you mean 'narma-l2'?"),
    C("run-no-controller", ["run", "emergency-brake"], "--controller"),
    C("run-unknown-parameter", [*EB, "--set", "warp=9"], "unknown parameter 'warp'"),
    C(
        "run-misspelt-parameter",
        [*EB, "--set", "ego_sped=20"],
        "unknown parameter 'ego_sped'; did you mean 'ego_speed'?",
    ),
    C("run-misspelt-controller-parameter", [*EB, "--set", "kp_latt=1"], "did you mean 'kp_lat'?"),
    C("run-parameter-of-another-controller", [*EB, "--set", "fx_gain=100"], "unknown parameter 'fx_gain'"),
    C("run-set-without-equals", [*EB, "--set", "ego_speed"], "bad --set item 'ego_speed' (expected key=value)"),
    C("run-set-without-key", [*EB, "--set", "=5"], "bad --set item '=5'"),
    C(
        "run-require-twice",
        [*EB, "--require", "a: always (gap_front >= 2 m)", "--require", "a : always (gap_front >= 3 m)"],
        "--require a is given twice ('always (gap_front >= 2 m)' and 'always (gap_front >= 3 m)')",
    ),
    C(
        "compare-require-twice",
        [
            *CMP,
            "--controllers",
            "pid",
            "--require",
            "a: always (gap_front >= 2 m)",
            "--require",
            "a: eventually (t >= 1 s)",
        ],
        "--require a is given twice",
    ),
    C("run-set-twice", [*EB, "--set", "dt=0.01", "--set", "dt=0.02"], "--set dt is given twice"),
    C("misspelt-command", ["runn"], "invalid choice: 'runn'"),
    C("misspelt-command-suggests", ["comprae"], "did you mean 'compare'?"),
    C("list-unknown-option", ["list", "--jsn"], "unrecognized arguments: --jsn"),
    C("list-unknown-controller", ["list", "nosuch"], "unknown controller 'nosuch' (known: fuzzy, pid"),
    C("list-misspelt-controller", ["list", "narma"], "unknown controller 'narma'; did you mean 'narma-l2'?"),
    C("list-missing-file", ["list", "nosuch.py:X"], "no file 'nosuch.py'"),
    C("list-missing-module", ["list", "nosuchmod:X"], "cannot import 'nosuchmod'"),
    C("list-missing-class", ["list", "ego.control.pid:Nothing"], "'ego.control.pid' has no 'Nothing'"),
    C("list-syntax-error", ["list", "{syntax_error.py}:X"], "SyntaxError"),
    C("list-fmu-folder", ["list", "{folder.fmu}"], "it is a folder (expected a file ending in .fmu"),
    C(
        "list-xosc-unknown-ego",
        ["list", XOSC, "--ego", "Nobody"],
        "bad value for --ego: 'Nobody' (entities: Ego, CutIn)",
    ),
    C("run-json-with-value", [*EB, "--json=1"], "--json"),
    # -- scenario values: type, then range ----------------------------------------------------------------
    C(
        "text-for-number",
        [*EB, "--set", "lead_decel=fast"],
        "bad value for lead_decel: 'fast' (expected a number from 0.5 to 12 (m/s^2))",
    ),
    C("negative-time", [*EB, "--set", "ttc_threshold=-1"], "bad value for ttc_threshold: -1"),
    C("nan", [*EB, "--set", "ego_speed=nan"], "bad value for ego_speed: nan"),
    C("inf", [*EB, "--set", "ego_speed=inf"], "bad value for ego_speed: inf"),
    C("minus-inf", [*EB, "--set", "ego_speed=-inf"], "bad value for ego_speed: -inf"),
    C("value-1e308", [*EB, "--set", "ego_speed=1e308"], "bad value for ego_speed: 1e+308"),
    C("overflowing-text", [*EB, "--set", "ego_speed=1e999"], "bad value for ego_speed: inf"),
    C("empty-value", [*EB, "--set", "ego_speed="], "bad value for ego_speed: ''"),
    C("hex", [*EB, "--set", "ego_speed=0x10"], "bad value for ego_speed: '0x10'"),
    C("underscored-digits", [*EB, "--set", "ego_speed=1_0"], "bad value for ego_speed: '1_0'"),
    C("other-script-digits", [*EB, "--set", "ego_speed=\u0662\u0660"], "bad value for ego_speed: '\u0662\u0660'"),
    C("int-other-script-digits", [*EB, "--set", "substeps=\u0662"], "bad value for substeps: '\u0662'"),
    C("comma-decimal", [*EB, "--set", "ego_speed=20,5"], "bad value for ego_speed: '20,5'"),
    C("unit-in-value", [*EB, "--set", "ego_speed=20m/s"], "bad value for ego_speed: '20m/s'"),
    C("long-text-is-cut", [*EB, "--set", "ego_speed=" + "9" * 500 + "x"], "..."),
    C("newline-in-value", [*EB, "--set", "ego_speed=2\n0"], "bad value for ego_speed: '2\\n0'"),
    C(
        "int-as-float",
        [*EB, "--set", "substeps=2.0"],
        "bad value for substeps: '2.0' (expected a whole number from 1 to 100: write 2)",
    ),
    C("int-as-exponent", [*EB, "--set", "substeps=1e2"], "write 100"),
    C("int-fraction", [*EB, "--set", "substeps=2.5"], "bad value for substeps: '2.5'"),
    C("int-zero", [*EB, "--set", "substeps=0"], "bad value for substeps: 0 (expected a whole number from 1 to 100)"),
    C("int-too-big", [*EB, "--set", "substeps=101"], "bad value for substeps: 101"),
    C("int-as-bool", [*EB, "--set", "substeps=true"], "bad value for substeps: 'true'"),
    C("int-huge", [*EB, "--set", "substeps=" + "9" * 40], "bad value for substeps: 9999"),
    C("int-beyond-a-float", [*PLATOON, "--set", "followers=" + "9" * 400], "bad value for followers: 9999"),
    C("choice-out", [*EB, "--set", "ego_lane=3"], "bad value for ego_lane: 3 (expected one of 0, 1, 2)"),
    C("choice-float", [*EB, "--set", "ego_lane=1.0"], "bad value for ego_lane: '1.0'"),
    C("bool-maybe", [*EB, "--set", "abs=maybe"], "bad value for abs: 'maybe' (expected true or false)"),
    C("bool-two", [*EB, "--set", "abs=2"], "bad value for abs: '2'"),
    C("bool-misspelt", [*EB, "--set", "block_left=ture"], "bad value for block_left: 'ture'"),
    C("dt-not-dividing", [*EB, "--set", "dt=0.03"], "bad value for sumo_step"),
    C("dt-zero", [*EB, "--set", "dt=0"], "bad value for dt: 0"),
    C("duration-1e308", [*EB, "--set", "duration=1e308"], "bad value for duration: 1e+308"),
    C("duration-zero", [*EB, "--set", "duration=0"], "bad value for duration: 0"),
    C(
        "brake-after-the-run",
        [*EB, "--set", "lead_brake_time=30"],
        "bad value for lead_brake_time: 30 (expected at most duration=25 s",
    ),
    C("brake-time-1e308", [*EB, "--set", "lead_brake_time=1e308"], "bad value for lead_brake_time: 1e+308"),
    C("lead-speed-between", [*EB, "--set", "lead_speed=-0.5"], "bad value for lead_speed: -0.5"),
    C(
        "traffic-too-dense",
        [*EB, "--set", "traffic_density=25", "--set", "traffic_speed=40"],
        "bad value for traffic_density: 25",
    ),
    C("sublane-zero", [*EB, "--set", "lateral_resolution=0"], "bad value for lateral_resolution: 0"),
    C("sumo-step-huge", [*EB, "--set", "sumo_step=1e9"], "bad value for sumo_step: 1000000000"),
    C("ego-start-negative", [*EB, "--set", "ego_start=-10"], "bad value for ego_start: -10"),
    C("cut-in-side-case", ["run", "cut-in", "-c", "pid", "--set", "cut_in_side=LEFT"], "did you mean 'left'?"),
    C(
        "cut-in-speed-type",
        ["run", "cut-in", "-c", "pid", "--set", "cut_in_speed=slow"],
        "bad value for cut_in_speed: 'slow'",
    ),
    C("curve-preview", ["run", "curve", "-c", "pid", "--set", "preview=30"], "bad value for preview: 30"),
    C("curve-entry-speed", ["run", "curve", "-c", "pid", "--set", "entry_speed=100"], "bad value for entry_speed: 100"),
    C("curve-accel-inf", ["run", "curve", "-c", "pid", "--set", "accel=inf"], "bad value for accel: inf"),
    C("lane-plant-misspelt", [*LANE, "--set", "plant=dynamic-bicycel"], "did you mean 'dynamic-bicycle'?"),
    C("lane-offset", [*LANE, "--set", "offset=2"], "bad value for offset: 2"),
    C("lane-speed-zero", [*LANE, "--set", "speed=0"], "bad value for speed: 0"),
    C("platoon-followers-zero", [*PLATOON, "--set", "followers=0"], "bad value for followers: 0"),
    C("platoon-followers-float", [*PLATOON, "--set", "followers=2.0"], "write 2"),
    C("platoon-followers-many", [*PLATOON, "--set", "followers=11"], "bad value for followers: 11"),
    C("platoon-variant", [*PLATOON, "--set", "variant=toy"], "bad value for variant: 'toy'"),
    C("platoon-variant-misspelt", [*PLATOON, "--set", "variant=scale-modle"], "did you mean 'scale-model'?"),
    C("platoon-manoeuvres", [*PLATOON, "--set", "manoeuvres=brake hard"], "bad value for manoeuvres: 'brake hard'"),
    C("platoon-manoeuvres-nan", [*PLATOON, "--set", "manoeuvres=nan:20:2"], "bad value for manoeuvres"),
    C("platoon-headway", [*PLATOON, "--set", "headway=-1"], "bad value for headway: -1"),
    C(
        "platoon-manoeuvre-never",
        [*PLATOON, "--set", "manoeuvres=1e308:20:2"],
        "bad value for manoeuvres: '1e308:20:2'",
    ),
    C("platoon-manoeuvres-long-text-is-cut", [*PLATOON, "--set", "manoeuvres=" + "10:20:2," * 500], "10:20:2,..."),
    C(
        "platoon-road-too-short",
        [*PLATOON, "--set", "manoeuvres=none", "--set", "start_speed=100", "--set", "duration=200"],
        "need 5779 m of road; the platoon network has 3000 m",
    ),
    C(
        "cut-in-no-lane-on-that-side",
        ["run", "cut-in", "-c", "pid", "--set", "ego_lane=2"],
        "no left lane next to ego_lane=2",
    ),
    C(
        "cut-in-right-of-the-right-lane",
        ["run", "cut-in", "-c", "pid", "--set", "ego_lane=0", "--set", "cut_in_side=right"],
        "no right lane next to ego_lane=0",
    ),
    C("platoon-start-error", [*PLATOON, "--set", "start_error=-40"], "bad value for start_error"),
    C(
        "report-case",
        ["run", "report-000", "-c", "pid", "--set", "case=ramp"],
        "bad value for case: 'ramp' (expected one of step, sine)",
    ),
    C("report-step", ["run", "report-000", "-c", "pid", "--set", "step=1e308"], "bad value for step: 1e+308"),
    # -- controller values ---------------------------------------------------------------------------------
    C("pid-gain-text", [*EB, "--set", "kp_lat=x"], "bad value for kp_lat: 'x'"),
    C("pid-gain-huge", [*EB, "--set", "kp_lon=1e308"], "bad value for kp_lon: 1e+308"),
    C(
        "pid-steer-limit-above-quarter-turn",
        [*EB, "--set", "steer_limit=2"],
        "bad value for steer_limit: 2 (expected a number above 0 and up to 1.5708 (rad))",
    ),
    C("pid-steer-limit-zero", [*EB, "--set", "steer_limit=0"], "bad value for steer_limit: 0"),
    C("pid-fx-limit-huge", [*EB, "--set", "fx_limit=1e9"], "bad value for fx_limit: 1000000000"),
    C("pid-tau-negative", [*EB, "--set", "tau_d=-1"], "bad value for tau_d: -1"),
    C(
        "fuzzy-gain-huge",
        ["run", "emergency-brake", "-c", "fuzzy", "--set", "fx_gain=1e6"],
        "bad value for fx_gain: 1000000 (expected a number from 0 to 20000 (N))",
    ),
    C(
        "fuzzy-input-gain-negative",
        ["run", "emergency-brake", "-c", "fuzzy", "--set", "ke_lon=-1"],
        "bad value for ke_lon: -1",
    ),
    C("fuzzy-pid-adapt", ["run", "emergency-brake", "-c", "fuzzy-pid", "--set", "adapt=2"], "bad value for adapt: 2"),
    C(
        "fuzzy-pid-variant",
        ["run", "emergency-brake", "-c", "fuzzy-pid", "--set", "variant=repor"],
        "did you mean 'report'?",
    ),
    C(
        "bp-pid-learning-rate",
        ["run", "emergency-brake", "-c", "bp-pid", "--set", "learning_rate=2"],
        "bad value for learning_rate: 2 (expected a number from 0 to 1)",
    ),
    C(
        "bp-pid-learning-rate-1e308",
        ["run", "emergency-brake", "-c", "bp-pid", "--set", "learning_rate=1e308"],
        "bad value for learning_rate: 1e+308",
    ),
    C(
        "bp-pid-momentum",
        ["run", "emergency-brake", "-c", "bp-pid", "--set", "momentum=1"],
        "bad value for momentum: 1",
    ),
    C(
        "bp-pid-init-scale",
        ["run", "emergency-brake", "-c", "bp-pid", "--set", "init_scale=1e308"],
        "bad value for init_scale: 1e+308",
    ),
    C(
        "bp-pid-variant-case",
        ["run", "emergency-brake", "-c", "bp-pid", "--set", "variant=STABLE"],
        "did you mean 'stable'?",
    ),
    C(
        "rbf-width-1e-300",
        ["run", "emergency-brake", "-c", "rbf-smc", "--set", "width=1e-300"],
        "bad value for width: 1e-300 (expected a number from 0.01 to 1000)",
    ),
    C("rbf-width-zero", ["run", "emergency-brake", "-c", "rbf-smc", "--set", "width=0"], "bad value for width: 0"),
    C("rbf-w0-1e308", ["run", "emergency-brake", "-c", "rbf-smc", "--set", "w0=1e308"], "bad value for w0: 1e+308"),
    C(
        "rbf-gamma-negative",
        ["run", "emergency-brake", "-c", "rbf-smc", "--set", "gamma=-1"],
        "bad value for gamma: -1",
    ),
    C("rbf-scale-nan", ["run", "emergency-brake", "-c", "rbf-smc", "--set", "scale=nan"], "bad value for scale: nan"),
    C("curve-pid-steer-limit", ["run", "curve", "-c", "pid", "--set", "steer_limit=3"], "bad value for steer_limit: 3"),
    C("fuzzy-curve-weight", ["run", "curve", "-c", "fuzzy-curve", "--set", "w=1.5"], "bad value for w: 1.5"),
    C(
        "fuzzy-curve-range-1e-300",
        ["run", "curve", "-c", "fuzzy-curve", "--set", "position_range=1e-300"],
        "bad value for position_range: 1e-300",
    ),
    C("narma-rho", [*CURVE_NARMA, "--set", "rho=1"], "bad value for rho: 1"),
    C("narma-g-min", [*CURVE_NARMA, "--set", "g_min=0"], "bad value for g_min: 0"),
    C("narma-sample-period", [*CURVE_NARMA, "--set", "dt=0.02"], "dt must divide"),
    C("cascade-steer-limit", [*LANE, "--set", "steer_limit=90"], "bad value for steer_limit: 90"),
    C("cascade-alpha", [*LANE, "--set", "alpha=0"], "bad value for alpha: 0"),
    C("cascade-preset", [*LANE, "--set", "preset=tunned"], "did you mean 'tuned'?"),
    C(
        "acc-init-range-1e308",
        [*PLATOON, "--set", "init_range=1e308"],
        "bad value for init_range: 1e+308 (expected a number above 0 and up to 10)",
    ),
    C("acc-learning-rate", [*PLATOON, "--set", "learning_rate=5"], "bad value for learning_rate: 5"),
    C("acc-period", ["run", "platoon", "-c", "pid", "--set", "period=0.015"], "bad value for period: 0.015"),
    # -- files: NARMA-L2 models ----------------------------------------------------------------------------
    C("model-missing", [*CURVE_NARMA, "--set", "model=/nowhere/m.npz"], "no trained NARMA-L2 model at /nowhere/m.npz"),
    C("model-folder", [*CURVE_NARMA, "--set", "model={model_dir.npz}"], "it is a folder"),
    C("model-suffix", [*CURVE_NARMA, "--set", "model={model.txt}"], "(expected a file ending in .npz)"),
    C("model-text", [*CURVE_NARMA, "--set", "model={model_text.npz}"], "not a readable .npz file"),
    C("model-empty", [*CURVE_NARMA, "--set", "model={model_empty.npz}"], "not a readable .npz file"),
    C("model-truncated", [*CURVE_NARMA, "--set", "model={model_truncated.npz}"], "not a readable .npz file"),
    C("model-wrong-keys", [*CURVE_NARMA, "--set", "model={model_keys.npz}"], "the array mean is missing"),
    C("model-missing-array", [*CURVE_NARMA, "--set", "model={model_missing_g.npz}"], "the array g_w2 is missing"),
    C(
        "model-wrong-shape",
        [*CURVE_NARMA, "--set", "model={model_shape.npz}"],
        "the array f_w1 has shape (32, 7) (expected (32, 12))",
    ),
    C(
        "model-wrong-mean-shape",
        [*CURVE_NARMA, "--set", "model={model_mean_shape.npz}"],
        "the array mean has shape (5,)",
    ),
    C(
        "model-nan-weights",
        [*CURVE_NARMA, "--set", "model={model_nan.npz}"],
        "the array f_w2 holds NaN or infinite values",
    ),
    C(
        "model-inf-scale",
        [*CURVE_NARMA, "--set", "model={model_inf.npz}"],
        "the array dy_scale holds NaN or infinite values",
    ),
    C("model-zero-std", [*CURVE_NARMA, "--set", "model={model_std0.npz}"], "std has values that are not positive"),
    C("model-string-array", [*CURVE_NARMA, "--set", "model={model_strings.npz}"], "the array g_b1 is not numeric"),
    C("model-pickled-objects", [*CURVE_NARMA, "--set", "model={model_object.npz}"], "not a readable .npz file"),
    C("model-meta-garbled", [*CURVE_NARMA, "--set", "model={model_meta_garbled.npz}"], "not valid JSON"),
    C("model-meta-list", [*CURVE_NARMA, "--set", "model={model_meta_list.npz}"], "its metadata is not a JSON object"),
    C("model-meta-period-text", [*CURVE_NARMA, "--set", "model={model_meta_period.npz}"], "sample_period is 'fast'"),
    C("model-meta-period-zero", [*CURVE_NARMA, "--set", "model={model_meta_period0.npz}"], "sample_period is 0"),
    C(
        "model-meta-features",
        [*CURVE_NARMA, "--set", "model={model_meta_features.npz}"],
        "trained on features ['speed']",
    ),
    C("model-meta-nan", [*CURVE_NARMA, "--set", "model={model_meta_nan.npz}"], "NaN is not a number JSON allows"),
    C(
        "model-meta-missing",
        [*CURVE_NARMA, "--set", "model={model_no_meta.npz}"],
        "its metadata model_no_meta.json is missing",
    ),
    C("model-not-text", [*CURVE_NARMA, "--set", "model=0"], "(expected a file ending in .npz)"),
    # -- files: cascade gains presets ----------------------------------------------------------------------
    C("gains-garbage", [*LANE, "--set", "gains_file={gains_garbage.json}"], "not valid JSON"),
    C("gains-list", [*LANE, "--set", "gains_file={gains_list.json}"], 'expected an object with "gains"'),
    C(
        "gains-strings",
        [*LANE, "--set", "gains_file={gains_strings.json}"],
        "kp_e = 'high' (expected a number from 0 to 100)",
    ),
    C("gains-nan", [*LANE, "--set", "gains_file={gains_nan.json}"], "NaN is not a number JSON allows"),
    C("gains-infinity", [*LANE, "--set", "gains_file={gains_inf.json}"], "Infinity is not a number JSON allows"),
    C("gains-binary", [*LANE, "--set", "gains_file={gains_binary.json}"], "not a text file"),
    C("gains-folder", [*LANE, "--set", "gains_file={gains_dir.json}"], "it is a folder"),
    C("gains-missing-gain", [*LANE, "--set", "gains_file={gains_missing.json}"], "the gain kd_r is missing"),
    C("gains-negative", [*LANE, "--set", "gains_file={gains_negative.json}"], "kp_e = -1.0"),
    C("gains-huge", [*LANE, "--set", "gains_file={gains_huge.json}"], "ki_psi = 1e+308"),
    C("gains-bool", [*LANE, "--set", "gains_file={gains_bool.json}"], "kp_vy = True"),
    C("gains-misspelt-gain", [*LANE, "--set", "gains_file={gains_extra.json}"], "unknown gain 'kp_rr'"),
    C("gains-not-object", [*LANE, "--set", "gains_file={gains_not_object.json}"], 'expected an object with "gains"'),
    C("gains-empty-file", [*LANE, "--set", "gains_file={gains_empty.json}"], "not valid JSON"),
    C("gains-missing-file", [*LANE, "--set", "gains_file=/nowhere/g.json"], "no tuned gains at /nowhere/g.json"),
    C("gains-suffix", [*LANE, "--set", "gains_file={gains.txt}"], "(expected a file ending in .json)"),
    # -- files: SUMO networks (EGO_SUMO_NETS) --------------------------------------------------------------
    C("net-truncated", EB, "is not valid XML", env={"EGO_SUMO_NETS": "{nets_truncated}"}),
    C("net-garbled", EB, "is not valid XML", env={"EGO_SUMO_NETS": "{nets_garbled}"}),
    C("net-empty", EB, "is not valid XML", env={"EGO_SUMO_NETS": "{nets_empty}"}),
    C("net-not-a-network", EB, "is not a SUMO network", env={"EGO_SUMO_NETS": "{nets_not-a-net}"}),
    C(
        "nets-folder-missing",
        EB,
        "SUMO networks folder /nowhere/nets not found",
        env={"EGO_SUMO_NETS": "/nowhere/nets"},
    ),
    C("nets-folder-a-file", EB, "not found", env={"EGO_SUMO_NETS": "{file.txt}"}),
    # -- seeds and outputs of run --------------------------------------------------------------------------
    C("seed-negative", [*EB, "--seed", "-1"], "bad value for --seed: -1"),
    C("seed-2-31", [*EB, "--seed", "2147483648"], "bad value for --seed: 2147483648"),
    C("seed-float", [*EB, "--seed", "1.5"], "invalid whole number (digits 0-9) value: '1.5'"),
    C("seed-text", [*EB, "--seed", "abc"], "invalid whole number (digits 0-9) value: 'abc'"),
    C("record-suffix", [*EB, "--record", "{out}/x.txt"], "expected a file ending in .rrd"),
    C("record-empty", [*EB, "--record", ""], "bad --record path ''"),
    C("record-folder", [*EB, "--record", "{folder.rrd}"], "it is a folder"),
    C("record-under-a-file", [*EB, "--record", "{file.txt}/x.rrd"], "is a file, not a folder"),
    C("record-proc", [*EB, "--record", "/proc/x.rrd"], "not a place for files"),
    # -- compare -------------------------------------------------------------------------------------------
    C("compare-twice", [*CMP, "--controllers", "pid,pid"], "'pid' is listed twice"),
    C("compare-no-names", [*CMP, "--controllers", ",,"], "--controllers needs at least one name"),
    C("compare-unknown-controller", [*CMP, "--controllers", "pid,magic"], "unknown controller 'magic'"),
    C("compare-misspelt-controller", [*CMP, "--controllers", "pid,fuzy"], "did you mean 'fuzzy'?"),
    C("compare-seeds-zero", [*CMP, "--controllers", "pid", "--seeds", "0"], "bad value for --seeds: 0"),
    C(
        "compare-seeds-huge",
        [*CMP, "--controllers", "pid", "--seeds", "1000000000"],
        "bad value for --seeds: 1000000000",
    ),
    C("compare-jobs-zero", [*CMP, "--controllers", "pid", "--jobs", "0"], "bad value for --jobs: 0"),
    C("compare-jobs-huge", [*CMP, "--controllers", "pid", "--jobs", "100000"], "bad value for --jobs: 100000"),
    C(
        "compare-out-a-file",
        ["compare", "emergency-brake", "--controllers", "pid", "--out", "{file.txt}"],
        "it is a file",
    ),
    C("compare-out-empty", ["compare", "emergency-brake", "--controllers", "pid", "--out", ""], "bad --out ''"),
    C("compare-no-out", ["compare", "emergency-brake", "--controllers", "pid"], "--out"),
    C("compare-unknown-parameter", [*CMP, "--controllers", "pid", "--set", "warp=1"], "unknown parameter 'warp'"),
    C(
        "compare-misspelt-parameter",
        [*CMP, "--controllers", "pid,fuzzy", "--set", "ego_sped=1"],
        "did you mean 'ego_speed'?",
    ),
    C("compare-bad-value", [*CMP, "--controllers", "pid", "--set", "lead_decel=nan"], "bad value for lead_decel: nan"),
    C(
        "compare-bad-controller-value",
        [*CMP, "--controllers", "pid,rbf-smc", "--set", "width=0"],
        "bad value for width: 0",
    ),
    C(
        "compare-bad-model",
        ["compare", "curve", "--controllers", "narma-l2", "--out", "{out}", "--set", "model={model_nan.npz}"],
        "holds NaN",
    ),
    # -- sweep ---------------------------------------------------------------------------------------------
    C(
        "sweep-missing-spec",
        ["sweep", "/nowhere/s.toml", "--out", "{out}"],
        "cannot read the sweep spec '/nowhere/s.toml'",
    ),
    C("sweep-spec-folder", _sweep("spec_dir.toml"), "cannot read the sweep spec"),
    C("sweep-spec-binary", _sweep("spec_binary.toml"), "not a text file (expected TOML)"),
    C("sweep-spec-garbled", _sweep("spec_garbled.toml"), "not valid TOML"),
    C("sweep-misspelt-section", _sweep("spec_top.toml"), "unknown key 'gird'"),
    C("sweep-misspelt-section-suggests", _sweep("spec_top.toml"), "did you mean 'grid'?"),
    C("sweep-misspelt-scenario", _sweep("spec_scenario.toml"), "did you mean 'emergency-brake'?"),
    C("sweep-controllers-not-a-list", _sweep("spec_controllers.toml"), "controllers must be a non-empty list"),
    C("sweep-misspelt-controller", _sweep("spec_controller.toml"), "unknown controller 'pdi'"),
    C("sweep-misspelt-axis", _sweep("spec_axis.toml"), "[grid] unknown parameter 'ego_sped'"),
    C("sweep-misspelt-axis-suggests", _sweep("spec_axis.toml"), "did you mean 'ego_speed'?"),
    C("sweep-grid-out-of-range", _sweep("spec_range.toml"), "[grid] ego_speed: bad value for ego_speed: 250"),
    C("sweep-grid-text", _sweep("spec_type.toml"), "bad value for ego_speed: 'fast'"),
    C(
        "sweep-grid-float-for-int",
        _sweep("spec_int.toml"),
        "bad value for substeps: 2.0 (expected a whole number from 1 to 100, not a float)",
    ),
    C("sweep-grid-bool-for-number", _sweep("spec_bool.toml"), "not true/false"),
    C("sweep-grid-empty", _sweep("spec_empty_grid.toml"), "must be a non-empty list"),
    C("sweep-grid-combination", _sweep("spec_mix.toml"), "bad value for sumo_step"),
    C("sweep-misspelt-method", _sweep("spec_method.toml"), "did you mean 'sobol'?"),
    C("sweep-sample-n-zero", _sweep("spec_n.toml"), "n must be a whole number of at least 1, got 0"),
    C("sweep-sample-reversed", _sweep("spec_reversed.toml"), "must be a range [low, high] with low < high"),
    C("sweep-sample-out-of-range", _sweep("spec_sample_range.toml"), "bad value for lead_gap: 4000"),
    C("sweep-sample-a-switch", _sweep("spec_sample_text.toml"), "abs is not a number to sample"),
    C("sweep-seed-negative", _sweep("spec_seeds.toml"), "seed -1 is not a whole number"),
    C("sweep-seeds-zero", _sweep("spec_seeds0.toml"), "seeds = 0"),
    C("sweep-too-many-runs", _sweep("spec_huge.toml"), "expands to 200,000,000 runs; the limit is 10,000,000"),
    C("sweep-misspelt-engine", _sweep("spec_ok.toml", "--engine", "proces"), "did you mean 'process'?"),
    C("sweep-misspelt-record", _sweep("spec_ok.toml", "--record", "fail"), "did you mean 'failed'?"),
    C("sweep-jobs-zero", _sweep("spec_ok.toml", "--jobs", "0"), "bad value for --jobs: 0"),
    C("sweep-address-without-ray", _sweep("spec_ok.toml", "--address", "auto"), "--address needs --engine ray"),
    C("sweep-plot-malformed", _sweep("spec_ok.toml", "--plot", "ego_speed"), "bad --plot 'ego_speed'"),
    C("sweep-plot-not-swept", _sweep("spec_ok.toml", "--plot", "ego_sped,lead_gap"), "did you mean 'ego_speed'?"),
    C(
        "sweep-plot-metric",
        _sweep("spec_ok.toml", "--plot", "ego_speed,ego_speed:min_gap_frnt"),
        "did you mean 'min_gap_front'?",
    ),
    C(
        "sweep-plot-against-itself",
        _sweep("spec_ok.toml", "--plot", "ego_speed,ego_speed"),
        "bad --plot 'ego_speed,ego_speed': X and Y are both 'ego_speed'",
    ),
    C(
        "sweep-require-twice",
        _sweep("spec_ok.toml", "--require", "a: always (speed >= 0 m/s)", "--require", "a: always (speed >= 1 m/s)"),
        "--require a is given twice",
    ),
    C("sweep-out-a-file", ["sweep", "{spec_ok.toml}", "--out", "{file.txt}"], "it is a file"),
    # -- train ---------------------------------------------------------------------------------------------
    C("train-samples-few", [*TRAIN, "--samples", "5"], "bad value for --samples: 5"),
    C("train-samples-many", [*TRAIN, "--samples", "100000000"], "bad value for --samples: 100000000"),
    C("train-epochs-zero", [*TRAIN, "--epochs", "0"], "bad value for --epochs: 0"),
    C("train-epochs-many", [*TRAIN, "--epochs", "1000000"], "bad value for --epochs: 1000000"),
    C("train-speeds-one", [*TRAIN, "--speeds", "30"], "bad value for --speeds: '30' (expected LO,HI"),
    C("train-speeds-nan", [*TRAIN, "--speeds", "nan,30"], "bad value for --speeds: 'nan,30'"),
    C("train-speeds-reversed", [*TRAIN, "--speeds", "40,20"], "bad value for --speeds: '40,20'"),
    C("train-speeds-outside", [*TRAIN, "--speeds", "1,200"], "expected km/h within 5..60"),
    C("train-radii", [*TRAIN, "--radii", "1,2"], "bad value for --radii: '1,2'"),
    C("train-accels", [*TRAIN, "--accels=-5,5"], "bad value for --accels: '-5,5'"),
    C("train-out-suffix", [*TRAIN, "--out", "{out}/x.pt"], "expected a file ending in .npz"),
    C("train-out-and-install", [*TRAIN, "--out", "{out}/a.npz", "--install"], "give --out or --install, not both"),
    C("train-out-empty", [*TRAIN, "--out", ""], "bad --out path '' (expected a file ending in .npz)"),
    C(
        "train-negative-accels-as-two-words",
        [*TRAIN, "--accels", "-1,0"],
        "argument --accels: expected one argument (a value that starts with - is written --accels=VALUE)",
    ),
    C("train-unknown-model", ["train", "narma"], "did you mean 'narma-l2'?"),
    C("train-seed", [*TRAIN, "--seed", "-1"], "bad value for --seed: -1"),
    # -- tune ----------------------------------------------------------------------------------------------
    C("tune-workers-zero", [*TUNE, "--workers", "0"], "bad value for --workers: 0"),
    C("tune-workers-many", [*TUNE, "--workers", "100000"], "bad value for --workers: 100000"),
    C("tune-drive-nan", [*TUNE, "--drives", "8:nan"], "bad value for --drives: '8:nan'"),
    C("tune-drive-three-parts", [*TUNE, "--drives", "8:1:2"], "bad value for --drives: '8:1:2'"),
    C("tune-drive-fast", [*TUNE, "--drives", "100"], "expected speeds from 2 to 30 m/s"),
    C(
        "tune-drive-zero",
        [*TUNE, "--drives", "0"],
        "bad value for --drives: '0' (expected speeds from 2 to 30 m/s and offsets within",
    ),
    C("tune-drive-empty", [*TUNE, "--drives", ""], "bad value for --drives: ''"),
    C("tune-cost-misspelt", [*TUNE, "--cost", "sumoo"], "did you mean 'sumo'?"),
    C("tune-engine-misspelt", [*TUNE, "--cost", "sumo", "--engine", "rayy"], "did you mean 'ray'?"),
    C("tune-duration-without-sumo", [*TUNE, "--duration", "5"], "go with --cost sumo"),
    C("tune-duration-zero", [*TUNE, "--cost", "sumo", "--duration", "0"], "bad value for --duration: 0.0"),
    C("tune-duration-nan", [*TUNE, "--cost", "sumo", "--duration", "nan"], "bad value for --duration: nan"),
    C("tune-address-without-ray", [*TUNE, "--cost", "sumo", "--address", "auto"], "--address needs --engine ray"),
    C("tune-seed", [*TUNE, "--seed", "2147483648"], "bad value for --seed: 2147483648"),
    C("tune-out-empty", [*TUNE, "--out", ""], "bad --out path '' (expected a file ending in .json)"),
    C("tune-out-empty-and-install", [*TUNE, "--out", "", "--install"], "give --out or --install, not both"),
    C("tune-out-suffix", [*TUNE, "--out", "{out}/g.txt"], "expected a file ending in .json"),
    C("tune-unknown-task", ["tune", "lane-centring"], "did you mean 'lane-centering'?"),
    # -- export-fmu: a start value the model cannot run from -----------------------------------------------
    C("fmu-mass-negative", [*FMU, "m=-1"], "bad value for m: -1 (expected a number above 0 and up to 100000 (kg))"),
    C("fmu-mass-zero", [*LINEAR_FMU, "m=0"], "bad value for m: 0 (expected a number above 0"),
    C("fmu-inertia-zero", [*FMU, "Iz=0"], "bad value for Iz: 0"),
    C("fmu-axle-zero", [*FMU, "a=0"], "bad value for a: 0"),
    C("fmu-friction-negative", [*FMU, "F_max=-5"], "bad value for F_max: -5"),
    C("fmu-substeps-zero", [*FMU, "substeps=0"], "bad value for substeps: 0 (expected a whole number from 1 to 100)"),
    C("fmu-substeps-negative", [*LINEAR_FMU, "substeps=-3"], "bad value for substeps: -3"),
    C("fmu-substeps-fraction", [*LINEAR_FMU, "substeps=1.5"], "bad value for substeps: '1.5'"),
    C("fmu-wheels-negative", [*FMU, "Nw=-1"], "bad value for Nw: -1 (expected a whole number from 1 to 4)"),
    C("fmu-abs-five", [*FMU, "abs=5"], "bad value for abs: '5' (expected true or false)"),
    C("fmu-abs-negative", [*FMU, "abs=-1"], "bad value for abs: '-1'"),
    C("fmu-speed-huge", [*LINEAR_FMU, "u0=1e6"], "bad value for u0: 1000000 (expected a number from 0 to 100 (m/s))"),
    C("fmu-stiffness-positive", [*LINEAR_FMU, "Cf=5"], "bad value for Cf: 5"),
    C("fmu-nan", [*LINEAR_FMU, "m=nan"], "bad value for m: nan"),
]


@pytest.mark.parametrize("args, message, env", CLI)
def test_bad_input_on_the_command_line_is_one_line_exit_2_nothing_written_no_sumo(
    args, message, env, files, tmp_path, capsys, monkeypatch
):
    monkeypatch.chdir(tmp_path)  # anything written to the working folder shows too
    for key, value in env.items():
        monkeypatch.setenv(key, _fill([value], files)[0])
    inputs = Path(files["file.txt"]).parent
    before, inputs_before, started = _tree(tmp_path), _tree(inputs), SumoBridge.started
    status = main(_fill(args, files))
    out = capsys.readouterr()
    assert status == 2, out.err
    assert out.out == ""
    assert out.err.startswith("ego: error: ") and out.err.count("\n") == 1, out.err
    assert "Traceback" not in out.err
    assert _fill([message], files)[0] in out.err
    assert _tree(tmp_path) == before and _tree(inputs) == inputs_before  # nothing written
    assert SumoBridge.started == started  # refused before SUMO starts


@pytest.mark.parametrize(
    "args, message",
    [
        pytest.param([*EB, "--set", "substeps=2.0"], "write 2", id="int-as-float"),
        pytest.param([*PLATOON, "--set", "init_range=1e308"], "bad value for init_range: 1e+308", id="init-range"),
        pytest.param([*LANE, "--set", "gains_file={gains_binary.json}"], "not a text file", id="binary-gains"),
        pytest.param(
            [*CURVE_NARMA, "--set", "model={model_truncated.npz}"], "not a readable .npz file", id="truncated-model"
        ),
        pytest.param(["comprae"], "did you mean 'compare'?", id="misspelt-command"),
    ],
)
def test_as_a_subprocess_bad_input_exits_2_with_one_line(args, message, files, tmp_path):
    before = _tree(tmp_path)
    res = subprocess.run(
        [sys.executable, "-m", "ego", *_fill(args, files)], capture_output=True, text=True, cwd=tmp_path, timeout=120
    )
    assert res.returncode == 2 and res.stdout == ""
    assert res.stderr.startswith("ego: error: ") and res.stderr.count("\n") == 1, res.stderr
    assert message in res.stderr and "Traceback" not in res.stderr
    assert _tree(tmp_path) == before


def test_a_network_spoilt_after_the_check_is_still_refused_before_sumo(files, monkeypatch):
    from ego.runner import RunSpec, build

    monkeypatch.setenv("EGO_SUMO_NETS", files["nets_truncated"])
    started = SumoBridge.started
    with pytest.raises(ConfigError, match="highway.net.xml is not valid XML"):
        build(RunSpec("emergency-brake", "pid")).reset()
    assert SumoBridge.started == started


# -- the Python API ------------------------------------------------------------------------------------------


def _configure(scenario="emergency-brake", controller="pid", seed=0, **overrides):
    from ego.runner import RunSpec, resolve

    return lambda files: resolve(RunSpec(scenario, controller, seed, overrides))


def _spec_of(**kw):
    from ego.runner import RunSpec

    return lambda files: RunSpec(**{"scenario": "emergency-brake", "controller": "pid", **kw})


def _make(cls_path: str, **kw):
    def make(files):
        import importlib

        module, name = cls_path.rsplit(".", 1)
        cls = getattr(importlib.import_module(module), name)
        return cls(**{k: _fill([v], files)[0] if isinstance(v, str) else v for k, v in kw.items()})

    return make


def _apply(cls_path: str, overrides: dict):
    def apply(files):
        from ego.params import apply_overrides

        return apply_overrides(_make(cls_path)(files), overrides)

    return apply


def _compare(**changes):
    def call(files):
        from ego.compare import compare

        kw = {
            "scenario": "emergency-brake",
            "controllers": ["pid"],
            "seeds": 1,
            "overrides": {},
            "out": Path(files["out"]),
        }
        kw.update(changes)
        return compare(**kw)

    return call


def _sweep_parse(**changes):
    def parse(files):
        from ego.sweep.spec import parse

        data = {"scenario": "emergency-brake", "controllers": ["pid"], "grid": {"ego_speed": [20, 25]}}
        data.update(changes)
        return parse(data)

    return parse


def _loader(fn_path: str, file: str):
    def load(files):
        import importlib

        module, name = fn_path.rsplit(".", 1)
        fn = getattr(importlib.import_module(module), name)
        return fn(files[file] if file in files else file)

    return load


def A(id: str, call, message: str):  # noqa: N802 - a table row
    return pytest.param(call, message, id=id)


API = [
    A(
        "runspec-substeps-float",
        _configure(substeps=2.0),
        "bad value for substeps: 2.0 (expected a whole number from 1 to 100, not a float)",
    ),
    A("runspec-substeps-bool", _configure(substeps=True), "bad value for substeps: True"),
    A("runspec-substeps-numpy-float", _configure(substeps=np.float64(2.0)), "not a float"),
    A("runspec-dt-text", _configure(dt="x"), "bad value for dt: 'x'"),
    A(
        "runspec-dt-none",
        _configure(dt=None),
        "bad value for dt: None (expected a number from 0.001 to 0.1 (s), not None)",
    ),
    A("runspec-dt-list", _configure(dt=[0.01]), "bad value for dt: [0.01]"),
    A("runspec-dt-complex", _configure(dt=1j), "bad value for dt: 1j"),
    A("runspec-dt-nan", _configure(dt=math.nan), "bad value for dt: nan"),
    A("runspec-abs-int", _configure(abs=1), "bad value for abs: 1 (expected true or false, not a whole number)"),
    A("runspec-lane-bool", _configure(ego_lane=True), "bad value for ego_lane: True"),
    A("runspec-lane-float", _configure(ego_lane=1.0), "bad value for ego_lane: 1.0"),
    A(
        "runspec-text-param-number",
        _configure("curve", "narma-l2", model=3),
        "bad value for model: 3 (expected text, not a whole number)",
    ),
    A("runspec-choice-number", _configure("platoon", "pid", variant=1), "bad value for variant: 1"),
    A("runspec-init-range", _configure("platoon", "bp-pid-acc", init_range=1e308), "bad value for init_range: 1e+308"),
    A("runspec-misspelt-parameter", _configure(ego_sped=1), "did you mean 'ego_speed'?"),
    A("runspec-misspelt-scenario", _configure("emergency-brak"), "did you mean 'emergency-brake'?"),
    A("runspec-misspelt-controller", _configure(controller="fuzy"), "did you mean 'fuzzy'?"),
    A("runspec-seed-float", _configure(seed=1.0), "bad value for seed: 1.0"),
    A("runspec-seed-text", _configure(seed="1"), "bad value for seed: '1'"),
    A("runspec-seed-bool", _configure(seed=True), "bad value for seed: True"),
    A("runspec-scenario-not-text", _spec_of(scenario=3), "bad scenario 3"),
    A("runspec-controller-none", _spec_of(controller=None), "bad controller None"),
    A("runspec-overrides-list", _spec_of(overrides=[("dt", 0.01)]), "bad overrides"),
    A("runspec-overrides-key-not-text", _spec_of(overrides={1: 2}), "bad overrides"),
    A("runspec-record-number", _spec_of(record=5), "bad record 5"),
    A("runspec-background-text", _spec_of(background_recording="yes"), "bad background_recording 'yes'"),
    A("params-init-range", _make("ego.control.BPPIDAccParams", init_range=1e308), "bad value for init_range: 1e+308"),
    A("params-learning-rate", _make("ego.control.BPPIDParams", learning_rate=2.0), "bad value for learning_rate: 2"),
    A("params-width", _make("ego.control.RBFSMCParams", width=1e-300), "bad value for width: 1e-300"),
    A("params-steer-limit", _make("ego.control.PIDParams", steer_limit=2.0), "bad value for steer_limit: 2"),
    A(
        "params-gain-text",
        _make("ego.control.PIDParams", kp_lat="1"),
        "bad value for kp_lat: '1' (expected a number from 0 to 10 (rad/m), not text)",
    ),
    A("params-gain-nan", _make("ego.control.FuzzyParams", fx_gain=math.nan), "bad value for fx_gain: nan"),
    A("params-period-zero", _make("ego.control.FollowingPIDParams", period=0.0), "bad value for period: 0"),
    A("params-preset", _make("ego.control.CascadePIDParams", preset="tunned"), "did you mean 'tuned'?"),
    A("params-gains-file", _make("ego.control.CascadePIDParams", gains_file="{gains_garbage.json}"), "not valid JSON"),
    A("params-model-file", _make("ego.control.NarmaL2Params", model="{model_nan.npz}"), "holds NaN"),
    A("config-substeps-float", _make("ego.scenarios.base.TimingConfig", substeps=2.0), "bad value for substeps: 2.0"),
    A(
        "config-brake-after-run",
        _make("ego.scenarios.EmergencyBrakeConfig", lead_brake_time=100.0),
        "bad value for lead_brake_time: 100",
    ),
    A("config-followers-bool", _make("ego.scenarios.PlatoonConfig", followers=True), "bad value for followers: True"),
    A("config-preview-huge", _make("ego.scenarios.CurveConfig", preview=1e308), "bad value for preview: 1e+308"),
    A(
        "apply-numpy-nan",
        _apply("ego.scenarios.EmergencyBrakeConfig", {"lead_gap": np.float64("nan")}),
        "bad value for lead_gap: nan",
    ),
    A("apply-misspelt", _apply("ego.scenarios.PlatoonConfig", {"folowers": 3}), "did you mean 'followers'?"),
    A("compare-seeds-text", _compare(seeds="3"), "bad value for seeds: '3' (expected a whole number from 1 to 100000)"),
    A("compare-seeds-float", _compare(seeds=2.0), "bad value for seeds: 2.0"),
    A(
        "compare-controllers-text",
        _compare(controllers="pid,fuzzy"),
        "bad controllers 'pid,fuzzy' (expected a list of names)",
    ),
    A("compare-overrides-list", _compare(overrides=["dt=0.01"]), "bad overrides"),
    A("compare-misspelt", _compare(overrides={"ego_sped": 1}), "did you mean 'ego_speed'?"),
    A("sweep-float-for-int", _sweep_parse(grid={"substeps": [1, 2.0]}), "bad value for substeps: 2.0"),
    A("sweep-parse-misspelt-axis", _sweep_parse(grid={"ego_sped": [20]}), "did you mean 'ego_speed'?"),
    A(
        "sweep-misspelt-sample-axis",
        _sweep_parse(grid={}, sample={"n": 4, "lead_gapp": [20, 40]}),
        "did you mean 'lead_gap'?",
    ),
    A("sweep-seeds-text", _sweep_parse(seeds="3"), "seeds must be a count or a list"),
    A("sweep-set-text", _sweep_parse(set={"ego_speed": "fast"}), "bad value for ego_speed: 'fast'"),
    A("sweep-set-not-table", _sweep_parse(set=[1]), "[set] must be a table"),
    A("trainspec-data-samples", _make("ego.train.narma_l2.DataSpec", samples=5), "bad value for samples: 5"),
    A(
        "trainspec-data-reversed-speeds",
        _make("ego.train.narma_l2.DataSpec", speed_min=50.0, speed_max=30.0),
        "bad value for speed_min: 50 (expected at most speed_max=30)",
    ),
    A(
        "trainspec-data-sample-period",
        _make("ego.train.narma_l2.DataSpec", sample_period=0.025),
        "bad value for sample_period",
    ),
    A("trainspec-epochs-float", _make("ego.train.narma_l2.TrainSpec", epochs=2.0), "bad value for epochs: 2.0"),
    A("trainspec-lr-zero", _make("ego.train.narma_l2.TrainSpec", lr=0.0), "bad value for lr: 0"),
    A("trainspec-data-not-a-spec", _make("ego.train.narma_l2.TrainSpec", data={"samples": 10}), "bad data"),
    A("tunespec-workers", _make("ego.train.lane_centering.TuneSpec", workers=0), "bad value for workers: 0"),
    A("tunespec-seed", _make("ego.train.lane_centering.TuneSpec", seed=-1), "bad value for seed: -1"),
    A(
        "tunespec-drives-fast",
        _make("ego.train.lane_centering.TuneSpec", drives=((100.0, 0.0),)),
        "expected speeds from 2 to 30 m/s",
    ),
    A("tunespec-drives-flat", _make("ego.train.lane_centering.TuneSpec", drives=(8.0, 0.0)), "bad value for drives"),
    A(
        "tunespec-drives-nan",
        _make("ego.train.lane_centering.TuneSpec", drives=((8.0, math.nan),)),
        "bad value for drives",
    ),
    A("tunespec-cost", _make("ego.train.lane_centering.TuneSpec", cost="sumoo"), "did you mean 'sumo'?"),
    A("tunespec-duration", _make("ego.train.lane_centering.TuneSpec", duration=0.0), "bad value for duration: 0.0"),
    A("tunespec-tol-nan", _make("ego.train.lane_centering.TuneSpec", tol=math.nan), "bad value for tol: nan"),
    A("load-preset-binary", _loader("ego.control.cascade.load_preset", "gains_binary.json"), "not a text file"),
    A(
        "load-preset-nan",
        _loader("ego.control.cascade.load_preset", "gains_nan.json"),
        "NaN is not a number JSON allows",
    ),
    A(
        "load-model-truncated",
        lambda files: __import__("ego.control.narma").control.narma.NarmaModel.load(files["model_truncated.npz"]),
        "not a readable .npz file",
    ),
    A("load-model-shape", _loader("ego.control.narma.load_model", "model_shape.npz"), "the array f_w1 has shape"),
    A("load-sweep-binary", _loader("ego.sweep.spec.load", "spec_binary.toml"), "cannot read the sweep spec"),
    A(
        "controller-spec-misspelt",
        lambda files: __import__("ego.control").control.controller_spec("rbf_smc"),
        "did you mean 'rbf-smc'?",
    ),
    A(
        "controller-spec-task",
        lambda files: __import__("ego.control").control.controller_spec("pid", "curv"),
        "did you mean 'curve'?",
    ),
    A(
        "network-misspelt",
        lambda files: __import__("ego.sumo.net").sumo.net.net_file("highwya"),
        "did you mean 'highway'?",
    ),
]


def _network_check(files):
    from ego.sumo.net import check_network

    return check_network(Path(files["nets_truncated"]) / "highway" / "highway.net.xml")


API.append(A("check-network-truncated", _network_check, "is not valid XML"))


@pytest.mark.parametrize("call, message", API)
def test_bad_input_in_python_is_a_config_error_naming_the_value(call, message, files):
    with pytest.raises(Exception) as err:
        call(files)
    assert type(err.value) is ConfigError, f"{type(err.value).__name__}: {err.value}"
    text = str(err.value)
    assert "\n" not in text and message in text, text


def test_the_catalogue_is_big_enough_and_its_ids_are_unique():
    ids = [p.id for p in CLI + API]
    assert len(ids) >= 150 and len(set(ids)) == len(ids)


# -- what is right is still accepted ---------------------------------------------------------------------------


def test_values_at_the_bounds_and_numpy_scalars_are_accepted_as_plain_python_values():
    from ego.control import BPPIDAccParams, PIDParams, RBFSMCParams
    from ego.params import HALF_PI, apply_overrides
    from ego.scenarios import PlatoonConfig

    config, _ = apply_overrides(
        PlatoonConfig(), {"followers": np.int64(10), "headway": np.float64(5.0), "standstill_gap": 3}
    )
    assert config.followers == 10 and type(config.followers) is int
    assert type(config.headway) is float and type(config.standstill_gap) is float
    assert PIDParams(steer_limit=HALF_PI).steer_limit == HALF_PI
    assert BPPIDAccParams(init_range=10.0, learning_rate=0.0).learning_rate == 0.0  # 0: no learning
    assert RBFSMCParams(width=0.01).width == 0.01
    params, _ = apply_overrides(PIDParams(), {"kp_lat": "0.5"})
    assert params.kp_lat == 0.5


def test_a_good_gains_file_and_model_are_read(files, tmp_path):
    from ego.control.cascade import CascadePIDParams
    from ego.control.narma import NarmaL2Params

    good = tmp_path / "good.json"
    good.write_text(json.dumps({"gains": GOOD_GAINS}))
    assert CascadePIDParams(gains_file=str(good)).gains() == tuple([0.5] * 12)
    model = tmp_path / "copy.npz"
    _model()(model)
    assert NarmaL2Params(model=str(model)).model == str(model)


def test_a_misspelt_name_far_from_any_gets_no_suggestion():
    from ego.params import did_you_mean

    assert did_you_mean("zzz", ["pid", "fuzzy"]) == ""
    assert did_you_mean("fuzy", ["pid", "fuzzy"]) == "; did you mean 'fuzzy'?"
    assert did_you_mean(3, ["pid"]) == ""


def test_the_inputs_reference_in_the_docs_is_what_ego_list_markdown_prints(capsys):
    assert main(["list", "--markdown"]) == 0
    generated = capsys.readouterr().out
    doc = (Path(__file__).resolve().parents[1] / "docs" / "inputs.md").read_text()
    assert "ego list --markdown" in doc
    assert doc.endswith(generated), "docs/inputs.md is stale: regenerate its reference with ego list --markdown"
    for name in ("init_range", "learning_rate", "width", "lead_brake_time", "substeps", "gains_file", "model"):
        assert f"| `{name}` |" in generated
