"""Run many independent tasks on workers: one ``Executor`` interface, a process pool
(:class:`~ego.parallel.executor.ProcessExecutor`), a Ray cluster
(:class:`~ego.parallel.ray_engine.RayExecutor`) and an in-process one for tests, chosen by
name with :func:`make_executor`. Generic: it knows nothing of scenarios; ``ego compare``,
``ego sweep``, the docs generator and ``ego tune`` run on it.
"""

from ego.parallel.executor import ENGINES, Executor, InlineExecutor, ProcessExecutor, make_executor
from ego.parallel.outcome import Outcome

__all__ = ["ENGINES", "Executor", "InlineExecutor", "Outcome", "ProcessExecutor", "make_executor"]
