"""The tables of docs/results/openscenario.md (``python -m ego.docs results --page
openscenario``): the CCR matrices run from the .xosc files, and the equivalence of every
shipped file that mirrors a built-in scenario with that scenario, run for run."""

from __future__ import annotations

import itertools
from pathlib import Path

from ego.docs.common import KMH, ROOT, SWEEPS, TRACKING, Row, Table, ccr_cell, sim

XOSC = ROOT / "scenarios" / "openscenario"
PAGE = "openscenario"
#: metrics that name the scenario or measure the machine, or that only multi-backend
#: scenarios report
NOT_COMPARED = ("scenario", "wall_time", "backend")


def _header(spec) -> tuple[str, ...]:
    labels = [
        ", ".join(f"{v * KMH:.0f} km/h" if k == "EgoSpeed" else f"{k} {v:g}" for k, v in zip(spec.grid, point))
        for point in itertools.product(*spec.grid.values())
    ]
    return ("controller",) + tuple(labels)


def _spec_jobs(path: Path):
    from ego.sweep.spec import load

    spec = load(path)
    return spec, [(r.controller, sim(r.scenario, r.controller, r.seed, **r.overrides)) for r in spec.runs()]


def ccr_tables() -> list[Table]:
    out = []
    for test in ("s", "m", "b"):
        path = XOSC / f"ccr-{test}.toml"
        spec, jobs = _spec_jobs(path)
        rows = tuple(
            Row(c, tuple(j for n, j in jobs if n == c), lambda ms: [ccr_cell(m) for m in ms]) for c in spec.controllers
        )
        out.append(
            Table(
                f"xosc-ccr{test}",
                PAGE,
                (f"ego sweep {path.relative_to(ROOT)} --out runs/xosc-ccr-{test}",),
                _header(spec),
                rows,
            )
        )
    return out


def _differences(ms: list[dict]) -> list[str]:
    """Cells comparing the first half of the runs (built-in) with the second (file), pair by pair."""
    half = len(ms) // 2
    pairs = list(zip(ms[:half], ms[half:]))
    same = sum(all(b.get(k) == a[k] for k in a if k not in NOT_COMPARED) for a, b in pairs)
    gaps = [
        abs(a["min_gap_front"] - b["min_gap_front"])
        for a, b in pairs
        if a.get("min_gap_front") is not None and b.get("min_gap_front") is not None
    ]
    hits = [
        abs(a["impact_speed"] - b["impact_speed"]) * KMH
        for a, b in pairs
        if a.get("impact_speed") is not None and b.get("impact_speed") is not None
    ]
    return [
        str(len(pairs)),
        f"{same}/{len(pairs)}",
        f"{max(gaps):.4f}" if gaps else "-",
        f"{max(hits):.4f}" if hits else "- (no impacts)",
    ]


def equivalence_table() -> Table:
    rows = []
    eb = str(XOSC / "emergency_brake.xosc")
    for c in TRACKING:
        rows.append(
            Row(f"emergency_brake.xosc / emergency-brake, {c}", (sim("emergency-brake", c), sim(eb, c)), _differences)
        )
    for test in ("s", "m", "b"):
        _, toml = _spec_jobs(SWEEPS / f"aeb-ccr-{test}.toml")
        _, xosc = _spec_jobs(XOSC / f"ccr-{test}.toml")
        rows.append(
            Row(
                f"ccr-{test}.toml / aeb-ccr-{test}.toml, every controller",
                tuple(j for _, j in toml) + tuple(j for _, j in xosc),
                _differences,
            )
        )
    for trigger in (1.5, 1.0):  # later triggers: collisions, so impact speeds are compared too
        for test in ("s", "b"):
            _, toml = _spec_jobs(SWEEPS / f"aeb-ccr-{test}.toml")
            _, xosc = _spec_jobs(XOSC / f"ccr-{test}.toml")
            extra = (("ttc_threshold", trigger),)
            toml = [
                (c, type(j)(j.scenario, j.controller, j.seed, tuple(sorted(dict(j.overrides + extra).items()))))
                for c, j in toml
            ]
            xosc = [
                (c, type(j)(j.scenario, j.controller, j.seed, tuple(sorted(dict(j.overrides + extra).items()))))
                for c, j in xosc
            ]
            rows.append(
                Row(
                    f"ccr-{test}.toml / aeb-ccr-{test}.toml, ttc_threshold = {trigger:g}",
                    tuple(j for _, j in toml) + tuple(j for _, j in xosc),
                    _differences,
                )
            )
    return Table(
        "xosc-equivalence",
        PAGE,
        (
            "ego run scenarios/openscenario/emergency_brake.xosc -c pid",
            "ego sweep scenarios/openscenario/ccr-s.toml --out runs/xosc-ccr-s",
        ),
        (
            "file / built-in",
            "runs",
            "identical metrics",
            "largest gap difference [m]",
            "largest impact speed difference [km/h]",
        ),
        tuple(rows),
        (
            "Identical metrics: every metric of the run equal (the scenario's name, the wall time and "
            "the built-in's backend aside). The CCR rows pair each run of the TOML sweep with the "
            ".xosc sweep's run of the same cell.",
        ),
    )


def tables() -> list[Table]:
    return [equivalence_table(), *ccr_tables()]
