"""emergency-brake over its operating envelope: no divergence, and no collision that
braking at the friction limit from the trigger would have avoided."""

from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

from ego.models import NonlinearBicycleParams
from ego.runner import RunSpec, resolve, run
from ego.scenarios.envelope import avoidable, braking_min_gap, lead_speed, sample

P = NonlinearBicycleParams()
#: the car's braking limit: the friction circle plus rolling resistance (m/s^2)
DECEL_LIMIT = P.F_max / P.m + P.f * P.g

CONTROLLERS = ("pid", "fuzzy", "fuzzy-pid", "bp-pid", "rbf-smc")

#: cases that spun the car (fuzzy, rbf-smc over-braking) or hit the lead (fuzzy's slow
#: brake) before the friction-aware brake and the AEB
FAILED_BEFORE = [
    ("fuzzy", 8889, dict(lead_decel=4.72, ego_speed=26.61, lead_gap=39.49, traffic_density=11.7)),
    ("rbf-smc", 1282, dict(lead_decel=5.3, ego_speed=26.73, lead_gap=29.57, traffic_density=21.11)),
    ("fuzzy", 8630, dict(lead_decel=6.46, ego_speed=24.75, lead_gap=35.74, traffic_density=13.54)),
    ("rbf-smc", 9264, dict(lead_decel=4.32, ego_speed=29.22, lead_gap=54.94, traffic_density=3.52, block_right=True)),
    ("fuzzy", 384, dict(lead_decel=4.7, ego_speed=27.99, lead_gap=34.98, traffic_density=19.28)),
]


def _spec(controller, seed, case, **extra):
    return RunSpec("emergency-brake", controller, seed, {k: str(v).lower() for k, v in {**case, **extra}.items()})


def test_braking_min_gap_matches_the_closed_form():
    # a lead at constant 10 m/s, the ego at 25 m/s braking at 6 m/s^2 from 40 m:
    # the gap shrinks by (25 - 10)^2 / (2 * 6) = 18.75 m
    gap = braking_min_gap(0.0, 40.0, 25.0, 6.0, lambda t: np.full_like(t, 10.0))
    assert gap == pytest.approx(40.0 - 18.75, abs=1e-3)
    # a lead braking to a stop: both stopping distances
    speed = lambda t: lead_speed(t, 20.0, 0.0, 8.0, 0.0)  # noqa: E731
    gap = braking_min_gap(0.0, 10.0, 20.0, 6.0, speed)
    assert gap == pytest.approx(10.0 + 20.0**2 / 16.0 - 20.0**2 / 12.0, abs=1e-3)


def _sensed_world_min_gap(t0, gap0, v0, decel, speed, step, dt=2e-4, horizon=7.0):
    """The run's world stepped by hand: the lead moves only at SUMO's steps (multiples of
    ``step`` on the simulation clock, each by its speed at the step's end), the sensor carries
    it on at its last step's speed in between; the ego brakes from ``t0``."""
    k = np.floor(t0 / step + 1e-9)
    t_k = k * step
    x_k = 0.0  # the lead at its last step
    v_k = float(speed(np.array([t_k]))[0])
    lead0 = x_k + v_k * (t0 - t_k)
    ego, v, t, best = 0.0, v0, t0, gap0
    while t < t0 + horizon:
        t += dt
        a = decel if v > 0.0 else 0.0
        ego += max(v - 0.5 * a * dt, 0.0) * dt if v > a * dt else 0.5 * v * v / max(a, 1e-12) if v > 0 else 0.0
        v = max(v - a * dt, 0.0)
        while t >= (k + 1) * step - 1e-12:
            k += 1
            v_k = float(speed(np.array([k * step]))[0])
            x_k += v_k * step
            t_k = k * step
        best = min(best, gap0 + (x_k + v_k * (t - t_k) - lead0) - ego)
    return best


@pytest.mark.parametrize("t0", [2.0, 2.02, 2.06, 2.09])
def test_braking_min_gap_sees_the_lead_as_the_run_does_between_sumo_steps(t0):
    # the lead braking at 7 m/s^2 from 30 to 5 m/s, SUMO stepping every 0.1 s: the margin
    # from a trigger between steps is the one of the run's own world (found by falsify:
    # a trigger 0.06 s after a step once read +1.1 cm where the run hit the lead)
    speed = lambda t: lead_speed(t, 30.0, 1.0, 7.0, 5.0)  # noqa: E731
    want = _sensed_world_min_gap(t0, 30.0, 34.0, 6.96, speed, 0.1)
    got = braking_min_gap(t0, 30.0, 34.0, 6.96, speed, lead_step=0.1)
    assert got == pytest.approx(want, abs=2e-3)


#: avoidable collisions ego falsify found with pid over the whole envelope (2,000 runs): a
#: trigger between two SUMO steps, both neighbour lanes rejected, the AEB braking at the
#: friction limit from the trigger's step. The criterion had put the lead's SUMO steps at the
#: trigger plus multiples of 0.1 s, not on SUMO's clock, and read a margin of 0.4-11 mm
#: where the run's own world has none: physics, not the controller
FOUND_BY_FALSIFY = [
    (55235, dict(ego_speed=34.618, lead_decel=7.3843, lead_gap=79.6204, traffic_density=22.6405, block_right=True)),
    (73543, dict(ego_speed=34.9364, lead_decel=5.6081, lead_gap=77.4584, traffic_density=24.8071, block_right=True)),
    (
        37630,
        dict(
            ego_speed=35.1204,
            lead_decel=5.369,
            lead_gap=73.9409,
            traffic_density=24.6122,
            block_left=True,
            block_right=True,
        ),
    ),
]


@pytest.mark.sumo
@pytest.mark.parametrize("seed, case", FOUND_BY_FALSIFY, ids=[str(s) for s, _ in FOUND_BY_FALSIFY])
def test_a_trigger_between_sumo_steps_is_judged_on_sumos_clock(seed, case):
    m = run(_spec("pid", seed, case)).metrics
    # the collision stays reported; braking at the limit from the trigger (which the AEB did)
    # could not have avoided it
    assert m["status"] == "collision" and m["collision_with"] == "lead"
    assert m["aeb_time"] == m["trigger_time"] and m["max_decel"] == pytest.approx(DECEL_LIMIT, abs=0.01)
    assert m["collision_avoidable"] is False


@pytest.mark.sumo
@pytest.mark.parametrize("controller, seed, case", FAILED_BEFORE, ids=[f"{c}-{s}" for c, s, _ in FAILED_BEFORE])
def test_cases_that_failed_before_complete(controller, seed, case, fuzzy_ready):
    m = run(_spec(controller, seed, case)).metrics
    assert m["status"] == "completed" and not m["collision"], m["status_detail"]


@pytest.mark.sumo
def test_the_raw_model_spins_where_the_friction_aware_brake_holds(fuzzy_ready):
    controller, seed, case = FAILED_BEFORE[0]
    r = run(_spec(controller, seed, case, abs=False))
    assert r.status == "diverged" and "heading" in r.metrics["status_detail"]
    # the rear was asked for more than the friction circle: Fx beyond F_max / Nw
    assert r.column("Fx").min() < -1.5 * P.F_max / P.Nw
    held = run(_spec(controller, seed, case))
    assert held.status == "completed"
    assert held.column("Fx").min() >= -P.F_max / P.Nw - 1e-6  # the actuator never asks more


@pytest.mark.sumo
def test_in_lane_braking_does_not_wait_for_the_position_loop(fuzzy_ready):
    # both lanes rejected: the AEB brakes at the friction limit right away, where the
    # fuzzy position loop alone hits the lead
    controller, seed, case = FAILED_BEFORE[4]
    with_aeb = run(_spec(controller, seed, case)).metrics
    assert with_aeb["target_side"] is None and with_aeb["aeb_time"] is not None
    assert with_aeb["aeb_time"] - with_aeb["trigger_time"] < 1.0
    without = run(_spec(controller, seed, case, aeb=False)).metrics
    assert without["status"] == "collision" and without["collision_with"] == "lead"


def _classify(args):
    controller, case = args
    case = dict(case)
    seed = case.pop("seed")
    m = run(_spec(controller, seed, case)).metrics
    verdict = None
    if m["collision"]:
        verdict = "avoidable" if m["collision_avoidable"] else "unavoidable"
    return controller, seed, case, m["status"], verdict, m["status_detail"]


@pytest.mark.sumo
def test_the_scenario_classifies_its_collision_by_the_braking_criterion(fuzzy_ready):
    # no controller and no AEB: braking from the trigger would have stopped in time
    m = run(_spec("none", 0, {}, aeb=False)).metrics
    assert m["collision"] and m["collision_avoidable"] is True
    # a lead braking at 8.5 m/s^2 from 57 m ahead at 32.5 m/s: beyond the tyres
    r = run(
        _spec(
            "pid", 3751, dict(ego_speed=32.5, lead_decel=8.52, lead_gap=57.37, traffic_density=22.07, block_left=True)
        )
    )
    assert r.metrics["collision"] and r.metrics["collision_avoidable"] is False
    # the same verdict from the trace, by the envelope's criterion
    config = resolve(
        _spec(
            "pid", 3751, dict(ego_speed=32.5, lead_decel=8.52, lead_gap=57.37, traffic_density=22.07, block_left=True)
        )
    ).config
    i = int(np.searchsorted(r.column("t"), r.metrics["trigger_time"]))
    assert not avoidable(r.metrics, float(r.column("gap_front")[i]), float(r.column("ds")[i]), config, DECEL_LIMIT)
    assert run(_spec("pid", 0, {})).metrics["collision_avoidable"] is None  # no collision


@pytest.mark.sumo
@pytest.mark.long  # tens of seconds; the docs' envelope and platoon tables run the same code
def test_the_envelope_has_no_divergence_and_no_avoidable_collision(fuzzy_ready):
    cases = list(sample(20, seed=1))
    jobs = [(c, case) for c in CONTROLLERS for case in cases]
    with ProcessPoolExecutor(2) as pool:
        results = list(pool.map(_classify, jobs))
    bad = [r for r in results if r[3] in ("diverged",) or r[4] == "avoidable"]
    assert not bad, "\n".join(map(str, bad))
    # physics leaves no way out in some cases (a lead braking beyond the friction limit):
    # those collisions are reported, never hidden
    unavoidable = [r for r in results if r[4] == "unavoidable"]
    for r in unavoidable:
        assert r[2]["lead_decel"] > 6.0 or r[2]["lead_gap"] < 30.0, r
    assert len(results) == 100
