"""What the results pages and their per-report modules share: the paths, the controller
lists, a job (:class:`Sim`, one ``ego run``), a table (:class:`Table` of :class:`Row`) and
the CCR cell. Its own module so ``ego.docs`` and its report modules both import it from
below (no import circle).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "docs" / "results"
SWEEPS = ROOT / "scenarios" / "sweeps"
TRACKING = ("pid", "fuzzy", "fuzzy-pid", "bp-pid", "rbf-smc")
CURVE = ("pid", "fuzzy-curve", "narma-l2")
FOLLOWING = ("pid", "bp-pid-acc")
KMH = 3.6


@dataclass(frozen=True)
class Sim:
    """One ``ego run``: scenario, controller, seed and ``--set`` overrides (name, value)."""

    scenario: str
    controller: str
    seed: int = 0
    overrides: tuple[tuple[str, Any], ...] = ()
    #: ``collision_preventable``: False never, None after a collision (``--preventable``)
    preventable: bool | None = False

    def __call__(self) -> dict:
        from ego.runner import RunSpec, run

        spec = RunSpec(self.scenario, self.controller, self.seed, dict(self.overrides), preventable=self.preventable)
        return _table_metrics(run(spec))


def _table_metrics(result) -> dict:
    """A run's metrics as a table reads them: without the wall time (it differs run to run)
    and the event list."""
    return {k: v for k, v in result.metrics.items() if k not in ("wall_time", "events")}


def sim(scenario: str, controller: str, seed: int = 0, preventable: bool | None = False, **overrides: Any) -> Sim:
    return Sim(scenario, controller, seed, tuple(sorted(overrides.items())), preventable)


@dataclass(frozen=True)
class Row:
    """One table row: its label (first cell), the jobs it needs and how its other cells
    come from their results (in the order of ``jobs``)."""

    label: str
    jobs: tuple
    cells: Callable[[list], list[str]]


@dataclass(frozen=True)
class Table:
    name: str
    page: str  #: docs/results/<page>.md
    commands: tuple[str, ...]  #: what a user runs for the same runs
    header: tuple[str, ...]
    rows: tuple[Row, ...]
    notes: tuple[str, ...] = field(default=())
    #: writes the table's figures (docs/img/) from the same results, when the page is written
    figures: Callable[[dict], None] | None = None

    def row(self, label: str) -> Row:
        for r in self.rows:
            if r.label == label:
                return r
        raise KeyError(f"{self.name} has no row {label!r} (rows: {', '.join(r.label for r in self.rows)})")


def ccr_cell(m: dict) -> str:
    """``no (6.8 m)``: avoided, the smallest bumper gap; ``HIT 24.7 (20.1)``: the impact speed and
    in brackets the relative impact speed, km/h; ``HIT <id>``: a collision with another vehicle
    than the lead; a status: the run neither completed nor collided."""
    if m["status"] not in ("completed", "collision"):
        return m["status"]
    if not m["collision"]:
        return f"no ({m['min_gap_front']:.1f} m)"
    if m["collision_with"] != "lead":  # not what the test is about: say what it hit
        return f"HIT {m['collision_with']}"
    return f"HIT {m['impact_speed'] * KMH:.1f} ({m['impact_relative_speed'] * KMH:.1f})"
