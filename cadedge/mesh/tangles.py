"""A face's boundary segments that cross where it is laid out flat, and the layout moved so that none do.

A face whose edges cross each other within their tolerance has a boundary that crosses itself wherever its
grids are laid out: the Fusion tyre's face 31, a plane lens 0.01 mm wide between a line and a B-spline that
passes up to 0.003 mm to the other side of the line near both ends (tolerance 0.0018 mm). gmsh, meshing in the
face's parameters, hung on it in every strategy (60 s, then 15 s each, and the face was left failed):
splitting the crossing segments, as it does for the chords of two nearby curves, never ends when the curves
themselves cross. :func:`crossings` finds the segments that cross (a sweep along the axis where fewer
overlap), :func:`untangle` moves nodes in the layout only, each across the segment it crosses, until none
cross. The plane region is then meshed and the nodes keep their places on the surface, so the few triangles
at a crossing fold there, as the B-rep's own boundary does.
"""

from __future__ import annotations

import numpy as np

from .flat import loop_areas, loops

#: Pairs of segments whose boxes overlap along the sweep's axis past which :func:`crossings` gives up (a
#: few hundred milliseconds of tests).
MAX_PAIRS = 2_000_000
#: Rounds of moves :func:`untangle` makes: a round moves one node per crossing, and the nodes beyond a
#: crossing go back one a round.
ROUNDS = 400
#: Two crossing segments at most this many segments apart along their loop close a small loop that
#: :func:`untangle` cuts off first (:func:`_cut_loops`).
SHORT_LOOP = 16
#: ... where they cross at this many degrees or more: across a segment nearly parallel to its own side (a lens's
#: sides, a B-spline dipping across a line) a node keeps its order along that side when it moves; across
#: one at a corner it goes back past its neighbours.
CUT_ANGLE = 45.0


def cross_properly(p: np.ndarray, q: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Whether segments ``p``-``q`` properly cross segments ``a``-``b`` (points (..., 2), broadcast): each
    has the other's ends strictly on both sides."""
    def side(o, d, r):
        return np.sign(d[..., 0] * (r[..., 1] - o[..., 1]) - d[..., 1] * (r[..., 0] - o[..., 0]))

    return ((side(p, q - p, a) * side(p, q - p, b) < 0)
            & (side(a, b - a, p) * side(a, b - a, q) < 0))


def crossings(plane: np.ndarray, segments: list[tuple[int, int]] | np.ndarray, *,
              limit: int = MAX_PAIRS) -> np.ndarray | None:
    """The pairs of ``segments`` (rows of ``plane`` (n, 2)) that properly cross, as (k, 2) segment indices;
    segments sharing a point are not tested. None when more than ``limit`` pairs would need testing."""
    seg = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    a, b = plane[seg[:, 0]], plane[seg[:, 1]]
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    best: tuple[np.ndarray, np.ndarray] | None = None
    for axis in (0, 1):  # segments sorted by their start along the axis; each against those starting in it
        order = np.argsort(lo[:, axis], kind="stable")
        reach = np.searchsorted(lo[order, axis], hi[order, axis], side="right")
        count = np.maximum(reach - np.arange(1, len(order) + 1), 0)
        if best is None or count.sum() < best[1].sum():
            best = (order, count)
    order, count = best
    total = int(count.sum())
    if total > limit:
        return None
    first = np.repeat(np.arange(len(order)), count)
    i = order[first]
    j = order[first + 1 + np.arange(total) - np.repeat(np.cumsum(count) - count, count)]
    keep = np.all((lo[i] <= hi[j]) & (lo[j] <= hi[i]), axis=1)
    keep &= ~(seg[i][:, :, None] == seg[j][:, None, :]).any(axis=(1, 2))
    i, j = i[keep], j[keep]
    hit = cross_properly(a[i], b[i], a[j], b[j])
    return np.column_stack([i[hit], j[hit]])


def inward(plane: np.ndarray, segments: list[tuple[int, int]]) -> np.ndarray | None:
    """+1 where the region bounded by ``segments`` is left of a segment (run from its first row to its
    second), -1 where it is right; None if they do not close into loops. The largest loop is the outer
    one, the others holes."""
    chains = loops(segments)
    if not chains:
        return None
    areas = loop_areas(plane, segments, chains)
    outer = int(np.argmax(np.abs(areas)))
    side = np.zeros(len(segments))
    for k, chain in enumerate(chains):
        left = areas[k] > 0 if k == outer else areas[k] < 0
        for s in chain:
            side[s if s >= 0 else -s - 1] = 1.0 if left == (s >= 0) else -1.0
    return side


def _across(points: np.ndarray, origin: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Signed distances of ``points`` (k, 2) from the line through ``origin`` along ``direction``."""
    d = direction / max(float(np.hypot(*direction)), 1e-300)
    return (points[:, 0] - origin[0]) * d[1] - (points[:, 1] - origin[1]) * d[0]


def _cut_loops(x: np.ndarray, seg: np.ndarray, pairs: np.ndarray, reach: float) -> list[np.ndarray]:
    """Undo, in place, each crossing of two segments at most :data:`SHORT_LOOP` apart along their boundary
    loop, at :data:`CUT_ANGLE` or more: the nodes between them (a small loop turned inside out, the other
    way round from the face) go onto the two segments' own lines through their crossing point, in order,
    from halfway along one to halfway along the other, each side's nodes on its own line (the split
    where the fewest lie nearer the other line). A vertex off both its edges' curves beyond where they
    cross makes one (a TraceParts USB socket's plane face 787: its corner 0.0014 off one line, 0.0004 off
    the other, both edges' grids fine there); moving a node at a time across the other segment's line
    only turned it back on itself, and gmsh made no triangles of it. Returns the nodes moved, one array
    per loop; none goes further than ``reach``."""
    chains = loops([tuple(r) for r in seg.tolist()])
    if not chains or not len(pairs):
        return []
    where: dict[int, tuple[int, int]] = {}  # segment -> (its loop, its place along it)
    for k, chain in enumerate(chains):
        for i, signed in enumerate(chain):
            where[signed if signed >= 0 else -signed - 1] = (k, i)
    def ends(signed: int) -> tuple[int, int]:
        """A segment's rows in the order its loop runs it (``signed`` as :func:`loops` gives it)."""
        a, b = seg[signed if signed >= 0 else -signed - 1]
        return (int(a), int(b)) if signed >= 0 else (int(b), int(a))

    moved = np.zeros(len(x), dtype=bool)
    out = []
    for s, t in pairs.tolist():
        (ks, i), (kt, j) = where[s], where[t]
        chain = chains[ks]
        if ks != kt:
            continue
        if (j - i) % len(chain) > (i - j) % len(chain):
            i, j = j, i
        if not 1 <= (j - i) % len(chain) <= SHORT_LOOP:
            continue
        first, last = ends(chain[i]), ends(chain[j])
        inner = [ends(chain[(i + m) % len(chain)])[0] for m in range(1, (j - i) % len(chain) + 1)]
        if moved[inner].any() or moved[[first[0], last[1]]].any():
            continue
        p, q = x[first[0]], x[last[1]]
        d1, d2 = x[first[1]] - p, x[last[1]] - x[last[0]]
        det = d1[0] * -d2[1] + d2[0] * d1[1]
        if abs(det) <= np.sin(np.radians(CUT_ANGLE)) * np.linalg.norm(d1) * np.linalg.norm(d2):
            continue  # nearly parallel: moving a node across keeps the order along its side
        rhs = x[last[0]] - p
        u = (rhs[0] * -d2[1] + d2[0] * rhs[1]) / det
        cross_at = p + u * d1
        start, end = cross_at + 0.5 * (p - cross_at), cross_at + 0.5 * (q - cross_at)
        # each side's nodes stay on their own side's line: a node of one edge put on the other's line
        # makes a triangle of three nodes of one straight edge, flat where they lie (the socket at 1e-3)
        off_first = np.abs(_across(x[inner], p, d1))
        off_last = np.abs(_across(x[inner], x[last[0]], d2))
        wrong = [np.count_nonzero(off_first[:n] > off_last[:n]) + np.count_nonzero(off_last[n:] > off_first[n:])
                 for n in range(len(inner) + 1)]
        split = int(np.argmin(wrong))
        rest = len(inner) - split
        new = np.vstack([start + (np.arange(1, split + 1) / (split + 1))[:, None] * (cross_at - start),
                         cross_at + (np.arange(1, rest + 1) / (rest + 1))[:, None] * (end - cross_at)])
        if np.linalg.norm(new - x[inner], axis=1).max() > reach:
            continue
        x[inner] = new
        moved[inner] = True
        out.append(np.unique(np.concatenate([first, last, inner])))
    return out


def untangle(plane: np.ndarray, segments: list[tuple[int, int]], reach: float) -> tuple[
        np.ndarray, list[np.ndarray]] | str:
    """``plane`` (n, 2) with nodes moved so that no two ``segments`` cross, and the places where they
    crossed: the rows of the segments that crossed, one array per place (segments crossing in turn as the
    nodes went across, at one place); or why not. At each crossing, of the four ends the one beyond the
    other segment by the least goes across that segment's line, as far inside as it was out; a round
    moves each node once at most. No node goes further than ``reach`` from where it was. A boundary with
    too many segments to look at (:data:`MAX_PAIRS`) is returned as it is."""
    seg = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    side = inward(plane, segments)
    if side is None:
        return "its boundary does not close"
    x = np.array(plane, dtype=float)
    extent = float(np.ptp(x, axis=0).max()) if len(x) else 0.0
    owner = np.arange(len(x))  # union-find over the rows of segments that crossed
    took_part = np.zeros(len(x), dtype=bool)

    def root(i: int) -> int:
        while owner[i] != i:
            owner[i] = owner[owner[i]]
            i = int(owner[i])
        return i

    first = crossings(x, seg)
    for cut in _cut_loops(x, seg, first if first is not None else np.zeros((0, 2), dtype=np.int64), reach):
        took_part[cut] = True
        for i in cut[1:]:
            owner[root(int(i))] = root(int(cut[0]))
    for round_ in range(ROUNDS):
        pairs = crossings(x, seg)
        if pairs is None and not round_:
            return x, []  # too many to look at: gmsh's mesher will tell
        if pairs is None:
            return "too many boundary segments to look for crossings"
        if not len(pairs):
            involved = np.flatnonzero(took_part)
            roots = np.array([root(int(i)) for i in involved], dtype=np.int64)
            return x, [involved[roots == r] for r in np.unique(roots)]
        moved: set[int] = set()
        for s, t in pairs.tolist():
            ends = seg[[s, t]].ravel().tolist()
            took_part[ends] = True
            for i in ends[1:]:
                owner[root(i)] = root(ends[0])
            best = None
            for mine, other in ((s, t), (t, s)):
                a, b = x[seg[other, 0]], x[seg[other, 1]]
                d = b - a
                n = side[other] * np.array([-d[1], d[0]]) / max(float(np.hypot(*d)), 1e-300)
                for node in seg[mine].tolist():
                    out = -float((x[node] - a) @ n)  # how far beyond the other segment's line
                    if out > 0 and node not in moved and (best is None or out < best[0]):
                        best = (out, node, n)
            if best is not None:
                out, node, n = best
                x[node] += (2.0 * out + 1e-9 * extent) * n
                moved.add(node)
        far = float(np.linalg.norm(x - plane, axis=1).max())
        if far > reach:
            return f"its boundary crosses itself too deep to untangle ({far:.2g} across, more than {reach:.2g})"
    return f"its boundary still crosses itself after {ROUNDS} rounds of moves"
