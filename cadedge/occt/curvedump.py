"""The definitions of many OCCT curves read in one call, through OCCT's binary curve writer.

Reading a B-spline's knots and poles from Python is one OCP call per number (a few microseconds
each). ``BinTools_CurveSet`` writes every curve added to it, exactly (IEEE doubles, little-endian),
in one C++ call, and ``cadedge/_bintools.c`` parses that stream straight into rows of the edge table's
geometry (``parse_curves``). A curve handle added twice (edges sharing one curve) is written once.
Only the types the edge table evaluates are read: lines, circles, ellipses, hyperbolas, Bezier and B-spline
curves (``BinTools_CurveSet.cxx`` fixes their layout).
"""

from __future__ import annotations

import io

import numpy as np
from OCP.BinTools import BinTools_CurveSet

from ..kernels import parse_curves

#: BinTools' type codes of the curves read (column ``TYPE`` of :attr:`Curves.meta`).
LINE, CIRCLE, ELLIPSE, BEZIER, BSPLINE = 1, 2, 3, 6, 7
#: Columns of :attr:`Curves.meta`.
KIND, DEGREE, KNOTS, DIM, PERIODIC, TYPE = range(6)


class Curves:
    """Parsed curves: curve ``c`` (0-based: index ``c + 1`` in the set) is the geometry table row
    ``numbers[offsets[c]:offsets[c + 1]]``, and ``meta[c]`` is (table kind, degree, number of knots, dim,
    periodic, BinTools type); see ``parse_curve`` in ``cadedge/_shapedump.c`` for the layout."""

    def __init__(self, meta: np.ndarray, offsets: np.ndarray, numbers: np.ndarray):
        self.meta, self.offsets, self.numbers = meta, offsets, numbers


class CurveSet:
    """Collects curve handles (``add`` returns the curve's 1-based index; a handle added again gets
    its first index) and parses them all with :meth:`curves`."""

    def __init__(self):
        self._set = BinTools_CurveSet()
        self.add = self._set.Add

    def curves(self) -> Curves:
        """Every added curve, in index order."""
        buf = io.BytesIO()
        self._set.Write(buf)
        data = buf.getvalue()
        eol = data.index(b"\n")
        count = int(data[:eol].split()[1])  # the header line: "Curves <count>"
        meta, offsets, numbers, end = parse_curves(data, eol + 1, count)
        if end != len(data):
            raise ValueError(f"OCCT's curve stream has {len(data) - end} bytes past its {count} curves")
        return Curves(meta, offsets, numbers)
