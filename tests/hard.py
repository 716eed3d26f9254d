"""Generators of hard inputs with known answers (the stability suite of ``test_hard.py``).

Each family is a function of its sweep parameter that returns the operands and the
translations whose answer is known without cspace:

- :func:`gap_comb`: a comb whose slots are exactly as wide as the robot, turned about z by an
  irrational angle. With the robot in a slot its C-obstacles of the two teeth only touch, so
  the translations along the slot, pushed ``depth`` into one tooth, are collisions; snapping
  the float input can open a slit of free space there (about a grid step wide) unless the
  C-obstacle is rounded outwards.
- :class:`VoxelCase`: a union of axis-aligned voxels (:func:`voxel_mesh`, e.g. the L of
  :func:`l_cells`) and an axis-aligned box robot, moved or scaled by any float map: the exact
  C-obstacle of the *float input* is a union of boxes in rationals (membership, distance,
  volume).

Used only by tests and benchmarks; nothing here depends on :mod:`cspace`.
"""

from __future__ import annotations

import itertools
from fractions import Fraction
from typing import NamedTuple

import numpy as np
from zoo import comb_occupancy, voxel_solid

__all__ = ["GapCase", "gap_comb", "GAP_ANGLES", "l_robot", "l_cells", "VoxelCase", "voxel_mesh"]

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


def l_cells() -> np.ndarray:
    """An L of three by three voxels, one layer."""
    occ = np.zeros((3, 3, 1), dtype=bool)
    occ[:, 0, 0] = True
    occ[0, :, 0] = True
    return occ


class VoxelCase:
    """A voxel obstacle and a box robot in float coordinates, with the exact reference."""

    def __init__(self, occ, cell, robot_size, transform=lambda x: x, robot_at=(0.0, 0.0, 0.0)):
        self.occ = np.asarray(occ, bool)
        cell = np.asarray(cell, float)
        V, F = voxel_mesh(self.occ)
        self.vertices = transform(V * cell)  # floats: the input
        self.faces = F
        # lattice coordinates per axis as the input floats (cell corners are mesh vertices)
        self.axes = [np.unique(self.vertices[:, a]) for a in range(3)]
        half = np.asarray(robot_size, float) / 2
        corners = np.array(list(itertools.product(*[(-h, h) for h in half])))
        self.robot = np.unique(transform(corners + np.asarray(robot_at)) - transform(
            np.asarray(robot_at)[None]), axis=0)  # robot frame: centred on its reference
        r_lo = [Fraction(float(x)) for x in self.robot.min(axis=0)]
        r_hi = [Fraction(float(x)) for x in self.robot.max(axis=0)]
        self.boxes = []
        for i, j, k in zip(*np.nonzero(self.occ)):
            idx = (i, j, k)
            lo = [Fraction(float(self.axes[a][idx[a]])) - r_hi[a] for a in range(3)]
            hi = [Fraction(float(self.axes[a][idx[a] + 1])) - r_lo[a] for a in range(3)]
            self.boxes.append((lo, hi))
        self.lo = np.array([[float(x) for x in b[0]] for b in self.boxes])
        self.hi = np.array([[float(x) for x in b[1]] for b in self.boxes])

    def contains(self, q: np.ndarray) -> np.ndarray:
        """Exact membership of float translations in the reference (boxes, closed)."""
        out = np.zeros(len(q), dtype=bool)
        for r, x in enumerate(q.tolist()):
            X = [Fraction(v) for v in x]
            out[r] = any(all(lo[a] <= X[a] <= hi[a] for a in range(3)) for lo, hi in self.boxes)
        return out

    def distance(self, q: np.ndarray) -> np.ndarray:
        """Float distance to the reference union (0 inside)."""
        gap = np.maximum(np.maximum(self.lo[None] - q[:, None], q[:, None] - self.hi[None]), 0)
        return np.sqrt((gap ** 2).sum(axis=2)).min(axis=1)

    def volume(self) -> Fraction:
        """Exact volume of the union of boxes (cells of the grid of their bounds)."""
        cuts = [sorted({b[0][a] for b in self.boxes} | {b[1][a] for b in self.boxes})
                for a in range(3)]
        total = Fraction(0)
        for i in range(len(cuts[0]) - 1):
            for j in range(len(cuts[1]) - 1):
                for k in range(len(cuts[2]) - 1):
                    lo = (cuts[0][i], cuts[1][j], cuts[2][k])
                    if any(all(b[0][a] <= lo[a] and (cuts[a][(i, j, k)[a] + 1]) <= b[1][a]
                               for a in range(3)) for b in self.boxes):
                        total += ((cuts[0][i + 1] - cuts[0][i]) * (cuts[1][j + 1] - cuts[1][j])
                                  * (cuts[2][k + 1] - cuts[2][k]))
        return total

    def samples(self, n: int, rng) -> np.ndarray:
        lo, hi = self.lo.min(axis=0), self.hi.max(axis=0)
        size = float(np.linalg.norm(hi - lo))
        pad = 0.1 * (hi - lo)
        uni = rng.uniform(lo - pad, hi + pad, (n // 2, 3))
        m = n - n // 2
        b = rng.integers(0, len(self.boxes), m)
        axis = rng.integers(0, 3, m)
        side = rng.integers(0, 2, m)
        p = rng.uniform(self.lo[b], self.hi[b])
        face = np.where(side == 0, self.lo[b, axis], self.hi[b, axis])
        p[np.arange(m), axis] = face
        off = size * 10.0 ** rng.uniform(-12, -1, m) * rng.choice([-1.0, 1.0], m)
        off[rng.random(m) < 0.1] = 0.0
        p[np.arange(m), axis] += off
        return np.vstack([uni, p])


def voxel_mesh(occ):
    """Unit voxel surface of ``occ``; where voxels touch only along an edge or at a vertex
    (not a 2-manifold) each voxel is its own cube, the cubes welded at shared corners."""
    try:
        return voxel_solid(occ, 1.0)
    except ValueError:
        one = np.ones((1, 1, 1), dtype=bool)
        Vs, Fs, n = [], [], 0
        for idx in zip(*np.nonzero(occ)):
            V, F = voxel_solid(one, 1.0, origin=np.asarray(idx, float))
            Vs.append(V)
            Fs.append(F + n)
            n += len(V)
        V, inverse = np.unique(np.vstack(Vs), axis=0, return_inverse=True)
        return V, inverse.reshape(-1)[np.vstack(Fs)]
