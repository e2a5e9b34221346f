"""The kit example of docs/architecture.md runs as written."""

from pathlib import Path

import pytest

ARCHITECTURE = Path(__file__).resolve().parents[1] / "docs" / "architecture.md"


@pytest.mark.sumo
def test_the_kit_example_in_the_docs_runs(fuzzy_ready):
    text = ARCHITECTURE.read_text()
    block = text.split("## Writing a scenario from the kit")[1].split("```python")[1].split("```")[0]
    scope: dict = {}
    exec(compile(block, str(ARCHITECTURE), "exec"), scope)  # noqa: S102
    from ego.control import FuzzyController, FuzzyParams

    cfg = scope["SlowTruckConfig"](block_left=True, block_right=True)
    r = scope["SlowTruck"](cfg, FuzzyController(FuzzyParams(), cfg.dt), seed=0).run()
    m = r.metrics
    # nowhere to go: it brakes behind the truck and follows it
    assert m["status"] == "completed" and not m["collision"] and m["target_side"] is None
    assert m["truck_speed"] == 15.0 and m["final_speed"] == pytest.approx(15.0, abs=0.5)
