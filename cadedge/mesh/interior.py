"""Inside the gmsh job: interiors of faces of varying curvature sized as ``k**-1/2``.

Flat triangles of size ``h`` on a surface of curvature ``k`` lose about ``C (h k)**2`` of their area, so a
face's deficit is ``integral C (h k)**2 dA / A`` for about ``integral h**-2 dA`` triangles. The fewest
triangles for a given deficit (Lagrange: ``h**-3 ~ lambda h k**2``) have ``h ~ k**-1/2``, not the
``k**-1`` of curvature sizing (gmsh's ``Mesh.MeshSizeFromCurvature``), which spends its triangles where
the face is most curved. Here a face's size is ``clip(alpha / sqrt(k), MeshSizeMin, MeshSizeMax)`` with
``alpha`` set (:func:`matched_scale`) so that it predicts the deficit curvature sizing at the face's
``N`` (triangles per ``2 pi``, the per-face knob the fidelity loop scales) is designed for; unbounded,
``alpha = 2 pi / (N sqrt(k_mean))`` and it takes ``mean(k)**2 / mean(k**2)`` of curvature sizing's
interior triangles (0.88 on periodic_u_cst's B-spline faces).

Faces of constant largest curvature (cylinders, spheres, tori) gain nothing and keep gmsh's own curvature
sizes. The others (cones, B-spline, revolved, extruded, offset surfaces) have their largest principal
curvature sampled by gmsh on a grid of their parameters; gmsh's size callback returns
``min(lc, size)``, ``lc`` being the graded boundary field gmsh computed and ``size`` the inverse-distance
mean of the :data:`NEAREST` nearest samples' sizes (the nearest sample's alone left steps in the sizes:
a revolved spline face at ALD 1e-2 came out at 37.5 degrees, 39.7 interpolated). gmsh takes the
minimum of its curvature size, background field and entity size, hands it to the callback as ``lc``,
uses what the callback returns and clamps it to ``[MeshSizeMin, MeshSizeMax]``
(``BGM_MeshSize`` in gmsh's ``BackgroundMeshTools.cpp``); so a sampled face is meshed with gmsh's own
curvature sizes off. The nearest samples are found by a scan in C (:func:`cadedge.kernels.idw_size`; a
face has at most :data:`SAMPLES` squared): scipy's ``cKDTree`` took 43 us per one-point query, 10 to 15 s
of the M6 screw's meshing at ALD 1e-3, when the callback cost about 4 calls and 30 us of CPU per
triangle (periodic_u_cst's two B-spline faces with gmsh alone: 0.99 s of meshing for 15 036 triangles,
against 0.58 s with gmsh's curvature sizes for 15 778). The samples cover the surface's whole parameter rectangle,
trimmed away or not: on a heavily trimmed face ``alpha`` comes from the whole surface's curvature, and
the measure-and-remesh loop of :mod:`cadedge.mesh.fidelity` corrects its scale (gmsh's per-point inside
test cost 0.2 s a face).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..kernels import idw_size

#: Surface types (OCCT names) whose largest principal curvature is the same everywhere: sized by gmsh.
CONSTANT_CURVATURE = frozenset({"Plane", "Cylinder", "Sphere", "Torus"})
#: Samples per parametric direction of a face's curvature.
SAMPLES = 24
#: Samples whose sizes are interpolated at a point (inverse-distance weights).
NEAREST = 4
#: A face whose sampled curvature spans more than this factor between its 2nd and 98th percentiles keeps
#: gmsh's curvature sizes: its curvature has sharp ridges or spikes where the ``(h k)**2`` model fails.
#: twisted_blade's lofted faces (114-292x) came out at 1.5e-2 against the target 1e-2 (gmsh's sizes:
#: 0.002), their thin edges meshed coarser; revolved_spline's face (54x) takes half the triangles at 1e-3,
#: periodic_u_cst's (4x) 8% fewer.
SPREAD = 64.0
#: Bisection steps (on log alpha) of :func:`matched_scale`.
STEPS = 60


def predicted(sizes: np.ndarray, k: np.ndarray, da: np.ndarray) -> float:
    """``sum (h k)**2 dA``: the deficit of sizes ``h`` on samples of curvature ``k`` and area ``dA``, up to
    the surface type's constant."""
    return float(np.sum((sizes * k) ** 2 * da))


def matched_scale(k: np.ndarray, da: np.ndarray, per_circle: float, lo: float, hi: float) -> float:
    """``alpha`` such that sizes ``clip(alpha / sqrt(k), lo, hi)`` predict the deficit curvature sizing
    ``2 pi / (per_circle k)`` is designed for, ``(2 pi / per_circle)**2`` of the area (what the surface
    type's ``per_circle`` aims at, and what the fidelity loop scales).

    Without the clips ``alpha = 2 pi / (per_circle sqrt(k_mean))``, ``k_mean`` the area-weighted mean
    curvature. With them it is the optimum under the bounds (Lagrange with box constraints): what a
    flatter part capped at ``hi`` leaves of the deficit goes to coarser triangles where the face is
    curved. Matched instead to the deficit curvature sizing predicts within the same bounds (which ``hi``
    had left under its design), the sizes were finer: lofted_spline at 1e-3 took 6 632 triangles against
    6 124."""
    goal = (2.0 * np.pi / per_circle) ** 2 * float(np.sum(da))
    with np.errstate(divide="ignore"):
        root = 1.0 / np.sqrt(k)
    a, b = np.log(lo * np.sqrt(k[k > 0].min())), np.log(hi * np.sqrt(k.max()))  # every size at lo, at hi
    if predicted(np.clip(np.exp(b) * root, lo, hi), k, da) <= goal:
        return float(np.exp(b))  # even every size at hi is within the deficit
    for _ in range(STEPS):
        mid = 0.5 * (a + b)
        if predicted(np.clip(np.exp(mid) * root, lo, hi), k, da) > goal:
            b = mid
        else:
            a = mid
    return float(np.exp(a))


@dataclass
class _Face:
    points: np.ndarray  # the sample points (m, 3), C-contiguous
    k: np.ndarray  # largest principal curvature at each sample
    da: np.ndarray  # area element at each sample
    sizes: np.ndarray | None = None  # size at each sample; None: not sized here (gmsh's own sizes)


class InteriorSizes:
    """The ``k**-1/2`` sizes of the sampled faces, and the smallest size of some faces
    (:func:`size_floors`); callable as gmsh's size callback."""

    def __init__(self) -> None:
        self.faces: dict[int, _Face] = {}
        self.floors: dict[int, float] = {}
        self.per_circle: dict[int, float] = {}  # what :func:`use_per_circle` last set each surface to
        self.caps: dict[int, float] = {}  # the budget's count per 2 pi of surfaces sized by gmsh (:meth:`cap`)
        self.samples: dict[int, tuple[np.ndarray, np.ndarray] | None] = {}  # :meth:`curvatures`
        self.target: float | None = None  # the job's surface target (|area deficit| per face), if any

    def sample(self, surface: int) -> bool:
        """Sample gmsh surface ``surface``'s curvature; False (left to gmsh) if it is flat or cannot be
        sampled."""
        samples = surface_samples(surface)
        if samples is None:
            return False
        x, k, da = samples
        good = np.isfinite(k) & np.isfinite(da) & np.all(np.isfinite(x), axis=1)
        if good.sum() < NEAREST or not np.sum(da[good] * k[good]) > 0:
            return False
        if ridged(k[good]):
            return False
        self.faces[surface] = _Face(np.ascontiguousarray(x[good]), k[good], da[good])
        return True

    def set(self, surface: int, per_circle: float) -> bool:
        """Size ``surface`` here at ``per_circle`` (0: not at all) within gmsh's ``Mesh.MeshSizeMin`` and
        ``Mesh.MeshSizeMax`` as set now; False if it was not sampled."""
        face = self.faces.get(surface)
        if face is None:
            return False
        face.sizes = root_sizes(face.k, face.da, per_circle) if per_circle > 0 else None
        return True

    def held(self, surface: int) -> bool:
        """Whether gmsh's curvature sizes on ``surface`` are held to its triangle budget (:meth:`cap`, as
        :func:`use_per_circle` set them); never on a sampled face."""
        return surface not in self.faces and self.per_circle.get(surface, 0.0) >= self.cap(surface)

    def cap(self, surface: int) -> float:
        """The most triangles per ``2 pi`` gmsh's curvature sizes are given on ``surface``: the largest count
        whose sizes put about :data:`~cadedge.mesh.budget.MAX_FACE_TRIANGLES` on it
        (:func:`~cadedge.mesh.budget.budget_per_circle` on its :func:`face_curvatures`, within
        :meth:`bounds`); infinite when no count does or it cannot be evaluated. Found once a surface."""
        from .budget import budget_per_circle

        if surface not in self.caps:
            found = self.curvatures(surface)
            self.caps[surface] = np.inf if found is None else budget_per_circle(*found, *self.bounds(surface))
        return self.caps[surface]

    def curvature_triangles(self, surface: int, per_circle: float) -> float:
        """About how many triangles gmsh's curvature sizes at ``per_circle`` put on ``surface``, the rest of
        the size field aside (:func:`~cadedge.mesh.budget.curvature_triangles` on its
        :func:`face_curvatures`, within :meth:`bounds`); infinite when it cannot be evaluated."""
        from .budget import curvature_triangles

        found = self.curvatures(surface)
        return np.inf if found is None else curvature_triangles(*found, per_circle, *self.bounds(surface))

    def curvatures(self, surface: int) -> tuple[np.ndarray, np.ndarray] | None:
        """:func:`face_curvatures` of ``surface``, sampled once."""
        if surface not in self.samples:
            self.samples[surface] = face_curvatures(surface)
        return self.samples[surface]

    def bounds(self, surface: int) -> tuple[float, float]:
        """The smallest and largest size gmsh gives ``surface``: its size floor or ``Mesh.MeshSizeMin``,
        and ``Mesh.MeshSizeMax`` (infinite when unset), as set now."""
        import gmsh

        hi = gmsh.option.getNumber("Mesh.MeshSizeMax")
        return (max(gmsh.option.getNumber("Mesh.MeshSizeMin"), self.floors.get(surface, 0.0)),
                hi if 0 < hi < 1e22 else np.inf)

    def __call__(self, dim: int, tag: int, x: float, y: float, z: float, lc: float) -> float:
        if dim != 2:
            return lc
        face = self.faces.get(tag)
        if face is not None and face.sizes is not None:
            lc = min(lc, idw_size(face.points, face.sizes, x, y, z, NEAREST))
        return max(lc, self.floors.get(tag, 0.0))


def root_sizes(k: np.ndarray, da: np.ndarray, per_circle: float) -> np.ndarray:
    """Sizes ``clip(alpha / sqrt(k), lo, hi)`` of samples of curvature ``k`` and area element ``da`` at
    ``per_circle`` (:func:`matched_scale`), within gmsh's ``Mesh.MeshSizeMin`` and ``Mesh.MeshSizeMax`` as
    set now (unset, the largest is curvature sizing's at the flattest sample)."""
    import gmsh

    lo = max(gmsh.option.getNumber("Mesh.MeshSizeMin"), 1e-12)
    hi = gmsh.option.getNumber("Mesh.MeshSizeMax")
    hi = max(hi if 0 < hi < 1e22 else 2.0 * np.pi / (per_circle * k[k > 0].min()), lo)
    alpha = matched_scale(k, da, per_circle, lo, hi)
    with np.errstate(divide="ignore"):
        return np.clip(alpha / np.sqrt(k), lo, hi)


#: The sizes of the job running in this process (one gmsh model at a time).
SIZES = InteriorSizes()


def size_floors(surfaces: dict[int, float], min_size: float) -> dict[int, float]:
    """The smallest size of the gmsh surfaces of ``surfaces`` (surface -> area) whose curvature has sharp
    ridges (it spans more than :data:`SPREAD` between its 2nd and 98th percentiles on a grid of the
    surface's parameters), where sizes at ``min_size`` would fill the face with more than
    :data:`~cadedge.mesh.budget.MAX_FACE_TRIANGLES` triangles: the size that fills it with about that
    many. gmsh's curvature sizes follow a ridge down to ``min_size``, a share of the finest edge spacing;
    on a blade with a sharp trailing edge (a radius of 0.007 mm along a 390 mm2 face, 0.006 mm sizes)
    gmsh ran out of time on the face with every strategy."""
    from .budget import filling_size

    floors = {}
    for s, area in surfaces.items():
        floor = float(filling_size(area))
        if floor <= min_size:
            continue
        samples = surface_samples(s)
        k = samples[1][np.isfinite(samples[1])] if samples is not None else np.zeros(0)
        if len(k) >= NEAREST and ridged(k):
            floors[s] = floor
    return floors


def ridged(k: np.ndarray) -> bool:
    """Whether curvature samples ``k`` (finite) have a sharp ridge: they span more than :data:`SPREAD`
    between their 2nd and 98th percentiles."""
    low, high = np.percentile(k, [2.0, 98.0])
    return bool(high > SPREAD * low)


def surface_samples(surface: int, n: int = SAMPLES) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Points (m, 3), largest |principal curvature| (m,) and area element (m,) of gmsh surface ``surface``
    on an ``n`` x ``n`` grid of its parameters (cell centres), as gmsh gives them (not filtered); None if
    gmsh cannot evaluate it."""
    import gmsh

    try:
        lo, hi = (np.asarray(b, dtype=float) for b in gmsh.model.getParametrizationBounds(2, surface))
        t = (np.arange(n) + 0.5) / n
        u, v = np.meshgrid(lo[0] + (hi[0] - lo[0]) * t, lo[1] + (hi[1] - lo[1]) * t)
        uv = np.column_stack([u.ravel(), v.ravel()]).ravel().tolist()
        x = np.asarray(gmsh.model.getValue(2, surface, uv), dtype=float).reshape(-1, 3)
        kmax, kmin, _, _ = gmsh.model.getPrincipalCurvatures(surface, uv)
        d = np.asarray(gmsh.model.getDerivative(2, surface, uv), dtype=float).reshape(-1, 6)
    except Exception:  # gmsh's bare Exception: a surface it cannot evaluate
        return None
    k = np.maximum(np.abs(np.asarray(kmax, dtype=float)), np.abs(np.asarray(kmin, dtype=float)))
    da = np.linalg.norm(np.cross(d[:, :3], d[:, 3:]), axis=1)
    if len(k) != len(x) or len(da) != len(x):
        return None
    return x, k, da


def face_curvatures(surface: int) -> tuple[np.ndarray, np.ndarray] | None:
    """Gmsh surface ``surface``'s largest principal curvature on a :data:`SAMPLES` square grid of its
    parameters, and the area each sample stands for: the area elements scaled to sum to the face's area
    (a trimmed face taken as curved like the rest of its surface). None when gmsh cannot evaluate it."""
    import gmsh

    samples = surface_samples(surface)
    if samples is None:
        return None
    _, k, da = samples
    good = np.isfinite(k) & np.isfinite(da)
    try:
        area = float(gmsh.model.occ.getMass(2, surface))
    except Exception:  # gmsh's bare Exception: a surface it cannot evaluate
        return None
    if not good.any() or not area > 0 or not np.sum(da[good]) > 0:
        return None
    return k[good], da[good] * (area / np.sum(da[good]))


def install(surfaces: list[int], floors: dict[int, float] | None = None,
            target: float | None = None) -> list[int]:
    """Sample ``surfaces`` (gmsh tags of curved faces whose curvature varies), keep the smallest sizes
    ``floors`` (surface -> size) and the job's surface ``target``, and make :data:`SIZES` gmsh's size
    callback if either of the first two is needed; returns the surfaces sampled."""
    import gmsh

    SIZES.faces.clear()
    SIZES.per_circle.clear()
    SIZES.caps.clear()
    SIZES.samples.clear()
    SIZES.floors = dict(floors or {})
    SIZES.target = target
    done = [s for s in surfaces if SIZES.sample(s)]
    if done or SIZES.floors:
        gmsh.model.mesh.setSizeCallback(SIZES)
    return done


def use_per_circle(surface: int, per_circle: float, *, uniform: bool = False) -> None:
    """Size gmsh surface ``surface`` at ``per_circle`` triangles per ``2 pi``: by :data:`SIZES` where it was
    sampled (gmsh's curvature sizes off), else by gmsh's ``Mesh.MeshSizeFromCurvature``. ``uniform``
    (the one-size strategy, which reads the gmsh option and keeps to the face's triangle budget, see
    :func:`~cadedge.mesh.generate.uniform_curvature_size`) always takes the latter. Otherwise gmsh's
    curvature sizes are given no more than the face's triangle budget allows (:meth:`InteriorSizes.cap`):
    a fillet of 0.2 mm along a 500 mm edge at 1e-3 took 736 000 triangles at its surface type's count, and
    meshing it again (coarser, or by another algorithm) ran past the 60 s of an attempt.

    A face held at a size floor keeps what gmsh's Frontal-Delaunay makes of it
    (``Mesh.AlgorithmSwitchOnFailure`` off there): across a ridge much sharper than its triangles some
    triangles always turn against the surface's normal, which gmsh takes for a failure, and its fallback
    (MeshAdapt, then every boundary curve split, again and again) never finished: the thin elliptic tube of
    the tests (semi-axes 10 and 0.05) and the propeller's blades hung in every strategy. Kept, the tube
    meshes in 4 s within the target; what such triangles cost a face is measured and reported like any
    deficit."""
    import gmsh

    gmsh.option.setNumber("Mesh.AlgorithmSwitchOnFailure", 0 if surface in SIZES.floors else 1)
    if not uniform and SIZES.set(surface, per_circle):
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    else:
        SIZES.set(surface, 0.0)
        if not uniform:  # the one-size strategy holds its size to the budget itself
            per_circle = sized_per_circle(surface, per_circle)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", per_circle)
    SIZES.per_circle[surface] = per_circle


def sized_per_circle(surface: int, per_circle: float) -> float:
    """The count per ``2 pi`` :func:`use_per_circle` sizes ``surface`` at when asked for ``per_circle``:
    itself on a sampled face, else no more than the face's triangle budget allows."""
    return per_circle if surface in SIZES.faces else min(per_circle, SIZES.cap(surface))
