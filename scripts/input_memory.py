"""Peak memory of ego refusing each hostile input of the catalogue (tests/hostile_inputs.py):
every case in a process of its own (``python -m ego ...``), its peak resident set size read
from the kernel's accounting of that child (``os.wait4`` in a small starter process: Linux
counts a process's pre-exec parent memory into its peak otherwise), against the 500 MB bound of
docs/reliability.md ("Limits").

    python scripts/input_memory.py            # the table; exit 1 if a case passes the bound
    python scripts/input_memory.py --bound 400

Each row: the case, the size of the largest input file it names (the sparse 17 MiB .xosc
takes no disk), ego's exit status (2: refused), and the peak. The first three rows are
legal inputs for scale: ``ego list`` and ``ego run`` of the shipped emergency_brake.xosc,
and ``ego list`` of a file with 9,999 parameter declarations (just under the limit).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))


#: a small process (no site packages) that starts ``python ARGS`` and reports its peak: the
#: kernel's maxrss of a process counts the memory of the process it was forked from (Linux
#: carries the pre-exec high-water mark over exec), so the child must come from a small one
_STARTER = (
    "import os, sys\n"
    "pid = os.fork()\n"
    "if pid == 0:\n"
    "    os.execv(sys.executable, [sys.executable] + sys.argv[1:])\n"
    "_, status, usage = os.wait4(pid, 0)\n"
    "sys.stderr.write('EGO-PEAK-KIB %d\\n' % usage.ru_maxrss)\n"
    "sys.exit(os.waitstatus_to_exitcode(status))\n"
)


def peak_of(argv: list[str], tmp: Path) -> tuple[int, float]:
    """(exit status, peak resident set size in MB) of ``python -m ego argv``, measured by the
    kernel for that process alone (``os.wait4`` in a small starter process)."""
    env = dict(os.environ, TMPDIR=str(tmp), PYTHONPATH=str(ROOT))
    proc = subprocess.run(
        [sys.executable, "-S", "-c", _STARTER, "-m", "ego", *argv],
        cwd=tmp,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    kib = [int(line.split()[1]) for line in proc.stderr.splitlines() if line.startswith("EGO-PEAK-KIB ")]
    if not kib:
        raise RuntimeError(f"no peak reported for {argv}: {proc.stderr[-500:]}")
    return proc.returncode, kib[-1] / 1024.0


def largest_input(argv: list[str]) -> float:
    sizes = [os.stat(a).st_size for a in argv if os.path.isfile(a)]
    return max(sizes, default=0) / 2**20


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--bound", type=float, default=500.0, help="MB a case may reach (default 500)")
    args = ap.parse_args(argv)
    from hostile_inputs import CASES, EB_XOSC, XOSC_DIR, build, fill

    over = []
    with tempfile.TemporaryDirectory(prefix="ego-input-memory-") as tmp:
        (Path(tmp) / "files").mkdir()
        files = build(Path(tmp) / "files")
        rows = [("baseline: ego list emergency_brake.xosc", ["list", str(XOSC_DIR / "emergency_brake.xosc")])]
        rows.append(
            ("a run: ego run emergency_brake.xosc", ["run", str(XOSC_DIR / "emergency_brake.xosc"), "-c", "pid"])
        )
        legal = Path(tmp) / "files" / "9999-declarations.xosc"  # just under the 10,000 limit: read whole
        decls = "".join(f'<ParameterDeclaration name="p{i}" parameterType="double" value="1"/>' for i in range(9_990))
        legal.write_text(EB_XOSC.replace("<ParameterDeclarations>", "<ParameterDeclarations>" + decls, 1))
        rows.append(("legal: ego list of 9,999 declarations", ["list", str(legal)]))
        rows += [(case, fill(list(a), files, Path(tmp))) for case, a, _ in CASES]
        print(f"{'case':44s} {'input MiB':>9s} {'exit':>4s} {'peak MB':>8s}")
        for i, (case, a) in enumerate(rows):
            work = Path(tmp) / f"run{i}"
            work.mkdir()
            code, peak = peak_of(a, work)
            print(f"{case:44s} {largest_input(a):9.2f} {code:4d} {peak:8.1f}", flush=True)
            if peak > args.bound:
                over.append(case)
    print(f"{len(rows)} cases; peak above {args.bound:g} MB: {', '.join(over) if over else 'none'}")
    return 1 if over else 0


if __name__ == "__main__":
    sys.exit(main())
