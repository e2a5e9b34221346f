"""The ego of a scenario file: which entity it is, and the actions on it that become the
references of ego's controller under test (hand-written files on xosc_scenes' straight road,
real SUMO): a trajectory (its lateral offset at the ego's s, and its timing), a longitudinal
distance (the standard's law drives the reference point the ego follows), a speed profile,
and an Init offset from the lane's centre (held). Each tracking controller's error is measured
against the analytic path."""

from __future__ import annotations

import math

import numpy as np
import pytest
from xosc_scenes import event, scene, sim_time, trigger

from ego.cli import main
from ego.openscenario.scenario import choose_ego, file_listing
from ego.params import ConfigError
from ego.runner import RunSpec, build

#: the other cars out of the ego's way (lane -1, far ahead)
AWAY = {"A": (-1, 400.0, 25.0), "B": (-1, 450.0, 25.0), "C": (-1, 480.0, 25.0)}


def _run(path, controller: str = "pid", duration: float = 10.0, **overrides):
    """Run the file; the scenario, and (t, s, d, speed) of the ego's reference point (its box
    centre: the scene's cars have center.x 0) in its lane frame at every storyboard step."""
    sc = build(RunSpec(str(path), controller, overrides={"duration": duration, **overrides}))
    sc.reset()
    rows: list[tuple[float, float, float, float]] = []
    step = sc.board.step

    def spy(t):
        e = sc.board.states[sc.ego_name]
        s, d, _ = sc.road.project(e.x, e.y)
        rows.append((t, s, d, e.speed))
        step(t)

    sc.board.step = spy
    obs = sc.obs
    while not sc.done:
        obs = sc.step(sc.controller.step(obs))
    sc.close()
    return sc, rows


# -- which entity is the ego ----------------------------------------------------------------------
def test_the_ego_is_the_one_named_ego_then_hero_then_the_first_vehicle():
    car, walker, turned = "vehicle", "other", "turned"
    assert choose_ego([("Lead", car), ("EGO", car)], "", "f") == ("EGO", "named Ego (any case)")
    assert choose_ego([("Lead", car), ("hero", car)], "", "f") == ("hero", "named hero")
    name, why = choose_ego([("Walker", walker), ("Car2", car), ("Car1", car)], "", "f")
    assert name == "Car2" and why.startswith("the first vehicle in file order")
    # a car turned against its lane is passed over (the ego drives its lane's way), unless all are
    name, why = choose_ego([("Wrong", turned), ("Right", car)], "", "f")
    assert name == "Right" and "Wrong start turned against theirs" in why
    assert choose_ego([("Wrong", turned)], "", "f")[0] == "Wrong"
    assert choose_ego([("Lead", car), ("Ego", car)], "lead", "f") == ("Lead", "chosen by --ego")
    with pytest.raises(ConfigError, match=r"f: no vehicle to be the ego .* \(entities: Walker\)"):
        choose_ego([("Walker", walker)], "", "f")
    with pytest.raises(ConfigError, match="bad value for --ego: 'Nope'"):
        choose_ego([("Ego", car)], "Nope", "f")


def test_without_an_ego_name_the_first_vehicle_drives_and_list_and_run_agree(tmp_path, capsys):
    path = scene(tmp_path, [])
    path.write_text(path.read_text().replace('"Ego"', '"Car"'))
    listing = file_listing(str(path))
    assert listing["ego"] == "Car" and listing["supported"], listing["error"]
    sc, _ = _run(path, duration=1.0)
    assert sc.events[0].kind == "ego"
    assert sc.events[0].text.startswith("the ego is 'Car': the first vehicle in file order")
    assert main(["list", str(path)]) == 0
    assert "<- the ego: the first vehicle in file order" in capsys.readouterr().out


# -- an Init offset -------------------------------------------------------------------------------
def test_the_ego_starts_at_its_init_offset_and_holds_it(tmp_path):
    """The ego 0.4 m left of its lane's centre in Init starts there (SUMO inserts on the centre;
    the plant starts at the offset) and holds it as its lateral reference."""
    path = scene(tmp_path, [], at=AWAY)
    path.write_text(path.read_text().replace('laneId="-3" s="20.0" offset="0"', 'laneId="-3" s="20.0" offset="0.4"'))
    sc, rows = _run(path, duration=4.0)
    assert sc.status == "completed"
    assert rows[0][2] == pytest.approx(0.4, abs=1e-6)
    assert max(abs(d - 0.4) for _, _, d, _ in rows) < 0.01


# -- a trajectory ---------------------------------------------------------------------------------
S0, L, W = 100.0, 60.0, 3.5  #: a sinusoidal lane change of 3.5 m to the left over s = 100...160 m


def d_path(s: float) -> float:
    u = min(max((s - S0) / L, 0.0), 1.0)
    return W * (1.0 - math.cos(math.pi * u)) / 2.0


def _trajectory(speed: float | None = None) -> str:
    """The lane change as a polyline of lane positions every 2 m from s = 80 m to 200 m; with
    ``speed`` timed (absolute) as a car at that speed from s = 20 m at t = 0."""
    verts = ""
    for k in range(61):
        s = S0 - 20.0 + 2.0 * k
        tt = f' time="{(s - 20.0) / speed:.6f}"' if speed else ""
        verts += (
            f'<Vertex{tt}><Position><LanePosition roadId="0" laneId="-3" s="{s}" offset="{d_path(s):.9f}"/>'
            "</Position></Vertex>"
        )
    ref = '<Timing domainAbsoluteRelative="absolute" scale="1" offset="0"/>' if speed else "<None/>"
    return (
        '<RoutingAction><FollowTrajectoryAction><TrajectoryRef><Trajectory name="t" closed="false"><Shape>'
        f"<Polyline>{verts}</Polyline></Shape></Trajectory></TrajectoryRef><TimeReference>{ref}</TimeReference>"
        '<TrajectoryFollowingMode followingMode="position"/></FollowTrajectoryAction></RoutingAction>'
    )


#: the largest lateral error (m) of the ego's reference point from the analytic path, measured
#: (2026-11-29) with a margin: pid 0.58, fuzzy 1.12, fuzzy-pid 0.79, bp-pid 0.75, rbf-smc 0.026
LATERAL_BOUND = {"pid": 0.65, "fuzzy": 1.2, "fuzzy-pid": 0.85, "bp-pid": 0.8, "rbf-smc": 0.04}


@pytest.mark.parametrize("controller", sorted(LATERAL_BOUND))
def test_a_trajectory_on_the_ego_is_its_lateral_reference(tmp_path, controller):
    """The ego (20 m/s) follows the lane change the trajectory draws: its reference point's
    offset against the path's offset at its s, over the whole change and 40 m after."""
    path = scene(tmp_path, [event("T", "Ego", _trajectory(), trigger([sim_time(0)]))], at=AWAY)
    sc, rows = _run(path, controller)
    assert sc.status == "completed", sc.status_detail
    err = [d - d_path(s) for _, s, d, _ in rows if S0 - 20.0 < s < S0 + L + 40.0]
    assert len(err) >= 55
    worst = max(map(abs, err))
    print(f"{controller}: max |e| {worst:.3f} m, rms {math.sqrt(np.mean(np.square(err))):.3f} m")
    assert worst < LATERAL_BOUND[controller]
    assert rows[-1][2] == pytest.approx(W, abs=0.15)  # in the left lane at the end


def test_a_timed_trajectory_on_the_ego_sets_its_speed_reference(tmp_path):
    """Timed as a car at 15 m/s from s = 20 m at t = 0 (its first point, s = 80 m, at t = 4 s),
    the trajectory slows the ego (20 m/s) to 15 m/s: before the first point the reference goes
    there at the speed that reaches it on time, then it is the path's s and speed at the time."""
    path = scene(tmp_path, [event("T", "Ego", _trajectory(15.0), trigger([sim_time(0)]))], at=AWAY)
    sc, rows = _run(path, duration=9.0)
    assert sc.status == "completed", sc.status_detail
    tr, names = sc.trace.array(), sc.trace.names
    t, v_ref = tr[:, names.index("t")], tr[:, names.index("speed_ref")]
    assert np.all(np.abs(v_ref[t > 0.1] - 15.0) < 1e-3)  # the lead-in and the path (times to 1e-6 s)
    late = [(t, s) for t, s, _, v in rows if t > 6.0]
    # the reference point's s against the path's 20 + 15 t
    assert max(abs(s - (20.0 + 15.0 * t)) for t, s in late) < 1.5
    assert rows[-1][3] == pytest.approx(15.0, abs=0.3)


# -- a longitudinal distance ----------------------------------------------------------------------
def _distance(attrs: str) -> str:
    return (
        f'<LongitudinalAction><LongitudinalDistanceAction entityRef="A" {attrs} freespace="true" '
        'continuous="true"/></LongitudinalAction>'
    )


def test_a_longitudinal_distance_on_the_ego_is_a_gap_reference(tmp_path):
    """From t = 1 s the ego (20 m/s, 45.5 m behind A at 18 m/s, bumper to bumper) keeps 30 m
    behind A: the reference point the standard's law drives is at 30 m from the first step on
    (unconstrained), and the ego closes on it (pid, slow on position: 2.1 m off 10 s later,
    closer after)."""
    at = {**AWAY, "A": (-3, 70.0, 18.0)}
    path = scene(tmp_path, [event("D", "Ego", _distance('distance="30"'), trigger([sim_time(1.0)]))], at=at)
    sc, _ = _run(path, duration=20.0, evade=False)
    tr, names = sc.trace.array(), sc.trace.names
    t, s, s_ref = (tr[:, names.index(k)] for k in ("t", "s", "s_ref"))
    g = sc.geometry
    off = g.cg_to_front - 0.5 * g.length  # the box centre ahead of the cg
    a_s = 70.0 + 18.0 * t  # A's box centre at constant speed (SUMO: exactly)
    held = a_s - 30.0 - 4.5 - off  # the cg's s 30 m bumper to bumper behind A
    late = t > 1.1 - 1e-9  # from the step after the start: unconstrained, at the distance after one step
    assert np.max(np.abs(s_ref[late] - held[late])) < 0.2
    gap = a_s - (s + off) - 4.5
    assert abs(gap[np.searchsorted(t, 11.0)] - 30.0) < 2.5
    assert abs(gap[-1] - 30.0) < abs(gap[np.searchsorted(t, 11.0)] - 30.0)


# -- a speed profile ------------------------------------------------------------------------------
def test_a_speed_profile_on_the_ego_is_its_speed_reference(tmp_path):
    """From 20 m/s at t = 1 s to 25 m/s in 2 s, then to 15 m/s in 4 s: the speed reference goes
    through the knots and the ego follows (pid: within 1.51 m/s, the most where the rate turns
    from +2.5 to -2.5 m/s^2)."""
    entries = '<SpeedProfileEntry speed="25" time="2"/><SpeedProfileEntry speed="15" time="4"/>'
    action = (
        f'<LongitudinalAction><SpeedProfileAction followingMode="position">{entries}</SpeedProfileAction>'
        "</LongitudinalAction>"
    )
    path = scene(tmp_path, [event("P", "Ego", action, trigger([sim_time(1.0)]))], at=AWAY)
    sc, _ = _run(path, duration=9.0)
    tr, names = sc.trace.array(), sc.trace.names
    t, v, v_ref = (tr[:, names.index(k)] for k in ("t", "speed", "speed_ref"))
    want = np.interp(t, [1.0, 3.0, 7.0], [20.0, 25.0, 15.0])
    # the reference is the profile at its time from the storyboard's step that starts it on
    # (the storyboard steps at 1 s before the ego's controller plans from there)
    on = t > 1.0 - 1e-9
    assert np.max(np.abs(v_ref - want)) < 1e-9
    assert np.all(v_ref[~on] == 20.0) and np.any(v_ref[(t > 1.0) & (t < 1.1)] > 20.0)
    assert np.max(np.abs(v - want)) < 1.6


def test_a_time_gap_on_the_ego_is_its_reference_speed_times_the_gap(tmp_path):
    """timeGap 1.5 s behind A (18 m/s, freespace): the law makes the reference point's gap 1.5 s
    times its own speed after each step (the standard's time gap: the actor's speed), so the gap
    closes on 27 m at A's speed geometrically (by 1.5 / 1.6 a step: within 1 cm 12 s later), and
    the ego follows it (pid: within 2.5 m 10 s later)."""
    at = {**AWAY, "A": (-3, 70.0, 18.0)}
    path = scene(tmp_path, [event("D", "Ego", _distance('timeGap="1.5"'), trigger([sim_time(1.0)]))], at=at)
    sc, _ = _run(path, duration=14.0, evade=False)
    tr, names = sc.trace.array(), sc.trace.names
    t, s, s_ref, v_ref = (tr[:, names.index(k)] for k in ("t", "s", "s_ref", "speed_ref"))
    g = sc.geometry
    off = g.cg_to_front - 0.5 * g.length
    a_s = 70.0 + 18.0 * t
    late = t > 13.0
    gap_ref = a_s - (s_ref + off) - 4.5
    assert np.max(np.abs(gap_ref[late] - 27.0)) < 0.01
    assert np.max(np.abs(v_ref[late] - 18.0)) < 0.01
    assert np.all(np.diff(gap_ref[(t > 1.35) & (t < 13.0)]) <= 1e-9)  # closing, never overshooting
    gap = a_s - (s + off) - 4.5
    assert abs(gap[np.searchsorted(t, 11.0)] - 27.0) < 2.5
