"""Checks of the refinement options, shared by ``refine_curve``, ``refine_shape`` and ``run_batch``.

One wording everywhere, and no OCCT: the API entry points reject bad options before any (possibly
slow) file is read or any worker started.
"""

from __future__ import annotations

import math
from typing import Any

from .errors import InputError

#: The smallest arc-length deficit target accepted. A polyline is measured in double precision: a
#: unit circle refined to 1e-10 needs about 1.2e5 segments, whose summed rounding already shifts the
#: deficit by some 2e-11 (its true deficit came out 1.21e-10), and below that the result is noise.
#: 1e-9 is the smallest target met with margin (true deficit 9.94e-10); see docs/target.md.
MIN_ALD = 1e-9
MIN_ALD_TEXT = "1e-9"


def check_ald(value: Any, name: str = "ald") -> float:
    """``value`` as a target in [MIN_ALD, 1); InputError naming the smallest accepted value otherwise."""
    v = positive(name, value, upper=1.0)
    if v is None:
        raise InputError(f"{name} must be a number, got None")
    if v < MIN_ALD:
        raise InputError(f"{name} {value!r} is below {MIN_ALD_TEXT}, the smallest target double precision can "
                         "resolve")
    return v


def positive(name: str, value: Any, *, upper: float | None = None) -> float | None:
    """``value`` as a finite float above 0 (and below ``upper``), or None if it is None."""
    if value is None:
        return None
    if isinstance(value, bool):
        raise InputError(f"{name} must be a number, got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(v) or v <= 0 or (upper is not None and v >= upper):
        bound = f" and below {upper:g}" if upper is not None else ""
        raise InputError(f"{name} must be positive{bound}, got {value!r}")
    return v


def refine_options(ald: Any, min_length: Any = None, max_length: Any = None,
                   max_growth: Any = None) -> dict[str, float | None]:
    """The target-mode options checked and as floats: ``ald`` in [MIN_ALD, 1) (required), lengths positive
    with ``min_length <= max_length``, ``max_growth`` above 1. Raises :class:`InputError`."""
    if ald is None:
        raise InputError("ald must be a number, got None")
    out = {"ald": check_ald(ald), "min_length": positive("min_length", min_length),
           "max_length": positive("max_length", max_length), "max_growth": positive("max_growth", max_growth)}
    lo, hi = out["min_length"], out["max_length"]
    if lo is not None and hi is not None and lo > hi:
        raise InputError(f"min_length {lo:g} exceeds max_length {hi:g}")
    if out["max_growth"] is not None and out["max_growth"] <= 1.0:
        raise InputError(f"max_growth must be greater than 1, got {max_growth!r}")
    return out
