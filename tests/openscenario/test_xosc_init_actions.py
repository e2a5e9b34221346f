"""Actions in Init that take time (the standard's non-instantaneous Init actions, 8.5.1.2):
started at t = 0 and left running until they end or a later action on the same domain of the
entity overrides them. Each file is hand-written for the test (xosc_scenes' straight road)."""

from __future__ import annotations

import numpy as np
import pytest
from xosc_scenes import event, run_scene, scene, sim_time, speed, trigger

from ego.openscenario.loader import load
from ego.openscenario.xmltree import ScenarioFileError


def _init(path, who: str, action: str) -> None:
    """Add ``action`` (a PrivateAction's content) to ``who``'s Init."""
    text = path.read_text()
    tag = f'<Private entityRef="{who}">'
    assert tag in text
    path.write_text(text.replace(tag, f"{tag}<PrivateAction>{action}</PrivateAction>", 1))


def _follow(ref: str, delta: float) -> str:
    return (
        '<LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="step" value="0" '
        f'dynamicsDimension="time"/><SpeedActionTarget><RelativeTargetSpeed entityRef="{ref}" value="{delta}" '
        'speedTargetValueType="delta" continuous="true"/></SpeedActionTarget></SpeedAction></LongitudinalAction>'
    )


def _distance(ref: str, distance: float) -> str:
    return (
        f'<LongitudinalAction><LongitudinalDistanceAction entityRef="{ref}" distance="{distance}" '
        'freespace="false" continuous="true"/></LongitudinalAction>'
    )


def test_a_continuous_relative_speed_in_init_starts_and_keeps_following(tmp_path):
    """B's Init speed is A's minus 5 m/s (continuous): 20 m/s from the start, and when A steps
    to 15 m/s at t = 1 s, B is at 10 m/s one step after A's change."""
    path = scene(tmp_path, [event("E", "A", speed(15.0), trigger([sim_time(1.0)]))])
    text = path.read_text()
    # B's own Init speed is replaced by the continuous relative one
    old = '<Private entityRef="B"><PrivateAction><TeleportAction>'
    assert old in text
    b_init = text[text.index(old) :].split("</Private>", 1)[0]
    new_b = b_init.rsplit("<PrivateAction>", 1)[0] + f"<PrivateAction>{_follow('A', -5.0)}</PrivateAction>"
    path.write_text(text.replace(b_init, new_b, 1))
    sc = load(path)
    assert [type(a).__name__ for a in sc.init_runs["B"]] == ["SpeedAction"]
    run = run_scene(path, 3.0)
    hist = {round(t, 1): v for t, v, _ in run._history["B"]}
    a_hist = {round(t, 1): v for t, v, _ in run._history["A"]}
    assert hist[0.0] == pytest.approx(20.0, abs=1e-9)
    assert all(hist[t] == pytest.approx(a_hist[t] - 5.0, abs=1e-6) for t in hist if t <= 1.0 or t >= 1.3)
    assert hist[2.0] == pytest.approx(10.0, abs=1e-6)


def test_a_distance_in_init_is_held_from_the_first_step(tmp_path):
    """B (lane -2) keeps 50 m behind C (lane -3, 15 m/s) from Init: exact after one step."""
    path = scene(tmp_path, [], at={"B": (-2, 348.0, 15.0)})
    _init(path, "B", _distance("C", 50.0))
    run = run_scene(path, 2.0)
    b, c = run.board.states["B"], run.board.states["C"]
    assert c.s - b.s == pytest.approx(50.0, abs=1e-6)
    assert any("LongitudinalDistanceAction in Init on B" in e.text for e in run.events)


def test_a_later_action_overrides_the_running_init_action(tmp_path):
    """A SpeedAction at t = 1 s on B takes B's speed from the distance action of its Init."""
    path = scene(tmp_path, [event("E", "B", speed(5.0), trigger([sim_time(1.0)]))], at={"B": (-2, 348.0, 15.0)})
    _init(path, "B", _distance("C", 50.0))
    run = run_scene(path, 3.0)
    assert run.board.states["B"].speed == pytest.approx(5.0, abs=1e-6)


def test_an_init_action_the_ego_cannot_do_is_refused_with_its_line(tmp_path):
    path = scene(tmp_path, [])
    sync = (
        '<SynchronizeAction masterEntityRef="A"><TargetPositionMaster><LanePosition roadId="0" laneId="-1" '
        's="300" offset="0"/></TargetPositionMaster><TargetPosition><LanePosition roadId="0" laneId="-3" s="280" '
        'offset="0"/></TargetPosition></SynchronizeAction>'
    )
    _init(path, "Ego", sync)
    with pytest.raises(ScenarioFileError, match=r"<SynchronizeAction> on the ego \(Ego\) is not supported"):
        run_scene(path, 1.0)


def test_a_longitudinal_distance_in_the_egos_init_is_its_reference_from_the_start(tmp_path):
    """In the ego's Init (a running action from t = 0), 30 m behind C (centres; C at 15 m/s from
    s = 400 m): the ego's position reference is there from the first step on."""
    path = scene(tmp_path, [])
    _init(path, "Ego", _distance("C", 30.0))
    run = run_scene(path, 2.0)
    tr, names = run.trace.array(), run.trace.names
    t, s_ref = tr[:, names.index("t")], tr[:, names.index("s_ref")]
    g = run.geometry
    held = 400.0 + 15.0 * t - 30.0 - (g.cg_to_front - 0.5 * g.length)  # the ego's cg 30 m behind C's centre
    on = t > 0.1 + 1e-9
    assert np.max(np.abs(s_ref[on] - held[on])) < 1e-6


def _trajectory(points) -> str:
    verts = "".join(
        f'<Vertex time="{tt}"><Position><WorldPosition x="{x}" y="{y}"/></Position></Vertex>' for tt, x, y in points
    )
    return (
        '<RoutingAction><FollowTrajectoryAction><Trajectory name="t" closed="false"><Shape>'
        f"<Polyline>{verts}</Polyline></Shape></Trajectory><TimeReference>"
        '<Timing domainAbsoluteRelative="relative" scale="1" offset="0"/></TimeReference>'
        '<TrajectoryFollowingMode followingMode="position"/></FollowTrajectoryAction></RoutingAction>'
    )


def test_a_trajectory_in_init_without_a_teleport_starts_the_entity_at_its_first_vertex(tmp_path):
    """C has no TeleportAction, only a timed trajectory in Init (the reference player's
    alks_pedestrian.xosc form): it starts at the first vertex (s = 420 m on the ego's lane) and
    drives the first leg's 40 m in 2 s, the second (sqrt(40^2 + 3.5^2) m) in the next 2 s."""
    path = scene(tmp_path, [])
    text = path.read_text()
    old = text[text.index('<Private entityRef="C">') :].split("</Private>", 1)[0] + "</Private>"
    traj = _trajectory(((0.0, 420.0, -3.5), (2.0, 460.0, -3.5), (4.0, 500.0, 0.0)))
    path.write_text(text.replace(old, f'<Private entityRef="C"><PrivateAction>{traj}</PrivateAction></Private>'))
    sc = load(path)
    assert type(sc.init["C"][0]).__name__ == "TeleportAction"
    run = run_scene(path, 5.0)
    hist = {round(t, 6): (v, d) for t, v, d in run._history["C"]}
    assert sc.init["C"][0].position.x == 420.0  # type: ignore[union-attr]
    for t in (0.0, 0.5, 1.0, 1.5, 1.9):
        assert hist[t][0] == pytest.approx(20.0, abs=1e-6)
        assert hist[t][1] == pytest.approx(0.0, abs=1e-6)
    assert hist[3.0][0] == pytest.approx((40.0**2 + 3.5**2) ** 0.5 / 2.0, abs=1e-6)


def test_a_continuous_relative_speed_of_the_ego_moves_its_speed_reference(tmp_path):
    """The ego follows A's speed less 5 m/s from Init: when A steps down to 15 m/s at t = 1 s the
    ego's speed reference is 10 m/s, and pid brings the ego there (its speed within 0.5 m/s at
    t = 10 s). (Before, a continuous relative speed on the ego ended in a traceback once its
    profile was done: the SUMO command meant for the others was sent to the ego.)"""
    path = scene(tmp_path, [event("E", "A", speed(15.0), trigger([sim_time(1.0)]))])
    _init(path, "Ego", _follow("A", -5.0))
    run = run_scene(path, 10.0)
    assert run.status in ("completed", "timeout")
    assert run.ego.state[1] == pytest.approx(10.0, abs=0.5)


def test_a_continuous_relative_speed_on_the_ego_in_an_event_runs(tmp_path):
    """The same in an event (a traceback before: SUMO has no vehicle 'Ego' to command)."""
    path = scene(tmp_path, [event("F", "Ego", _follow("A", -5.0), trigger([sim_time(1.0)]))])
    run = run_scene(path, 6.0)
    assert run.status in ("completed", "timeout")
    assert run.ego.state[1] == pytest.approx(20.0, abs=0.5)


def _light(mode: str) -> str:
    return (
        '<AppearanceAction><LightStateAction transitionTime="0"><LightType><VehicleLight vehicleLightType="fogLights"/>'
        f'</LightType><LightState mode="{mode}" luminousIntensity="0"/></LightStateAction></AppearanceAction>'
    )


def test_a_light_state_changes_nothing_and_a_bad_mode_is_one_line(tmp_path):
    """AppearanceAction/LightStateAction (1.2), in Init and in an event: accepted, done at once,
    the run as without it (A's speeds alike); a mode outside on/off/flashing is refused."""
    (tmp_path / "plain").mkdir()
    plain = run_scene(scene(tmp_path / "plain", []), 2.0)
    path = scene(tmp_path, [event("L", "A", _light("on"), trigger([sim_time(0.5)]))])
    _init(path, "A", _light("off"))
    lit = run_scene(path, 2.0)
    assert [v for _, v, _ in lit._history["A"]] == [v for _, v, _ in plain._history["A"]]
    path = scene(tmp_path, [event("L", "A", _light("dim"), trigger([sim_time(0.5)]))])
    with pytest.raises(ScenarioFileError, match=r"bad value for mode in <LightState>: 'dim'"):
        load(path)
