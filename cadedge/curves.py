"""Curves as black boxes u -> point, and the counting evaluator that every refiner goes through.

A cadedge curve is any object with ``evaluate(u) -> points`` (``u`` a 1-D float array, ``points`` of shape
(len(u), 2) or (len(u), 3)) and a ``domain`` attribute (``(a, b)`` or ``None``). Plain Python callables are
wrapped by :class:`FunctionCurve`, which detects whether they are vectorised. No derivatives anywhere.
"""

from __future__ import annotations

from typing import Any, Callable, Protocol, runtime_checkable

import numpy as np

from .errors import CurveEvaluationError, InputError


@runtime_checkable
class Curve(Protocol):
    """What the refiners need of a curve: batched evaluation and (optionally) its own domain."""

    domain: tuple[float, float] | None

    def evaluate(self, u: np.ndarray) -> np.ndarray:
        """Points at parameters ``u`` (1-D), shape (len(u), 2 or 3)."""
        ...


def _is_complex(raw: Any) -> bool:
    if isinstance(raw, (np.ndarray, np.generic)):
        return bool(np.iscomplexobj(raw))
    if isinstance(raw, (list, tuple)):
        return any(_is_complex(x) for x in raw)
    return isinstance(raw, complex)


def _reject_complex(raw: Any, u: np.ndarray) -> None:
    """CurveEvaluationError if a curve answered with complex numbers (their imaginary part would be lost)."""
    if _is_complex(raw):
        ui = float(u[0]) if len(u) else None
        raise CurveEvaluationError(f"curve returned complex values at u={ui!r}; points must be real", ui)


def _as_points(raw: Any, n: int) -> np.ndarray | None:
    """Interpret a callable's return value for ``n`` parameters as an (n, d) array, or ``None``."""
    try:
        arr = np.asarray(raw, dtype=float)
    except (TypeError, ValueError):
        return None
    if arr.ndim == 2 and arr.shape[0] == n and arr.shape[1] in (2, 3):
        return arr
    if arr.ndim == 2 and arr.shape[1] == n and arr.shape[0] in (2, 3):
        return arr.T
    return None


class FunctionCurve:
    """A plain callable u -> point, scalar or vectorised, detected on first use.

    Detection calls the function once with the first batch of two or more parameters. An answer of
    shape (n, d) or (d, n), d = 2 or 3, means vectorised (one scalar call settles the square case
    n == d); anything else, including an exception, means scalar, and the function is then called once
    per parameter. ``calls`` counts the points the function gave (a vectorised call of k parameters
    counts k) and one for a probe that gave none, so for a scalar function it is its number of calls.
    Complex answers raise :class:`CurveEvaluationError` (the imaginary part would be lost).
    """

    def __init__(self, fn: Callable[..., Any], domain: tuple[float, float] | None = None):
        if not callable(fn):
            raise InputError(f"curve must be callable or a cadedge curve object, got {type(fn).__name__}")
        self.fn = fn
        self.domain = domain
        self.layout: str | None = None  # "rows", "cols" or "scalar" once detected
        self.calls = 0

    def _scalar(self, u: np.ndarray) -> np.ndarray:
        out = np.empty((len(u), 3))
        dim = 3
        for i, ui in enumerate(u):
            self.calls += 1
            try:
                raw = self.fn(float(ui))
            except Exception as exc:  # the black box failed: name the parameter
                raise CurveEvaluationError(
                    f"curve raised {type(exc).__name__}: {exc} at u={float(ui)!r}", float(ui)) from exc
            _reject_complex(raw, u[i:i + 1])
            try:
                p = np.asarray(raw, dtype=float).ravel()
            except (TypeError, ValueError) as exc:
                raise CurveEvaluationError(
                    f"curve returned {raw!r}, not numbers, at u={float(ui)!r}", float(ui)) from exc
            if p.shape not in ((2,), (3,)):
                raise CurveEvaluationError(
                    f"curve returned a point of shape {p.shape} at u={float(ui)!r}; "
                    "expected 2 or 3 coordinates", float(ui))
            dim = len(p)
            out[i, :dim] = p
        return out[:, :dim]

    def _detect(self, u: np.ndarray) -> np.ndarray:
        n = len(u)
        try:
            raw = self.fn(u)
        except Exception:
            raw = None
        _reject_complex(raw, u)
        try:
            arr = np.asarray(raw, dtype=float) if raw is not None else np.empty(0)
        except (TypeError, ValueError):
            arr = np.empty(0)
        rows = arr.ndim == 2 and arr.shape[0] == n and arr.shape[1] in (2, 3)
        cols = arr.ndim == 2 and arr.shape[1] == n and arr.shape[0] in (2, 3)
        if rows and cols:  # square answer: one scalar call says whether rows or columns are points
            first = self._scalar(u[:1])[0]
            rows = bool(np.allclose(arr[0], first, equal_nan=True))
            cols = not rows
        if rows or cols:
            self.calls += n
            self.layout = "rows" if rows else "cols"
            return arr if rows else arr.T
        self.calls += 1  # the probe was one call of the function, which gave no points
        self.layout = "scalar"
        return self._scalar(u)

    def evaluate(self, u: np.ndarray) -> np.ndarray:
        """Points at ``u``; see the class docstring for how the function is called."""
        u = np.asarray(u, dtype=float).ravel()
        if self.layout == "scalar" or len(u) == 0 or (self.layout is None and len(u) < 2):
            return self._scalar(u)
        if self.layout is None:
            return self._detect(u)
        try:
            raw = self.fn(u)
        except Exception:
            raw = None
        _reject_complex(raw, u)
        try:
            arr = np.asarray(raw, dtype=float) if raw is not None else None
        except (TypeError, ValueError):
            arr = None
        if arr is not None and arr.ndim == 2:
            arr = arr if self.layout == "rows" else arr.T
            if arr.shape[0] == len(u):
                self.calls += len(u)
                return arr
        return self._scalar(u)  # find and name the parameter that fails

    def __repr__(self) -> str:
        return f"FunctionCurve({getattr(self.fn, '__name__', self.fn)!r}, domain={self.domain})"


class SampledCurve:
    """A digital curve: sampled points joined by straight lines (scanner or image contours).

    ``params`` default to the cumulative chord length normalised to [0, 1]; evaluation is linear
    interpolation between samples, vectorised.
    """

    def __init__(self, points: Any, params: Any = None):
        pts = np.asarray(points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] not in (2, 3) or len(pts) < 2:
            raise InputError(f"sampled curve needs at least 2 points of 2 or 3 coordinates, got shape {pts.shape}")
        if not np.all(np.isfinite(pts)):
            raise InputError("sampled curve has non-finite coordinates")
        if params is None:
            s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
            params = s / s[-1] if s[-1] > 0 else np.linspace(0.0, 1.0, len(pts))
        t = np.asarray(params, dtype=float).ravel()
        if t.shape != (len(pts),) or np.any(np.diff(t) <= 0):
            raise InputError("sampled curve params must be strictly increasing, one per point")
        self.points, self.params = pts, t
        self.domain = (float(t[0]), float(t[-1]))

    def evaluate(self, u: np.ndarray) -> np.ndarray:
        """Linear interpolation at ``u`` (clamped to the domain)."""
        u = np.asarray(u, dtype=float).ravel()
        return np.column_stack([np.interp(u, self.params, self.points[:, k]) for k in range(self.points.shape[1])])

    def __repr__(self) -> str:
        return f"SampledCurve({len(self.points)} points, domain={self.domain})"


def as_curve(obj: Any, domain: tuple[float, float] | None = None) -> Any:
    """Wrap ``obj`` as a cadedge curve: curve objects pass through, callables become FunctionCurve."""
    if hasattr(obj, "evaluate") and hasattr(obj, "domain"):
        return obj
    if isinstance(obj, np.ndarray):
        return SampledCurve(obj)
    return FunctionCurve(obj, domain)


class Evaluator:
    """Counts, checks and pads every evaluation of a curve; the refiners see only this.

    ``__call__(u)`` returns an (n, 3) array (2-D curves padded with z = 0) and raises
    :class:`CurveEvaluationError` naming the first parameter whose point is not finite.
    ``evaluations`` is the exact number of points asked of the black box.
    """

    def __init__(self, curve: Any):
        self.curve = curve
        self._asked = 0
        self._calls_before = getattr(curve, "calls", None)  # a curve object reused counts on from there

    @property
    def evaluations(self) -> int:
        calls = getattr(self.curve, "calls", None)
        if calls is None or self._calls_before is None:
            return self._asked
        return int(calls) - int(self._calls_before)

    def __call__(self, u: np.ndarray) -> np.ndarray:
        u = np.asarray(u, dtype=float).ravel()
        self._asked += len(u)
        raw = self.curve.evaluate(u)
        _reject_complex(raw, u)
        pts = np.asarray(raw, dtype=float)
        if pts.ndim != 2 or pts.shape[0] != len(u) or pts.shape[1] not in (2, 3):
            raise CurveEvaluationError(f"curve returned shape {pts.shape} for {len(u)} parameters")
        if not np.isfinite(pts).all():
            ui = float(u[np.argmax(~np.all(np.isfinite(pts), axis=1))])
            raise CurveEvaluationError(f"curve returned a non-finite point at u={ui!r}", ui)
        if pts.shape[1] == 2:
            pts = np.column_stack([pts, np.zeros(len(u))])
        return pts
