"""The definitions of many OCCT curves read in one call, through OCCT's binary curve writer.

Reading a B-spline's knots and poles from Python is one OCP call per number (a few microseconds
each). ``BinTools_CurveSet`` writes every curve added to it, exactly (IEEE doubles, little-endian),
in one C++ call; :func:`dump_curves` parses that stream with :mod:`struct`. A curve handle added
twice (edges sharing one curve) is written once. Only the types the edge table evaluates are read:
lines, circles, ellipses, Bezier and B-spline curves (``BinTools_CurveSet.cxx`` fixes their layout).
"""

from __future__ import annotations

import io
import struct

from OCP.BinTools import BinTools_CurveSet

LINE, CIRCLE, ELLIPSE, BEZIER, BSPLINE = 1, 2, 3, 6, 7

_F3 = struct.Struct("<3d")
_CONIC = struct.Struct("<12d")
_BSPLINE_HEAD = struct.Struct("<??Hii")
_BEZIER_HEAD = struct.Struct("<?H")


class Curve:
    """One parsed curve: ``kind`` (one of the constants above), ``numbers`` (a line's location and
    direction; a conic's location, X and Y directions and radii; a spline's poles, homogeneous
    (x w, y w, z w, w) when ``rational``), and for splines ``degree``, ``knots`` (the flat sequence,
    each knot repeated by its multiplicity) and ``periodic``."""

    __slots__ = ("kind", "numbers", "degree", "knots", "rational", "periodic")

    def __init__(self, kind: int, numbers: list[float], degree: int = 0, knots: list[float] | None = None,
                 rational: bool = False, periodic: bool = False):
        self.kind, self.numbers, self.degree, self.knots = kind, numbers, degree, knots
        self.rational, self.periodic = rational, periodic


class CurveSet:
    """Collects curve handles (``add`` returns the curve's 1-based index; a handle added again gets
    its first index) and parses them all with :meth:`curves`."""

    def __init__(self):
        self._set = BinTools_CurveSet()
        self.add = self._set.Add

    def curves(self) -> list[Curve]:
        """Every added curve, in index order (index ``i`` is item ``i - 1``)."""
        buf = io.BytesIO()
        self._set.Write(buf)
        data = buf.getvalue()
        eol = data.index(b"\n")
        count = int(data[:eol].split()[1])
        out, pos = [], eol + 1
        for _ in range(count):
            curve, pos = _parse(data, pos)
            out.append(curve)
        return out


def _poles(data: bytes, pos: int, n: int, rational: bool) -> tuple[list[float], int]:
    """``n`` poles from ``pos``: (x, y, z) each, or homogeneous (x w, y w, z w, w) when rational."""
    if not rational:
        return list(struct.unpack_from(f"<{3 * n}d", data, pos)), pos + 24 * n
    raw = struct.unpack_from(f"<{4 * n}d", data, pos)
    out: list[float] = []
    for k in range(0, 4 * n, 4):
        x, y, z, w = raw[k:k + 4]
        out += (x * w, y * w, z * w, w)
    return out, pos + 32 * n


def _parse(data: bytes, pos: int) -> tuple[Curve, int]:
    kind = data[pos]
    pos += 1
    if kind == LINE:
        return Curve(LINE, list(struct.unpack_from("<6d", data, pos))), pos + 48
    if kind == CIRCLE or kind == ELLIPSE:
        v = _CONIC.unpack_from(data, pos)
        pos += 96
        if kind == CIRCLE:
            (r,) = struct.unpack_from("<d", data, pos)
            return Curve(CIRCLE, [*v[0:3], *v[6:12], r, r]), pos + 8
        rx, ry = struct.unpack_from("<2d", data, pos)
        return Curve(ELLIPSE, [*v[0:3], *v[6:12], rx, ry]), pos + 16
    if kind == BEZIER:
        rational, degree = _BEZIER_HEAD.unpack_from(data, pos)
        numbers, pos = _poles(data, pos + _BEZIER_HEAD.size, degree + 1, rational)
        knots = [0.0] * (degree + 1) + [1.0] * (degree + 1)
        return Curve(BEZIER, numbers, degree, knots, rational), pos
    if kind == BSPLINE:
        rational, periodic, degree, n, nk = _BSPLINE_HEAD.unpack_from(data, pos)
        numbers, pos = _poles(data, pos + _BSPLINE_HEAD.size, n, rational)
        pairs = struct.unpack_from("<" + "di" * nk, data, pos)
        knots: list[float] = []
        for k in range(0, 2 * nk, 2):
            knots += [pairs[k]] * pairs[k + 1]
        return Curve(BSPLINE, numbers, degree, knots, rational, periodic), pos + 12 * nk
    raise ValueError(f"curve type {kind} is not read by the edge table")
