"""Target mode: a guaranteed arc-length deficit with close to the fewest segments.

1. :func:`cadedge.explore.explore` samples the curve densely enough that its Richardson length
   estimate is good to a small share of the target (``EXPLORE_SHARE``), catching features that
   chords miss, and finds the kinks a node must sit on.
2. Two placements compete for the fewest segments within the rest of the budget:
   continuous equidistribution of the deficit measure (:func:`cadedge.placement.equidistribute`,
   its count predicted by the cube law and corrected by measuring), and a choice among the dense
   samples (:func:`cadedge.placement.fewest_nodes`, no further evaluations). This is the paper's
   future-work global optimisation with a fixed point count, solved by equidistribution.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import InputError
from .explore import explore
from .grid import polyline_length, row_norms
from .placement import chord_length, deficit_measure, equidistribute, fewest_nodes
from .splitting import evaluate_new, regrade, worst_growth

#: Share of the target deficit that the dense exploration may leave unresolved.
EXPLORE_SHARE = 1.0 / 16.0
#: Share of the target kept in reserve against error in the length estimate itself.
MARGIN = 0.03
#: Share of the target kept in reserve when the curve knows its length (``exact_length(a, b)``, to about
#: 1e-9): only against that error, rounding and the snapping of the ends to B-rep vertices.
EXACT_MARGIN = 1e-3
#: How far (as a share of the target) the exploration's estimate may differ from a curve's own length
#: for that length to be used; past that the estimate and its margins are kept.
AGREEMENT = 0.25
#: Most placements measured while searching for the fewest equidistributed segments.
MAX_TRIALS = 10
#: Fewest segments on a closed curve: one has no length and two retrace each other, neither bounds a face.
MIN_CLOSED_SEGMENTS = 3
#: Ends closer than this share of the length make a curve closed.
CLOSED = 1e-9
#: Samples per max_length that a max_length placement can choose among.
MAX_LENGTH_SAMPLES = 8
#: Most segments ``max_length`` may force on one curve (each takes ``MAX_LENGTH_SAMPLES`` samples): past
#: that the option is refused up front instead of filling memory (1e-7 on a 100 mm edge asked for 8e9).
MAX_LENGTH_SEGMENTS = 200_000
def _equidistributed(ev, ex, corner_idx: np.ndarray, total: float, limit: float, budget: float,
                     min_segments: int) -> tuple[np.ndarray, np.ndarray] | None:
    """Fewest equidistributed segments whose deficit against ``total`` stays within ``limit``."""
    u, p, cum = ex.params, ex.points, ex.cumulative
    measure = deficit_measure(p, cum, corner_idx)
    m_tot = measure[-1]
    n = max(min_segments, math.ceil(math.sqrt(m_tot ** 3 / budget)) if budget > 0 and m_tot > 0 else min_segments)
    fixed = limit - budget  # the deficit no placement can remove (what the samples do not show)
    lo, hi = min_segments - 1, None  # lo: largest count known too few; hi: smallest known enough
    best = None
    for _ in range(MAX_TRIALS):
        params = equidistribute(u, cum, measure, n, corner_idx)
        pts = evaluate_new(ev, u, params, p)
        miss = total - polyline_length(pts)
        # the cube law: the removable deficit falls with the square of the count
        predicted = math.ceil(n * math.sqrt(max(miss - fixed, 0.0) / budget)) if budget > 0 else n + 1
        if miss <= limit:
            hi, best = n, (params, pts)
            n = max(lo + 1, min(predicted, n - 1))
        else:
            lo = n
            n = max(n + 1, min(predicted, 2 * n))
            if hi is not None:
                n = min(n, hi - 1)
        if hi is not None and hi - lo <= 1:
            break
    return best


def _densify(ev, ex, spacing: float):
    """The exploration with extra samples wherever two neighbours are more than ``spacing`` apart.

    A straight run is explored with its two ends only; a ``max_length`` placement needs samples
    along it to put nodes on.
    """
    gap = row_norms(np.diff(ex.points, axis=0))
    pieces = np.ceil(gap / spacing).astype(int)
    long_ = np.flatnonzero(pieces > 1)
    if not len(long_):
        return ex
    new = np.concatenate([np.linspace(ex.params[i], ex.params[i + 1], pieces[i] + 1)[1:-1] for i in long_])
    return ex.with_samples(new, ev(new))


def refine_target(ev, a: float, b: float, *, ald: float, min_length: float | None = None,
                  max_length: float | None = None, max_growth: float | None = None,
                  search_tol: float | None = None) -> tuple[np.ndarray, np.ndarray, float, list[str]]:
    """Refine to ``ald``; returns (params, points, ald_estimate, notes).

    With ``max_growth`` the nodes are re-placed along a graded size field
    (:func:`cadedge.splitting.regrade`), never
    coarser than the grid it grades, so the target still holds; a note says if a ratio is left over.
    ``search_tol`` belongs to paper mode's golden-section search and does not apply here.
    """
    ex = explore(ev, a, b, ald * EXPLORE_SHARE)
    notes = list(ex.notes)
    total = ex.length_estimate
    u, p = ex.params, ex.points
    if not total > 0.0:
        notes.append(f"curve has zero length on [{a!r}, {b!r}] (all {len(u)} samples are one point); "
                     "returning its two ends")
        return np.array([a, b]), p[[0, -1]], 0.0, notes
    if max_length is not None:
        if total / max_length > MAX_LENGTH_SEGMENTS:
            raise InputError(f"max_length {max_length:g} would split a curve {total:.6g} long into more than "
                             f"{MAX_LENGTH_SEGMENTS:,} segments, the cap per edge; use a larger max_length")
        ex = _densify(ev, ex, max_length / MAX_LENGTH_SAMPLES)
        u, p = ex.params, ex.points
    known = getattr(ev.curve, "exact_length", None)
    exact = known(a, b) if known is not None else None
    if exact is not None and exact > 0.0 and abs(exact - total) <= AGREEMENT * ald * exact:
        # the curve's own length (closed form or integrated), confirmed by the exploration's estimate
        total = float(exact)
        remainder = max(total - float(ex.cumulative[-1]), 0.0)
        limit = ald * (1.0 - EXACT_MARGIN) * total
    else:
        remainder = ex.remainder
        limit = ald * (1.0 - MARGIN) * total
    budget = max(limit - remainder, 0.0)
    corner_idx = np.searchsorted(u, ex.corners) if len(ex.corners) else np.zeros(0, dtype=int)
    competing = min_length is None and max_length is None  # the equidistributed placement below competes
    nodes = fewest_nodes(p, ex.cumulative, budget, min_length=min_length, max_length=max_length,
                         forced=corner_idx, drop=not competing)
    params, points = u[nodes], p[nodes]
    if competing:
        eq = _equidistributed(ev, ex, corner_idx, total, limit, budget, min_segments=len(corner_idx) + 1)
        if eq is not None and (len(eq[0]) < len(params) or (
                len(eq[0]) == len(params) and polyline_length(eq[1]) > chord_length(p, nodes))):
            params, points = eq
    if len(params) <= MIN_CLOSED_SEGMENTS and row_norms(p[-1:] - p[:1])[0] <= CLOSED * total:
        params = equidistribute(u, ex.cumulative, ex.cumulative, MIN_CLOSED_SEGMENTS, corner_idx)
        points = evaluate_new(ev, u, params, p)
        if min_length is not None:
            notes.append(f"min_length {min_length:g} would leave this closed curve fewer than "
                         f"{MIN_CLOSED_SEGMENTS} segments (no polygon); it has {len(params) - 1}")
    if max_growth is not None and min_length is None and len(params) > 2 and worst_growth(points) > max_growth:
        params, points = regrade(ev, ex, corner_idx, params, points, max_growth, ald, total, limit)
    length = polyline_length(points)
    estimate = max(1.0 - length / total, 0.0)
    if max_growth is not None and worst_growth(points) > max_growth * (1 + 1e-9):
        notes.append(f"max_growth {max_growth:g} not met everywhere: worst ratio of adjacent segments "
                     f"is {worst_growth(points):.3g}")
    if estimate > ald:
        reason = "min_length" if min_length is not None else "the sampling cap"
        notes.append(f"ald target {ald:g} not reached (estimate {estimate:.3g}) because of {reason}")
    return params, points, estimate, notes
