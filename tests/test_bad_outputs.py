"""A catalogue of bad output places, and of writes that fail anyway (issue 23).

The output side is held to the standard of ``tests/test_bad_inputs.py``:

* **Before anything runs** - every output location of every command (``--record``,
  ``--trace`` in each format, ``--video``, ``compare/sweep --out``, ``train/tune --out``) and
  every name ego will create inside it, under its final and its temporary
  (``.<pid>.partial``) name: names too long for the filesystem, symlink loops, ``/proc`` and
  ``/sys``, names occupied by a file, a folder or a FIFO, read-only trees, a filesystem with
  too little room, the files ego ships. Each case: exit 2, one line ``ego: error: ...`` naming
  the place, no traceback, nothing written, no SUMO started.
* **A write that fails anyway** (a disk that fills during the run: a tiny tmpfs when this
  process may mount one, else ``RLIMIT_FSIZE``): one line naming the file and the errno, the
  metrics still printed, no temporary file left, exit 1, never a traceback and never a hang.
* **Signals in the first second**, odd inputs, and the sweep's writer errors.
"""

from __future__ import annotations

import hashlib
import json
import os
import resource
import shutil
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path
from typing import Self

import numpy as np
import pytest

from ego.cli import main
from ego.control.cascade import TUNED_PRESET
from ego.control.narma import DEFAULT_MODEL
from ego.params import ConfigError
from ego.sumo.bridge import SumoBridge
from ego.sumo.net import nets_dir

EB = ["run", "emergency-brake", "-c", "pid", "--set", "duration=4"]
SPEC = (
    'scenario = "emergency-brake"\ncontrollers = ["pid"]\n[set]\nduration = 4\n'
    "[grid]\nego_speed = [20, 25]\nlead_gap = [30]\n"
)
FSPEC = (
    'scenario = "emergency-brake"\ncontroller = "pid"\nrequirement = "far"\nseed = 3\nbudget = 2\n'
    '[requirements]\nfar = "always (gap_front >= 25 m)"\n[set]\nduration = 4\n'
    "[search]\nego_speed = [15, 30]\nlead_gap = [20, 60]\n"
)
FALSIFY = ["falsify", "{fspec}", "--out", "{out}", "--optimizer", "lhs"]
LONG = "x" * 250  # a valid name (<= 255) that the temporary suffix makes too long
TOO_LONG = "y" * 256
DEEP = "/".join(["d" * 200] * 25)  # longer than PATH_MAX in all


def _tree(root: Path) -> list[str]:
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


def _can_mount() -> bool:
    if os.geteuid() != 0 or shutil.which("mount") is None:
        return False
    probe = Path(f"/tmp/ego-mount-probe-{os.getpid()}")
    probe.mkdir(exist_ok=True)
    ok = (
        subprocess.run(
            ["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(probe)],
            capture_output=True,
        ).returncode
        == 0
    )
    if ok:
        subprocess.run(["umount", str(probe)], check=False, capture_output=True)
    probe.rmdir()
    return ok


MOUNT = _can_mount()


@pytest.fixture(scope="module")
def places(tmp_path_factory):
    """The odd places of the catalogue, made once: a file, a FIFO, a symlink loop, a
    read-only tree, a tiny filesystem."""
    root = tmp_path_factory.mktemp("places")
    (root / "file.txt").write_text("x")
    os.mkfifo(root / "fifo.rrd")
    for suffix in (".csv", ".parquet", ".mat", ".npz", ".json", ".gif"):
        os.mkfifo(root / f"fifo{suffix}")
    (root / "folder.rrd").mkdir()
    for suffix in (".csv", ".parquet", ".mat", ".npz", ".json", ".gif"):
        (root / f"folder{suffix}").mkdir()
    os.symlink(root / "loop_b", root / "loop_a")
    os.symlink(root / "loop_a", root / "loop_b")
    os.symlink(root / "self", root / "self")
    for suffix in (".rrd", ".csv", ".parquet", ".mat", ".npz", ".json", ".gif"):
        os.symlink(root / f"loop{suffix}", root / f"loop{suffix}")
    ro, tiny = root / "ro", root / "tiny"
    ro.mkdir()
    tiny.mkdir()
    mounted = []
    if MOUNT:
        subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m,ro", "tmpfs", str(ro)], check=True)
        subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", str(tiny)], check=True)
        mounted = [ro, tiny]
    else:  # without mount: a folder without write permission, and the free-space floor raised
        ro.chmod(0o555)
    paths = {"root": str(root), "ro": str(ro), "tiny": str(tiny)}
    yield paths
    for m in mounted:
        subprocess.run(["umount", str(m)], check=False)


def C(id: str, args: list[str], message: str, env: dict | None = None):
    return pytest.param(args, message, env or {}, id=id)


# every command's output option, with a name of the right suffix
FILE_OPTIONS = {
    "record": (EB + ["--record"], ".rrd", "--record path"),
    "trace-csv": (EB + ["--trace"], ".csv", "--trace path"),
    "trace-parquet": (EB + ["--trace"], ".parquet", "--trace path"),
    "trace-mat": (EB + ["--trace"], ".mat", "--trace path"),
    "video": (
        ["run", "emergency-brake", "-c", "pid", "--backend", "highway-env", "--video"],
        ".gif",
        "--video path",
    ),
    "train": (
        ["train", "narma-l2", "--samples", "400", "--epochs", "1", "--out"],
        ".npz",
        "--out path",
    ),
    "tune": (["tune", "lane-centering", "--quick", "--out"], ".json", "--out path"),
}
DIR_OPTIONS = {
    "compare": (
        [
            "compare",
            "emergency-brake",
            "--controllers",
            "pid",
            "--set",
            "duration=4",
            "--out",
        ],
        "--out",
    ),
    "sweep": (["sweep", "{spec}", "--out"], "--out"),
    "falsify": (["falsify", "{fspec}", "--out"], "--out"),
}

CASES = []
for key, (args, suffix, _what) in FILE_OPTIONS.items():
    CASES += [
        C(f"{key}-name-too-long", [*args, f"{{root}}/{TOO_LONG}{suffix}"], "too long"),
        C(
            f"{key}-name-too-long-with-partial-suffix",
            [*args, f"{{root}}/{LONG[: 250 - len(suffix)]}{suffix}"],
            "temporary suffix",
        ),
        C(
            f"{key}-folder-name-too-long",
            [*args, f"{{root}}/{TOO_LONG}/x{suffix}"],
            "longer than the filesystem",
        ),
        C(f"{key}-path-too-long", [*args, f"{{root}}/{DEEP}/x{suffix}"], "too long"),
        C(f"{key}-symlink-loop", [*args, f"{{root}}/loop_a/x{suffix}"], "symlink loop"),
        C(f"{key}-self-loop", [*args, f"{{root}}/self/x{suffix}"], "symlink loop"),
        C(f"{key}-loop-as-the-file", [*args, f"{{root}}/loop{suffix}"], "symlink loop"),
        C(f"{key}-in-proc", [*args, f"/proc/x{suffix}"], ""),
        C(f"{key}-in-sys", [*args, f"/sys/x{suffix}"], ""),
        C(
            f"{key}-under-a-file",
            [*args, f"{{root}}/file.txt/x{suffix}"],
            "is a file, not a folder",
        ),
        C(f"{key}-a-folder", [*args, f"{{root}}/folder{suffix}"], "folder"),
        C(f"{key}-a-fifo", [*args, f"{{root}}/fifo{suffix}"], "not a regular file"),
        C(f"{key}-read-only", [*args, f"{{ro}}/x{suffix}"], "{ro}"),
        C(f"{key}-read-only-subfolder", [*args, f"{{ro}}/a/b/x{suffix}"], "{ro}"),
        C(f"{key}-tiny-filesystem", [*args, f"{{tiny}}/x{suffix}"], "free"),
    ]
for key, (args, _what) in DIR_OPTIONS.items():
    CASES += [
        C(f"{key}-out-name-too-long", [*args, f"{{root}}/{TOO_LONG}"], "too long"),
        C(f"{key}-out-path-too-long", [*args, f"{{root}}/{DEEP}"], "too long"),
        C(f"{key}-out-symlink-loop", [*args, "{root}/loop_a"], "symlink loop"),
        C(f"{key}-out-inside-a-loop", [*args, "{root}/loop_a/out"], "symlink loop"),
        C(f"{key}-out-self-loop", [*args, "{root}/self"], "symlink loop"),
        C(f"{key}-out-proc", [*args, "/proc"], "not a place for files"),
        C(f"{key}-out-sys", [*args, "/sys"], "not a place for files"),
        C(f"{key}-out-proc-sub", [*args, "/proc/ego-out"], ""),
        C(f"{key}-out-sys-sub", [*args, "/sys/kernel/ego-out"], ""),
        C(f"{key}-out-a-file", [*args, "{root}/file.txt"], "it is a file"),
        C(f"{key}-out-a-fifo", [*args, "{root}/fifo.rrd"], "it is a file"),
        C(
            f"{key}-out-under-a-file",
            [*args, "{root}/file.txt/out"],
            "is a file, not a folder",
        ),
        C(f"{key}-out-read-only", [*args, "{ro}"], "{ro}"),
        C(f"{key}-out-read-only-sub", [*args, "{ro}/out"], "{ro}"),
        C(f"{key}-out-tiny-filesystem", [*args, "{tiny}/out"], "free"),
        # a folder PATH_MAX allows whose files' temporary names it does not: nothing made
        C(f"{key}-out-too-long-for-its-files", [*args, "{long}"], "too long"),
        C(f"{key}-out-the-package", [*args, str(DEFAULT_MODEL.parents[2])], "inside the ego package"),
        C(f"{key}-out-inside-the-package", [*args, str(DEFAULT_MODEL.parent)], "inside the ego package"),
        C(f"{key}-out-new-in-the-package", [*args, str(DEFAULT_MODEL.parent / "out")], "inside the ego package"),
    ]

# names occupied inside an --out folder: (what to make, relative path), the option's args
OCCUPIED = [
    ("compare", "file", "runs", []),
    ("compare", "dir", "metrics.csv", []),
    ("compare", "dir", "metrics_units.csv", []),
    ("compare", "dir", "metrics.md", []),
    ("compare", "dir", ".ego.lock", []),
    ("compare", "fifo", ".ego.lock", []),
    ("compare", "dir", "runs/pid-seed0.rrd", []),
    ("compare", "fifo", "runs/pid-seed0.rrd", []),
    ("compare", "file", "traces", ["--traces", "csv"]),
    ("compare", "dir", "traces/pid-seed0.csv", ["--traces", "csv"]),
    ("compare", "dir", "traces/pid-seed0.units.csv", ["--traces", "csv"]),
    ("compare", "dir", "traces/pid-seed0.traffic.csv", ["--traces", "csv"]),
    ("compare", "dir", "traces/pid-seed0.parquet", ["--traces", "parquet"]),
    ("compare", "dir", "traces/pid-seed0.traffic.parquet", ["--traces", "parquet"]),
    ("compare", "dir", "traces/pid-seed0.mat", ["--traces", "mat"]),
    (
        "compare",
        "dir",
        f"runs/{'p' * 10}",
        [],
    ),  # harmless: another name; must NOT be refused
    ("sweep", "dir", "results.parquet", []),
    ("sweep", "dir", "summary.md", []),
    ("sweep", "dir", ".ego.lock", []),
    ("sweep", "file", "runs", []),
    ("sweep", "dir", "runs/pid-{run_id}.rrd", []),
    ("sweep", "fifo", "runs/pid-{run_id}.rrd", []),
    (
        "sweep",
        "dir",
        "envelope_ego_speed_lead_gap.png",
        ["--plot", "ego_speed,lead_gap"],
    ),
    ("sweep", "fifo", "summary.md", []),
    ("falsify", "dir", "results.parquet", []),
    ("falsify", "dir", "falsified.md", []),
    ("falsify", "fifo", "falsified.md", []),
    ("falsify", "dir", "convergence.png", []),
    ("falsify", "dir", ".ego.lock", []),
    ("falsify", "file", "runs", []),
]
for command, kind, name, extra in OCCUPIED:
    if name.startswith("runs/pppp"):
        continue
    args = DIR_OPTIONS[command][0]
    CASES.append(
        C(
            f"{command}-occupied-{kind}-{name.replace('/', '_')}{'-' + extra[1] if extra else ''}",
            [*args, "{out}", *extra, f"@{kind}:{name}"],
            name.split("/")[-1].replace("pid-{run_id}", "") + " inside it",
        )
    )

# the trace's side files, and shipped files
CASES += [
    C(
        "trace-units-sidecar-a-folder",
        [*EB, "--trace", "{out}/x.csv", "@dir:x.units.csv"],
        "x.units.csv",
    ),
    C(
        "trace-traffic-sidecar-a-folder",
        [*EB, "--trace", "{out}/x.csv", "@dir:x.traffic.csv"],
        "x.traffic.csv",
    ),
    C(
        "trace-parquet-traffic-sidecar-a-fifo",
        [*EB, "--trace", "{out}/x.parquet", "@fifo:x.traffic.parquet"],
        "x.traffic.parquet",
    ),
    C(
        "trace-units-sidecar-too-long",
        [*EB, "--trace", "{root}/" + "z" * 232 + ".csv"],
        "too long",
    ),
    C(
        "train-out-the-shipped-model",
        [
            "train",
            "narma-l2",
            "--samples",
            "400",
            "--epochs",
            "1",
            "--out",
            str(DEFAULT_MODEL),
        ],
        "--install",
    ),
    C(
        "tune-out-the-shipped-preset",
        ["tune", "lane-centering", "--quick", "--out", str(TUNED_PRESET)],
        "--install",
    ),
    C(
        "train-out-inside-the-package",
        [
            "train",
            "narma-l2",
            "--samples",
            "400",
            "--epochs",
            "1",
            "--out",
            str(DEFAULT_MODEL.parent / "new.npz"),
        ],
        "inside the ego package",
    ),
    C(
        "record-inside-the-package",
        [*EB, "--record", str(DEFAULT_MODEL.parent / "x.rrd")],
        "inside the ego package",
    ),
    C(
        "seed-underscore",
        ["run", "emergency-brake", "-c", "pid", "--seed", "1_0"],
        "'1_0'",
    ),
    C(
        "seed-arabic-digit",
        ["run", "emergency-brake", "-c", "pid", "--seed", "\u0663"],
        "'\u0663'",
    ),
    C("train-seed-underscore", ["train", "narma-l2", "--seed", "1_0"], "'1_0'"),
    C("falsify-jobs-underscore", [*FALSIFY, "--jobs", "1_0"], "--jobs: invalid whole number (digits 0-9) value: '1_0'"),
    C(
        "falsify-budget-underscore",
        [*FALSIFY, "--budget", "1_0"],
        "--budget: invalid whole number (digits 0-9) value: '1_0'",
    ),
    C("falsify-optimizer-seed-arabic-digit", [*FALSIFY, "--optimizer-seed", "\u0663"], "'\u0663'"),
    C(
        "compare-seeds-underscore",
        [
            "compare",
            "emergency-brake",
            "--controllers",
            "pid",
            "--seeds",
            "1_0",
            "--out",
            "{out}",
        ],
        "'1_0'",
    ),
    C(
        "compare-duplicate-variants",
        [
            "compare",
            "emergency-brake",
            "--controllers",
            "pid@kp_lat=0.02,pid@kp_lat= 0.02",
            "--out",
            "{out}",
        ],
        "same controller",
    ),
    C(
        "sweep-address-nothing-listening",
        [
            "sweep",
            "{spec}",
            "--out",
            "{out}",
            "--engine",
            "ray",
            "--address",
            "127.0.0.1:1",
        ],
        "127.0.0.1:1",
    ),
    C("falsify-address-nothing-listening", [*FALSIFY, "--engine", "ray", "--address", "127.0.0.1:1"], "127.0.0.1:1"),
    C(
        "sweep-address-malformed",
        [
            "sweep",
            "{spec}",
            "--out",
            "{out}",
            "--engine",
            "ray",
            "--address",
            "127.0.0.1:notaport",
        ],
        "127.0.0.1:notaport",
    ),
    C(
        "tune-address-nothing-listening",
        [
            "tune",
            "lane-centering",
            "--quick",
            "--cost",
            "sumo",
            "--engine",
            "ray",
            "--address",
            "127.0.0.1:1",
            "--out",
            "{out}/g.json",
        ],
        "127.0.0.1:1",
    ),
]


def _occupy(folder: Path, spec: str) -> None:
    kind, _, name = spec[1:].partition(":")
    if "{run_id}" in name:
        import tomllib

        from ego.sweep.spec import parse

        first = next(parse(tomllib.loads(SPEC)).runs())
        name = name.replace("{run_id}", first.run_id)
    target = folder / name
    target.parent.mkdir(parents=True, exist_ok=True)
    {
        "dir": lambda p: p.mkdir(),
        "file": lambda p: p.write_text("x"),
        "fifo": os.mkfifo,
    }[kind](target)


def _near_path_max(folder: Path, length: int = 4070) -> str:
    """A path below ``folder`` ``length`` bytes long (PATH_MAX is 4096): a valid folder name
    that ``results.parquet.<pid>.partial`` inside it makes too long."""
    path = str(folder.absolute())
    while len(path) < length:
        path += "/" + "l" * min(200, max(1, length - len(path) - 1))
    return path


def _fill(args, paths) -> list[str]:
    out = []
    for a in args:
        for k, v in paths.items():
            a = a.replace("{" + k + "}", v)
        out.append(a)
    return out


@pytest.mark.parametrize("args, message, env", CASES)
def test_a_bad_output_place_is_one_line_exit_2_before_anything_runs(
    args, message, env, places, tmp_path, capsys, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "out"
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC)
    (tmp_path / "fspec.toml").write_text(FSPEC)
    if not MOUNT:  # the tiny filesystem stands for itself only when mounted: raise the floor instead
        if "{tiny}" in " ".join(args):
            monkeypatch.setenv("EGO_MIN_FREE_MB", str(10**9))
    paths = {
        **places,
        "out": str(out),
        "spec": str(spec),
        "fspec": str(tmp_path / "fspec.toml"),
        "long": _near_path_max(out),
    }
    occupy = [a for a in args if a.startswith("@")]
    args = [a for a in args if not a.startswith("@")]
    for o in occupy:
        out.mkdir(exist_ok=True)
        _occupy(out, o)
    before, started = _tree(tmp_path), SumoBridge.started
    root_before = _tree(Path(places["root"])) if MOUNT or not os.access(places["ro"], os.W_OK) else None
    shipped = {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in (DEFAULT_MODEL, TUNED_PRESET)}
    package = _tree(DEFAULT_MODEL.parent)
    t0 = time.monotonic()
    status = main(_fill(args, paths))
    res = capsys.readouterr()
    assert status == 2, res.err
    assert res.out == ""
    assert res.err.startswith("ego: error: ") and res.err.count("\n") == 1, res.err
    assert "Traceback" not in res.err
    assert _fill([message], paths)[0] in res.err
    assert _tree(tmp_path) == before  # nothing written
    if root_before is not None:
        assert _tree(Path(places["root"])) == root_before
    assert SumoBridge.started == started
    assert {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in shipped} == shipped
    assert _tree(DEFAULT_MODEL.parent) == package
    assert time.monotonic() - t0 < 15


def test_a_harmless_extra_name_inside_out_is_not_refused(tmp_path):
    """The checks refuse occupied names only: another file in runs/ is fine."""
    from ego.compare import plan
    from ego.paths import check_compare_outputs

    out = tmp_path / "out"
    (out / "runs" / "notes.txt").parent.mkdir(parents=True)
    (out / "runs" / "notes.txt").write_text("mine")
    specs = plan("emergency-brake", ["pid"], 1, {}, out)
    check_compare_outputs(out, specs, None)


def test_the_catalogue_is_big_enough_and_its_ids_unique():
    ids = [c.id for c in CASES]
    assert len(ids) == len(set(ids))
    assert len(ids) >= 140


# -- odd inputs in Python ---------------------------------------------------------------------------


def _gains_file(path: Path, text: str) -> str:
    path.write_text(text)
    return str(path)


def _shipped_model(path: Path, change: dict | None = None, member: tuple[str, bytes] | None = None) -> str:
    with np.load(DEFAULT_MODEL) as data:
        arrays = {k: data[k] for k in data.files}
    arrays.update(change or {})
    np.savez(path, **arrays)
    if member is not None:
        with zipfile.ZipFile(path, "a") as z:
            z.writestr(*member)
    shutil.copy(DEFAULT_MODEL.with_suffix(".json"), path.with_suffix(".json"))
    return str(path)


def _huge_header_model(path: Path) -> str:
    """A model whose std member's header claims 10^12 values."""
    _shipped_model(path)
    header = {"descr": "<f8", "fortran_order": False, "shape": (10**12,)}
    import io

    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, header)
    data = buf.getvalue()
    tmp = path.with_suffix(".tmp.npz")
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(tmp, "w") as dst:
        for info in src.infolist():
            payload = src.read(info)
            if info.filename == "std.npy":
                payload = b"\x93NUMPY\x01\x00" + data[8:] + b"\0" * 96
            dst.writestr(info.filename, payload)
    tmp.replace(path)
    return str(path)


def _nets_copy(tmp_path: Path, how: str) -> str:
    dst = tmp_path / f"nets-{how}"
    shutil.copytree(nets_dir(), dst, ignore=shutil.ignore_patterns("*.py", "__pycache__"))
    net = dst / "highway" / "highway.net.xml"
    if how == "no-length":
        import re

        net.write_text(re.sub(r' length="[^"]*"', "", net.read_text()))
    elif how == "other-scenario":
        shutil.copy(dst / "platoon" / "platoon.net.xml", net)
    elif how == "fewer-lanes":
        shutil.copy(
            dst / "lane_centering" / "lane_centering.net.xml",
            dst / "platoon" / "platoon.net.xml",
        )
    return str(dst)


def test_odd_inputs_in_python_are_config_errors(tmp_path, monkeypatch):
    from ego.compare import compare
    from ego.control.cascade import load_preset
    from ego.control.narma import NarmaModel
    from ego.falsify import spec as falsify_spec
    from ego.runner import RunSpec, resolve
    from ego.sweep import spec as sweep_spec

    cases = {
        "spec.parse(None)": (lambda: sweep_spec.parse(None), "expected a table"),
        "spec.parse([])": (lambda: sweep_spec.parse([]), "expected a table"),
        "spec.load(5)": (lambda: sweep_spec.load(5), "bad sweep spec path 5"),
        "spec.load(/dev/zero)": (lambda: sweep_spec.load("/dev/zero"), "not a regular file (a device"),
        "falsify load(/dev/zero)": (lambda: falsify_spec.load("/dev/zero"), "not a regular file (a device"),
        "falsify load(folder)": (lambda: falsify_spec.load(str(tmp_path)), "it is a folder"),
        "spec.load(folder)": (lambda: sweep_spec.load(str(tmp_path)), "it is a folder"),
        "compare(out=5)": (
            lambda: compare("emergency-brake", ["pid"], 1, {}, 5),
            "bad out 5",
        ),
        "RunSpec(label=5)": (
            lambda: RunSpec("emergency-brake", "pid", label=5),
            "bad label 5",
        ),
        "RunSpec(trace=5)": (
            lambda: RunSpec("emergency-brake", "pid", trace=5),
            "bad trace 5",
        ),
        "gains-duplicate-key": (
            lambda: load_preset(_gains_file(tmp_path / "dup.json", '{"gains": [1], "gains": [2]}')),
            "given twice",
        ),
        "gains-deep-nesting": (
            lambda: load_preset(_gains_file(tmp_path / "deep.json", "[" * 100000 + "]" * 100000)),
            "nested too deeply",
        ),
        "model-std-denormal": (
            lambda: NarmaModel.load(_shipped_model(tmp_path / "denormal.npz", {"std": np.full(5, 1e-320)})),
            "std",
        ),
        "model-member-not-npy": (
            lambda: NarmaModel.load(_shipped_model(tmp_path / "member.npz", member=("notes.txt", b"hello"))),
            "not npy data",
        ),
        "model-member-garbage-npy": (
            lambda: NarmaModel.load(_shipped_model(tmp_path / "garbage.npz", member=("extra.npy", b"garbage"))),
            "not npy data",
        ),
        "model-header-10^12": (
            lambda: NarmaModel.load(_huge_header_model(tmp_path / "huge.npz")),
            "claims",
        ),
        "model-metadata-deep": (
            lambda: (
                _shipped_model(tmp_path / "deepmeta.npz"),
                (tmp_path / "deepmeta.json").write_text('{"a":' * 50000 + "1" + "}" * 50000),
                NarmaModel.load(tmp_path / "deepmeta.npz"),
            ),
            "nested too deeply",
        ),
    }
    with np.load(DEFAULT_MODEL) as data:  # the denormal case needs the model's own std length
        n = data["std"].size
    cases["model-std-denormal"] = (
        lambda: NarmaModel.load(_shipped_model(tmp_path / "denormal.npz", {"std": np.full(n, 1e-320)})),
        "std",
    )
    for name, (call, message) in cases.items():
        with pytest.raises(ConfigError) as info:
            call()
        assert message in str(info.value), (name, str(info.value))
        assert "\n" not in str(info.value), name
    assert RunSpec("emergency-brake", "pid", seed=np.int64(3)).seed == 3
    assert type(RunSpec("emergency-brake", "pid", seed=np.int64(3)).seed) is int
    resolve(RunSpec("emergency-brake", "pid", seed=np.int32(7)))
    for how, message in (
        ("no-length", "without a valid length"),
        ("other-scenario", "is not the highway network"),
        ("fewer-lanes", "is not the platoon network"),
    ):
        monkeypatch.setenv("EGO_SUMO_NETS", _nets_copy(tmp_path, how))
        scenario = "platoon" if how == "fewer-lanes" else "emergency-brake"
        controller = "bp-pid-acc" if how == "fewer-lanes" else "pid"
        with pytest.raises(ConfigError, match=message):
            resolve(RunSpec(scenario, controller))


def test_sweep_spec_values_are_checked_against_set_not_defaults():
    from ego.sweep import spec as sweep_spec

    ok = sweep_spec.parse(
        {
            "scenario": "emergency-brake",
            "controllers": ["pid"],
            "set": {"duration": 40},
            "grid": {"lead_brake_time": [30]},
        }
    )
    assert ok.count() == 1
    for data, message in [
        (
            {"set": {"duration": 3}, "grid": {"lead_brake_time": [2, 10]}},
            "lead_brake_time: 10",
        ),
        ({"grid": {"ego_speed": [20, "25"]}}, "mixes numbers and text"),
        ({"grid": {"abs": [True, "false"]}}, "mixes"),
        ({"grid": {"ego_speed": [20, 20.0]}}, "twice"),
        ({"grid": {"ego_speed": [20, 25, 20]}}, "twice"),
        ({"grid": {"abs": [True, True]}}, "twice"),
        ({"grid": {"duration": [3, 40], "lead_brake_time": [10]}}, "duration = 3"),
    ]:
        with pytest.raises(ConfigError, match=message):
            sweep_spec.parse({"scenario": "emergency-brake", "controllers": ["pid"], **data})


# -- the sweep's results file ---------------------------------------------------------------------------


def _ego(*args, cwd, env=None, timeout=240, preexec_fn=None, stdout=subprocess.PIPE):
    """``python -m ego ARGS`` in a session of its own; the result's ``pid`` is its session id."""
    full_env = dict(os.environ, **(env or {}))
    proc = subprocess.Popen(
        [sys.executable, "-m", "ego", *args],
        cwd=cwd,
        env=full_env,
        stdout=stdout,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=preexec_fn,  # noqa: PLW1509 - sets a limit only, before exec
        start_new_session=True,
    )
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        raise
    res = subprocess.CompletedProcess(proc.args, proc.returncode, out, err)
    res.pid = proc.pid
    return res


def _one_line_error(res, status: int, *needles: str) -> None:
    assert res.returncode == status, (res.returncode, res.stderr[-2000:])
    lines = [line for line in res.stderr.splitlines() if line.startswith("ego: error: ")]
    assert len(lines) == 1, res.stderr[-2000:]
    assert "Traceback" not in res.stderr and "Exception ignored" not in res.stderr, res.stderr[-2000:]
    for needle in needles:
        assert needle in lines[0], lines[0]


def test_sweep_results_that_cannot_take_the_new_rows_are_refused_before_running(
    tmp_path,
):
    import pyarrow as pa
    import pyarrow.parquet as pq

    (tmp_path / "a.toml").write_text(
        'scenario = "emergency-brake"\ncontrollers = ["pid"]\n[set]\nduration = 2\n[grid]\nabs = ["true", "false"]\n'
    )
    (tmp_path / "b.toml").write_text(
        'scenario = "emergency-brake"\ncontrollers = ["pid"]\n[set]\nduration = 2\n[grid]\nabs = [true, false]\n'
    )
    (tmp_path / "c.toml").write_text('scenario = "fast-follower"\ncontrollers = ["pid"]\n[set]\nduration = 2\n')
    first = _ego("sweep", "a.toml", "--out", "o", "--jobs", "1", "--record", "none", cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    before = (tmp_path / "o" / "results.parquet").read_bytes()
    for spec, needle in (
        ("b.toml", "column abs holds text"),
        ("c.toml", "holds results of emergency-brake"),
    ):
        res = _ego("sweep", spec, "--out", "o", "--jobs", "1", cwd=tmp_path)
        _one_line_error(res, 2, needle)
        assert (tmp_path / "o" / "results.parquet").read_bytes() == before
    (tmp_path / "p").mkdir()
    pq.write_table(pa.table({"x": [1, 2]}), tmp_path / "p" / "results.parquet")
    res = _ego("sweep", "b.toml", "--out", "p", cwd=tmp_path)
    _one_line_error(res, 2, "no run_id column")
    assert sorted(p.name for p in (tmp_path / "p").iterdir()) == ["results.parquet"]


def test_a_results_file_with_odd_rows_keeps_them_as_text(tmp_path):
    """Rows whose values cannot share a column type are kept (as text), never lost."""
    from ego.sweep.results import ResultStore

    store = ResultStore(tmp_path, flush_rows=1000)
    store.add({"run_id": "a", "scenario": "s", "controller": "c", "seed": 0, "m": 1.5})
    store.add({"run_id": "b", "scenario": "s", "controller": "c", "seed": 0, "m": "odd"})
    store.flush()
    store.add({"run_id": "c", "scenario": "s", "controller": "c", "seed": 0, "m": True})
    store.flush()
    assert store.table().column("m").to_pylist() == ["1.5", "odd", "true"]


# -- a disk that fills during the run ---------------------------------------------------------------------


class FullDisk:
    """A place where a write fails after the checks: a tmpfs with ~``room`` bytes free (and the
    free-space floor off) when this process may mount one, else ``RLIMIT_FSIZE`` of ``room``
    bytes in the child (every file it writes is limited: EFBIG)."""

    def __init__(self, root: Path, room: int) -> None:
        self.root = root
        self.room = room
        self.mounted = False

    def __enter__(self) -> Self:
        self.root.mkdir(parents=True, exist_ok=True)
        if MOUNT:
            subprocess.run(
                ["mount", "-t", "tmpfs", "-o", "size=4m", "tmpfs", str(self.root)],
                check=True,
            )
            self.mounted = True
            free = os.statvfs(self.root).f_bavail * os.statvfs(self.root).f_frsize
            with open(self.root / ".filler", "wb") as f:
                f.write(b"\0" * max(0, free - self.room))
        return self

    def __exit__(self, *exc) -> None:
        if self.mounted:
            subprocess.run(["umount", "-l", str(self.root)], check=False)

    @property
    def env(self) -> dict:
        return {"EGO_MIN_FREE_MB": "0"}

    def preexec(self):
        if self.mounted:
            return None
        room = self.room

        def limit() -> None:
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
            resource.setrlimit(resource.RLIMIT_FSIZE, (room, room))

        return limit

    def files(self) -> list[str]:
        return sorted(str(p.relative_to(self.root)) for p in self.root.rglob("*") if p.name != ".filler")


@pytest.mark.parametrize(
    "option, name, room",
    [
        ("--trace", "t.csv", 20_000),
        ("--trace", "t.parquet", 8_000),
        ("--trace", "t.mat", 20_000),
        ("--record", "r.rrd", 20_000),
        ("--video", "v.gif", 20_000),
    ],
)
def test_a_run_whose_output_fills_the_disk_prints_its_metrics_and_one_line(option, name, room, tmp_path, monkeypatch):
    run = EB + (["--backend", "highway-env"] if option == "--video" else [])
    monkeypatch.setenv("MPLCONFIGDIR", str(tmp_path / "mpl"))
    with FullDisk(tmp_path / "disk", room) as disk:
        res = _ego(
            *run,
            option,
            str(disk.root / name),
            "--json",
            cwd=tmp_path,
            env=disk.env,
            preexec_fn=disk.preexec(),
        )
        _one_line_error(res, 1, "cannot write", str(disk.root / name).rsplit(".", 1)[0], "Errno")
        metrics = json.loads(res.stdout)  # the metrics are still printed, the status unchanged
        assert metrics["status"] in ("completed", "ended", "timeout")
        assert metrics["status"] == json.loads(_ego(*run, "--json", cwd=tmp_path).stdout)["status"]
        assert disk.files() == []  # no partial, no half file under the final name


def test_a_sweep_whose_results_fill_the_disk_stops_in_one_line_without_hanging(
    tmp_path,
):
    (tmp_path / "s.toml").write_text(SPEC)
    with FullDisk(tmp_path / "disk", 6_000) as disk:  # room for the lock, not for the results
        t0 = time.monotonic()
        res = _ego(
            "sweep",
            "s.toml",
            "--out",
            str(disk.root / "o"),
            "--jobs",
            "2",
            "--record",
            "none",
            cwd=tmp_path,
            env=disk.env,
            preexec_fn=disk.preexec(),
            timeout=120,
        )
        _one_line_error(res, 1, "results.parquet", "Errno")
        assert time.monotonic() - t0 < 100
        assert not [f for f in disk.files() if f.endswith(".partial")]
        assert not _session_left(res.pid), "worker processes outlived the sweep"


def _session_left(sid: int) -> list[int]:
    """Processes still alive in the session the command led (its workers, fork server...)."""
    import psutil

    deadline = time.monotonic() + 10
    while True:
        left = []
        for p in psutil.process_iter(["pid", "status"]):
            try:
                if os.getsid(p.pid) == sid and p.info["status"] != psutil.STATUS_ZOMBIE:
                    left.append(p.pid)
            except OSError:
                pass
        if not left or time.monotonic() > deadline:
            return left
        time.sleep(0.2)


def test_a_sweep_recording_every_run_on_a_full_disk_keeps_the_metrics(tmp_path):
    """--record all on a disk without room: each row keeps its metrics and names the
    recording it could not write; no recording, whole or partial, is left."""
    import pyarrow.parquet as pq

    (tmp_path / "s.toml").write_text(SPEC)
    with FullDisk(tmp_path / "disk", 60_000) as disk:
        out = disk.root / "o"
        res = _ego(
            "sweep",
            "s.toml",
            "--out",
            str(out),
            "--jobs",
            "1",
            "--record",
            "all",
            cwd=tmp_path,
            env=disk.env,
            preexec_fn=disk.preexec(),
            timeout=180,
        )
        assert "Traceback" not in res.stderr, res.stderr[-2000:]
        assert not [f for f in disk.files() if f.endswith((".partial", ".rrd"))], disk.files()
        if res.returncode == 0:
            table = pq.read_table(out / "results.parquet").to_pydict()
            assert set(table["status"]) <= {
                "completed",
                "ended",
                "timeout",
                "collision",
            }, table["status"]
            assert all("cannot write" in e and "Errno" in e for e in table["error"]), table["error"]
            assert all(isinstance(v, float) for v in table["sim_time"])
        else:  # the results file itself did not fit: one line, exit 1
            _one_line_error(res, 1, "cannot write", "Errno")
        assert not _session_left(res.pid)


@pytest.mark.parametrize(
    "args, room",
    [
        (
            [
                "train",
                "narma-l2",
                "--samples",
                "400",
                "--epochs",
                "1",
                "--out",
                "{disk}/m.npz",
            ],
            2_000,
        ),
        (["tune", "lane-centering", "--quick", "--out", "{disk}/g.json"], 100),
        (
            [
                "compare",
                "emergency-brake",
                "--controllers",
                "pid",
                "--set",
                "duration=4",
                "--out",
                "{disk}/c",
            ],
            0,
        ),
    ],
)
def test_train_tune_compare_on_a_full_disk_end_in_one_line(args, room, tmp_path):
    with FullDisk(tmp_path / "disk", room) as disk:
        res = _ego(
            *[a.replace("{disk}", str(disk.root)) for a in args],
            cwd=tmp_path,
            env=disk.env,
            preexec_fn=disk.preexec(),
        )
        _one_line_error(res, 1, "cannot write", "Errno")
        assert not [f for f in disk.files() if f.endswith(".partial")]


@pytest.mark.parametrize(
    "args",
    [
        ["list"],
        ["list", "--json"],
        ["list", "--markdown"],
        [*EB, "--json"],
        ["--version"],
    ],
)
def test_stdout_on_a_full_device_is_one_line(args, tmp_path):
    with open("/dev/full", "w") as full:
        res = _ego(*args, cwd=tmp_path, stdout=full)
    _one_line_error(res, 1, "No space left on device")


def test_the_shipped_files_survive_train_and_tune_pointed_at_them(tmp_path):
    before = {p: p.read_bytes() for p in (DEFAULT_MODEL, TUNED_PRESET)}
    res = _ego(
        "train",
        "narma-l2",
        "--samples",
        "400",
        "--epochs",
        "1",
        "--out",
        str(DEFAULT_MODEL),
        cwd=tmp_path,
    )
    _one_line_error(res, 2, "--install")
    res = _ego("tune", "lane-centering", "--quick", "--out", str(TUNED_PRESET), cwd=tmp_path)
    _one_line_error(res, 2, "--install")
    assert {p: p.read_bytes() for p in before} == before


# -- signals in the first second ------------------------------------------------------------------------------


def _rerun_env(tmp_path: Path) -> dict:
    return {
        "XDG_CONFIG_HOME": str(tmp_path / "xdg-config"),
        "XDG_DATA_HOME": str(tmp_path / "xdg-data"),
    }


def _verify(path: Path, tmp_path: Path) -> bool:
    rerun = Path(sys.executable).with_name("rerun")
    res = subprocess.run(
        [str(rerun), "rrd", "verify", str(path)],
        check=False,
        capture_output=True,
        text=True,
        timeout=120,
        env=dict(os.environ, **_rerun_env(tmp_path)),
    )
    return res.returncode == 0


#: a run long enough that a signal within its first two seconds always lands during it (a quiet
#: fast machine finishes EB's 4 s in under a second)
EB_LONG = [*EB[:-1], "duration=30"]


def _launch(tmp_path: Path, *extra: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "ego", *EB_LONG, "--record", str(tmp_path / "r.rrd"), *extra],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        env=dict(os.environ, **_rerun_env(tmp_path)),
    )


@pytest.mark.parametrize("delay", [0.35, 0.5, 0.7, 1.0])
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_signal_in_the_first_second_is_exit_130_without_a_traceback(sig, delay, tmp_path):
    proc = _launch(tmp_path)
    time.sleep(delay)
    os.killpg(proc.pid, sig) if sig == signal.SIGINT else proc.send_signal(sig)  # Ctrl-C reaches the group
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, (proc.returncode, err)
    assert "Traceback" not in err and "Exception ignored" not in err, err
    assert "ego: interrupted" in err or "INTERRUPTED" in out, (out, err)
    assert not list(tmp_path.glob("*.partial")), list(tmp_path.iterdir())
    if (tmp_path / "r.rrd").exists():
        assert _verify(tmp_path / "r.rrd", tmp_path)


@pytest.mark.parametrize("delay", [0.4, 0.8, 1.2, 1.6, 2.0])
def test_a_double_ctrl_c_never_leaves_a_broken_recording(delay, tmp_path):
    proc = _launch(tmp_path)
    time.sleep(delay)
    os.killpg(proc.pid, signal.SIGINT)
    time.sleep(0.05)
    try:
        os.killpg(proc.pid, signal.SIGINT)
    except ProcessLookupError:
        pass
    _out, err = proc.communicate(timeout=120)
    assert proc.returncode in (0, 1, 130), (proc.returncode, err)
    assert "Traceback" not in err and "Exception ignored" not in err, err
    for path in tmp_path.glob("r.rrd*"):  # a final recording or a partial one: each whole
        assert _verify(path, tmp_path), path
    assert not list(tmp_path.glob("*.partial"))


def test_a_recorder_whose_writer_never_started_is_collected_quietly():
    from ego.record.rerun_recorder import RerunRecorder

    rec = RerunRecorder.__new__(RerunRecorder)
    import multiprocessing

    rec._proc = multiprocessing.get_context("spawn").Process(target=print)  # made, never started
    rec.__del__()


def test_a_ctrl_c_landing_in_a_finaliser_prints_nothing_and_other_errors_still_do():
    # the double Ctrl-C above, when the second KeyboardInterrupt lands in a weakref callback
    # (an import's module lock): Python would print "Exception ignored in ..." with a traceback
    code = (
        "import sys, weakref\n"
        "import ego._entry as entry\n"
        "sys.unraisablehook = entry._unraisable()\n"
        "class A: pass\n"
        "def interrupted(ref): raise KeyboardInterrupt\n"
        "def broken(ref): raise ValueError('a real error')\n"
        "a, b = A(), A()\n"
        "ra, rb = weakref.ref(a, interrupted), weakref.ref(b, broken)\n"
        "del a\n"
        "print('still running', flush=True)\n"
        "del b\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0 and proc.stdout == "still running\n"
    assert "KeyboardInterrupt" not in proc.stderr
    assert "Exception ignored" in proc.stderr and "ValueError: a real error" in proc.stderr
