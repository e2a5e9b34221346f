"""``ego concrete``: a run of a logical scenario (``--set`` values, a sweep row) written as a
standalone concrete .xosc that makes the same run when given back to ``ego run``."""

from __future__ import annotations

import json
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from ego.cli import main
from ego.openscenario.loader import declared_parameters, load

XOSC = Path(__file__).resolve().parents[2] / "scenarios" / "openscenario" / "emergency_brake.xosc"


@pytest.fixture(autouse=True)
def _in_tmp(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)


def test_set_values_go_into_the_file_and_the_road_is_found_from_elsewhere(tmp_path, capsys):
    out = tmp_path / "deep" / "er" / "eb-18.xosc"
    assert main(["concrete", str(XOSC), "--set", "LeadGap=18", "--set", "duration=5", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "with LeadGap=18" in printed and "--set duration=5" in printed  # ego's own setting: the command
    assert declared_parameters(out)["LeadGap"].value == 18.0
    assert declared_parameters(out)["LeadDecel"].value == 6.0  # the others as the template has them
    assert load(out).road.name == "straight3.xodr"  # the road resolved from the new folder
    assert "concrete scenario written by ego concrete" in out.read_text()


def test_a_sweep_row_written_out_makes_the_same_run(tmp_path, capsys):
    spec = tmp_path / "spec.toml"
    spec.write_text(
        f'scenario = "{XOSC}"\ncontrollers = ["pid"]\n\n[set]\nduration = 4\ntraffic_density = 0\n\n'
        "[grid]\nLeadGap = [25, 40]\n"
    )
    assert main(["sweep", str(spec), "--out", "sw", "--jobs", "1", "--record", "none"]) == 0
    rows = pq.read_table(tmp_path / "sw" / "results.parquet").to_pylist()
    capsys.readouterr()
    for row in rows:
        out = tmp_path / "elsewhere" / f"{row['run_id']}.xosc"
        assert main(["concrete", "sw", "--run", row["run_id"], "--out", str(out)]) == 0
        command = capsys.readouterr().out.splitlines()[-1].split("the same run: ego ")[1].split()
        assert command[:2] == ["run", str(out)] and "--set" in command  # duration: not a file parameter
        assert main([*command, "--json"]) in (0, 1)
        again = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
        for key in ("status", "trigger_time", "min_gap_front", "min_ttc_front", "max_decel"):
            assert again[key] == pytest.approx(row[key]), key


@pytest.mark.parametrize(
    "args, message",
    [
        (["--set", "LeadGap=-4"], "parameter 'LeadGap' = -4 breaks its value constraint: greaterOrEqual 5"),
        (["--set", "LeadGap=far"], "bad value for parameter 'LeadGap': 'far' (expected a number)"),
        (["--run", "abc"], "--run goes with a sweep or falsify folder"),
    ],
)
def test_a_bad_value_is_one_line_and_nothing_is_written(tmp_path, capsys, args, message):
    assert main(["concrete", str(XOSC), *args, "--out", "c.xosc"]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert not (tmp_path / "c.xosc").exists()


def test_folder_errors_and_a_file_it_did_not_write(tmp_path, capsys):
    (tmp_path / "mine.xosc").write_text("<OpenSCENARIO/>")
    assert main(["concrete", str(XOSC), "--out", "mine.xosc"]) == 2
    assert "ego concrete did not write it (give --force" in capsys.readouterr().err
    assert (tmp_path / "mine.xosc").read_text() == "<OpenSCENARIO/>"
    assert main(["concrete", str(XOSC), "--out", "mine.xosc", "--force"]) == 0
    (tmp_path / "empty").mkdir()
    assert main(["concrete", "empty", "--run", "x", "--out", "e.xosc"]) == 2
    assert "empty" in capsys.readouterr().err and not (tmp_path / "e.xosc").exists()
    assert main(["concrete", "nothing.txt", "--out", "e.xosc"]) == 2
    assert "expected an .xosc file or an ego sweep / falsify folder" in capsys.readouterr().err
