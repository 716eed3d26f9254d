"""Rigid transforms of point arrays, written so that equal inputs give equal outputs.

Rotations act on column vectors; every function returns ``(3, 3)`` or ``(n, 3)`` float64.
Quarter turns use exact cosines and sines (0, +-1), so boxes turned by multiples of 90
degrees keep exact coordinates. Points are transformed element by element (no BLAS), with
the same expression for every row.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["cos_sin_degrees", "euler_xyz", "euler_xyz_degrees", "axis_angle", "axis_angle_degrees",
           "transform"]


def cos_sin_degrees(angle: float) -> tuple[float, float]:
    """Cosine and sine of an angle in degrees, exact for multiples of 90."""
    quarters, rest = divmod(float(angle), 90.0)
    if rest == 0.0 and abs(quarters) < 2.0**52:
        return ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0))[int(quarters) % 4]
    radians = math.radians(angle)
    return math.cos(radians), math.sin(radians)


def euler_xyz(angles_degrees) -> np.ndarray:
    """``Rz(c) @ Ry(b) @ Rx(a)`` for ``[a, b, c]`` in degrees (extrinsic XYZ)."""
    (ca, sa), (cb, sb), (cc, sc) = (cos_sin_degrees(x) for x in angles_degrees)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, ca, -sa], [0.0, sa, ca]])
    ry = np.array([[cb, 0.0, sb], [0.0, 1.0, 0.0], [-sb, 0.0, cb]])
    rz = np.array([[cc, -sc, 0.0], [sc, cc, 0.0], [0.0, 0.0, 1.0]])
    return rz @ ry @ rx


def euler_xyz_degrees(rotation) -> np.ndarray:
    """The angles ``[a, b, c]`` (degrees) with ``euler_xyz([a, b, c]) == rotation`` up to
    float64 rounding (scipy's extrinsic ``'xyz'``; exact multiples of 90 where the rotation
    is a quarter-turn rotation, so that :func:`euler_xyz` gives it back exactly)."""
    from scipy.spatial.transform import Rotation

    angles = Rotation.from_matrix(np.asarray(rotation, dtype=np.float64)).as_euler(
        "xyz", degrees=True)
    snapped = np.round(angles / 90.0) * 90.0
    if np.array_equal(euler_xyz(snapped), np.asarray(rotation, dtype=np.float64)):
        return snapped + 0.0
    return angles


def _rodrigues(axis, c: float, s: float) -> np.ndarray:
    axis = np.asarray(axis, dtype=np.float64)
    norm = float(np.linalg.norm(axis))
    if norm == 0.0 or (c == 1.0 and s == 0.0):
        return np.eye(3)
    x, y, z = axis / norm
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + s * k + (1.0 - c) * (k @ k)


def axis_angle(axis, theta: float) -> np.ndarray:
    """Rotation by ``theta`` radians about ``axis`` (normalised; zero axis: identity)."""
    return _rodrigues(axis, math.cos(theta), math.sin(theta))


def axis_angle_degrees(axis, angle: float) -> np.ndarray:
    """Rotation by ``angle`` degrees about ``axis``; quarter turns about a coordinate axis
    are exact."""
    return _rodrigues(axis, *cos_sin_degrees(angle))


def transform(points: np.ndarray, rotation=None, translation=None) -> np.ndarray:
    """``rotation @ p + translation`` for each row, element by element (no BLAS).

    Each output coordinate is ``((x r0 + y r1) + z r2) + t`` in float64, the same expression
    for every row, so equal input rows give equal output rows. ``rotation`` may be any
    ``(3, 3)`` matrix (a scale or shear too).
    """
    out = np.array(points, dtype=np.float64)
    if rotation is not None and not np.array_equal(rotation, np.eye(3)):
        r = np.asarray(rotation, dtype=np.float64)
        out = out[:, 0:1] * r[:, 0] + out[:, 1:2] * r[:, 1] + out[:, 2:3] * r[:, 2]
    if translation is not None:
        out = out + np.asarray(translation, dtype=np.float64)
    return out + 0.0  # no negative zeros
