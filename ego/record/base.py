"""The recorder interface the simulation loop talks to, and a recorder that does nothing."""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np


@dataclass(frozen=True)
class Series:
    """One recorded time series: a column of the run's trace.

    ``path`` is its place in the recording: ``plots/<panel>/.../<name>``, and the series
    sharing a parent path are drawn in one panel, titled by ``<panel>`` and the unit (so a
    panel holds one unit only); ``label`` names the series in the panel's title and when
    hovered (short: "ego", "reference", "f1"). Two special kinds:

    * ``states``: the column holds a state index (0, 1, ...); it is recorded as the named
      states ``states[i]`` (a state timeline under ``states/<name>``), not as a number;
    * ``constant``: no column, a horizontal line at this value (a threshold) over the run.
    """

    column: str
    path: str
    unit: str
    label: str = ""
    states: tuple[str, ...] = ()
    constant: float | None = None

    @property
    def panel(self) -> str:
        """The panel's entity path: the series' parent."""
        return self.path.rpartition("/")[0]


@dataclass(frozen=True)
class Scene:
    """What a recording shows besides time series."""

    lanes: Sequence[tuple[float, Sequence[tuple[float, float]]]]  #: (width m, centre line)
    title: str = ""
    followed: str = "the ego"  #: what the road views follow, as their titles name it
    #: what the close view shows around the followed point: x0, x1, y0, y1 (m, x ahead)
    follow_view: tuple[float, float, float, float] = (-20.0, 40.0, -10.0, 10.0)
    #: what the wide view shows around it: 300 m of road, 100 m behind to 200 m ahead
    around_view: tuple[float, float, float, float] = (-100.0, 200.0, -9.0, 9.0)


class Recorder(Protocol):
    """Receives a run in batches; must never slow the loop by more than a few percent."""

    def begin(self, scene: Scene, series: Sequence[Series], meta: dict) -> None:
        """Static content (lanes, series styles) before the first batch."""

    def write_rows(self, columns: Sequence[str], rows: np.ndarray) -> None:
        """A batch of trace rows; ``columns[0]`` is the time column ``t`` (s)."""

    def vehicles(self, t: float, ids: Sequence[str], poses: Sequence[tuple], follow: tuple[float, float]) -> None:
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

    def vehicles(self, t: float, ids: Sequence[str], poses: Sequence[tuple], follow: tuple[float, float]) -> None:
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


def unit_path(unit: str) -> str:
    """A unit as an entity-path part: "N/(m s)" -> "N_per_m_s", "m/s^2" -> "m_per_s_2",
    no unit or "-" -> "1"."""
    return re.sub(r"[^A-Za-z0-9]+", "_", unit.replace("/", " per ")).strip("_") or "1"
