"""The recorder interface the simulation loop talks to, and a recorder that does nothing."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np


@dataclass(frozen=True)
class Series:
    """One recorded time series: a column of the run's trace.

    ``path`` is its place in the recording (``plots/<panel>/<name>``: series sharing a
    panel are drawn together); ``unit`` is shown in the legend.
    """

    column: str
    path: str
    unit: str
    label: str = ""


@dataclass(frozen=True)
class Scene:
    """What a recording shows besides time series."""

    lanes: Sequence[tuple[float, Sequence[tuple[float, float]]]]  #: (width m, centre line)
    bounds: tuple[float, float, float, float] = (0.0, 100.0, -10.0, 10.0)  #: x0, x1, y0, y1 (m)
    title: str = ""
    #: what the following view shows around the followed point: x0, x1, y0, y1 (m)
    follow_view: tuple[float, float, float, float] = (-35.0, 85.0, -14.0, 14.0)


class Recorder(Protocol):
    """Receives a run in batches; must never slow the loop by more than a few percent."""

    def begin(self, scene: Scene, series: Sequence[Series], meta: dict) -> None:
        """Static content (lanes, series styles) before the first batch."""

    def write_rows(self, columns: Sequence[str], rows: np.ndarray) -> None:
        """A batch of trace rows; ``columns[0]`` is the time column ``t`` (s)."""

    def vehicles(self, t: float, ids: Sequence[str], poses: Sequence[tuple],
                 follow: tuple[float, float]) -> None:
        """Vehicles at time ``t`` as SUMO reports them: rows (front bumper x, y in m, SUMO
        angle in deg, length, width in m); ``follow`` is the point (m) the following view
        keeps in place. Must be cheap: convert later, off the loop."""

    def event(self, t: float, text: str, level: str = "INFO") -> None:
        """A line in the event log at time ``t`` (s)."""

    def flush(self) -> None:
        """Send what is buffered."""

    def close(self) -> None:
        """Flush and finish the file."""


class NullRecorder:
    """Records nothing (headless sweeps, tests of the loop itself)."""

    def begin(self, scene: Scene, series: Sequence[Series], meta: dict) -> None:
        pass

    def write_rows(self, columns: Sequence[str], rows: np.ndarray) -> None:
        pass

    def vehicles(self, t: float, ids: Sequence[str], poses: Sequence[tuple],
                 follow: tuple[float, float]) -> None:
        pass

    def event(self, t: float, text: str, level: str = "INFO") -> None:
        pass

    def flush(self) -> None:
        pass

    def close(self) -> None:
        pass


def box_outlines(boxes: np.ndarray) -> np.ndarray:
    """Closed outlines (n, 5, 2) of oriented boxes given as rows (cx, cy, yaw, length, width)."""
    cx, cy, yaw, length, width = boxes.T
    c, s = np.cos(yaw), np.sin(yaw)
    hl, hw = 0.5 * length, 0.5 * width
    corners = np.array([(1, 1), (-1, 1), (-1, -1), (1, -1), (1, 1)], dtype=float)
    lx = corners[None, :, 0] * hl[:, None]
    ly = corners[None, :, 1] * hw[:, None]
    out = np.empty((len(boxes), 5, 2))
    out[:, :, 0] = cx[:, None] + lx * c[:, None] - ly * s[:, None]
    out[:, :, 1] = cy[:, None] + lx * s[:, None] + ly * c[:, None]
    return out


def lane_edges(width: float, centre: Sequence[tuple[float, float]]) -> tuple[np.ndarray, np.ndarray]:
    """Left and right edge polylines of a lane (offset the centre line by +-width/2)."""
    pts = np.asarray(centre, dtype=float)
    d = np.gradient(pts, axis=0) if len(pts) > 2 else np.repeat(np.diff(pts, axis=0), 2, axis=0)
    n = np.column_stack([-d[:, 1], d[:, 0]])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return pts + 0.5 * width * n, pts - 0.5 * width * n
