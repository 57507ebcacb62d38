"""numpy-facing wrappers of the compiled inner loops (``cadedge/_kernels.c``, ``_batch.c``, ``_bintools.c``,
``_shapedump.c``, ``_lengths.c``, ``_angles.c``, ``_idw.c``).

A refine runs these loops a few times per edge on short arrays, where numpy's per-call overhead
dominated; :func:`refine_edges` runs the whole target mode of many edges in one call. They are plain C
compiled when the package is installed, so a new process loads them in about a millisecond and never
compiles anything. Each wrapper allocates the outputs and passes C-contiguous arrays of the right
type; the C side checks them.
"""

from __future__ import annotations

import numpy as np

try:
    from . import _kernels
except ImportError as exc:  # a source tree used without installing it
    raise ImportError("cadedge's compiled kernels (cadedge/_kernels.c) are not built: install the package "
                      "(pip install -e .), which compiles them") from exc


def _f64(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64)


def classify(ua: np.ndarray, um: np.ndarray, ub: np.ndarray, pa: np.ndarray, pm: np.ndarray, pb: np.ndarray,
             ratio: np.ndarray, tol: float, scale: float, min_width: float, noise: float, straight: float,
             asymptotic: float) -> tuple[float, np.ndarray, np.ndarray, np.ndarray, float]:
    """One exploration level over the live triples (a, m, b): (remainder of the finished ones, params
    of new corners, indices to split, their gains, scale). ``scale`` < 0 asks for it to be set from
    this (first) level's half chords. See :func:`cadedge.explore.explore` for the rules."""
    n = len(ua)
    corners, split, gains = np.empty(n), np.empty(n, dtype=np.int64), np.empty(n)
    rem, n_corners, n_split, scale = _kernels.classify(
        _f64(ua), _f64(um), _f64(ub), _f64(pa), _f64(pm), _f64(pb), _f64(ratio), corners, split, gains,
        tol, scale, min_width, noise, straight, asymptotic)
    return rem, corners[:n_corners], split[:n_split], gains[:n_split], scale


def children(ua: np.ndarray, um: np.ndarray, ub: np.ndarray, pa: np.ndarray, pm: np.ndarray, pb: np.ndarray,
             split: np.ndarray, gains: np.ndarray, q: np.ndarray, pq: np.ndarray) -> tuple[np.ndarray, ...]:
    """The live triples of the next level: (a, q1, m) and (m, q3, b) of each split (a, m, b), all left
    halves first, each with (G_left + G_right) / G_parent: (ua, um, ub, pa, pm, pb, ratio)."""
    n = 2 * len(split)
    out = (np.empty(n), np.empty(n), np.empty(n), np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)), np.empty(n))
    _kernels.children(_f64(ua), _f64(um), _f64(ub), _f64(pa), _f64(pm), _f64(pb),
                      np.ascontiguousarray(split, dtype=np.int64), _f64(gains), _f64(q), _f64(pq), *out)
    return out


def fewest(points: np.ndarray, cum: np.ndarray, budget: float, min_length: float, max_length: float,
           stops: np.ndarray, fixed: np.ndarray, drop: bool = True) -> np.ndarray:
    """Greedy cover + bisection on the cap + polish (see :func:`cadedge.placement.fewest_nodes`)."""
    out = np.empty(len(points), dtype=np.int64)
    count = _kernels.fewest(_f64(points), _f64(cum), np.ascontiguousarray(stops, dtype=np.int64),
                            np.ascontiguousarray(fixed, dtype=np.bool_), out, budget, min_length, max_length, drop)
    return out[:count]


def deficit_measure(points: np.ndarray, cum: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """See :func:`cadedge.placement.deficit_measure`."""
    out = np.empty(len(cum))
    _kernels.deficit_measure(_f64(points), _f64(cum), np.ascontiguousarray(corners, dtype=np.int64), out)
    return out


def interp_sorted(x: np.ndarray, xp: np.ndarray, fp: np.ndarray) -> np.ndarray:
    """``np.interp(x, xp, fp)`` for increasing ``x`` and non-decreasing ``xp`` (the same values)."""
    out = np.empty(len(x))
    _kernels.interp_sorted(_f64(x), _f64(xp), _f64(fp), out)
    return out


def place(params: np.ndarray, cum: np.ndarray, measure: np.ndarray, cut: np.ndarray,
          alloc: np.ndarray) -> np.ndarray:
    """Parameters at equal steps of ``measure`` within each piece between ``cut`` samples (``alloc``
    segments each), interpolated in arc length then in parameter; strictly increasing."""
    alloc = np.ascontiguousarray(alloc, dtype=np.int64)
    out = np.empty(1 + int(np.maximum(alloc, 1).sum()))
    count = _kernels.place(_f64(params), _f64(cum), _f64(measure), np.ascontiguousarray(cut, dtype=np.int64),
                           alloc, out)
    return out[:count]


def de_boor(knots: np.ndarray, coef: np.ndarray, degree: int, u: np.ndarray) -> np.ndarray:
    """Points of the spline (knots, coef (n, d), degree) at ``u``; outside the knots the end pieces are
    extended."""
    coef = _f64(coef)
    out = np.empty((len(u), coef.shape[1]))
    _kernels.de_boor(_f64(knots), coef, _f64(u), out, int(degree))
    return out


def evaluate_edges(kind: np.ndarray, gofs: np.ndarray, ints: np.ndarray, gdata: np.ndarray, edge: np.ndarray,
                   u: np.ndarray) -> np.ndarray:
    """Points (len(u), 3) of the geometry table's edges ``edge[i]`` at ``u[i]`` (see ``cadedge/_batch.c``)."""
    u = _f64(u).ravel()
    out = np.empty((len(u), 3))
    _kernels.evaluate_edges(kind, gofs, ints, gdata, np.ascontiguousarray(edge, dtype=np.int64), u, out)
    return out


def edge_lengths(kind: np.ndarray, gofs: np.ndarray, ints: np.ndarray, gdata: np.ndarray, hofs: np.ndarray,
                 hdata: np.ndarray, domain: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """The lengths of the geometry table's rows ``rows`` over their domains (n, 2), by adaptive Gauss-Legendre
    quadrature (see ``cadedge/_lengths.c``); NaN for a row it does not integrate to its tolerance."""
    rows = np.ascontiguousarray(rows, dtype=np.int64)
    out = np.empty(len(rows))
    _kernels.edge_lengths(kind, gofs, ints, gdata, hofs, _f64(hdata), _f64(domain), rows, out)
    return out


def refine_edges(kind: np.ndarray, gofs: np.ndarray, ints: np.ndarray, gdata: np.ndarray, hofs: np.ndarray,
                 hdata: np.ndarray, domain: np.ndarray, ald: np.ndarray, exact: np.ndarray, first: np.ndarray,
                 last: np.ndarray, settings: np.ndarray) -> tuple[np.ndarray, ...]:
    """Target-mode grids of every edge of the geometry table in one call (see ``cadedge/_batch.c``):
    (status, offsets, params, points (n, 3), estimate, raw_estimate, evaluations)."""
    raw = _kernels.refine_edges(kind, gofs, ints, gdata, hofs, _f64(hdata), _f64(domain), _f64(ald), _f64(exact),
                                _f64(first), _f64(last), _f64(settings))
    status, offsets, params, points, estimate, raw_estimate, evaluations = raw
    return (np.frombuffer(status, dtype=np.int64), np.frombuffer(offsets, dtype=np.int64),
            np.frombuffer(params, dtype=float), np.frombuffer(points, dtype=float).reshape(-1, 3),
            np.frombuffer(estimate, dtype=float), np.frombuffer(raw_estimate, dtype=float),
            np.frombuffer(evaluations, dtype=np.int64))


def parse_curves(data: bytes, start: int, count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """The ``count`` curves OCCT's ``BinTools_CurveSet`` wrote in ``data`` from byte ``start``, as geometry
    table rows (see ``cadedge/_batch.c``): (meta (count, 6), offsets (count + 1), numbers, end byte)."""
    meta, offsets, numbers, end = _kernels.parse_curves(data, start, count)
    return (np.frombuffer(meta, dtype=np.int64).reshape(-1, 6), np.frombuffer(offsets, dtype=np.int64),
            np.frombuffer(numbers, dtype=float), end)


def parse_shapes(data: bytes, root: int, orientation: int) -> tuple:
    """A shape written by OCCT's ``BinTools_ShapeSet`` (its set index ``root``, its orientation): the raw
    arrays of ``cadedge/_shapedump.c``'s ``parse_shapes`` (read by :mod:`cadedge.occt.shapedump`);
    ValueError where the stream is not one it takes."""
    return _kernels.parse_shapes(data, root, orientation)


def min_angles(nodes: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """The smallest interior angle (degrees) of each triangle (rows of node indices into ``nodes`` (n, 3))."""
    tri = np.ascontiguousarray(triangles, dtype=np.int64).reshape(-1, 3)
    out = np.empty(len(tri))
    _kernels.min_angles(_f64(nodes).reshape(-1, 3), tri, out)
    return out


def tri_normals(x: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Each triangle's normal ``(b - a) x (c - a)`` (m, 3), twice its area in length (rows of node indices
    ``tri`` into ``x`` (n, 3))."""
    tri = np.ascontiguousarray(tri, dtype=np.int64).reshape(-1, 3)
    out = np.empty((len(tri), 3))
    _kernels.tri_normals(_f64(x).reshape(-1, 3), tri, out)
    return out


def idw_size(points: np.ndarray, sizes: np.ndarray, x: float, y: float, z: float, k: int) -> float:
    """The sizes of the ``k`` points nearest to ``(x, y, z)`` averaged with weights ``1 / (distance +
    1e-12)``; ``points`` (m, 3) and ``sizes`` (m,) C-contiguous float64 (gmsh's size callback calls this
    once per point: no conversion here)."""
    return _kernels.idw_size(points, sizes, x, y, z, k)


def climb_trials(x: np.ndarray, tri: np.ndarray, node: np.ndarray, slot: np.ndarray, t: np.ndarray,
                 u: np.ndarray, v: np.ndarray, h: np.ndarray, steps: np.ndarray, cosines: np.ndarray,
                 sines: np.ndarray, best: np.ndarray, best_pos: np.ndarray) -> None:
    """The local search's trials in one call: for each of ``steps`` and then each direction (``cosines``,
    ``sines``), each node of the incidences tried at ``x + step * h * (cos * u + sin * v)``; where its
    smallest angle there (that of its worst triangle) beats ``best`` by more than 1e-9, ``best`` and
    ``best_pos`` (float64, C-contiguous, updated in place) take it."""
    i64 = np.int64
    for a in (best, best_pos):
        if a.dtype != np.float64 or not a.flags.c_contiguous:
            raise ValueError("climb_trials: best and best_pos must be C-contiguous float64 arrays")
    _kernels.climb_trials(_f64(x), np.ascontiguousarray(tri, dtype=i64), np.ascontiguousarray(node, dtype=i64),
                          np.ascontiguousarray(slot, dtype=i64), np.ascontiguousarray(t, dtype=i64), _f64(u), _f64(v),
                          _f64(h), _f64(steps), _f64(cosines), _f64(sines), best, best_pos)
