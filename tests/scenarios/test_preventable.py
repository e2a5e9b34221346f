"""collision_preventable: UN R157's careful driver on the same concrete scenario."""

import pytest

from ego.runner import RunSpec, collision_preventable, reference_run, resolve, run

pytestmark = pytest.mark.sumo

OFF = {"evade": "false", "aeb": "false"}


def _careful_collides(scenario: str, seed: int, overrides: dict) -> bool:
    """The careful driver's own run, set up by hand: same scenario, seed and overrides, the
    ego's evasion and AEB off."""
    return bool(run(RunSpec(scenario, "careful-driver", seed, {**overrides, **OFF})).metrics["collision"])


def test_a_collision_the_careful_driver_avoids_is_preventable():
    overrides = {**OFF, "traffic_density": "0"}
    r = run(RunSpec("cut-in", "none", 0, overrides, preventable=None))
    assert r.metrics["collision"]
    assert not _careful_collides("cut-in", 0, overrides)
    assert r.metrics["collision_preventable"] is True


def test_a_collision_the_careful_driver_has_too_is_not_preventable():
    overrides = {**OFF, "cut_in_gap": "4", "cut_in_speed": "12"}
    r = run(RunSpec("cut-in", "none", 3, overrides, preventable=None))
    assert r.metrics["collision"]
    assert _careful_collides("cut-in", 3, overrides)
    assert r.metrics["collision_preventable"] is False


def test_the_reference_is_the_same_concrete_scenario_with_its_own_systems_off():
    resolved = resolve(RunSpec("emergency-brake", "pid", 7, {"lead_decel": "9", "kp_lat": "0.02"}))
    ref = reference_run(resolved)
    assert ref is not None and ref.spec.controller == "careful-driver" and ref.spec.seed == 7
    assert ref.config.lead_decel == 9.0 and ref.config.evade is False and ref.config.aeb is False
    # every other field of the scenario's configuration as the run had it
    assert ref.config == resolved.config.__class__(**{**vars(resolved.config), "evade": False, "aeb": False})
    assert ref.spec.record is None and ref.spec.trace is None and ref.spec.requirements == ()


def test_only_after_a_collision_or_when_asked():
    assert RunSpec("cut-in", "pid", 0).preventable is False  # a sweep's, a table's: one run each
    spec = RunSpec("cut-in", "pid", 0, preventable=None)
    r = run(spec)
    assert not r.metrics["collision"] and "collision_preventable" not in r.metrics
    asked = run(RunSpec("cut-in", "pid", 0, preventable=True))
    assert asked.metrics["collision_preventable"] is False  # nothing to prevent
    # the run's own figures are the same either way
    assert {k: v for k, v in asked.metrics.items() if k not in ("collision_preventable", "wall_time")} == {
        k: v for k, v in r.metrics.items() if k != "wall_time"
    }
    # a task the careful driver does not drive (the curve's a_x and steer): it cannot be asked
    curve = resolve(RunSpec("curve", "pid", 0))
    assert collision_preventable(curve, run(curve)) is None


def test_compare_runs_the_careful_driver_after_each_collision_only_when_asked(tmp_path):
    from ego.compare import compare
    from ego.parallel.executor import InlineExecutor

    overrides = {**OFF, "traffic_density": "0", "duration": "16"}
    args = ("cut-in", ["none", "pid"], 1, overrides)
    plain = compare(*args, tmp_path / "plain", progress=None, executor=InlineExecutor())
    asked = compare(*args, tmp_path / "asked", progress=None, executor=InlineExecutor(), preventable=True)
    assert all("collision_preventable" not in r.metrics for r in plain)
    by = {r.controller: r.metrics for r in asked}
    assert by["none"]["collision"] and by["none"]["collision_preventable"] is True
    assert not by["pid"]["collision"] and "collision_preventable" not in by["pid"]
    assert "- none: 1 of 1" in (tmp_path / "asked" / "metrics.md").read_text()


def test_sweep_carries_collision_preventable_when_asked(tmp_path, capsys):
    """``ego sweep --preventable``: the careful driver after each collision, its verdict a
    results.parquet column (null where there was no collision) and a line of summary.md."""
    import pyarrow.parquet as pq

    from ego.cli import main

    spec = tmp_path / "s.toml"
    spec.write_text(
        'scenario = "cut-in"\ncontrollers = ["none", "pid"]\n\n[set]\nevade = false\naeb = false\n'
        "traffic_density = 0\nduration = 16\n"
    )
    assert main(["sweep", str(spec), "--out", str(tmp_path / "sw"), "--jobs", "1", "--preventable"]) == 0
    rows = {r["controller"]: r for r in pq.read_table(tmp_path / "sw" / "results.parquet").to_pylist()}
    assert rows["none"]["collision"] and rows["none"]["collision_preventable"] is True
    assert not rows["pid"]["collision"] and rows["pid"]["collision_preventable"] is None
    assert "- none: 1 of 1" in (tmp_path / "sw" / "summary.md").read_text()


ALKS_CUT_IN = "scenarios/alks/alks_4_4_cut_in.xosc"


def test_r157_files_default_to_no_preventable_collision_and_other_files_do_not():
    from ego.requirements import defaults
    from ego.scenarios import scenario_class

    def names(path):
        return defaults(path, scenario_class(path))

    assert names(ALKS_CUT_IN)["no_preventable_collision"] == "always (not preventable_collision)"
    assert "no_preventable_collision" in names("scenarios/alks/alks_4_2_blocking.xosc")
    assert "no_preventable_collision" not in names("scenarios/openscenario/cut_in.xosc")
    assert "no_preventable_collision" not in defaults("cut-in")


def test_an_r157_run_whose_collision_the_careful_driver_avoids_fails_no_preventable_collision(tmp_path, capsys):
    from ego.cli import main

    overrides = {"aeb": "false"}  # the ALKS file's own evasion is off already
    r = run(RunSpec(ALKS_CUT_IN, "none", 0, overrides))
    assert r.metrics["collision"] and r.metrics["collision_preventable"] is True
    assert not _careful_collides(ALKS_CUT_IN, 0, overrides)
    assert r.metrics["requirements"]["no_preventable_collision"] < 0
    hit = next(e.t for e in r.events if e.kind == "collision")
    assert r.metrics["first_violation"]["no_preventable_collision"] == pytest.approx(hit, abs=0.011)
    # the command line says why it failed
    assert main(["run", ALKS_CUT_IN, "-c", "none", "--set", "aeb=false"]) == 1
    assert "no_preventable_collision" in capsys.readouterr().out


def test_an_r157_collision_the_careful_driver_has_too_passes_no_preventable_collision():
    overrides = {"aeb": "false", "CutInGap": "8", "RelSpeed_kph": "20", "LateralVelocity": "3.0", "CutInTTCMargin": "0"}
    r = run(RunSpec(ALKS_CUT_IN, "none", 0, overrides))
    assert r.metrics["collision"] and r.metrics["collision_preventable"] is False
    assert _careful_collides(ALKS_CUT_IN, 0, overrides)
    assert r.metrics["requirements"]["no_preventable_collision"] > 0
    # without a collision there is no second run: nothing to prevent
    calm = run(RunSpec(ALKS_CUT_IN, "pid", 0))
    assert not calm.metrics["collision"] and "collision_preventable" not in calm.metrics
    assert calm.metrics["requirements"]["no_preventable_collision"] > 0
