"""Meshes to and from meshio (duck-typed: meshio is optional), length units, and the size
check that catches a mesh read in the wrong units."""

from __future__ import annotations

import warnings
from typing import Any, Tuple, Union

import numpy as np

#: Metres per unit, for Mesh.load(units=...) and Mesh.from_meshio(units=...).
UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3}

#: A mesh whose largest extent is outside this range (m) was most likely read in the wrong units.
PLAUSIBLE_EXTENT = (1e-3, 2.0)


class UnitsWarning(UserWarning):
    """A mesh's size suggests a units mistake (e.g. a file in mm read as m)."""


def unit_scale(units: Union[str, float]) -> float:
    """Metres per unit of units: "m", "cm", "mm", or a number of metres per file unit (finite
    and > 0, for files in other units); ValueError otherwise."""
    if isinstance(units, str):
        if units in UNITS:
            return UNITS[units]
    elif isinstance(units, (int, float)) and np.isfinite(units) and units > 0:
        return float(units)
    raise ValueError("units must be one of %s or metres per unit (> 0), not %r" % (", ".join(UNITS), units))


def warn_if_implausible(bounds_min: Any, bounds_max: Any, origin: str) -> None:
    """Warn (UnitsWarning) if the largest extent of the box bounds_min..bounds_max is outside
    PLAUSIBLE_EXTENT: organs and instruments are millimetres to a metre or two."""
    extent = float(np.max(np.asarray(bounds_max) - np.asarray(bounds_min)))
    low, high = PLAUSIBLE_EXTENT
    if extent > high or extent < low:
        warnings.warn(
            "%s is %.3g m across: softhap works in metres; if the file is in mm or cm, load it with "
            "units=\"mm\" or units=\"cm\" (or Mesh.transform(scale))" % (origin, extent),
            UnitsWarning,
            stacklevel=3,
        )


def tets_of_meshio(mesh: Any) -> Tuple[np.ndarray, np.ndarray, int]:
    """(points, tets, skipped cells) of a meshio.Mesh-like object: its points and its "tetra"
    cell blocks (a "tetra10" block gives its corner nodes); other cells are skipped."""
    points = np.asarray(mesh.points, dtype=float)
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise ValueError("mesh.points must be an (n, 3) array")
    if points.shape[1] == 2:
        raise ValueError("a 2-D mesh has no tetrahedra")
    tets, skipped = [], 0
    for block in mesh.cells:
        kind, data = (block.type, block.data) if hasattr(block, "type") else block
        data = np.asarray(data)
        if kind in ("tetra", "tetra10"):
            tets.append(data[:, :4])
        else:
            skipped += len(data)
    if not tets:
        raise ValueError("the mesh has no tetra cells (found only %d other cells)" % skipped)
    return points, np.concatenate(tets).astype(np.int32), skipped


def to_meshio_mesh(nodes: np.ndarray, tets: np.ndarray) -> Any:
    """A meshio.Mesh of nodes and tets; ImportError if meshio is not installed."""
    try:
        import meshio
    except ImportError as exc:
        raise ImportError("Mesh.to_meshio needs meshio (pip install meshio)") from exc
    return meshio.Mesh(points=nodes, cells=[("tetra", tets)])


def read_with_meshio(path: Any) -> Any:
    """meshio.read(path), or None if meshio is not installed or cannot read the file (the
    caller then reports the C reader's error, which names the line)."""
    try:
        import meshio
    except ImportError:
        return None
    try:
        return meshio.read(path)
    except Exception:  # meshio raises many kinds (ReadError, ValueError, KeyError, ...)
        return None


def rotation_matrix(rotation: Any) -> np.ndarray:
    """A 3x3 rotation from a unit quaternion (w, x, y, z; normalised here) or a 3x3 matrix
    (checked orthonormal with det +1 to 1e-9)."""
    r = np.asarray(rotation, dtype=float)
    if r.shape == (4,):
        norm = np.linalg.norm(r)
        if not np.isfinite(norm) or norm == 0.0:
            raise ValueError("rotation quaternion must be finite and non-zero")
        w, x, y, z = r / norm
        return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                         [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                         [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    if r.shape == (3, 3):
        if not (np.allclose(r @ r.T, np.eye(3), atol=1e-9) and np.linalg.det(r) > 0):
            raise ValueError("rotation matrix must be orthonormal with determinant +1")
        return r
    raise ValueError("rotation must be a quaternion (w, x, y, z) or a 3x3 matrix")
