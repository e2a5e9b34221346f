"""The Ray engine against the process engine: same values, same failure rules.

One local Ray instance (2 CPUs) serves the whole module: it starts in ~4 s and is shut
down at the end. Behavioural tests run on both engines (``engine`` fixture); the task
functions live in ``tests/engine_tasks.py``, which both engines' workers import by name.
"""

import itertools
import os
import subprocess
import sys
import time
from pathlib import Path

import engine_tasks as T
import pytest

from ego.parallel.executor import Outcome, ProcessExecutor, make_executor
from ego.params import ConfigError

WORKERS = 2
ROOT = Path(__file__).resolve().parents[2]
#: emergency-brake with both lane-change controllers, two seeds each
SPECS = [("emergency-brake", c, s) for c in ("pid", "fuzzy") for s in (0, 1)]


@pytest.fixture(scope="module")
def ray_executor():
    pytest.importorskip("ray")
    from ego.parallel.ray_engine import RayExecutor

    t0 = time.perf_counter()
    saved = os.environ.get("PYTHONPATH")
    os.environ.update(T.ray_env())  # Ray's workers start with it: they import engine_tasks
    try:
        executor = RayExecutor(WORKERS)
    finally:
        if saved is None:
            os.environ.pop("PYTHONPATH")
        else:
            os.environ["PYTHONPATH"] = saved
    print(f"\nRay start-up (ray.init, {WORKERS} CPUs): {time.perf_counter() - t0:.2f} s")
    yield executor
    t0 = time.perf_counter()
    executor.close()
    print(f"\nRay shut-down: {time.perf_counter() - t0:.2f} s")
    import ray

    assert not ray.is_initialized()


@pytest.fixture(scope="module")
def process_executor():
    with ProcessExecutor(WORKERS) as executor:
        yield executor


@pytest.fixture(scope="module", params=["process", "ray"])
def engine(request):
    return request.getfixturevalue(f"{request.param}_executor")


def outcomes(executor, fn, tasks) -> list[Outcome]:
    return list(executor.run(fn, tasks))


# -- the interface ---------------------------------------------------------------------------


def test_executor_module_does_not_import_ray():
    code = "import sys, ego.parallel.executor; assert 'ray' not in sys.modules, 'ray imported'"
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT, env={"PYTHONPATH": str(ROOT), "PATH": ""})


def test_without_ray_the_engine_is_a_config_error(monkeypatch):
    from ego.parallel.ray_engine import RayExecutor

    monkeypatch.setitem(sys.modules, "ray", None)  # import ray -> ImportError
    with pytest.raises(ConfigError, match=r"pip install 'ego\[ray\]'"):
        RayExecutor(2)


def test_make_executor_ray_joins_the_running_instance(ray_executor):
    import ray

    executor = make_executor("ray", WORKERS)
    assert type(executor).__name__ == "RayExecutor" and executor.workers == WORKERS
    assert [o.value for o in executor.run(T.square, [3])] == [9]
    executor.close()  # it started nothing, so it shuts nothing down
    assert ray.is_initialized()


def test_workers_import_the_callers_ego(engine):
    (outcome,) = outcomes(engine, T.ego_location, [0])
    assert outcome.value == str(ROOT / "ego"), outcome


# -- values and laziness -----------------------------------------------------------------------


def test_values_come_back_once_each(engine):
    got = outcomes(engine, T.square, range(20))
    assert sorted(o.task for o in got) == list(range(20))
    assert all(o.value == o.task**2 and o.error == "" and o.attempts == 1 for o in got)


def test_tasks_are_read_lazily(engine):
    pulled = itertools.count()

    def tasks():
        for i in itertools.count():
            next(pulled)
            yield i

    gen = engine.run(T.square, tasks())
    first = [next(gen) for _ in range(10)]
    gen.close()  # stop early: the engine must not have read ahead more than a few per worker
    assert all(o.value == o.task**2 for o in first)
    assert next(pulled) <= 10 + 2 * engine.workers + 1
    assert [o.value for o in engine.run(T.square, [5])] == [25]  # still usable after


@pytest.mark.sumo
def test_sumo_runs_give_the_same_metrics_on_both_engines(process_executor, ray_executor):
    by_engine = {}
    for name, executor in (("process", process_executor), ("ray", ray_executor)):
        got = outcomes(executor, T.run_metrics, SPECS)
        assert all(o.error == "" for o in got), [o.error for o in got]
        by_engine[name] = {o.task: o.value for o in got}
    assert set(by_engine["ray"]) == set(SPECS)
    for spec in SPECS:
        assert by_engine["ray"][spec] == by_engine["process"][spec], spec
        assert by_engine["ray"][spec]["status"] == "completed"


# -- libsumo: one simulation per process ---------------------------------------------------------


@pytest.mark.sumo
def test_many_sumo_runs_on_two_reused_workers(engine):
    specs = [("emergency-brake", "pid", seed) for seed in range(6)]
    got = outcomes(engine, T.run_in_worker, specs)
    assert sorted(o.task for o in got) == specs
    assert all(o.error == "" and o.attempts == 1 for o in got), [o.error for o in got]
    pids = {o.value[0] for o in got}
    assert len(pids) < len(specs)  # workers ran several simulations each, one after another
    assert all(o.value[1] == "completed" and o.value[2] is False for o in got)  # each closed its SUMO


@pytest.mark.sumo
def test_a_second_simulation_in_one_task_is_refused(engine):
    (outcome,) = outcomes(engine, T.second_simulation_refused, [0])
    assert outcome.error == ""
    assert outcome.value.startswith("SumoError: ") and "one per process" in outcome.value


# -- failures ------------------------------------------------------------------------------------


def test_a_raising_task_is_an_error_outcome_not_retried(engine):
    (outcome,) = outcomes(engine, T.fail, [7])
    assert outcome.error == "ValueError: bad task 7"
    assert outcome.value is None and outcome.attempts == 1


def test_a_dead_worker_costs_one_retry(engine, tmp_path):
    (outcome,) = outcomes(engine, T.die_once, [str(tmp_path / "marker")])
    assert outcome.error == "" and outcome.attempts == 2
    assert isinstance(outcome.value, int) and outcome.value != int((tmp_path / "marker").read_text())


def test_a_worker_dying_twice_is_an_error_while_the_others_complete(engine, tmp_path):
    jobs = [
        ("square", 1),
        ("always_die", 0),
        ("square", 2),
        ("fail", 3),
        ("die_once", str(tmp_path / "marker")),
        ("square", 4),
    ]
    got = {o.task: o for o in outcomes(engine, T.call, jobs)}
    assert set(got) == set(jobs)
    dead = got[("always_die", 0)]
    assert dead.value is None and dead.attempts == 2 and "died 2 times" in dead.error
    assert [got[("square", x)].value for x in (1, 2, 4)] == [1, 4, 16]
    assert all(got[("square", x)].attempts == 1 for x in (1, 2, 4))
    assert got[("fail", 3)].error == "ValueError: bad task 3" and got[("fail", 3)].attempts == 1
    assert got[("die_once", str(tmp_path / "marker"))].attempts == 2
    assert got[("die_once", str(tmp_path / "marker"))].error == ""
    # the engine is still whole afterwards
    assert sorted(o.value for o in engine.run(T.square, range(4))) == [0, 1, 4, 9]


def test_a_dead_ray_workers_row_names_the_fmu_its_run_loaded(ray_executor, tmp_path):
    """An FMU that SIGKILLs its process: Ray's error names no process (the process engine
    names the FMU from the folder its worker left: tests/fmi/test_fmu_watchdog.py), so the
    row names it from the run itself; no extraction folder stays."""
    sys.path.insert(0, str(ROOT / "tests" / "fmi"))
    import fmu_zoo

    from ego.runner import RunSpec, resolve
    from ego.sweep.pipeline import RunTask, execute, row_of

    fmu = str(fmu_zoo.build(fmu_zoo.misbehave("kill"), tmp_path))
    task = RunTask(resolve(RunSpec("emergency-brake", fmu, overrides={"duration": 3.0})))
    (outcome,) = outcomes(ray_executor, execute, [task])
    row = row_of(outcome)
    assert row.status == "error" and row.attempts == 2
    assert row.error.startswith("the worker process died 2 times running it (") and row.error.endswith(
        "FMU 'kill_fmu' loaded)"
    ), row.error
    assert not fmu_zoo.fmu_folders_left(set()), "a dead worker's FMU folder stayed"


# -- cost ----------------------------------------------------------------------------------------


def test_per_task_overhead_printed(engine):
    """Not asserted: the figure docs/performance.md quotes (200 trivial tasks, 2 workers)."""
    outcomes(engine, T.square, range(10))  # warm
    t0 = time.perf_counter()
    got = outcomes(engine, T.square, range(200))
    elapsed = time.perf_counter() - t0
    assert len(got) == 200
    print(
        f"\n{type(engine).__name__}({engine.workers}): 200 square tasks in {elapsed:.2f} s, "
        f"{200 / elapsed:.0f} tasks/s, {elapsed / 200 * 1e3:.2f} ms per task"
    )
