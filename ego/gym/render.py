"""The top-down frame of ``render_mode="rgb_array"``: the lanes and every vehicle's box as SUMO
has it, in the scenario's colours (the ego red, other scripted cars in theirs, the background
traffic blue), the agent's car drawn in its own colour (green, thick outline: in the platoon
the first follower among the red ones), the view following the agent's car (``screen_width`` x ``screen_height`` px at ``scaling``
px/m). Drawn with matplotlib's Agg canvas (no display, no window)."""

from __future__ import annotations

import math

import numpy as np

#: colours (RGB 0-1)
_ROAD, _MARK, _OTHER, _BG = (0.42, 0.42, 0.42), (0.9, 0.9, 0.9), (0.2, 0.5, 0.85), (0.33, 0.55, 0.3)
_CONTROLLED = (0.86, 0.16, 0.16)
_AGENT = (0.1, 0.85, 0.3)


class TopDown:
    """One figure reused frame after frame: the lanes are drawn at the first frame of a run,
    the vehicles at every frame."""

    def __init__(self, cfg) -> None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        self.width, self.height, self.scaling = cfg.screen_width, cfg.screen_height, cfg.scaling
        dpi = 100
        self.fig = Figure(figsize=(self.width / dpi, self.height / dpi), dpi=dpi, facecolor=_BG)
        self.canvas = FigureCanvasAgg(self.fig)
        self.ax = self.fig.add_axes((0.0, 0.0, 1.0, 1.0))
        self.ax.set_axis_off()
        self.ax.set_aspect("equal")
        self._lanes_of = None
        self._vehicles: list = []

    def _draw_lanes(self, scenario) -> None:
        from matplotlib.patches import Polygon

        ax = self.ax
        for patch in list(ax.patches) + list(ax.lines):
            patch.remove()
        lanes = list(getattr(scenario, "lanes", {}).values()) or [scenario.lane]
        for lane in lanes:
            s = np.linspace(0.0, lane.length, max(2, int(lane.length / 2.0)))
            half = 0.5 * lane.width
            left = [lane.offset_point(x, half) for x in s]
            right = [lane.offset_point(x, -half) for x in s]
            ax.add_patch(
                Polygon(left + right[::-1], closed=True, facecolor=_ROAD, edgecolor=_MARK, linewidth=0.6, zorder=1)
            )
        self._lanes_of = scenario

    def draw(self, scenario, view) -> np.ndarray:
        """The frame now: (screen_height, screen_width, 3) uint8."""
        from matplotlib.patches import Polygon

        if self._lanes_of is not scenario or getattr(self, "_k", 1) > scenario.k:
            self._draw_lanes(scenario)
        self._k = scenario.k
        for patch in self._vehicles:
            patch.remove()
        ids, boxes = scenario.bridge.boxes()
        controlled = set(scenario.controlled_ids)
        agent = scenario.agent_id if scenario.controlled_ids else None
        colors = scenario.colors  # the scenario's own (0-255), as in its recording
        self._vehicles = []
        centre = None
        for vid, (x, y, yaw, length, width) in zip(ids, boxes):
            c, s = math.cos(yaw), math.sin(yaw)
            hl, hw = 0.5 * length, 0.5 * width
            corners = [(x + c * a - s * b, y + s * a + c * b) for a, b in ((hl, hw), (-hl, hw), (-hl, -hw), (hl, -hw))]
            mine = vid in controlled
            rgb = colors.get(vid)
            face = tuple(c / 255.0 for c in rgb) if rgb is not None else (_CONTROLLED if mine else _OTHER)
            if vid == agent:
                face = _AGENT
            patch = Polygon(
                corners,
                closed=True,
                facecolor=face,
                edgecolor="black",
                linewidth=1.5 if vid == agent else 0.5,
                zorder=3 if vid == agent else 2,
            )
            self.ax.add_patch(patch)
            self._vehicles.append(patch)
            if vid == agent:
                centre = (x, y)
        if centre is None:
            x, y, _ = view.plant().pose()
            centre = (x, y)
        hw, hh = 0.5 * self.width / self.scaling, 0.5 * self.height / self.scaling
        self.ax.set_xlim(centre[0] - hw, centre[0] + hw)
        self.ax.set_ylim(centre[1] - hh, centre[1] + hh)
        self.canvas.draw()
        return np.asarray(self.canvas.buffer_rgba())[:, :, :3].copy()

    def close(self) -> None:
        self.fig.clear()
