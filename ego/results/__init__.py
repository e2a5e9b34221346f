"""What a run leaves behind, below the scenarios that produce it.

:class:`~ego.results.run.RunResult` and :class:`~ego.results.run.Event` (one run's outcome),
the named trace (:mod:`ego.results.trace`: columns, metrics and plots declared with units),
the traffic log (:mod:`ego.results.traffic_log`), the exports to CSV, Parquet and MATLAB
(:mod:`ego.results.export`), the metric helpers (:mod:`ego.results.metrics`), and the one
summary formatter (:mod:`ego.results.summary`) and progress display
(:mod:`ego.results.progress`) ``ego compare`` and ``ego sweep`` share. Nothing here imports
a scenario.
"""

from ego.results.run import Event, RunResult
from ego.results.trace import Column, Metric, Plot, Trace
from ego.results.traffic_log import TrafficLog

__all__ = ["Column", "Event", "Metric", "Plot", "RunResult", "Trace", "TrafficLog"]
