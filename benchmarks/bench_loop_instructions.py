"""The loop against bare SUMO in instructions, which a busy machine does not change.

    python benchmarks/bench_loop_instructions.py [--scenario emergency-brake] [--controller fuzzy]
                                                 [--set key=value ...] [--tree PATH]

``benchmarks/bench_loop.py`` divides CPU times, and on a shared VM the same code reads
1.65-2.3x from one minute to the next (bare SUMO's step itself moves from ~200 to ~360 us).
This script counts instructions instead, with valgrind's callgrind: two processes, each with
one warm-up run (imports, caches) and then one measured part, collection switched on and off
around it by callgrind's client request (a small C helper compiled here):

* the loop: ``scenario.step(controller.step(obs))`` until the run ends, no recording;
* bare SUMO: ``simulationStep()`` on the same traffic (the same scenario, seed and values,
  no control), as many SUMO steps as the loop took.

Printed: both counts, their ratio (issue 18's target: <= 1.8 without recording) and ego's
own instructions per SUMO step; with ``--parts``, the loop's count split (inclusive, by
``callgrind_annotate``) into SUMO's step, SUMO's ``moveToXY`` (the ego's pose pushed every
step) and ego's own (the rest: Python, the C kernels of ``ego._native``, each also printed, and
libsumo's other calls). Comparing two roads part by part says which side a difference is on (issue 38). ``--tree`` measures another checkout (``git worktree add``)
with this script, to compare two versions in the same session (its code and its
``sumo_nets``). Needs ``valgrind`` and its
headers (Debian: ``apt-get install valgrind``) and a C compiler; each count takes one to
two minutes (the two run at once on two cores).
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent

_HELPER = """#include <valgrind/callgrind.h>
void ego_bench_toggle(void) { CALLGRIND_TOGGLE_COLLECT; }
"""

#: the measured process: argv = tree, helper, mode, scenario, controller, steps, overrides...
_CHILD = r"""
import ctypes, sys
tree, helper, mode, scenario, controller, steps = sys.argv[1:7]
sys.path.insert(0, tree)
from ego.params import parse_overrides
from ego.runner import RunSpec, build
toggle = ctypes.CDLL(helper).ego_bench_toggle
overrides = parse_overrides(sys.argv[7:])

def loop(measure):
    sc = build(RunSpec(scenario, controller, 0, overrides))
    try:
        obs = sc.reset()
        ctrl = sc.controller
        if measure:
            toggle()
        while not sc.done:
            obs = sc.step(ctrl.step(obs))
        if measure:
            toggle()
        return sc.k // sc.config.control_per_sumo
    finally:
        sc.close()

def bare(measure, n):
    sc = build(RunSpec(scenario, "none", 0, overrides))
    try:
        sc.reset()
        step = sc.bridge.libsumo.simulationStep
        if measure:
            toggle()
        for _ in range(n):
            step()
        if measure:
            toggle()
        return n
    finally:
        sc.close()

if mode == "loop":
    loop(False)
    print("sumo_steps", loop(True))
else:
    bare(False, int(steps))
    print("sumo_steps", bare(True, int(steps)))
"""


def _collected(text: str) -> int:
    m = re.search(r"Collected\s*:\s*(\d+)", text)
    if m is None:
        raise RuntimeError(f"callgrind printed no count:\n{text[-2000:]}")
    return int(m.group(1))


def _start(work: Path, tree: str, mode: str, args, steps: int) -> subprocess.Popen:
    env = {
        **os.environ,
        "PYTHONHASHSEED": "0",
        "XDG_CONFIG_HOME": str(work),
        "XDG_DATA_HOME": str(work),
        "PYTHONPATH": tree,
        # the tree's own networks (the curved motorways are data: two trees may differ there)
        "EGO_SUMO_NETS": str(Path(tree) / "sumo_nets"),
    }
    cmd = [
        "valgrind",
        "--tool=callgrind",
        "--collect-atstart=no",
        f"--callgrind-out-file={work / (mode + '.out')}",
        sys.executable,
        str(work / "child.py"),
        tree,
        str(work / "libhelper.so"),
        mode,
        args.scenario,
        args.controller,
        str(steps),
        *args.set,
    ]
    return subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


#: the loop's parts (--parts): label -> the function whose inclusive count is the part
PARTS = {
    "SUMO's step (simulationStep)": "libsumo::Simulation::step(double)",
    "SUMO's moveToXY (the ego's pose)": "libsumo::Vehicle::moveToXY(",
}


def parts(out_file: Path) -> dict[str, int]:
    """Inclusive instructions of the loop's parts in a callgrind output (:data:`PARTS`, then
    every function of ``ego._native`` the loop called, by name; a function listed more than
    once (recursion) counts its largest figure)."""
    try:
        import ego._native as native

        kernels = {name for name in dir(native) if not name.startswith("_")}
    except ImportError:
        kernels = set()
    text = subprocess.run(
        ["callgrind_annotate", "--inclusive=yes", "--threshold=100", str(out_file)],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    found: dict[str, int] = {}
    for line in text.splitlines():
        m = re.match(r"\s*([\d,]+)\s+\([^)]*\)\s+(\S.*)$", line)
        if m is None or "=>" in line:
            continue
        count, name = int(m.group(1).replace(",", "")), m.group(2)
        for label, function in PARTS.items():
            if function in name and label not in found:
                found[label] = count
        kernel = re.search(r"_native\.c:(\w+) ", name)
        if kernel is not None and kernel.group(1) in kernels:
            label = f"ego._native.{kernel.group(1)}"
            found[label] = max(found.get(label, 0), count)
    return found


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="emergency-brake")
    ap.add_argument("--controller", default="fuzzy")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a scenario override")
    ap.add_argument("--tree", default=str(HERE.parent), help="the checkout to measure (default: this one)")
    ap.add_argument("--steps", type=int, default=250, help="bare SUMO steps when they cannot be read from the loop")
    ap.add_argument("--parts", action="store_true", help="split the loop's count into its parts")
    args = ap.parse_args(argv)
    for tool in ("valgrind", "cc"):
        if shutil.which(tool) is None:
            raise SystemExit(f"bench_loop_instructions: needs {tool} on PATH (apt-get install valgrind gcc)")
    with tempfile.TemporaryDirectory(prefix="ego-instructions-") as tmp:
        work = Path(tmp)
        (work / "helper.c").write_text(_HELPER)
        (work / "child.py").write_text(_CHILD)
        subprocess.run(
            ["cc", "-O2", "-shared", "-fPIC", str(work / "helper.c"), "-o", str(work / "libhelper.so")], check=True
        )
        # the loop's SUMO steps are known only after it; the default duration's steps
        # (250) start the bare count at the same time, and it is run again if they differ
        loop = _start(work, args.tree, "loop", args, args.steps)
        bare = _start(work, args.tree, "bare", args, args.steps)
        out_loop, err_loop = loop.communicate()
        out_bare, err_bare = bare.communicate()
        if loop.returncode or bare.returncode:
            raise SystemExit(f"bench_loop_instructions: a measured process failed:\n{(err_loop + err_bare)[-3000:]}")
        steps = int(out_loop.split()[-1])
        if steps != int(out_bare.split()[-1]):
            bare = _start(work, args.tree, "bare", args, steps)
            out_bare, err_bare = bare.communicate()
        n_loop, n_bare = _collected(err_loop), _collected(err_bare)
        split = parts(work / "loop.out") if args.parts else {}
    figures = {
        "sumo_steps": steps,
        "loop_instructions": n_loop,
        "bare_instructions": n_bare,
        "ratio": n_loop / n_bare,
        "ego_per_sumo_step": (n_loop - n_bare) / steps,
    }
    print(f"{args.scenario}, {args.controller}, no recording, {steps} SUMO steps, tree {args.tree}")
    print(f"  the loop                 {n_loop / 1e6:9.1f} M instructions")
    print(f"  bare SUMO, same traffic  {n_bare / 1e6:9.1f} M instructions")
    print(f"  loop / bare SUMO         {figures['ratio']:9.2f}     (target <= 1.8)")
    print(f"  ego's own per SUMO step  {figures['ego_per_sumo_step'] / 1e3:9.1f} k instructions")
    if split:
        # the kernels nest (look_between may call the Python look, which calls place and
        # nearest): ego's own is the loop less SUMO's two parts
        print("  the loop's parts (inclusive; the C kernels can nest):")
        for label, count in sorted(split.items(), key=lambda kv: -kv[1]):
            print(f"    {label:<38} {count / 1e6:9.1f} M")
        sumo = sum(split.get(label, 0) for label in PARTS)
        print(f"    {'ego own: the loop less the two above':<38} {(n_loop - sumo) / 1e6:9.1f} M")
        figures["parts"] = split
    return figures


if __name__ == "__main__":
    main()
