"""Analytic roads: a centre line defined by its curvature along the arc length.

A road is a chain of pieces - straights, circular arcs and cosine easements (curvature
ramping as (1 - cos(pi u / L)) / 2 / R) - each with a closed-form heading; positions are
integrated with 5-point Gauss-Legendre quadrature on 0.5 m steps (exact to ~1e-12 m).
Curvature and radius are signed: positive turns left.

:func:`report003_road` is report 003's lane-centring road; ``sumo_nets/lane_centering``
is built from it and the tuner simulates along it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

STRAIGHT, ARC, EASE_IN, EASE_OUT = "straight", "arc", "ease_in", "ease_out"
_GL_X, _GL_W = np.polynomial.legendre.leggauss(5)


@dataclass(frozen=True)
class Piece:
    """One piece: ``kind``, ``length`` (m) and, except for straights, the signed radius (m)
    it reaches (arc) or ramps from/to (easements)."""

    kind: str
    length: float
    radius: float = math.inf

    def __post_init__(self) -> None:
        if self.kind not in (STRAIGHT, ARC, EASE_IN, EASE_OUT):
            raise ValueError(f"unknown piece kind {self.kind!r}")
        if not self.length > 0:
            raise ValueError(f"a piece needs a positive length, got {self.length}")
        if self.kind != STRAIGHT and not (math.isfinite(self.radius) and self.radius != 0):
            raise ValueError(f"a {self.kind} needs a finite non-zero radius")

    def curvature(self, u: np.ndarray) -> np.ndarray:
        """Curvature (1/m) at ``u`` metres into the piece."""
        if self.kind == STRAIGHT:
            return np.zeros_like(u)
        k = 1.0 / self.radius
        if self.kind == ARC:
            return np.full_like(u, k)
        c = np.cos(np.pi * u / self.length)
        return 0.5 * k * ((1.0 - c) if self.kind == EASE_IN else (1.0 + c))

    def turn(self, u: np.ndarray) -> np.ndarray:
        """Heading change (rad) over the first ``u`` metres: the curvature's integral."""
        if self.kind == STRAIGHT:
            return np.zeros_like(u)
        k = 1.0 / self.radius
        if self.kind == ARC:
            return k * u
        sn = self.length / np.pi * np.sin(np.pi * u / self.length)
        return 0.5 * k * ((u - sn) if self.kind == EASE_IN else (u + sn))


class CurvatureRoad:
    """A centre line from ``pieces``, starting at (x0, y0) with ``heading0`` (rad)."""

    STEP = 0.5  #: quadrature step (m)

    def __init__(self, pieces: list[Piece], x0: float = 0.0, y0: float = 0.0, heading0: float = 0.0) -> None:
        if not pieces:
            raise ValueError("a road needs at least one piece")
        self.pieces = list(pieces)
        starts = np.cumsum([0.0] + [p.length for p in self.pieces])
        self.starts = starts[:-1]
        self.length = float(starts[-1])
        headings = [heading0]
        for p in self.pieces:
            headings.append(headings[-1] + float(p.turn(np.array(p.length))))
        self.headings = np.array(headings[:-1])
        self.final_heading = headings[-1]
        # positions on a grid, integrated piecewise exactly in heading, GL in position
        n = int(math.ceil(self.length / self.STEP))
        grid = np.linspace(0.0, self.length, n + 1)
        a, b = grid[:-1], grid[1:]
        mid, half = 0.5 * (a + b), 0.5 * (b - a)
        nodes = mid[:, None] + half[:, None] * _GL_X[None, :]
        th = self.heading(nodes.ravel()).reshape(nodes.shape)
        dx = (np.cos(th) * _GL_W).sum(axis=1) * half
        dy = (np.sin(th) * _GL_W).sum(axis=1) * half
        self._grid = grid
        self._xy = np.column_stack(
            [x0 + np.concatenate([[0.0], np.cumsum(dx)]), y0 + np.concatenate([[0.0], np.cumsum(dy)])]
        )

    def _per_piece(self, s, fn) -> np.ndarray:
        """``fn(i, piece, u)`` for every value of ``s``, u metres into its piece (clamped to
        the piece: beyond the ends the end pieces continue)."""
        s = np.asarray(s, dtype=float)
        idx = np.clip(np.searchsorted(self.starts, s, side="right") - 1, 0, len(self.pieces) - 1)
        out = np.zeros_like(s)
        for i, p in enumerate(self.pieces):
            m = idx == i
            if m.any():
                out[m] = fn(i, p, np.clip(s[m] - self.starts[i], 0.0, p.length))
        return out

    def curvature(self, s) -> np.ndarray:
        """Signed curvature (1/m) at arc length(s) ``s``."""
        return self._per_piece(s, lambda i, p, u: p.curvature(u))

    def heading(self, s) -> np.ndarray:
        """Heading (rad, unwrapped) at arc length(s) ``s``."""
        return self._per_piece(s, lambda i, p, u: self.headings[i] + p.turn(u))

    def point(self, s) -> np.ndarray:
        """(x, y) at arc length(s) ``s`` within [0, length]: shape (..., 2)."""
        s = np.clip(np.asarray(s, dtype=float), 0.0, self.length)
        i = np.clip(np.searchsorted(self._grid, s, side="right") - 1, 0, len(self._grid) - 2)
        a = self._grid[i]
        half = 0.5 * (s - a)
        nodes = (a + half)[..., None] + half[..., None] * _GL_X
        th = self.heading(nodes)
        dx = (np.cos(th) * _GL_W).sum(axis=-1) * half
        dy = (np.sin(th) * _GL_W).sum(axis=-1) * half
        return np.stack([self._xy[i, 0] + dx, self._xy[i, 1] + dy], axis=-1)

    def offset_point(self, s, d) -> np.ndarray:
        """The point ``d`` metres to the left of the centre line at arc length ``s``."""
        p = self.point(s)
        th = self.heading(np.clip(np.asarray(s, dtype=float), 0.0, self.length))
        d = np.asarray(d, dtype=float)
        return np.stack([p[..., 0] - d * np.sin(th), p[..., 1] + d * np.cos(th)], axis=-1)


#: report 003's road: R 500 m, 150 m easements, 90 degrees in all
REPORT003_RADIUS = 500.0
REPORT003_EASEMENT = 150.0
REPORT003_STRAIGHT = 1000.0


def report003_road(
    radius: float = REPORT003_RADIUS, easement: float = REPORT003_EASEMENT, straight: float = REPORT003_STRAIGHT
) -> CurvatureRoad:
    """1000 m straight, a 150 m cosine easement, an arc of radius 500 m, the easement back
    and 1000 m straight, turning left by 90 degrees in all.

    Each easement turns by L/(2R), so the arc is R pi/2 - L = 635.4 m long. (The report
    lists the arc as 1150-1893 m, 743 m, which with its easements would turn 102 degrees,
    not the 90 it states; we keep the 90.)
    """
    arc = radius * math.pi / 2 - easement
    if arc <= 0:
        raise ValueError("the easements alone turn more than 90 degrees")
    return CurvatureRoad(
        [
            Piece(STRAIGHT, straight),
            Piece(EASE_IN, easement, radius),
            Piece(ARC, arc, radius),
            Piece(EASE_OUT, easement, radius),
            Piece(STRAIGHT, straight),
        ]
    )
