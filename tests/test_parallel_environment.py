"""A warm worker pool sees the caller's search folders (``--path``, ``$EGO_PATH``) and printed
warnings as they are when a task is sent, not as they were when its processes started: a
forkserver worker starts from its server's environment, and a pool outlives one command."""

from __future__ import annotations

from engine_tasks import environ

from ego.parallel.executor import ProcessExecutor
from ego.parallel.outcome import CARRIED_ENV


def test_a_warm_pool_takes_the_callers_environment_with_each_task(monkeypatch):
    assert CARRIED_ENV == ("EGO_PATH", "EGO_WARNED")
    monkeypatch.delenv("EGO_PATH", raising=False)
    with ProcessExecutor(1) as ex:
        assert [o.value for o in ex.run(environ, ["EGO_PATH"])] == [None]
        monkeypatch.setenv("EGO_PATH", "/some/roads")
        assert [o.value for o in ex.run(environ, ["EGO_PATH"])] == ["/some/roads"]  # the same worker
        monkeypatch.delenv("EGO_PATH")
        assert [o.value for o in ex.run(environ, ["EGO_PATH"])] == [None]
