"""The tables of docs/results/alks.md (``python -m ego.docs results --page alks``): every
tracking controller and UN R157's careful driver (the reference, ``careful-driver``) on each
of ego's own ALKS scenario files (``scenarios/alks/``, written by
``scenarios/alks/make_alks.py``): the concrete files one run each, the variation files over
their combinations that meet the value constraints (a seeded subsample of :data:`SAMPLE` of
the larger ones, the same as ``ego sweep FILE --sample N --seed 0`` draws).

A collision's preventability is R157's question (``collision_preventable``, the
``--preventable`` of ``ego compare`` and ``ego sweep``): would the careful driver, on the same
concrete scenario, have avoided it?
"""

from __future__ import annotations

from pathlib import Path

from ego.docs.common import KMH, ROOT, TRACKING, Row, Table, sim
from ego.runner import REFERENCE_DRIVER, REFERENCE_OFF

PAGE = "alks"
ALKS = ROOT / "scenarios" / "alks"
#: the rows of every table: the tracking controllers, then the reference driver
DRIVERS = (*TRACKING, REFERENCE_DRIVER)
#: the reference row drives as ``collision_preventable``'s reference run does: without ego's
#: own AEB and evasion (R157's careful driver has neither; the files set ``evade=false``)
OFF = tuple(sorted(REFERENCE_OFF.items()))
#: a variation file with more combinations than this runs a seeded subsample of this many
SAMPLE = 40
SEED = 0


def concrete_files() -> list[Path]:
    return sorted(p for p in ALKS.glob("alks_*.xosc") if not p.stem.endswith("_variation"))


def variation_files() -> list[Path]:
    return sorted(ALKS.glob("alks_*_variation.xosc"))


def _fixed(v, digits: int = 2) -> str:
    return "-" if v is None else f"{v:.{digits}f}"


def _ttc(v) -> str:
    """A TTC (s): ``> 100`` above 100 s (never closing in earnest)."""
    return "-" if v is None else "> 100" if v > 100.0 else f"{v:.2f}"


def _collision(m: dict) -> str:
    if m["status"] not in ("completed", "collision", "timeout"):
        return m["status"]
    if not m.get("collision"):
        return "no"
    rel = m.get("impact_relative_speed")
    return f"**yes** ({m.get('collision_with')}, {rel * KMH:.1f} km/h)" if rel is not None else "**yes**"


def _preventable(m: dict, reference: bool) -> str:
    if reference:
        return "(reference)"
    if not m.get("collision"):
        return "-"
    p = m.get("collision_preventable")
    return "-" if p is None else ("**yes**" if p else "no")


def _concrete_cells(reference: bool):
    def cells(ms: list[dict]) -> list[str]:
        (m,) = ms
        return [
            _collision(m),
            _fixed(m.get("min_gap_front")),
            _ttc(m.get("min_ttc_front")),
            _fixed(m.get("max_lane_departure")),
            _preventable(m, reference),
        ]

    return cells


def _job(scenario: str, controller: str, overrides: dict):
    """One run of a row: a tracking controller with ``collision_preventable`` after a
    collision, the reference driver as the reference run drives."""
    if controller == REFERENCE_DRIVER:
        return sim(scenario, controller, **overrides, **dict(OFF))
    return sim(scenario, controller, preventable=None, **overrides)


def concrete_table() -> Table:
    rows = tuple(
        Row(f"{path.stem} / {c}", (_job(str(path), c, {}),), _concrete_cells(c == REFERENCE_DRIVER))
        for path in concrete_files()
        for c in DRIVERS
    )
    off = " ".join(f"--set {k}={str(v).lower()}" for k, v in OFF)
    return Table(
        "alks-concrete",
        PAGE,
        (
            f"ego compare scenarios/alks/FILE.xosc --controllers {','.join(TRACKING)} --preventable --out runs/alks",
            f"ego run scenarios/alks/FILE.xosc -c {REFERENCE_DRIVER} {off}",
        ),
        (
            "file / controller",
            "collision (with, relative impact speed)",
            "min front gap [m]",
            "min TTC front [s]",
            "max lane departure [m]",
            "collision preventable",
        ),
        rows,
        (
            "FILE: the first column's file. A front gap or TTC of `-`: no vehicle ever in the ego's path "
            "ahead. careful-driver: R157's reference driver, without ego's AEB and evasion, as the "
            "preventability question runs it. Preventable: the careful driver, on the same concrete "
            "scenario, avoids the collision; `-`: nothing to prevent.",
        ),
    )


def _lowest(ms: list[dict], key: str, cell=_fixed) -> str:
    values = [m[key] for m in ms if isinstance(m.get(key), (int, float))]
    return cell(min(values)) if values else "-"


def _highest(ms: list[dict], key: str) -> str:
    values = [m[key] for m in ms if isinstance(m.get(key), (int, float))]
    return _fixed(max(values)) if values else "-"


def _variation_cells(reference: bool):
    def cells(ms: list[dict]) -> list[str]:
        hits = [m for m in ms if m.get("collision")]
        prevented = sum(m.get("collision_preventable") is True for m in hits)
        kept = sum(m.get("collision_preventable") is False for m in hits)
        other = [m["status"] for m in ms if m["status"] not in ("completed", "collision")]
        return [
            f"{len(hits)}/{len(ms)}" + (f" ({len(other)} {', '.join(sorted(set(other)))})" if other else ""),
            "(reference)" if reference else str(prevented),
            "(reference)" if reference else str(kept),
            _lowest(ms, "min_gap_front"),
            _lowest(ms, "min_ttc_front", _ttc),
            _highest(ms, "max_lane_departure"),
        ]

    return cells


def variation_table(path: Path) -> Table:
    from ego.sweep.xosc import load

    variation = load(str(path), list(DRIVERS), SAMPLE if SAMPLE else None, SEED)
    runs = list(variation.spec.runs())
    sampled = variation.remaining > SAMPLE
    rows = tuple(
        Row(
            c,
            tuple(_job(r.scenario, c, r.overrides) for r in runs if r.controller == c),
            _variation_cells(c == REFERENCE_DRIVER),
        )
        for c in DRIVERS
    )
    short = path.stem.removesuffix("_variation")
    cmd = f"ego sweep scenarios/alks/{path.name} -c {','.join(TRACKING)} --preventable --out runs/{short}"
    if sampled:
        cmd += f" --sample {SAMPLE} --seed {SEED}"
    which = (
        f"a seeded subsample of {SAMPLE} (seed {SEED}) of the {variation.remaining} combinations"
        if sampled
        else f"all {variation.remaining} combinations"
    )
    kept = f"{variation.total} in the file, {variation.discarded} discarded by the value constraints"
    return Table(
        f"alks-{short.removeprefix('alks_').replace('_', '-')}",
        PAGE,
        (cmd,),
        (
            "controller",
            "collisions",
            "preventable",
            "not preventable",
            "smallest min front gap [m]",
            "smallest min TTC front [s]",
            "largest lane departure [m]",
        ),
        rows,
        (
            f"Runs: {which} that meet the value constraints ({kept}), one per controller. "
            f"careful-driver: the same points with {', '.join(f'`{k}={str(v).lower()}`' for k, v in OFF)} "
            "(R157's reference, as `--preventable` runs it after a collision); its collisions are the "
            "points where no collision is preventable.",
        ),
    )


def tables() -> list[Table]:
    return [concrete_table(), *(variation_table(p) for p in variation_files())]
