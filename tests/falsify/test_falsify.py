"""``ego falsify`` end to end on real SUMO runs (issue 21, point 2)."""

from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from ego.cli import main
from ego.falsify.optimizers import NAMES, PSYTALIRO, make
from ego.falsify.search import falsify
from ego.falsify.spec import load, parse
from ego.params import ConfigError

SPEC = """scenario = "emergency-brake"
controller = "pid"
requirement = "far"
seed = 3
[requirements]
far = "always (gap_front >= 25 m)"
[search]
ego_speed = [15, 30]
lead_gap = [20, 60]
"""


@pytest.mark.parametrize("name", NAMES)
def test_optimisers_propose_batches_in_the_cube_and_replay_identically(name):
    def sequence():
        opt = make(name, 3, 2, 7, 12)
        out = []
        for _ in range(3):
            x = opt.ask()
            assert x.shape[1] == 3 and (len(x) % 2 == 0 or name in PSYTALIRO) and np.all((x >= 0) & (x <= 1))
            opt.tell(x, np.sum((x - 0.3) ** 2, axis=1))
            out.append(x)
        return np.concatenate(out)

    assert np.array_equal(sequence(), sequence())


def test_cma_finds_a_small_region_faster_than_random():
    """A surrogate (no SUMO): a violating ball of radius 0.08 in 4 dimensions (0.04 % of the
    cube) with a robustness that grows with the distance from it."""
    centre = np.array([0.8, 0.2, 0.7, 0.35])

    def runs_to_first(name, seed, budget=2000):
        opt = make(name, 4, 2, seed, budget)
        n = 0
        while n < budget:
            x = opt.ask()
            rob = np.linalg.norm(x - centre, axis=1) - 0.08
            for r in rob:
                n += 1
                if r < 0:
                    return n
            opt.tell(x, rob)
        return budget

    cma = np.median([runs_to_first("cma", s) for s in range(5)])
    rnd = np.median([runs_to_first("random", s) for s in range(5)])
    assert cma * 5 <= rnd


@pytest.mark.parametrize(
    "text, what",
    [
        (
            'scenario = "emergency-brake"\ncontroller = "pid"\nrequirement = "nope"\n[search]\nego_speed = [10, 20]\n',
            "requirement = 'nope'",
        ),
        (
            SPEC.replace("ego_speed = [15, 30]", "ego_sped = [15, 30]"),
            "unknown parameter 'ego_sped'",
        ),
        (SPEC.replace("ego_speed = [15, 30]", "ego_speed = [30, 15]"), "low < high"),
        (SPEC.replace("ego_speed = [15, 30]", "ego_speed = [15, 300]"), "ego_speed"),
        (SPEC.replace("25 m", "25 s"), "units differ"),
        (SPEC.replace("seed = 3", "seed = [5, 2]"), "seed must be"),
        ("budget = 0\n" + SPEC, "budget must be"),
        ("bogus = 1\n" + SPEC, "unknown key 'bogus'"),
        ("#" * (1 << 20) + "\n" + SPEC, "larger than the limit of 1 MiB"),
    ],
)
def test_bad_specs_are_one_line_exit_2(text, what, tmp_path, capsys):
    path = tmp_path / "f.toml"
    path.write_text(text)
    assert main(["falsify", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ego: error:") and what in err and err.count("\n") == 1
    assert not (tmp_path / "out").exists()


def test_an_openscenario_file_is_named_relative_to_the_spec(tmp_path, monkeypatch):
    """As in a sweep spec: the spec beside its .xosc works from any current folder."""
    import shutil

    xosc = Path(__file__).resolve().parents[2] / "scenarios" / "openscenario"
    folder = tmp_path / "specs"
    folder.mkdir()
    for name in ("emergency_brake.xosc", "straight3.xodr"):
        shutil.copy(xosc / name, folder / name)
    (folder / "f.toml").write_text(
        'scenario = "emergency_brake.xosc"\ncontroller = "pid"\nrequirement = "no_collision"\n'
        "[search]\nLeadGap = [20, 40]\n"
    )
    monkeypatch.chdir(tmp_path)
    spec = load("specs/f.toml")
    assert spec.scenario == str(Path("specs") / "emergency_brake.xosc")


def test_bad_options_exit_2(tmp_path, capsys):
    path = tmp_path / "f.toml"
    path.write_text(SPEC)
    assert (
        main(
            [
                "falsify",
                str(path),
                "--out",
                str(tmp_path / "o"),
                "--optimizer",
                "gradient",
            ]
        )
        == 2
    )
    assert "--optimizer" in capsys.readouterr().err
    one = SPEC.replace("lead_gap = [20, 60]\n", "")
    with pytest.raises(ConfigError, match="cma needs at least 2"):
        parse(__import__("tomllib").loads(one), "x").check_optimizer("cma")


@pytest.mark.parametrize(
    "column, values, message",
    [
        ("scenario", ["fast-follower"], "holds results of fast-follower"),
        ("ego_speed", ["fast"], "column ego_speed holds text"),
        ("optimizer_seed", ["zero"], "column optimizer_seed holds text"),
    ],
)
def test_results_that_cannot_take_the_new_rows_are_refused_before_running(column, values, message, tmp_path, capsys):
    """As ``ego sweep``: no rows of another scenario (or of another kind) added to --out."""
    import pyarrow as pa

    path = tmp_path / "f.toml"
    path.write_text(SPEC)
    out = tmp_path / "out"
    out.mkdir()
    rows = {"run_id": ["a"], "scenario": ["emergency-brake"], "controller": ["pid"], "seed": [3], column: values}
    pq.write_table(pa.table(rows), out / "results.parquet")
    before = (out / "results.parquet").read_bytes()
    assert main(["falsify", str(path), "--out", str(out), "--budget", "2", "--optimizer", "lhs"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ego: error: bad --out") and message in err and err.count("\n") == 1, err
    assert [p.name for p in out.iterdir()] == ["results.parquet"]  # nothing run, nothing written
    assert (out / "results.parquet").read_bytes() == before


@pytest.mark.sumo
@pytest.mark.long
def test_falsify_finds_verifies_and_resumes(tmp_path, capsys):
    path = tmp_path / "f.toml"
    path.write_text(SPEC)
    out = tmp_path / "out"
    code = main(
        [
            "falsify",
            str(path),
            "--out",
            str(out),
            "--jobs",
            "2",
            "--budget",
            "6",
            "--optimizer",
            "lhs",
        ]
    )
    assert code == 1  # violations found
    table = pq.read_table(out / "results.parquet").to_pandas()
    assert len(table) == 6 and "requirements.far" in table and (table["requirements.far"] < 0).any()
    md = (out / "falsified.md").read_text()
    assert "reproduced by the command" in md and "NOT reproduced" not in md
    assert "ego run emergency-brake -c pid --seed 3 --set ego_speed=" in md
    assert list((out / "runs").glob("*.rrd")) and (out / "convergence.png").stat().st_size > 1000
    # the same command again: every point is stored, nothing runs
    capsys.readouterr()
    assert (
        main(
            [
                "falsify",
                str(path),
                "--out",
                str(out),
                "--jobs",
                "2",
                "--budget",
                "6",
                "--optimizer",
                "lhs",
                "--no-verify",
            ]
        )
        == 1
    )
    assert "0 runs ran now" in capsys.readouterr().out
    assert len(pq.read_table(out / "results.parquet")) == 6


@pytest.mark.sumo
def test_the_search_is_the_same_for_any_number_of_workers(tmp_path, capsys):
    """The batch (not --jobs) decides what the optimiser proposes: --jobs 1 and --jobs 2 write
    the same results (within a batch in the order the runs finished: each row is stored as
    it finishes), and one resumes the other without running anything."""
    path = tmp_path / "f.toml"
    path.write_text(SPEC)
    tables = []
    for jobs in ("1", "2"):
        out = tmp_path / f"out{jobs}"
        args = ["falsify", str(path), "--out", str(out), "--budget", "6", "--optimizer", "cma", "--no-verify"]
        main([*args, "--jobs", jobs])
        tables.append(pq.read_table(out / "results.parquet").to_pandas().sort_values("run_id"))
    one, two = tables
    assert list(one["run_id"]) == list(two["run_id"])
    assert list(one["requirements.far"]) == list(two["requirements.far"])
    capsys.readouterr()
    main(
        [
            "falsify",
            str(path),
            "--out",
            str(tmp_path / "out1"),
            "--budget",
            "6",
            "--optimizer",
            "cma",
            "--no-verify",
            "--jobs",
            "2",
        ]
    )
    assert "0 runs ran now" in capsys.readouterr().out


@pytest.mark.sumo
def test_until_first_stops_at_the_first_batch_with_a_violation(tmp_path):
    from ego.parallel.executor import ProcessExecutor

    path = tmp_path / "f.toml"
    path.write_text(SPEC.replace("lead_gap = [20, 60]", "lead_gap = [20, 24]"))
    report = falsify(
        load(path),
        tmp_path / "o",
        optimizer="random",
        budget=20,
        until="first",
        verify=False,
        executor=ProcessExecutor(2),
    )
    s = report.searches[0]
    assert s.first_violation is not None and len(s.evaluations) == 2
