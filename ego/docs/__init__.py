"""The result tables of ``docs/results/``, rewritten from real runs.

    python -m ego.docs results [--page NAME] [--table NAME] [--check] [--jobs N]

A tool of the checkout, not of the package: the wheel leaves ``ego.docs`` out (it needs the
checkout's ``docs/`` and ``scenarios/``); run it from a checkout (``pip install -e .``).

Every table in ``docs/results/*.md`` sits between ``<!-- results:NAME -->`` and
``<!-- /results:NAME -->``; this module knows, for each NAME, which runs make it (the same
runs as the ``ego compare`` / ``ego sweep`` commands printed beside the table) and how each
row is formatted. ``results`` reruns them and rewrites the blocks (atomically, the prose
around them untouched); ``--check`` compares instead and exits 1 on any difference.

Each row is computed from its own runs only, so a test can regenerate a few rows and compare
them with the committed text (``tests/test_docs.py``). Runs are deterministic (same
scenario, controller, parameters and seed: same metrics), and no wall time appears in a
table.
"""

from __future__ import annotations

import itertools
import math
import os
import sys
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ego.docs.common import (
    CURVE,
    FOLLOWING,
    KMH,
    RESULTS,
    ROOT,
    SWEEPS,
    TRACKING,
    Row,
    Sim,
    Table,
    _table_metrics,
    ccr_cell,
    sim,
)
from ego.outputs import write_text


# -- jobs: what a row needs run (picklable, hashable, deterministic) -------------------------
@dataclass(frozen=True)
class NarmaAsReport:
    """Train NARMA-L2 as report 002 did (100 samples at 30 km/h, 0.3 m/s^2, R 15 m; the
    command beside the table) into a temporary file, then run the curve with it for each of
    ``cases`` (overrides). Training is seeded and deterministic, so the model is the same
    every time."""

    cases: tuple[tuple[tuple[str, Any], ...], ...]
    seed: int = 0

    def __call__(self) -> list[dict]:
        import tempfile

        from ego.train.narma_l2 import DataSpec, TrainSpec, train

        with tempfile.TemporaryDirectory(prefix="ego-docs-") as tmp:
            model = Path(tmp) / "narma_report.npz"
            data = DataSpec(
                samples=100,
                speed_min=30.0,
                speed_max=30.0,
                accel_min=0.3,
                accel_max=0.3,
                radius_min=15.0,
                radius_max=15.0,
            )
            train(TrainSpec(seed=self.seed, data=data), model, log=lambda *_: None)
            return [Sim("curve", "narma-l2", 0, case + (("model", str(model)),))() for case in self.cases]


@dataclass(frozen=True)
class Recovery:
    """lane-centering from ``offset`` m off the lane centre at ``speed`` m/s: the run's metrics
    plus, from its trace, how far it overshoots the centre (m), when it first comes within
    ``band`` of it and when it stays there (s)."""

    speed: float
    offset: float = 1.0
    band: float = 0.01

    def __call__(self) -> dict:
        from ego.results.metrics import overshoot, settling_time
        from ego.runner import RunSpec, run

        r = run(RunSpec("lane-centering", "cascade-pid", 0, {"speed": self.speed, "offset": self.offset}))
        t, d = r.column("t"), r.column("d")
        inside = np.flatnonzero(np.abs(d) < self.band)
        return {
            **r.metrics,
            "overshoot": overshoot(d, -np.sign(self.offset)),
            "back_within": float(t[inside[0]]) if inside.size else None,
            "settle": settling_time(t, d, self.band, 0.0),
        }


@dataclass(frozen=True)
class CrossSim:
    """One run of a motorway scenario on ``backend`` (``sumo`` or ``highway-env``): its
    metrics plus the smallest rear gap after the trigger (m, ``min_gap_rear_after``) - how
    close the traffic of the lane the ego moved into came (SUMO's Krauss drivers or
    highway-env's IDM)."""

    scenario: str
    controller: str
    seed: int
    backend: str

    def __call__(self) -> dict:
        from ego.runner import RunSpec, run

        r = run(RunSpec(self.scenario, self.controller, self.seed, backend=self.backend))
        metrics = _table_metrics(r)
        gap = None
        if metrics.get("trigger_time") is not None:
            rear = r.column("gap_rear")[r.column("t") >= metrics["trigger_time"]]
            rear = rear[np.isfinite(rear)]
            gap = float(rear.min()) if len(rear) else None
        metrics["min_gap_rear_after"] = gap
        return metrics


def _call(job: Callable[[], Any]) -> Any:
    """Worker: run one job (a top-level function, so the process pool can send it)."""
    return job()


# -- tables ------------------------------------------------------------------------------------
def _line(cells: Sequence[str]) -> str:
    return "| " + " | ".join(cells) + " |"


def render_row(row: Row, results: dict) -> str:
    return _line([row.label] + row.cells([results[j] for j in row.jobs]))


def markdown(table: Table, results: dict) -> str:
    """The table alone (header and rows), as markdown."""
    lines = [_line(table.header), "|" + "---|" * len(table.header)]
    return "\n".join(lines + [render_row(r, results) for r in table.rows])


def render(table: Table, results: dict) -> str:
    """The whole block between the markers: the commands, the table, its notes."""
    cmds = ", ".join(f"`{c}`" for c in table.commands)
    lines = [
        f"<!-- results:{table.name} -->",
        f"Runs: {cmds}. Table: `python -m ego.docs results --table {table.name}`.",
        "",
        markdown(table, results),
    ]
    lines += [""] + list(table.notes) if table.notes else []
    lines.append(f"<!-- /results:{table.name} -->")
    return "\n".join(lines)


# -- cell formats --------------------------------------------------------------------------------
def _nums(values: Iterable) -> list[float]:
    return [float(v) for v in values if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)]


def mean_sd(values: Sequence, digits: int = 2) -> str:
    """Mean +- sample standard deviation at ``digits`` decimals (the spread left out when it
    rounds to 0); ``(k/n)`` when only k of the n runs have the value; ``-`` when none has."""
    nums = _nums(values)
    if not nums:
        return "-"
    sd = float(np.std(nums, ddof=1)) if len(nums) > 1 else 0.0
    parts = [f"{float(np.mean(nums)):.{digits}f}"]
    if round(sd, digits) > 0:
        parts.append(f"+- {sd:.{digits}f}")
    if len(nums) < len(values):
        parts.append(f"({len(nums)}/{len(values)})")
    return " ".join(parts)


def count(values: Sequence, what: Any = True) -> str:
    """``k/n``: how many of the n values equal ``what``."""
    return f"{sum(v == what for v in values)}/{len(values)}"


def statuses(ms: Sequence[dict]) -> str:
    """Runs by status, in order of first appearance: ``2 completed, 1 collision``."""
    seen: dict[str, int] = {}
    for m in ms:
        seen[m["status"]] = seen.get(m["status"], 0) + 1
    return ", ".join(f"{n} {s}" for s, n in seen.items())


def fixed(v: float | None, digits: int, sign: bool = False) -> str:
    if v is None:
        return "-"
    return f"{v:+.{digits}f}" if sign else f"{v:.{digits}f}"


def length(v: float | None) -> str:
    """A lateral error: millimetres (2 significant digits) below 0.1 m, else metres."""
    if v is None:
        return "-"
    return f"{v * 1e3:#.2g} mm" if abs(v) < 0.1 else f"{v:.2f} m"


def _settle(ms: Sequence[dict], window: str) -> list:
    return [(m.get("settle_times") or {}).get(window) for m in ms]


# -- report 000 ----------------------------------------------------------------------------------
def _traffic_cells(ms: list[dict]) -> list[str]:
    eb, ff = ms[: len(ms) // 2], ms[len(ms) // 2 :]
    col = lambda group, key: [m.get(key) for m in group]  # noqa: E731
    return [
        statuses(eb),
        mean_sd(col(eb, "lane_change_duration")),
        mean_sd(col(eb, "max_overshoot")),
        mean_sd(col(eb, "min_gap_front")),
        mean_sd(col(eb, "max_abs_lateral_accel"), 1),
        statuses(ff),
        mean_sd(col(ff, "lane_change_duration")),
        mean_sd(col(ff, "max_overshoot")),
        mean_sd(col(ff, "max_abs_lateral_accel"), 1),
    ]


def _traffic_row(label: str, controller: str, seeds: int = 3, **overrides: Any) -> Row:
    jobs = tuple(
        sim(s, controller, seed, **overrides) for s in ("emergency-brake", "fast-follower") for seed in range(seeds)
    )
    return Row(label, jobs, _traffic_cells)


def _cut_in_cells(ms: list[dict]) -> list[str]:
    responses: dict[str, int] = {}
    for m in ms:
        responses[str(m.get("response"))] = responses.get(str(m.get("response")), 0) + 1
    return [
        statuses(ms),
        ", ".join(f"{n} {r}" for r, n in responses.items()),
        mean_sd([m["min_gap"] for m in ms]),
        mean_sd([m["min_ttc"] for m in ms]),
        mean_sd([m["max_decel"] for m in ms], 1),
        mean_sd([m["reaction_time"] for m in ms], 1),
    ]


def _lane_change(m: dict) -> str:
    """A bare-model lane change: how long it took and how far it overshot."""
    if m["status"] != "completed":
        return f"**{m['status']}**"
    over = m["max_overshoot"]
    shot = "no overshoot" if over < 0.005 else f"{over:.2f} m overshoot"
    if m["lane_change_duration"] is None:
        return f"not settled in {m['sim_time']:.0f} s, {shot}"
    return f"{m['lane_change_duration']:.1f} s, {shot}"


def _bare_row(label: str, says: str, controller: str, **overrides: Any) -> Row:
    jobs = tuple(sim("report-000", controller, 0, ref_speed=v, **overrides) for v in (25, 15))
    return Row(label, jobs, lambda ms: [says] + [_lane_change(m) for m in ms])


def _sine_cell(m: dict) -> str:
    if m["status"] != "completed":
        return f"**{m['status']}**"
    return f"{m['max_abs_lateral_error_after_10s']:.3f} m"


#: ``--controllers`` of report 000's commands
TRACKING_NAMES = ",".join(TRACKING)


def report_000() -> list[Table]:
    return [_traffic_table(), _cut_in_table(), _bare_table(), _sine_table()]


def _traffic_table() -> Table:
    """Emergency-brake and fast-follower in traffic: every tracking controller, three seeds."""
    return Table(
        "traffic",
        "report-000",
        (
            f"ego compare emergency-brake --controllers {TRACKING_NAMES} --seeds 3 --out runs/eb",
            f"ego compare fast-follower --controllers {TRACKING_NAMES} --seeds 3 --out runs/ff",
            "the same with --controllers bp-pid --set variant=report [--set abs=false]",
        ),
        (
            "controller",
            "emergency-brake: runs",
            "lane change [s]",
            "overshoot [m]",
            "min front gap [m]",
            "max lateral accel [m/s^2]",
            "fast-follower: runs",
            "lane change [s]",
            "overshoot [m]",
            "max lateral accel [m/s^2]",
        ),
        tuple(_traffic_row(c, c) for c in TRACKING)
        + (
            _traffic_row("bp-pid, variant=report", "bp-pid", variant="report"),
            _traffic_row("bp-pid, variant=report, abs=false", "bp-pid", variant="report", abs="false"),
        ),
        (
            "Defaults (ego 20 m/s, lead 30 m ahead braking at 6 m/s^2; follower at 30 m/s), seeds 0-2; "
            "mean +- standard deviation over the seeds (left out when it rounds to 0); (k/n): only k "
            "of the n runs have the value (a lane change that never settled).",
        ),
    )


def _cut_in_table() -> Table:
    """The cut-in: how each tracking controller responds, three seeds."""
    return Table(
        "cut-in",
        "report-000",
        (f"ego compare cut-in --controllers {TRACKING_NAMES} --seeds 3 --out runs/cut-in",),
        (
            "controller",
            "runs",
            "response",
            "min gap [m]",
            "min TTC [s]",
            "max deceleration [m/s^2]",
            "reaction time [s]",
        ),
        tuple(Row(c, tuple(sim("cut-in", c, s) for s in range(3)), _cut_in_cells) for c in TRACKING),
    )


def _bare_table() -> Table:
    """The bare model's lane change (no traffic), beside what report 000 says."""
    return Table(
        "bare-model",
        "report-000",
        (
            "ego compare report-000 --controllers fuzzy,fuzzy-pid,bp-pid,rbf-smc --set ref_speed=25|15 "
            "[--set variant=report] --out runs/r000",
        ),
        ("", "report 000 says", "ours, accelerating (X_ref = 25 t)", "ours, decelerating (X_ref = 15 t)"),
        (
            _bare_row("fuzzy", "~5 s accelerating, ~14 s decelerating, little oscillation", "fuzzy"),
            _bare_row("fuzzy-PID, report scales", "~20 s, with overshoot", "fuzzy-pid", variant="report"),
            _bare_row("fuzzy-PID, tuned (default)", "-", "fuzzy-pid"),
            _bare_row("BP-NN PID as published", "unstable; manages one channel at a time", "bp-pid", variant="report"),
            _bare_row("BP-NN PID, stable (default)", "-", "bp-pid"),
            _bare_row("RBF adaptive SMC as published", "~10 s, no overshoot", "rbf-smc", variant="report"),
            _bare_row("RBF adaptive SMC, fixed (default)", "-", "rbf-smc"),
            _bare_row("PID (ours; the report has none)", "-", "pid"),
        ),
        (
            "A 5 m lane change (a Y step) from 20 m/s, 30 s; the lane change is done when |Y - Y_ref| "
            "stays below 0.2 m.",
        ),
    )


def _sine_table() -> Table:
    """Tracking 4 sin(0.5 t), accelerating and decelerating."""
    return Table(
        "sine",
        "report-000",
        (
            f"ego compare sine-tracking --controllers {TRACKING_NAMES} --set omega=0.5 --set ref_speed=25|15 --out runs/sine",
        ),
        ("controller", "accelerating (X_ref = 25 t)", "decelerating (X_ref = 15 t)"),
        tuple(
            Row(
                c,
                tuple(sim("sine-tracking", c, 0, omega=0.5, ref_speed=v) for v in (25, 15)),
                lambda ms: [_sine_cell(m) for m in ms],
            )
            for c in TRACKING
        ),
        ("Largest lateral error after 10 s tracking 4 sin(0.5 t) on the SUMO motorway.",),
    )


# -- report 002 ----------------------------------------------------------------------------------
def _curve_cells(ms: list[dict]) -> list[str]:
    m = ms[0]
    return [
        m["status"],
        fixed(m["max_abs_ed"], 3),
        fixed(m["final_ed"], 3, sign=True),
        fixed(m["max_abs_ea"], 3),
        fixed(m["final_ea"], 3, sign=True),
        fixed(m["time_in_arc"], 2),
        fixed(m["entry_speed"], 1),
        fixed(m["exit_speed"], 1),
    ]


def _ed_cell(m: dict) -> str:
    return fixed(m["max_abs_ed"], 3) if m["status"] == "completed" else f"**{m['status']}**"


SPEED_CASES = (
    (("entry_speed", 20),),
    (("entry_speed", 30),),
    (("entry_speed", 40),),
    (("accel", 0),),
    (("accel", 0.6),),
)


def _variation_cells(ms: list[dict]) -> list[str]:
    m = ms[0]
    return [m["status"], fixed(m["max_abs_ed"], 3), fixed(m["min_gap_front"], 1), fixed(m["exit_speed"], 1)]


def report_002() -> list[Table]:
    curve = Table(
        "curve",
        "report-002",
        ("ego compare curve --controllers pid,fuzzy-curve,narma-l2 --out runs/curve",),
        (
            "controller",
            "status",
            "max \\|e_d\\| [m]",
            "e_d at the exit [m]",
            "max \\|e_a\\| [rad]",
            "e_a at the exit [rad]",
            "time in the arc [s]",
            "entry speed [km/h]",
            "exit speed [km/h]",
        ),
        tuple(Row(c, (sim("curve", c),), _curve_cells) for c in CURVE),
        ("Seed 0: seeds only change the oncoming traffic, which never meets the ego.",),
    )
    speeds = Table(
        "curve-speeds",
        "report-002",
        (
            "ego run curve -c NAME --set entry_speed=20|30|40",
            "ego run curve -c NAME --set accel=0|0.6",
            "ego train narma-l2 --samples 100 --speeds 30,30 --accels 0.3,0.3 --radii 15,15 "
            "--out runs/narma_report.npz, then --set model=runs/narma_report.npz",
        ),
        ("controller", "20 km/h: max \\|e_d\\| [m]", "30 km/h", "40 km/h", "a_x = 0 (30 km/h)", "a_x = 0.6 (30 km/h)"),
        tuple(
            Row(c, tuple(Sim("curve", c, 0, case) for case in SPEED_CASES), lambda ms: [_ed_cell(m) for m in ms])
            for c in CURVE
        )
        + (
            Row(
                "narma-l2 trained as the report did (100 samples at 30 km/h, 0.3 m/s^2)",
                (NarmaAsReport(SPEED_CASES),),
                lambda ms: [_ed_cell(m) for m in ms[0]],
            ),
        ),
        (
            "One NARMA-L2 model (the shipped one, trained over 20-40 km/h and 0-0.6 m/s^2) for every "
            "case; a_x = 0.3 m/s^2 unless the column says otherwise.",
        ),
    )
    variations = Table(
        "curve-variations",
        "report-002",
        ("ego run curve -c NAME --set lead=15", "ego run curve -c pid --set pedal=true"),
        ("controller, setting", "status", "max \\|e_d\\| [m]", "min gap to the lead [m]", "exit speed [km/h]"),
        tuple(Row(f"{c}, lead=15", (sim("curve", c, lead=15),), _variation_cells) for c in CURVE)
        + (
            Row("pid, defaults", (sim("curve", "pid"),), _variation_cells),
            Row("pid, pedal=true", (sim("curve", "pid", pedal="true"),), _variation_cells),
        ),
        ("lead=15: a car driving 15 km/h 15 m ahead, met in the curve.",),
    )
    return [curve, speeds, variations]


# -- report 003 ----------------------------------------------------------------------------------
def _centring_cells(ms: list[dict]) -> list[str]:
    cells = []
    for m, full in zip(ms, (True, False)):
        if m["status"] != "completed":
            n = 5 if full else 3
            cells += [f"**leaves the road** after {m['sim_time']:.0f} s"] + [""] * (n - 1)
            continue
        cells += [length(m["max_abs_lateral_error"]), length(m["mean_abs_lateral_error"])]
        if full:
            cells += [length(m["std_lateral_error"]), f"{math.degrees(m['max_abs_steer']):.2f} deg"]
        cells.append(f"{m['max_abs_lateral_accel']:.2f} m/s^2")
    return cells


def _recovery_cells(ms: list[dict]) -> list[str]:
    m = ms[0]
    return [
        m["status"],
        fixed(m["back_within"], 2),
        fixed(m["overshoot"], 2),
        fixed(m["settle"], 1),
        fixed(m["max_abs_lateral_accel"], 1),
    ]


def report_003() -> list[Table]:
    rows = []
    for preset, gains in (("tuned", "tuned (default)"), ("report", "report 003's")):
        for plant in ("lateral-error", "dynamic-bicycle"):
            jobs = tuple(sim("lane-centering", "cascade-pid", 0, preset=preset, plant=plant, speed=v) for v in (8, 25))
            rows.append(Row(f"{gains}, {plant}", jobs, _centring_cells))
    recovery = Table(
        "recovery",
        "report-003",
        ("ego run lane-centering -c cascade-pid --set offset=1 [--set speed=25] --trace recovery.csv",),
        (
            "speed",
            "status",
            "first within 1 cm [s]",
            "overshoot past the centre [m]",
            "settled within 1 cm after [s]",
            "max \\|a_y\\| [m/s^2]",
        ),
        tuple(Row(f"{v} m/s", (Recovery(v),), _recovery_cells) for v in (8, 25)),
        ("The tuned gains (the default), starting 1 m left of the lane centre.",),
    )
    return [
        Table(
            "lane-centering",
            "report-003",
            (
                "ego run lane-centering -c cascade-pid [--set preset=report] [--set speed=25] "
                "[--set plant=dynamic-bicycle] --json",
            ),
            (
                "gains, plant",
                "8 m/s: max \\|e\\|",
                "mean \\|e\\|",
                "std e",
                "max \\|steer\\|",
                "max \\|a_y\\|",
                "25 m/s: max \\|e\\|",
                "mean \\|e\\|",
                "max \\|a_y\\|",
            ),
            tuple(rows),
            ("The whole 2935 m road, from the lane centre.",),
        ),
        recovery,
    ]


# -- report 004 ----------------------------------------------------------------------------------
WINDOWS = ("brake@10s", "accelerate@35s", "stop@60s")


def _platoon_cells(ms: list[dict]) -> list[str]:
    col = lambda key: [m[key] for m in ms]  # noqa: E731
    return (
        [
            statuses(ms),
            mean_sd(col("rms_spacing_error")),
            mean_sd(col("max_abs_spacing_error")),
            mean_sd(col("min_gap")),
            mean_sd(col("min_ttc")),
            mean_sd(col("max_abs_accel")),
            mean_sd(col("max_abs_jerk")),
        ]
        + [mean_sd(_settle(ms, w), 1) for w in WINDOWS]
        + [count(col("string_stable"))]
    )


def _follower_cells(m: dict) -> list[str]:
    return [
        fixed(m["rms_spacing_error"], 2),
        fixed(m["max_abs_spacing_error"], 2),
        fixed(m["min_gap"], 2),
        fixed(m["max_abs_accel"], 2),
        fixed(m["max_abs_jerk"], 2),
    ]


def _convergence_cell(ms: list[dict]) -> str:
    crashed = sum(m["collision"] for m in ms)
    settle = _settle(ms, "start@0s")
    settled = [s for s in settle if s is not None]
    text = f"{crashed}/{len(ms)} collide; settled {len(settled)}/{len(ms)}"
    if settled:
        text += f" in {mean_sd(settled, 1)} s"
    return (
        text + f"; max \\|delta_d\\| {mean_sd([m['max_abs_spacing_error'] for m in ms], 1)} m; "
        f"min gap {min(m['min_gap'] for m in ms):.1f} m"
    )


CONVERGE = {"followers": 1, "manoeuvres": "none", "start_error": 3, "settle_band": 0.15}
HEADWAYS = (0.2, 0.5, 1.0, 1.25, 1.5, 1.75, 2.0, 2.5, 3.0)
#: report 004's PID, the platoon's actuator lag and the control period's T/2 delay (s)
PID_GAINS, LAG, DELAY = (0.85, 0.2, 0.3), 0.2, 0.05


def _worst_l2(m: dict) -> float | None:
    ratios = [
        v for pair in m["amplification"].values() for k, v in pair.items() if k.startswith("l2_") and v is not None
    ]
    return max(ratios) if ratios else None


def headway_row(headway: float, seeds: int = 3, omega: float = 0.5) -> Row:
    """Theory (report 004's PID) beside SUMO runs at one time headway: for each controller
    ``seeds`` runs of the default drive and one with the leader's speed oscillating 1 km/h at
    ``omega`` (rad/s)."""
    from ego.scenarios import string_stability as ss

    drive = tuple(sim("platoon", c, s, headway=headway) for c in FOLLOWING for s in range(seeds))
    sine = tuple(
        sim(
            "platoon",
            c,
            0,
            headway=headway,
            manoeuvres="none",
            sine_amplitude=1.0,
            sine_omega=omega,
            duration=150.0,
            sine_transient=60.0,
        )
        for c in FOLLOWING
    )

    def cells(ms: list[dict]) -> list[str]:
        transfer = lambda w: ss.pid_transfer(w, *PID_GAINS, headway, LAG, DELAY)  # noqa: E731
        out = [f"{ss.peak_gain(transfer)[0]:.2f}", f"{abs(transfer(omega)):.3f}"]
        for i in range(len(FOLLOWING)):
            runs, wave = ms[i * seeds : (i + 1) * seeds], ms[len(drive) + i]
            gain = (wave["frequency_gain"] or {}).get("f1->f2")
            worst = [w for w in map(_worst_l2, runs) if w is not None]
            out += [
                count([m["collision"] for m in runs]),
                f"{min(m['min_gap'] for m in runs):.2f}",
                count([m["string_stable"] for m in runs]),
                f"{max(worst):.2f}" if worst else "-",
                f"{gain:.3f}" if gain is not None and wave["status"] == "completed" else f"({wave['status']})",
            ]
        return out

    return Row(f"{headway:g}", drive + sine, cells)


def headway_header(omega: float = 0.5) -> tuple[str, ...]:
    head = ("lambda [s]", "theory: max \\|H\\|", f"theory: \\|H({omega:g})\\|")
    for c in FOLLOWING:
        head += (
            f"{c}: collisions",
            f"{c}: min gap [m]",
            f"{c}: drive string stable",
            f"{c}: worst L2 ratio",
            f"{c}: measured gain f1->f2 at {omega:g}",
        )
    return head


def _scale_cells(ms: list[dict]) -> list[str]:
    return [
        statuses(ms),
        mean_sd([m["max_abs_spacing_error"] for m in ms], 3),
        mean_sd(_settle(ms, "accelerate@2s"), 1),
        f"{min(m['min_gap'] for m in ms):.2f}",
    ]


def report_004() -> list[Table]:
    return [_platoon_table(), _followers_table(), _convergence_table(), _headway_table(), _scale_table()]


def _platoon_table() -> Table:
    """The platoon's worst follower, three and ten seeds."""
    return Table(
        "platoon",
        "report-004",
        ("ego compare platoon --controllers pid,bp-pid-acc --seeds 3 --out runs/platoon", "... --seeds 10"),
        (
            "controller, seeds",
            "runs",
            "RMS delta_d [m]",
            "max \\|delta_d\\| [m]",
            "min gap [m]",
            "min TTC [s]",
            "max \\|a\\| [m/s^2]",
            "max \\|jerk\\| [m/s^3]",
            "settle: brake@10s [s]",
            "accelerate@35s [s]",
            "stop@60s [s]",
            "string stable",
        ),
        tuple(
            Row(f"{c}, 0-{n - 1}", tuple(sim("platoon", c, s) for s in range(n)), _platoon_cells)
            for n in (3, 10)
            for c in FOLLOWING
        ),
        (
            "Three followers, lambda = 2 s, the default drive; the worst follower's figures, mean +- "
            "standard deviation over the seeds; a settle time (k/n) when only k runs settled within the "
            "window.",
        ),
    )


def _followers_table() -> Table:
    """Each follower of the platoon, seed 0."""
    return Table(
        "followers",
        "report-004",
        ("ego run platoon -c NAME --json",),
        (
            "controller, follower",
            "RMS delta_d [m]",
            "max \\|delta_d\\| [m]",
            "min gap [m]",
            "max \\|a\\| [m/s^2]",
            "max \\|jerk\\| [m/s^3]",
        ),
        tuple(
            Row(f"{c}, {f}", (sim("platoon", c),), lambda ms, f=f: _follower_cells(ms[0]["followers"][f]))
            for c in FOLLOWING
            for f in ("f1", "f2", "f3")
        ),
        ("Seed 0, the default drive; f1 is right behind the leader.",),
    )


def _convergence_table() -> Table:
    """One follower converging from 3 m too far back, in three settings."""
    settings = (
        ("ours (lambda 2 s, lag 0.2 s, period 0.1 s; 60 s)", {"duration": 60}),
        (
            "the report's (lambda 0.2 s, no lag, period 1 s; 120 s)",
            {"headway": 0.2, "lag": 0, "period": 1, "duration": 120},
        ),
        ("the report's at period 0.1 s (lambda 0.2 s, no lag; 120 s)", {"headway": 0.2, "lag": 0, "duration": 120}),
    )
    return Table(
        "convergence",
        "report-004",
        (
            "ego compare platoon --controllers pid,bp-pid-acc --seeds 10 --set followers=1 --set manoeuvres=none "
            "--set start_error=3 --set settle_band=0.15 --set duration=60|120 "
            "[--set headway=0.2 --set lag=0 [--set period=1]] --out runs/converge",
        ),
        ("setting", "pid", "bp-pid-acc"),
        tuple(
            Row(
                label,
                tuple(sim("platoon", c, s, **CONVERGE, **extra) for c in FOLLOWING for s in range(10)),
                lambda ms: [_convergence_cell(ms[:10]), _convergence_cell(ms[10:])],
            )
            for label, extra in settings
        ),
        (
            "One follower starting 3 m too far back behind a leader at 40 km/h; settled: |delta_d| "
            "stays below 0.15 m (5 %); ten seeds.",
        ),
    )


def _headway_table() -> Table:
    """String stability against the headway: theory beside SUMO."""
    return Table(
        "headway",
        "report-004",
        ("python scenarios/platoon_headway.py",),
        headway_header(),
        tuple(headway_row(h) for h in HEADWAYS),
        (
            "lambda = 0.2 s is report 004's headway, 2 s the default. "
            "Theory: report 004's PID with the default lag (0.2 s) and the 0.1 s period as a T/2 delay. "
            "SUMO: three seeds of the default drive per cell, and one run with the leader's speed "
            "oscillating 1 km/h at 0.5 rad/s for the measured gain.",
        ),
    )


def _scale_table() -> Table:
    """Report 004's 3-car scale model."""
    return Table(
        "scale-model",
        "report-004",
        (
            "ego compare platoon --controllers pid,bp-pid-acc --seeds 10 --set variant=scale-model "
            "[--set headway=0.2 --set standstill_gap=0.3]",
        ),
        ("controller, headway", "runs", "max \\|delta_d\\| [m]", "settles after the start [s]", "min gap [m]"),
        tuple(
            Row(
                f"{c}, lambda {label}",
                tuple(sim("platoon", c, s, variant="scale-model", **extra) for s in range(10)),
                _scale_cells,
            )
            for label, extra in (("2 s", {}), ("0.2 s", {"headway": 0.2, "standstill_gap": 0.3}))
            for c in FOLLOWING
        ),
        (
            "The report's 3-car scale test: two followers, 0.5 m/s, a 40 cm target gap at standstill "
            "(0.3 m + 0.2 s x 0.5 m/s with the report's headway); ten seeds.",
        ),
    )


# -- sweeps: the envelope, cut-in, Euro NCAP AEB ---------------------------------------------
def _spec_rows(path: Path, cells: Callable[[list], list[str]], extra: dict | None = None) -> tuple[Row, ...]:
    """One row per controller of a sweep spec: its runs as ``ego sweep`` makes them."""
    from ego.sweep.spec import load

    spec = load(path)
    jobs = [
        (r.controller, sim(r.scenario, r.controller, r.seed, **{**r.overrides, **(extra or {})})) for r in spec.runs()
    ]
    return tuple(Row(c, tuple(j for name, j in jobs if name == c), cells) for c in spec.controllers)


def _outcomes(ms: list[dict]) -> list[str]:
    s = [m["status"] for m in ms]
    avoidable = sum(bool(m.get("collision_avoidable")) for m in ms)
    return [
        str(s.count("completed")),
        str(s.count("collision")),
        str(avoidable),
        str(s.count("diverged")),
        str(s.count("timeout")),
        str(s.count("failed")),
    ]


def ccr_header(path: Path) -> tuple[str, ...]:
    """The controller column, then one per [grid] point of the spec."""
    from ego.sweep.spec import load

    grid = load(path).grid
    labels = [
        ", ".join(f"{v * KMH:.0f} km/h" if k == "ego_speed" else f"{k} {v:g}" for k, v in zip(grid, point))
        for point in itertools.product(*grid.values())
    ]
    return ("controller",) + tuple(labels)


def ccr_table(name: str, path: Path, extra: dict | None = None) -> Table:
    """A Euro NCAP CCR matrix (one spec file) as a table; ``extra`` overrides every run."""
    sets = "".join(f" --set {k}={v}" for k, v in (extra or {}).items())
    shown = path.relative_to(ROOT) if path.resolve().is_relative_to(ROOT) else path
    command = (
        f"PYTHONPATH=. python scenarios/sweeps/ccr_table.py{sets} {shown}"
        if sets
        else f"ego sweep {shown} --out runs/{path.stem}"
    )
    return Table(
        name, "envelope", (command,), ccr_header(path), _spec_rows(path, lambda ms: [ccr_cell(m) for m in ms], extra)
    )


def envelope() -> list[Table]:
    env = Table(
        "envelope",
        "envelope",
        ("ego sweep scenarios/sweeps/envelope.toml --out runs/envelope --plot ego_speed,lead_decel:min_gap_front",),
        (
            "controller",
            "completed",
            "collision",
            "of which avoidable by braking from the trigger",
            "diverged",
            "timeout",
            "failed (a default requirement broken: the ego left its lane)",
        ),
        _spec_rows(SWEEPS / "envelope.toml", _outcomes),
    )
    cut_in = Table(
        "cut-in-sweep",
        "envelope",
        ("ego sweep scenarios/sweeps/cut-in.toml --out runs/cut-in --plot cut_in_gap,cut_in_speed:min_gap",),
        (
            "controller",
            "completed",
            "collision",
            "of which avoidable by braking from the car's intrusion into the ego's lane",
            "diverged",
            "timeout",
            "failed (a default requirement broken: the ego left its lane)",
        ),
        _spec_rows(SWEEPS / "cut-in.toml", _outcomes),
    )
    tables = [env, cut_in]
    for trigger in (None, 1.5, 1.0):
        for test in ("s", "m", "b"):
            suffix = "" if trigger is None else f"-ttc{trigger:g}"
            extra = None if trigger is None else {"ttc_threshold": trigger}
            tables.append(ccr_table(f"ccr{test}{suffix}", SWEEPS / f"aeb-ccr-{test}.toml", extra))
    return tables


#: the two registered traffic simulators the cross-simulator page compares, by their names in
#: the page's header (a choice of the page, not a copy of the registry: a plugin backend
#: adds no column)
CROSS_BACKENDS = {"sumo": "SUMO", "highway-env": "highway-env"}
#: per scenario: (metric, header) of the cross-simulator page; min_gap_rear_after from CrossSim
CROSS_FIGURES = {
    "emergency-brake": (
        ("min_gap_front", "min gap front [m]"),
        ("min_ttc_front", "min TTC front [s]"),
        ("lane_change_duration", "lane change [s]"),
        ("max_decel", "max decel [m/s^2]"),
        ("min_gap_rear_after", "new follower's min gap [m]"),
        ("min_ttc_rear", "min TTC rear [s]"),
    ),
    "fast-follower": (
        ("min_ttc_rear", "min TTC rear [s]"),
        ("min_gap_front", "min gap front [m]"),
        ("lane_change_duration", "lane change [s]"),
        ("min_gap_rear_after", "new follower's min gap [m]"),
        ("follower_passed", "follower passed"),
    ),
}


def _cross_cells(figures: tuple, seeds: int) -> Callable[[list], list[str]]:
    """Cells of a cross-simulator row: runs by status on each backend, then each figure's
    mean over the seeds on SUMO beside highway-env (``k/n`` for a yes/no figure)."""

    def cells(ms: list[dict]) -> list[str]:
        by = {b: ms[i * seeds : (i + 1) * seeds] for i, b in enumerate(CROSS_BACKENDS)}
        out = [statuses(by[b]) for b in CROSS_BACKENDS]
        for key, _ in figures:
            for b in CROSS_BACKENDS:
                values = [m.get(key) for m in by[b]]
                out.append(count(values) if all(isinstance(v, bool) for v in values) else mean_sd(values))
        return out

    return cells


def cross_simulator(seeds: int = 3) -> list[Table]:
    """Each motorway controller on SUMO beside highway-env (docs/results/cross-simulator.md)."""
    out = []
    for scenario, figures in CROSS_FIGURES.items():
        header = ["controller"] + [f"runs ({shown})" for shown in CROSS_BACKENDS.values()]
        for _, label in figures:
            header += [f"{label} SUMO", f"{label} highway-env"]
        rows = tuple(
            Row(
                c,
                tuple(CrossSim(scenario, c, seed, b) for b in CROSS_BACKENDS for seed in range(seeds)),
                _cross_cells(figures, seeds),
            )
            for c in TRACKING
        )
        out.append(
            Table(
                f"cross-{scenario}",
                "cross-simulator",
                tuple(
                    f"ego compare {scenario} --controllers {','.join(TRACKING)} --seeds {seeds} "
                    f"--backend {b} --out runs/{scenario}-{b}"
                    for b in CROSS_BACKENDS
                ),
                tuple(header),
                rows,
                (
                    f"Mean +- standard deviation over seeds 0-{seeds - 1}; the new follower's min gap is "
                    "the smallest rear gap after the trigger, from the run's trace.",
                ),
            )
        )
    return out


def _rate(rate: float, interval: tuple[float, float]) -> str:
    """A rate and its 95 % interval in per cent: ``40 % (17-69)``."""
    return f"{100 * rate:.0f} % ({100 * interval[0]:.0f}-{100 * interval[1]:.0f})"


def _rl_cells(results: list) -> list[str]:
    from ego.gym.baselines import summary

    s = summary(results)
    return [
        f"{s['mean']:.2f}",
        "-" if math.isnan(s["sd"]) else f"{s['sd']:.2f}",
        _rate(s["success"], s["success_interval"]),
        _rate(s["collision"], s["collision_interval"]),
        f"{s['length']:.0f}",
    ]


#: the columns of an RL baselines table after the policy's
RL_HEADER = (
    "mean return",
    "sd over training seeds",
    "success (95 % CI)",
    "collision (95 % CI)",
    "mean episode length (env steps)",
)


#: env id -> its table on docs/results/rl-baselines.md (one table each: regenerated one at a time)
RL_TABLES = {
    "ego/EmergencyBrake-v0": "rl-emergency-brake",
    "ego/FastFollower-v0": "rl-fast-follower",
    "ego/CutIn-v0": "rl-cut-in",
    "ego/Curve-v0": "rl-curve",
    "ego/LaneCentering-v0": "rl-lane-centering",
    "ego/Platoon-v0": "rl-platoon",
}
#: where the page reads the trained models (train_sb3.py --models writes them; a missing one the
#: page trains and writes itself): in the checkout, not committed (runs/ is ignored)
RL_MODELS = ROOT / "runs" / "rl-baselines"
#: the training seeds of the PPO and SAC rows
RL_SEEDS = (0, 1, 2)


def rl_baselines() -> list[Table]:
    """docs/results/rl-baselines.md: per env id, every controller of its task through
    ControllerPolicy and PPO / SAC (3 training seeds) on the same evaluation episodes."""
    from ego.control import CONTROLLERS
    from ego.gym.baselines import ALGOS, BUDGET, EVAL_SEEDS, ControllerEval, TrainedEval
    from ego.scenarios import scenario_class

    out = []
    for env_id, name in RL_TABLES.items():
        scenario = name.removeprefix("rl-")
        rows = [
            Row(controller, (ControllerEval(env_id, controller),), _rl_cells)
            for controller in CONTROLLERS[scenario_class(scenario).task]
            # the R157 reference driver is a yardstick for preventability, not a baseline
            if controller not in ("none", "careful-driver")
        ]
        rows += [
            Row(
                algo.upper(),
                tuple(TrainedEval(env_id, algo, seed, BUDGET, str(RL_MODELS)) for seed in RL_SEEDS),
                _rl_cells,
            )
            for algo in ALGOS
        ]
        out.append(
            Table(
                name,
                "rl-baselines",
                (
                    f"for algo in {' '.join(ALGOS)}; do for seed in {' '.join(map(str, RL_SEEDS))}; do python "
                    f"scenarios/rl/train_sb3.py --env {env_id} --algo $algo --seed $seed --steps {BUDGET} "
                    "--models runs/rl-baselines --no-score; done; done",
                ),
                (f"{env_id} policy", *RL_HEADER),
                tuple(rows),
                (
                    f"Evaluation episodes: seeds {EVAL_SEEDS[0]}-{EVAL_SEEDS[-1]}, through `ego.gym.evaluate`. PPO and "
                    f"SAC: {BUDGET} env steps each, training seeds {RL_SEEDS[0]}-{RL_SEEDS[-1]} (mean of the seeds' "
                    "mean returns +- their standard deviation; success and collision over all their episodes, "
                    "Wilson's 95 % interval); a controller is one deterministic run of the episodes.",
                ),
            )
        )
    return out


#: env id -> its table of the discrete setting (DQN against one meta action held all the time)
RL_DISCRETE_TABLES = {"ego/EmergencyBrake-v0": "rl-discrete-emergency-brake"}


def rl_discrete() -> list[Table]:
    """docs/results/rl-baselines.md: per env id of :data:`RL_DISCRETE_TABLES`, DQN (3
    training seeds) in the discrete setting against each meta action held all the time."""
    import json

    from ego.gym.baselines import DISCRETE_CONFIG, DQN_BUDGET, EVAL_SEEDS, ConstantEval, TrainedEval, discrete_actions

    out = []
    for env_id, name in RL_DISCRETE_TABLES.items():
        rows = [
            Row(f"always {action}", (ConstantEval(env_id, action),), _rl_cells) for action in discrete_actions(env_id)
        ]
        rows.append(
            Row(
                "DQN",
                tuple(TrainedEval(env_id, "dqn", seed, DQN_BUDGET, str(RL_MODELS)) for seed in RL_SEEDS),
                _rl_cells,
            )
        )
        out.append(
            Table(
                name,
                "rl-baselines",
                (
                    f"for seed in {' '.join(map(str, RL_SEEDS))}; do python scenarios/rl/train_sb3.py --env {env_id} "
                    f"--algo dqn --seed $seed --steps {DQN_BUDGET} --models runs/rl-baselines --no-score; done",
                ),
                (f"{env_id} policy", *RL_HEADER),
                tuple(rows),
                (
                    f"The env with `config={json.dumps(DISCRETE_CONFIG)}`; evaluation episodes: seeds "
                    f"{EVAL_SEEDS[0]}-{EVAL_SEEDS[-1]}, through `ego.gym.evaluate`. DQN: {DQN_BUDGET} env steps each, "
                    f"training seeds {RL_SEEDS[0]}-{RL_SEEDS[-1]} (mean of the seeds' mean returns +- their standard "
                    "deviation; success and collision over all their episodes, Wilson's 95 % interval).",
                ),
            )
        )
    return out


def rl_thresholds() -> Table:
    """docs/results/rl-baselines.md: each env's ``reward_threshold``, its default controller's
    mean return on the evaluation episodes with ``gym.make(id)``'s own defaults."""
    from ego.gym.baselines import EVAL_SEEDS, ThresholdEval
    from ego.scenarios import scenario_class

    rows = []
    for env_id, name in RL_TABLES.items():
        controller = scenario_class(name.removeprefix("rl-")).reference_controller()
        rows.append(Row(f"{env_id} ({controller})", (ThresholdEval(env_id),), _rl_threshold_cells))
    return Table(
        "rl-thresholds",
        "rl-baselines",
        (
            'python -c "import numpy as np; from ego.gym.baselines import ThresholdEval; '
            "print(np.mean(ThresholdEval('ego/CutIn-v0')()['returns']))\"",
        ),
        (
            "env id (default controller)",
            "reward_threshold: mean return",
            "success (95 % CI)",
            "collision (95 % CI)",
            "mean episode length (env steps)",
        ),
        tuple(rows),
        (
            f"Evaluation episodes: seeds {EVAL_SEEDS[0]}-{EVAL_SEEDS[-1]}, each env as `gym.make(id)` makes it "
            "(the benchmark's setting, ego.gym.BENCHMARK: 10 Hz, the lane-centring drive cut to 30 s, the default randomisation); "
            "the controller through `ego.gym.ControllerPolicy`, one deterministic run of the episodes.",
        ),
    )


def _rl_threshold_cells(results: list) -> list[str]:
    cells = _rl_cells(results)
    return [cells[0], *cells[2:]]


def tables() -> list[Table]:
    """Every table of docs/results/, page by page."""
    from ego.docs.alks import tables as alks
    from ego.docs.curved import tables as curved
    from ego.docs.falsify import docs_tables
    from ego.docs.openscenario import tables as openscenario

    return (
        report_000()
        + report_002()
        + report_003()
        + report_004()
        + envelope()
        + cross_simulator()
        + rl_baselines()
        + rl_discrete()
        + [rl_thresholds()]
        + openscenario()
        + docs_tables()
        + curved()
        + alks()
    )


# -- running and writing ---------------------------------------------------------------------------
def run_jobs(jobs: Iterable, workers: int | None = None, progress: bool = True) -> dict:
    """Each distinct job's result, run in a process pool (libsumo: one simulation per process)."""
    from ego.parallel.executor import ProcessExecutor
    from ego.results.progress import Progress

    todo = list(dict.fromkeys(jobs))
    results: dict = {}
    shown = Progress(len(todo)) if progress else None
    executor = ProcessExecutor(max(1, min(workers or os.cpu_count() or 1, len(todo) or 1)))
    try:
        for outcome in executor.run(_call, todo):
            if outcome.value is None:
                raise RuntimeError(f"{outcome.task}: {outcome.error}")
            results[outcome.task] = outcome.value
            if shown is not None:
                shown(type(outcome.task).__name__, "done")
    finally:
        executor.close()
    return results


def block(text: str, name: str) -> str:
    """The committed block of table ``name`` in a page's text (markers included)."""
    start, end = f"<!-- results:{name} -->", f"<!-- /results:{name} -->"
    i, j = text.find(start), text.find(end)
    if i < 0 or j < i:
        raise KeyError(f"no block {start} ... {end}")
    return text[i : j + len(end)]


def page_path(page: str) -> Path:
    return RESULTS / f"{page}.md"


def regenerate(selected: Sequence[Table], check: bool, workers: int | None = None) -> list[str]:
    """Rerun the tables' runs; write the pages, or (``check``) list the tables that differ."""
    results = run_jobs((j for t in selected for r in t.rows for j in r.jobs), workers)
    differ = []
    for page in dict.fromkeys(t.page for t in selected):
        path = page_path(page)
        text = original = path.read_text()
        for t in (t for t in selected if t.page == page):
            old, new = block(text, t.name), render(t, results)
            if old != new:
                differ.append(t.name)
                text = text.replace(old, new)
        if not check and text != original:
            write_text(path, text)
    if not check:
        for t in selected:
            if t.figures is not None:
                t.figures(results)
    return differ


def main(argv: Sequence[str] | None = None) -> int:
    import argparse

    from ego.params import ConfigError

    ap = argparse.ArgumentParser(prog="python -m ego.docs", description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    res = sub.add_parser("results", help="rerun the runs behind docs/results/ and rewrite its tables")
    res.add_argument(
        "--page", action="append", default=[], help="only this page (report-000, ..., envelope, cross-simulator)"
    )
    res.add_argument("--table", action="append", default=[], help="only this table (the marker's NAME)")
    res.add_argument("--check", action="store_true", help="compare with the committed text, write nothing")
    res.add_argument("--jobs", type=int, default=None, help="worker processes (default: one per CPU)")
    osc = sub.add_parser(
        "openscenario-table", help="rewrite docs/openscenario.md's supported-subset table from the element registry"
    )
    osc.add_argument("--check", action="store_true", help="compare with the committed text, write nothing")
    args = ap.parse_args(argv)
    if args.command == "openscenario-table":
        from ego.docs import subset

        current = subset.regenerate(args.check)
        if args.check:
            print(f"{subset.PAGE.name}: the subset table {'is' if current else 'differs from'} the registry's")
            return 0 if current else 1
        print(f"{'kept' if current else 'rewrote'} the subset table of {subset.PAGE.name}")
        return 0
    try:
        if not RESULTS.is_dir():
            raise ConfigError(
                f"no {RESULTS} here: the result pages live in a checkout of ego "
                "(pip install -e .), not in an installed wheel"
            )
        every = tables()
        pages = sorted({t.page for t in every})
        names = [t.name for t in every]
        for p in args.page:
            if p not in pages:
                raise ConfigError(f"unknown page {p!r} (known: {', '.join(pages)})")
        for n in args.table:
            if n not in names:
                raise ConfigError(f"unknown table {n!r} (known: {', '.join(names)})")
        if args.jobs is not None and args.jobs < 1:
            raise ConfigError(f"bad value for --jobs: {args.jobs} (expected a whole number of at least 1)")
    except ConfigError as exc:
        print(f"python -m ego.docs: error: {exc}", file=sys.stderr)
        return 2
    chosen = [t for t in every if (not args.page or t.page in args.page) and (not args.table or t.name in args.table)]
    differ = regenerate(chosen, args.check, args.jobs)
    if args.check:
        for name in differ:
            print(f"differs from the runs: {name}")
        print(f"{len(chosen) - len(differ)} of {len(chosen)} tables as committed")
        return 1 if differ else 0
    print(f"rewrote {len(differ)} of {len(chosen)} tables" + (f": {', '.join(differ)}" if differ else ""))
    return 0
