"""psy-taliro's uniform random and dual annealing as ``ego falsify`` optimisers (issue 40):
psy-taliro's own test loop proposes the points, ego runs them (psy-taliro: ego's test extra)."""

import numpy as np
import pyarrow.parquet as pq
import pytest
import staliro
from staliro import optimizers

from ego.cli import main
from ego.falsify.optimizers import PSYTALIRO, make, squash


def _direct(kind: str, seed: int, d: int, n: int, cost) -> list[np.ndarray]:
    """The first ``n`` samples psy-taliro's optimiser ``kind`` evaluates when psy-taliro runs
    it on its own (staliro.staliro with a cost function), as the adapter seeds it."""
    seen: list[np.ndarray] = []

    @staliro.costfunc
    def f(inputs):
        x = np.array([inputs.static[f"x{i}"] for i in range(d)])
        seen.append(x)
        return cost(x)

    options = staliro.TestOptions(
        static_inputs={f"x{i}": (0.0, 1.0) for i in range(d)}, iterations=n, runs=1, seed=seed + 1
    )
    staliro.staliro(f, getattr(optimizers, PSYTALIRO[kind])(), options)
    return seen[:n]


@pytest.mark.parametrize("kind", sorted(PSYTALIRO))
def test_the_adapter_proposes_what_psytaliro_proposes_on_its_own(kind):
    def cost(x):
        return float(np.sum((x - 0.3) ** 2)) - 0.01

    n = 25
    expected = _direct(kind, 4, 3, n, cost)
    opt = make(kind, 3, 2, 4, n)
    got = []
    try:
        for _ in range(n):
            x = opt.ask()
            assert x.shape == (1, 3)  # one point at a time: psy-taliro's optimisers are sequential
            got.append(x[0])
            opt.tell(x, np.array([squash(cost(x[0]))]))
    finally:
        opt.close()
    assert np.allclose(np.array(got), np.array(expected), rtol=0, atol=1e-12)
    assert not opt._thread.is_alive() or opt._thread.join(5) is None


SPEC = """scenario = "emergency-brake"
controller = "pid"
requirement = "far"
seed = 3
[set]
traffic_density = 0
duration = 8
evade = false
[requirements]
far = "always (gap_front >= 25 m)"
[search]
ego_speed = [15, 30]
lead_gap = [20, 60]
"""


@pytest.mark.sumo
@pytest.mark.parametrize("kind", sorted(PSYTALIRO))
def test_psytaliro_falsifies_an_easy_requirement_on_ego_runs_and_resumes(kind, tmp_path, capsys):
    path = tmp_path / "f.toml"
    path.write_text(SPEC)
    out = tmp_path / "out"
    args = ["falsify", str(path), "--out", str(out), "--jobs", "1", "--budget", "30", "--optimizer", kind]
    assert main([*args, "--until", "first", "--no-verify"]) == 1  # a violation found
    table = pq.read_table(out / "results.parquet").to_pandas()
    assert set(table["optimizer"]) == {kind} and (table["requirements.far"] < 0).any()
    assert len(table) < 30 and table["requirements.far"].iloc[-1] < 0  # it stopped at the first
    assert "ego run emergency-brake -c pid --seed 3 --set" in (out / "falsified.md").read_text()
    # psy-taliro's proposals replay identically: the same command runs nothing again
    capsys.readouterr()
    assert main([*args, "--until", "first", "--no-verify"]) == 1
    assert "0 runs ran now" in capsys.readouterr().out


def test_without_psytaliro_the_optimizer_is_one_line_and_exit_2(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(__import__("sys").modules, "staliro", None)  # as if not installed
    path = tmp_path / "f.toml"
    path.write_text(SPEC)
    out = tmp_path / "out"
    assert main(["falsify", str(path), "--out", str(out), "--optimizer", "psytaliro-annealing"]) == 2
    err = capsys.readouterr().err.strip()
    assert "psytaliro-annealing" in err and "pip install psy-taliro" in err and "\n" not in err
