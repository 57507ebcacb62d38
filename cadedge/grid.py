"""The result of refining one curve."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def row_norms(v: np.ndarray) -> np.ndarray:
    """Euclidean length of each row of ``v`` (n, d): the refiners' innermost operation."""
    return np.sqrt(np.einsum("ij,ij->i", v, v))


def unique_sorted(values: np.ndarray) -> np.ndarray:
    """The distinct values, sorted: ``np.unique`` for 1-D arrays, without the ``numpy.ma`` import that
    numpy 2's ``unique`` triggers (about 0.1 s of every refine's start-up)."""
    v = np.sort(np.asarray(values).ravel())
    return v[np.concatenate([[True], v[1:] != v[:-1]])] if len(v) else v


def polygon_area(points_2d: np.ndarray) -> float:
    """Signed shoelace area of a closed polygon given as (n, 2) points (last point joins the first)."""
    x, y = points_2d[:, 0], points_2d[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def polyline_length(points: np.ndarray) -> float:
    """Length of the polyline through ``points`` (n, d)."""
    return float(np.sum(row_norms(np.diff(points, axis=0))))


class Polyline:
    """Lengths derived from ``points`` (n, 3), shared by the grids of a curve and of a B-rep edge."""

    points: np.ndarray

    @property
    def segment_lengths(self) -> np.ndarray:
        """Length of each segment, shape (n - 1,)."""
        p = self.points
        return row_norms(p[1:] - p[:-1])  # np.diff's own overhead was a third of this on small grids

    @property
    def length(self) -> float:
        """Polyline length."""
        return float(self.segment_lengths.sum())

    @property
    def segments(self) -> int:
        """Number of segments (points - 1)."""
        return len(self.points) - 1

    @property
    def spacing(self) -> tuple[float, float]:
        """Lengths of the first and last segments: the point spacing a mesher should use at the ends."""
        p = self.points
        if len(p) < 2:
            return (0.0, 0.0)
        first, last = row_norms(p[[1, -1]] - p[[0, -2]])  # the two end segments only, as segment_lengths
        return (float(first), float(last))


@dataclass
class EdgeGrid(Polyline):
    """A polyline on a curve: parameters, points and how it was obtained.

    ``params`` increase strictly from the first domain end to the last; ``points[i]`` is the curve at
    ``params[i]`` (always 3-D: 2-D curves are padded with z = 0). ``evaluations`` counts every point
    the black box was asked for (a vectorised call of k parameters counts k). ``ald_estimate`` is the
    refiner's estimate of ``1 - length / true_length``; ``length`` is the polyline's length.
    """

    params: np.ndarray
    points: np.ndarray
    evaluations: int
    ald_estimate: float
    mode: str = "target"
    warnings: list[str] = field(default_factory=list)

    def __repr__(self) -> str:
        return (f"EdgeGrid(mode={self.mode!r}, segments={self.segments}, length={self.length:.6g}, "
                f"ald_estimate={self.ald_estimate:.3g}, evaluations={self.evaluations})")
