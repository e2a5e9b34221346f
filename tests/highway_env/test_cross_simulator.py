"""``scenarios/cross_simulator.py``: its tables and the file block it replaces (no runs)."""

import importlib.util
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "scenarios" / "cross_simulator.py"


@pytest.fixture(scope="module")
def cross():
    spec = importlib.util.spec_from_file_location("cross_simulator", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_cell_is_the_mean_and_says_how_many_runs_have_a_value(cross):
    assert cross._cell([1.0, 2.0, 4.5]) == "2.50"
    assert cross._cell([1.0, None, 3.0]) == "2.00 (2/3)"
    assert cross._cell([True, False, True]) == "2/3"
    assert cross._cell([None, None]) == "-"


def test_the_tables_put_sumo_beside_highway_env(cross):
    row = {"status": "completed", "min_gap_front": 5.0, "follower_passed": True}
    results = {("fast-follower", "pid", "sumo"): [row], ("fast-follower", "pid", "highway-env"):
               [dict(row, min_gap_front=3.0, status="collision")]}
    text = cross.tables(results, 1)
    header = next(line for line in text.splitlines() if line.startswith("| controller") and "TTC rear" in line)
    assert "min gap front [m] SUMO | min gap front [m] highway-env" in header
    pid = next(line for line in text.splitlines() if line.startswith("| pid") and "1 collision" in line)
    assert "| 1 completed | 1 collision |" in pid and "| 5.00 | 3.00 |" in pid and "| 1/1 | 1/1 |" in pid


def test_regenerating_replaces_only_the_marked_block(cross, tmp_path):
    path = tmp_path / "cross.md"
    path.write_text(f"# Title\n\nintro\n\n{cross.BEGIN}\nold table\n{cross.END}\n\nwhat it means\n")
    cross.write(path, "new table\n", "python scenarios/cross_simulator.py")
    text = path.read_text()
    assert "old table" not in text and "new table" in text
    assert text.startswith("# Title\n\nintro\n") and text.endswith("\n\nwhat it means\n")
    cross.write(path, "newer table\n", "python scenarios/cross_simulator.py")
    assert path.read_text() == text.replace("new table", "newer table")
    assert [p.name for p in tmp_path.iterdir()] == ["cross.md"]
