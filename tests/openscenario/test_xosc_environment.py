"""An EnvironmentAction's RoadCondition frictionScaleFactor, inline and from an
EnvironmentCatalog (esmini's cut-in_environment.xosc): the ego's tyres and SUMO's drivers get
the scaled friction. Each file here is hand-written for the test."""

from __future__ import annotations

import subprocess
import sys

import pytest
from xosc_scenes import event, run_scene, scene, sim_time, speed, starts, trigger

from ego.models import NonlinearBicycle, NonlinearBicycleParams, VehicleGeometry
from ego.models.actuators import ActuatorLimits
from ego.models.plant import BicyclePlant
from ego.openscenario.loader import load
from ego.openscenario.scenario import StoryDriver
from ego.openscenario.xmltree import ScenarioFileError

ENV = (
    '<GlobalAction><EnvironmentAction><Environment name="e"><TimeOfDay animation="false" '
    'dateTime="2025-06-13T12:00:00"/><Weather cloudState="free"/>{road}</Environment></EnvironmentAction>'
    "</GlobalAction>"
)
CATALOG = """<?xml version="1.0"?>
<OpenSCENARIO><FileHeader revMajor="1" revMinor="2" date="2026-11-29T00:00:00" description="c" author="t"/>
<Catalog name="EnvironmentCatalog">
<Environment name="winter"><ParameterDeclarations><ParameterDeclaration name="Mu" parameterType="double" value="0.5"/>
</ParameterDeclarations><TimeOfDay animation="false" dateTime="2025-01-13T12:00:00"/><Weather cloudState="overcast"/>
<RoadCondition frictionScaleFactor="$Mu"/></Environment>
</Catalog></OpenSCENARIO>
"""


def _braking_plant(scale: float | None) -> BicyclePlant:
    params = NonlinearBicycleParams(slip_speed_floor=1.0, abs=True)
    grip = params.F_max / params.Nw
    plant = BicyclePlant(
        NonlinearBicycle(params),
        VehicleGeometry(),
        0.01,
        1,
        ActuatorLimits(min_command=-grip, max_command=grip, stop_speed=0.5),
        state=(0.0, 30.0, 0.0, 0.0, 0.0, 0.0),
    )
    if scale is not None:
        plant.scale_friction(scale)
    return plant


@pytest.mark.parametrize("scale", [None, 1.0, 0.5, 0.25])
def test_the_plants_full_braking_follows_the_scaled_friction(scale):
    """Full braking straight ahead (ABS: the command at the friction circle) decelerates at
    (mu k + f) g, mu = 0.7 the tyres' friction, f = 0.01 the rolling resistance: after 1 s
    the speed and the distance are the constant-deceleration ones (RK4 integrates them
    exactly), so the braking distance v^2 / (2 (mu k + f) g) grows nearly 1/k."""
    plant = _braking_plant(scale)
    p = NonlinearBicycleParams()
    a = ((p.mu_max * (1.0 if scale is None else scale)) + p.f) * p.g
    step = plant.bind_step()
    for _ in range(100):
        step((-1e9, 0.0))
    x, u = plant.state[0], plant.state[1]
    assert u == pytest.approx(30.0 - a * 1.0, abs=1e-9)
    assert x == pytest.approx(30.0 * 1.0 - 0.5 * a, abs=1e-9)


def test_a_later_friction_scale_is_from_the_plants_own_not_compounded():
    plant = _braking_plant(0.5)
    plant.scale_friction(0.8)
    assert plant.model.params.mu_max == pytest.approx(0.7 * 0.8)
    assert plant.model.params.tyre.Dy == pytest.approx(0.7 * 0.8)
    assert plant.limits.max_command == pytest.approx(0.7 * 0.8 * 1400 * 9.806 / 2)


def _spy_decels(monkeypatch) -> list:
    """(storyboard time, the ego plant's mu_max, A's SUMO decel and emergencyDecel) every step."""
    rows: list = []
    inner = StoryDriver.step

    def spy(self):
        inner(self)
        veh = self.sc.bridge.libsumo.vehicle
        rows.append((self.board.t, self.sc.ego.model.params.mu_max, veh.getDecel("A"), veh.getEmergencyDecel("A")))

    monkeypatch.setattr(StoryDriver, "step", spy)
    return rows


@pytest.mark.sumo
def test_a_friction_scale_in_init_holds_from_the_start(tmp_path, monkeypatch):
    rows = _spy_decels(monkeypatch)
    path = scene(tmp_path, [event("Go", "A", speed(26), trigger([sim_time(1)]))])
    text = path.read_text().replace(
        "<Init><Actions>", "<Init><Actions>" + ENV.format(road='<RoadCondition frictionScaleFactor="0.5"/>')
    )
    path.write_text(text)
    run_scene(path, 1.0)
    # A's own: maxDeceleration 4.5 m/s^2 and SUMO's emergency deceleration (9 m/s^2 at least)
    for _, mu, decel, emergency in rows:
        assert mu == pytest.approx(0.35)
        assert decel == pytest.approx(0.5 * 4.5)
        assert emergency == pytest.approx(0.5 * 9.0)


@pytest.mark.sumo
def test_a_friction_scale_from_an_environment_catalog_at_an_event(tmp_path, monkeypatch):
    rows = _spy_decels(monkeypatch)
    (tmp_path / "env").mkdir()
    (tmp_path / "env" / "EnvironmentCatalog.xosc").write_text(CATALOG)
    ref = (
        '<GlobalAction><EnvironmentAction><CatalogReference catalogName="EnvironmentCatalog" entryName="winter">'
        '<ParameterAssignments><ParameterAssignment parameterRef="Mu" value="0.6"/></ParameterAssignments>'
        "</CatalogReference></EnvironmentAction></GlobalAction>"
    )
    path = scene(tmp_path, [event("Go", "A", speed(26), trigger([sim_time(1)]))])
    text = path.read_text()
    text = text.replace(
        "<RoadNetwork>",
        '<CatalogLocations><EnvironmentCatalog><Directory path="env"/></EnvironmentCatalog></CatalogLocations>'
        "<RoadNetwork>",
    )
    text = text.replace('<Action name="GoAction">', f'<Action name="Winter">{ref}</Action><Action name="GoAction">')
    path.write_text(text)
    sc = run_scene(path, 2.0)
    assert starts(sc, "Go") == [pytest.approx(1.0)]
    before = [r for r in rows if r[0] < 1.0 - 1e-9]
    after = [r for r in rows if r[0] >= 1.0 - 1e-9]
    assert before and after
    assert all(mu == pytest.approx(0.7) and d == pytest.approx(4.5) for _, mu, d, _ in before)
    assert all(mu == pytest.approx(0.42) and d == pytest.approx(0.6 * 4.5) for _, mu, d, _ in after), after
    assert any("road friction scaled by 0.6" in e.text for e in sc.events)


@pytest.mark.parametrize(
    ("road", "message"),
    [
        ('<RoadCondition frictionScaleFactor="0"/>', r"bad value for frictionScaleFactor in <RoadCondition>: 0"),
        ('<RoadCondition frictionScaleFactor="-0.5"/>', r"bad value for frictionScaleFactor in <RoadCondition>"),
        ("<RoadCondition/>", r"<RoadCondition> needs attribute frictionScaleFactor"),
    ],
)
def test_bad_friction_scales_are_refused_in_one_line(tmp_path, road, message):
    path = scene(tmp_path, [])
    path.write_text(path.read_text().replace("<Init><Actions>", "<Init><Actions>\n" + ENV.format(road=road)))
    with pytest.raises(ScenarioFileError, match=message):
        load(path)
    proc = subprocess.run(
        [sys.executable, "-m", "ego", "run", str(path), "-c", "pid", "--trace", str(tmp_path / "o.csv")],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert not (tmp_path / "o.csv").exists()


def test_an_unknown_environment_catalog_entry_is_refused(tmp_path):
    (tmp_path / "env").mkdir()
    (tmp_path / "env" / "EnvironmentCatalog.xosc").write_text(CATALOG)
    path = scene(tmp_path, [])
    text = path.read_text().replace(
        "<RoadNetwork>",
        '<CatalogLocations><EnvironmentCatalog><Directory path="env"/></EnvironmentCatalog></CatalogLocations>'
        "<RoadNetwork>",
    )
    ref = (
        '<GlobalAction><EnvironmentAction><CatalogReference catalogName="EnvironmentCatalog" entryName="summer"/>'
        "</EnvironmentAction></GlobalAction>"
    )
    path.write_text(text.replace("<Init><Actions>", "<Init><Actions>\n" + ref))
    with pytest.raises(
        ScenarioFileError, match=r"no entry 'summer' in catalog 'EnvironmentCatalog' \(entries: winter\)"
    ):
        load(path)


def _stopping(tmp_path, monkeypatch, k: float) -> tuple[float, float]:
    """The ego at 20 m/s told to stop at storyboard time 1 s on a road of friction scale ``k``
    (its evasive manoeuvre and AEB off): its speed at 1 s and the distance to its stop."""
    rows: list = []
    inner = StoryDriver.step

    def spy(self):
        inner(self)
        e = self.board.states["Ego"]
        rows.append((self.board.t, e.speed, e.traveled))

    monkeypatch.setattr(StoryDriver, "step", spy)
    (tmp_path / str(k)).mkdir()
    far = {"A": (-1, 1000.0, 25.0), "B": (-2, 1200.0, 15.0), "C": (-1, 1400.0, 15.0)}
    path = scene(tmp_path / str(k), [event("Stop", "Ego", speed(0), trigger([sim_time(1)]))], at=far)
    road = f'<RoadCondition frictionScaleFactor="{k}"/>'
    path.write_text(path.read_text().replace("<Init><Actions>", "<Init><Actions>" + ENV.format(road=road)))
    run_scene(path, 10.0, evade=False, aeb=False)
    t0 = next(r for r in rows if r[0] >= 1.0 - 1e-9)
    stop = next(r for r in rows if r[0] > 1.0 and r[1] < 0.05)
    return t0[1], stop[2] - t0[2]


@pytest.mark.sumo
@pytest.mark.parametrize("k", [1.0, 0.5])
def test_the_egos_braking_distance_follows_the_road_friction(tmp_path, monkeypatch, k):
    """The ego's speed reference drops to 0 at 1 s: the controller brakes as hard as the tyres
    carry (ABS), so from v0 it stops in v0 tau + v0^2 / (2 (0.7 k + 0.01) g), tau = 0.01 s (the
    step reference drops over the control period after 1 s: the storyboard steps at 1 s before
    the ego plans from there): 28.6 m (+0.2) on a dry road, 56.5 m (+0.2) at k = 0.5, within
    0.1 m."""
    v0, dist = _stopping(tmp_path, monkeypatch, k)
    g = NonlinearBicycleParams().g
    closed = v0 * 0.01 + v0**2 / (2.0 * (0.7 * k + 0.01) * g)
    assert dist == pytest.approx(closed, abs=0.1)
