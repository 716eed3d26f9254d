"""Generators of hard inputs with known answers (the stability suite of ``test_hard.py``).

Each family is a function of its sweep parameter that returns the operands and the
translations whose answer is known without cspace:

- :func:`gap_comb`: a comb whose slots are exactly as wide as the robot, turned about z by an
  irrational angle. With the robot in a slot its C-obstacles of the two teeth only touch, so
  the translations along the slot, pushed ``depth`` into one tooth, are collisions; snapping
  the float input can open a slit of free space there (about a grid step wide) unless the
  C-obstacle is rounded outwards.

Used only by tests and benchmarks; nothing here depends on :mod:`cspace`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from zoo import comb_occupancy, voxel_solid

__all__ = ["GapCase", "gap_comb", "GAP_ANGLES", "l_robot"]

# Irrational angles (square roots of non-squares, radians): rotated coordinates are not on
# any dyadic grid.
GAP_ANGLES = tuple(float(np.sqrt(k)) for k in range(2, 40) if int(np.sqrt(k)) ** 2 != k)


class GapCase(NamedTuple):
    obstacle: tuple  # (vertices, faces), closed, world frame
    robot: np.ndarray  # (8, 3) box corners, robot frame (reference point at the origin)
    colliding: np.ndarray  # (k, 3) translations that are collisions for the float input
    rotation: np.ndarray  # (3, 3)


def rotation_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def gap_comb(angle: float, width: float = 0.25, depth: float = 1e-9, teeth: int = 3,
             samples: int = 101) -> GapCase:
    """A comb of ``teeth`` teeth (voxels of edge ``width``, slots as wide) and a box robot
    exactly as wide as a slot (``width x 0.8 width x 0.8 width``), both turned by ``angle``
    about z. ``colliding``: the robot in the first slot, pushed ``depth`` into the first tooth
    (a collision whatever the float rounding of the turn, which is about 1e-16), at
    ``samples`` heights along the slot.
    """
    V, F = voxel_solid(comb_occupancy(teeth, 2), width)
    b = 0.8 * width
    R = np.array([[x, y, z] for x in (0.0, width) for y in (0.0, b) for z in (0.0, b)])
    Rz = rotation_z(angle)
    ys = np.linspace(1.05 * width, 2.95 * width - b, samples)
    q = np.stack([np.full(samples, width - depth), ys, np.full(samples, 0.1 * width)], axis=1)
    return GapCase((V @ Rz.T, F), R @ Rz.T, q @ Rz.T, Rz)


def l_robot(width: float = 0.25, angle: float = 0.0):
    """A non-convex closed robot: a stem ``width`` wide (it fits a slot of :func:`gap_comb`)
    and an arm above the comb (z above ``1.5 width``, clear of its teeth), turned about z.
    ``(vertices, faces)``, reference point at the origin (the stem's lower corner)."""
    occ = np.zeros((3, 1, 7), dtype=bool)
    occ[0, 0, :] = True  # the stem, 7 voxels high
    occ[:, 0, 6] = True  # the arm on top
    V, F = voxel_solid(occ, width)
    V = V * [1.0, 0.8, 1.0]  # as deep as the box robot
    return V @ rotation_z(angle).T, F
