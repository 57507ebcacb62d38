"""gmsh ``.geo`` exporter: the edge grids as built-in-kernel geometry that meshes back to themselves.

``Point(k)`` is cadedge vertex ``k`` with mesh size = the vertex spacing; interior grid points follow
with size = the shorter of their two segments. Every grid segment is a ``Line`` made transfinite with
2 nodes, so ``gmsh -1`` reproduces the grid exactly; ``Physical Curve("edge k", k)`` groups the
segments of cadedge edge ``k``. Degenerate edges have no segments and are left out.
"""

from __future__ import annotations

import numpy as np

from ..shapegrid import ShapeGrid
from ._common import comment


def _size(value: float | None) -> float:
    """gmsh reads a size of 0 as "no size given" (use the global default)."""
    return float(value) if value else 0.0


def to_bytes(grid: ShapeGrid) -> bytes:
    """A ``.geo`` script: sized points, transfinite 2-node lines, one physical curve per edge."""
    out = [f"// {comment(grid)}\n", "// Point(k) = cadedge vertex k; Physical Curve k = cadedge edge k\n"]
    out += [f"Point({v.id}) = {{{x!r}, {y!r}, {z!r}, {_size(v.spacing)!r}}};\n"
            for v in grid.vertices for x, y, z in [np.reshape(v.point, 3).astype(float).tolist()]]
    next_point = max((v.id for v in grid.vertices), default=0) + 1
    next_line = 1
    for e in grid.edges:
        if e.degenerate:
            continue
        pts = np.reshape(np.asarray(e.points, dtype=float), (-1, 3))
        seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        sizes = np.minimum(seg[:-1], seg[1:])
        tags = list(range(next_point, next_point + len(pts) - 2))
        next_point += len(tags)
        out += [f"Point({t}) = {{{x!r}, {y!r}, {z!r}, {s!r}}};\n"
                for t, (x, y, z), s in zip(tags, pts[1:-1].tolist(), sizes.tolist())]
        chain = [int(e.vertices[0]), *tags, int(e.vertices[1])]
        lines = list(range(next_line, next_line + len(chain) - 1))
        next_line += len(lines)
        out += [f"Line({t}) = {{{a}, {b}}};\n" for t, a, b in zip(lines, chain[:-1], chain[1:])]
        first, last = lines[0], lines[-1]
        out.append(f"Transfinite Curve{{{first}:{last}}} = 2;\n")
        out.append(f'Physical Curve("edge {e.id}", {e.id}) = {{{first}:{last}}};\n')
    return "".join(out).encode("ascii")
