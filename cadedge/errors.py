"""The one small error hierarchy of cadedge.

The library raises these and never prints or exits; the CLI turns them into one line on stderr
and an exit code (see ``cadedge.cli``).
"""

from __future__ import annotations


class CadedgeError(Exception):
    """Base of every error cadedge raises on purpose."""


class InputError(CadedgeError):
    """Bad input: a missing, unreadable or invalid file, or an invalid argument (CLI exit code 2)."""


class CurveEvaluationError(CadedgeError):
    """A black-box curve returned a non-finite point or raised; the message names the parameter."""

    def __init__(self, message: str, parameter: float | None = None):
        super().__init__(message)
        self.parameter = parameter


class GeometryError(CadedgeError):
    """OpenCASCADE failed on a shape, edge or face; the message carries OCCT's reason."""


class MeshError(CadedgeError):
    """gmsh failed to mesh, or the mesh check failed."""


class CadedgeWarning(UserWarning):
    """A usable result exists but something is off (degenerate curve, loose tolerances, ...)."""
