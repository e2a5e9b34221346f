"""The falsification benchmark's machinery (issue 21, point 3) on a tiny budget: real SUMO
runs through ``ego falsify``, the statistics, the resume from stored runs, the figure. The
full benchmark (20 repetitions x 4 optimisers, 300 runs each) is ``benchmarks/test_benchmarks.py``
(marked ``benchmark``)."""

import sys
from pathlib import Path

import pyarrow.parquet as pq

from ego.falsify import bench

ROOT = Path(__file__).resolve().parents[2]


def test_quartiles_count_a_repetition_without_a_violation_as_more_than_the_budget():
    q1, med, q3, found = bench.quartiles([10, None, 30, None, 5], 100)
    assert found == 3
    assert (q1, med, q3) == (10.0, 30.0, 101.0)
    assert bench.fmt_runs(q3, 100) == ">100" and bench.fmt_runs(med, 100) == "30"


def test_wilson_interval_holds_the_share_and_stays_in_zero_one():
    lo, hi = bench.wilson(8, 2048)
    assert lo < 8 / 2048 < hi and 0.0 < lo and hi < 0.01
    assert bench.wilson(0, 100)[0] == 0.0 and 0.0 < bench.wilson(0, 100)[1] < 0.05


def test_bench_runs_a_tiny_budget_resumes_and_plots(tmp_path):
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        from bench_falsify import main
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    names = bench.requirements()
    assert len(names) >= 2
    args = ["--repetitions", "1", "--budget", "3", "--optimizers", "cma", "--jobs", "2", "--cache", str(tmp_path / "c")]
    figures = main(args + ["--plot", str(tmp_path / "conv.png")])
    assert set(figures) == {(n, o) for n in names for o in ("cma", "lhs")}
    for fig in figures.values():
        assert len(fig["runs"]) == 1 and all(r is None or 1 <= r <= 3 for r in fig["runs"])
        assert fig["rate"] == (fig["runs"][0] is not None)  # the falsification rate at the budget
    assert (tmp_path / "conv.png").stat().st_size > 0
    folders = sorted((tmp_path / "c").glob("*/*"))
    assert [f.name for f in folders] == [f"{o}-seed0-budget3-batch2" for o in ("cma", "lhs")]
    # every run evaluates every requirement; the blind baseline's points serve both targets
    lhs = pq.read_table(folders[1] / "results.parquet").to_pandas()
    assert len(lhs) <= 3 and all(f"requirements.{n}" in lhs for n in names)
    sizes = {f: len(pq.read_table(f / "results.parquet")) for f in folders}
    # the same command again: the same figures from the stored runs, nothing run again
    assert main(args) == figures
    assert {f: len(pq.read_table(f / "results.parquet")) for f in folders} == sizes


def test_convergence_figure_draws_median_and_quartile_bands(tmp_path):
    curves = {("a", "cma"): [[3.0, 1.0, -0.5], [2.0, 2.0, 2.0]], ("a", "lhs"): [[4.0, 4.0, 3.0]] * 2}
    path = bench.convergence_figure(curves, 3, tmp_path / "c.png")
    assert path.stat().st_size > 0


def test_region_share_of_grids_matches_a_ball_in_a_corner_analytically():
    """The grids' geometry and the share arithmetic, without SUMO: a ball of radius 0.15
    around the corner (1, 0, 1) violates; its share of the unit cube is an eighth of the
    ball's volume, pi/6 * 0.15^3 = 0.1767 %."""
    import math

    import numpy as np

    corner = np.array([1.0, 0.0, 1.0])

    def measure(jobs):
        return [{"u": list(p), "r": float(np.linalg.norm(p - corner) - 0.15)} for j in jobs for p in j.points()]

    coarse = measure(bench.grid_jobs(((0.0, 1.0),) * 3, (12, 12, 12)))
    box = ((0.8, 1.0), (0.0, 0.2), (0.8, 1.0))
    fine = measure(bench.grid_jobs(box, (40, 40, 40)))
    r = bench.region_share(coarse, fine, "r", box)
    assert r["coarse_n"] == 1728 and r["fine_n"] == 64000 and r["outside_bad"] == 0
    assert math.isclose(r["volume"], 0.008)
    assert abs(r["share"] - math.pi / 6 * 0.15**3) < 0.02 * math.pi / 6 * 0.15**3
