"""The tables of docs/results/curved-roads.md (``python -m ego.docs results --page
curved-roads``): every tracking controller keeping its lane with no other traffic on the
straight motorway, in the R 1000 m arcs at 130 km/h, the R 250 m arcs at 60 km/h (left and
right) and on the road of changing curvature, and the emergency lane change and the cut-in
on each road beside the straight one (``--set road=``, ``sumo_nets/motorway_arcs.py``).

The lane-keeping runs are ``emergency-brake`` with ``traffic_density=0 lead_gap=300
lead_final_speed=40``: no background, the lead 300 m ahead and never slower than the ego, so
the ego only keeps its lane (:class:`LaneKeeping`); ``scripts/curved_manoeuvres.py`` prints
the manoeuvre tables' runs with these cells (:func:`manoeuvre_cells`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ego.docs.common import KMH, ROOT, TRACKING, Row, Table, sim

PAGE = "curved-roads"
#: s after the ego's centre of gravity enters a curve that the entry transient is over
SETTLE = 3.0
#: the lane-keeping cases: road, speed (km/h), duration (s: the ego leaves the curved part 5 s
#: or more before the end)
LANE_KEEPING = (
    ("straight", 130.0, 50.0),
    ("left-1000", 130.0, 50.0),
    ("right-1000", 130.0, 50.0),
    ("left-250", 60.0, 56.0),
    ("right-250", 60.0, 56.0),
    ("clothoid", 80.0, 58.0),
)
#: the roads of the manoeuvre tables, the straight one first (the reference)
ROADS = ("straight", "left-250", "right-250", "left-1000", "right-1000", "clothoid")


@dataclass(frozen=True)
class LaneKeeping:
    """One lane-keeping run (no other traffic near): its status, :func:`lane_keeping_figures`
    and the largest lane departure (m)."""

    controller: str
    road: str
    speed: float  #: km/h
    duration: float  #: s

    def __call__(self) -> dict:
        from ego.runner import RunSpec, run

        overrides = lane_keeping_overrides(self.road, self.speed / KMH, self.duration)
        r = run(RunSpec("emergency-brake", self.controller, overrides=overrides, requirements=()))
        return {
            "status": r.status,
            **lane_keeping_figures(r.column("t"), r.column("s"), r.column("e_lat"), curved_span(self.road)),
            "max_lane_departure": r.metrics.get("max_lane_departure"),
        }


def lane_keeping_overrides(road: str, speed: float, duration: float) -> dict:
    """emergency-brake's parameters for lane keeping on ``road`` at ``speed`` (m/s) for
    ``duration`` (s): no background traffic, the lead 300 m ahead and never slower."""
    return {
        "road": road,
        "ego_speed": speed,
        "traffic_density": 0,
        "lead_gap": 300,
        "lead_final_speed": 40,
        "duration": duration,
    }


def _road_design():
    """The roads' design, ``sumo_nets/motorway_arcs.py`` of the checkout, loaded by its path:
    the checkout's root is on no worker's ``sys.path`` (a pool worker of the page's runs, CI
    without ``PYTHONPATH``)."""
    import importlib.util
    import sys

    name = "ego_docs_motorway_arcs"
    module = sys.modules.get(name)
    if module is None:
        spec = importlib.util.spec_from_file_location(name, ROOT / "sumo_nets" / "motorway_arcs.py")
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return module


def curved_span(road: str) -> tuple[float, float] | None:
    """(start, end) m along the middle lane of ``road``'s curved part (its arc, or the road of
    changing curvature's clothoids and arcs); None for the straight road."""
    arcs = _road_design()
    ARCS, CLOTHOID, LEAD_IN = arcs.ARCS, arcs.CLOTHOID, arcs.LEAD_IN
    if road == "clothoid":
        return LEAD_IN, LEAD_IN + sum(piece[0] for piece in CLOTHOID)
    if road in ARCS:
        _, radius, turn, _ = ARCS[road]
        return LEAD_IN, LEAD_IN + radius * math.radians(turn)
    return None


def lane_keeping_figures(t: np.ndarray, s: np.ndarray, e_lat: np.ndarray, span: tuple[float, float] | None) -> dict:
    """max and RMS |e_lat| (m) over the run, and the max in the curve (``max_e_lat_in``): from
    SETTLE s after the centre of gravity passes ``span``'s start until it passes its end (None
    without a span or when the run leaves no such time)."""
    e = np.abs(e_lat)
    inside = None
    if span is not None:
        entered, left = np.flatnonzero(s >= span[0]), np.flatnonzero(s >= span[1])
        if entered.size:
            end = t[left[0]] if left.size else np.inf
            window = e[(t >= t[entered[0]] + SETTLE) & (t <= end)]
            inside = float(window.max()) if window.size else None
    return {"max_e_lat": float(e.max()), "rms_e_lat": float(np.sqrt(np.mean(e * e))), "max_e_lat_in": inside}


def _m(v, digits: int = 3) -> str:
    return "-" if v is None else f"{v:.{digits}f}"


def _lane_keeping_cells(ms: list[dict]) -> list[str]:
    (m,) = ms
    return [
        m["status"],
        _m(m["max_e_lat"]),
        _m(m["max_e_lat_in"]),
        _m(m["rms_e_lat"]),
        _m(m["max_lane_departure"]),
    ]


def lane_keeping_table() -> Table:
    rows = tuple(
        Row(f"{road}, {speed:g} km/h, {c}", (LaneKeeping(c, road, speed, duration),), _lane_keeping_cells)
        for road, speed, duration in LANE_KEEPING
        for c in TRACKING
    )
    return Table(
        "curved-lane-keeping",
        PAGE,
        (
            "ego run emergency-brake -c pid --set road=left-1000 --set ego_speed=36.111 --set traffic_density=0 "
            "--set lead_gap=300 --set lead_final_speed=40 --set duration=50",
        ),
        (
            "road, speed, controller",
            "status",
            "max \\|e_lat\\| [m]",
            f"max \\|e_lat\\| in the curve, from {SETTLE:g} s after its start [m]",
            "RMS e_lat [m]",
            "max lane departure [m]",
        ),
        rows,
        (
            "No other traffic near: emergency-brake with traffic_density=0, lead_gap=300 and "
            "lead_final_speed=40 (the lead 300 m ahead, never slower than the ego), seed 0. e_lat: the "
            "ego's centre of gravity from its lane's centre line. Every curved road starts to curve 350 m "
            "along (the ego's front starts at 300 m), and each run lasts until 5 s or more after the ego "
            "leaves the curved part: the first error column covers the entry and the exit. The second "
            f"leaves the entry transient out: from {SETTLE:g} s after the centre of gravity enters the "
            "curved part until it leaves it (on the road of changing curvature, 350 - 1450 m along, that "
            "is still its clothoids and arcs).",
        ),
    )


#: scenario -> the columns of its manoeuvre table (after the row label), as manoeuvre_cells
#: fills them
MANOEUVRE_HEADER = {
    "emergency-brake": ("status", "collision", "lane change [s]", "overshoot [m]"),
    "cut-in": ("status", "collision", "response", "max decel [m/s^2]"),
}
ALONG_THE_LANE = ("min front gap [m]", "min front TTC [s]", "max lane departure [m]")


def manoeuvre_cells(scenario: str, m: dict) -> list[str]:
    """The cells of one manoeuvre run under MANOEUVRE_HEADER[scenario] + ALONG_THE_LANE:
    status, collision, the lane change's duration (s) and overshoot (m) or the cut-in's
    response and largest deceleration (m/s^2), the min front gap along the lane (m), the min
    front TTC (s) and the largest lane departure (m)."""
    if scenario == "cut-in":
        what = [str(m.get("response") or "-"), _m(m.get("max_decel"), 2)]
    else:
        what = [_m(m.get("lane_change_duration"), 2), _m(m.get("max_overshoot"))]
    return [
        m["status"],
        "yes" if m.get("collision") else "no",
        *what,
        _m(m.get("min_gap_front"), 2),
        _m(m.get("min_ttc_front"), 2),
        _m(m.get("max_lane_departure")),
    ]


def _manoeuvre_row(scenario: str, road: str, controller: str) -> Row:
    straight = sim(scenario, controller)  # the default road: the same run as the straight row's
    curved = straight if road == "straight" else sim(scenario, controller, road=road)

    def cells(ms: list[dict]) -> list[str]:
        here, there = ms
        out = manoeuvre_cells(scenario, here)
        if scenario == "emergency-brake":
            a, b = here.get("max_overshoot"), there.get("max_overshoot")
            out.append("-" if a is None or b is None else f"{a - b:+.3f}")
        return out

    return Row(f"{road}, {controller}", (curved, straight), cells)


def manoeuvre_table(scenario: str) -> Table:
    rows = tuple(_manoeuvre_row(scenario, road, c) for road in ROADS for c in TRACKING)
    extra = ("overshoot vs straight [m]",) if scenario == "emergency-brake" else ()
    return Table(
        f"curved-{scenario}",
        PAGE,
        (
            f"ego run {scenario} -c pid --set road=left-250",
            f"python scripts/curved_manoeuvres.py --scenarios {scenario}",
        ),
        ("road, controller",) + MANOEUVRE_HEADER[scenario] + ALONG_THE_LANE + extra,
        rows,
        (
            "Default parameters, seed 0. The gap and TTC are along the ego's lane (arc length), "
            "bumper to bumper."
            + (
                " Overshoot vs straight: this run's overshoot minus the same controller's on the "
                "straight road (issue 38 asks for at most 0.1 m)."
                if extra
                else ""
            ),
        ),
    )


def tables() -> list[Table]:
    return [lane_keeping_table(), manoeuvre_table("emergency-brake"), manoeuvre_table("cut-in")]
