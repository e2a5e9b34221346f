"""``maximumExecutionCount``: the schema's unsignedInt >= 1, and -1 read as unlimited with a
warning, as the reference player reads it (esmini's ``StoryBoardElement::End`` puts an event or
maneuver group back to standby while its count is -1; its ``acc-toggle.xosc`` writes it).
Hand-written files on xosc_scenes' straight road, real SUMO."""

from __future__ import annotations

import pytest
from xosc_scenes import event, run_scene, scene, sim_time, speed, starts, trigger

from ego.cli import main


def _scene(tmp_path, count: int):
    # a step speed change on A from t = 1 s: it ends at once, so the event is back in
    # standby and (its trigger still true) starts again at the next step while runs remain
    return scene(tmp_path, [event("Again", "A", speed(25.0), trigger([sim_time(1.0)]), count=count)])


def test_an_unlimited_count_runs_the_event_again_every_time_it_ends(tmp_path, capsys):
    sc = run_scene(_scene(tmp_path, -1), duration=2.0)
    times = starts(sc, "Again")
    # from t = 1.0 s to the end at 2.0 s: it ends the step after it starts and starts again
    # the step after that, so every 0.2 s, as long as the run lasts (its last step at 2.0 s)
    assert times == pytest.approx([1.0, 1.2, 1.4, 1.6, 1.8, 2.0], abs=1e-9)
    err = capsys.readouterr().err
    assert "maximumExecutionCount=-1 in <Event> (the schema allows >= 1): unlimited" in err


def test_a_count_of_three_runs_three_times(tmp_path):
    sc = run_scene(_scene(tmp_path, 3), duration=2.0)
    assert len(starts(sc, "Again")) == 3


@pytest.mark.parametrize("count", [0, -2])
def test_other_counts_below_one_are_refused_in_one_line(tmp_path, capsys, count):
    assert main(["run", str(_scene(tmp_path, count)), "-c", "pid"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert f"bad value for maximumExecutionCount in <Event>: {count} (expected >= 1, or -1: unlimited)" in err[0]
