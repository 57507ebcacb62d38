"""cadedge: edge grids for CAD curves by arc-length-deficit optimisation.

Public API (reference: docs/api.md): :func:`refine_curve`, :func:`refine_shape`, :class:`EdgeGrid`,
:class:`ShapeGrid`, the curve adapters and the error hierarchy. OpenCASCADE is imported only when a
shape is refined, so curve refinement works without it. The public names are imported on first use
(PEP 562), so ``import cadedge`` (and the CLI's start-up) costs only what a command uses.
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Callable

from .errors import (CadedgeError, CadedgeWarning, CurveEvaluationError, GeometryError, InputError,
                     MeshError)

if TYPE_CHECKING:
    from .curves import Curve, Evaluator, FunctionCurve, SampledCurve
    from .grid import EdgeGrid
    from .refine import refine_curve
    from .shapegrid import ShapeEdgeGrid, ShapeGrid, VertexGrid

__version__ = "0.1.0"

#: Public name -> the module that defines it, imported when the name is first used.
_LAZY = {"Curve": "curves", "Evaluator": "curves", "FunctionCurve": "curves", "SampledCurve": "curves",
         "EdgeGrid": "grid", "refine_curve": "refine", "ShapeEdgeGrid": "shapegrid", "ShapeGrid": "shapegrid",
         "VertexGrid": "shapegrid"}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


def refine_shape(source: Any, *, ald: float = 1e-3, min_length: float | None = None,
                 max_length: float | None = None, max_growth: float | None = None,
                 ald_for: Mapping[Any, float] | None = None,
                 progress: Callable[[int, int], None] | None = None, allow_partial: bool = False) -> ShapeGrid:
    """Refine every edge of a STEP file, cadquery/build123d shape or ``TopoDS_Shape`` (see the contract).

    ``ald_for`` gives edges or faces their own target: keys are build123d/cadquery edges or faces,
    ``TopoDS`` shapes, or ids ``("edge", n)``/``("face", n)``; a face means its edges; the finest
    target reaching an edge wins. ``progress(done, total)``, if given, is called after each edge (the
    CLI's progress bar). ``source`` may also be an IGES (.igs/.iges) or OCCT BREP (.brep) path. A file
    that OCCT transfers only in part raises :class:`InputError` unless ``allow_partial``, which refines
    what did transfer and says what was lost in ``ShapeGrid.warnings``.
    """
    from .occt.shape import refine_shape as _refine_shape
    return _refine_shape(source, ald=ald, min_length=min_length, max_length=max_length, max_growth=max_growth,
                         ald_for=ald_for, progress=progress, allow_partial=allow_partial)


__all__ = ["refine_curve", "refine_shape", "EdgeGrid", "ShapeGrid", "ShapeEdgeGrid", "VertexGrid", "Curve",
           "FunctionCurve", "SampledCurve", "Evaluator", "CadedgeError", "InputError", "CurveEvaluationError",
           "GeometryError", "MeshError", "CadedgeWarning", "__version__"]
