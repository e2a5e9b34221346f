"""A TeleportAction on the ego during the run (the reference player's `lane_change_simple.xosc`
sends its ego back to the road's start): the plant's pose becomes the position's, its speed is
kept, its lane is found again there and the run goes on. Hand-written files on xosc_scenes'
straight road (its reference line y = 5.25 m, heading 0, three 3.5 m lanes: lane -2's centre is
y = 0), real SUMO."""

from __future__ import annotations

import math

import pytest
from xosc_scenes import event, scene, sim_time, trigger

from ego.runner import RunSpec, build

#: the other cars out of the ego's way (lane -1, far ahead)
AWAY = {"A": (-1, 400.0, 25.0), "B": (-1, 450.0, 25.0), "C": (-1, 480.0, 25.0)}


def teleport(lane: int, s: float, offset: float) -> str:
    return (
        f'<TeleportAction><Position><LanePosition roadId="0" laneId="{lane}" s="{s}" offset="{offset}"/>'
        "</Position></TeleportAction>"
    )


def test_a_teleport_moves_the_ego_there_keeps_its_speed_and_the_run_goes_on(tmp_path):
    # the ego in lane -3 at s = 20 m, 20 m/s; at t = 2 s back to s = 30 m in lane -2, 0.3 m left
    # of its centre: the world point (30, 0.3), heading 0 (the road's)
    path = scene(tmp_path, [event("Back", "Ego", teleport(-2, 30.0, 0.3), trigger([sim_time(2.0)]))], at=AWAY)
    sc = build(RunSpec(str(path), "pid", overrides={"duration": 8.0}))
    sc.reset()
    g = sc.geometry
    off = g.cg_to_front - 0.5 * g.length  # the box centre (the reference point: center x 0) ahead of the cg
    seen: list[tuple[float, float, float, float, float, float]] = []
    step = sc.board.step

    def spy(t):
        before = sc.ego.state
        step(t)
        X, u, Y, _, psi, _ = sc.ego.state
        seen.append((t, X + off * math.cos(psi), Y + off * math.sin(psi), psi, u, before[1]))

    sc.board.step = spy
    obs = sc.obs
    while not sc.done:
        obs = sc.step(sc.controller.step(obs))
    sc.close()
    assert sc.status in ("completed", "timeout"), sc.status_detail
    at = [row for row in seen if row[0] >= 2.0 - 1e-9]
    t, x, y, psi, u, u_before = at[0]
    assert t == pytest.approx(2.0, abs=1e-9)
    assert (
        x == pytest.approx(30.0, abs=1e-6) and y == pytest.approx(0.3, abs=1e-6) and psi == pytest.approx(0.0, abs=1e-9)
    )
    assert u == u_before and u > 15.0  # the speed kept
    # the run goes on from there: in lane -2, the offset held as its lateral reference
    lanes = sc.lane_offset
    assert sc.target_lane == sorted(lanes, key=lambda i: lanes[i])[1]
    X, _, Y, _, _, _ = sc.ego.state
    assert Y == pytest.approx(0.3, abs=0.15) and X > 30.0 + 5.0 * 15.0
    ego = sc.board.states[sc.ego_name]
    assert ego.traveled < 8.0 * 25.0 - 30.0  # the jump back is no distance travelled


def test_a_teleport_off_the_ego_road_is_a_warning_and_nothing_moves(tmp_path, capsys):
    # 100 m beside the road: ego drives on its start road only
    far = '<TeleportAction><Position><WorldPosition x="50" y="100" h="0"/></Position></TeleportAction>'
    path = scene(tmp_path, [event("Away", "Ego", far, trigger([sim_time(1.0)]))], at=AWAY)
    sc = build(RunSpec(str(path), "pid", overrides={"duration": 3.0}))
    sc.run()
    assert sc.status in ("completed", "timeout"), sc.status_detail
    assert "TeleportAction on the ego: the position is off the ego's road" in capsys.readouterr().err
    X, _, Y, _, _, _ = sc.ego.state
    assert X > 20.0 + 2.5 * 15.0 and abs(Y - -3.5) < 0.2  # on in lane -3 (centre y = -3.5)
