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
  volume); the zoo's stairs and grate occupancies (a 10 x 10 grate: genus 100) are such
  unions too.
- :class:`TiltCase`: a prism whose top dips by 10^-k (two top faces nearly coplanar), with an
  exact reference in rationals.

Used only by tests and benchmarks; nothing here depends on :mod:`cspace`.
"""

from __future__ import annotations

import itertools
from fractions import Fraction
from typing import NamedTuple

import numpy as np
from zoo import comb_occupancy, voxel_solid

__all__ = ["GapCase", "gap_comb", "GAP_ANGLES", "l_robot", "l_cells", "VoxelCase", "voxel_mesh",
           "TiltCase"]

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

    def __init__(self, occ, cell, robot_size, transform=lambda x: x, robot_at=(0.0, 0.0, 0.0),
                 caps: int = 0, lift: float = 0.0):
        self.occ = np.asarray(occ, bool)
        cell = np.asarray(cell, float)
        V, F = voxel_mesh(self.occ)
        self.vertices = transform(V * cell)  # floats: the input
        self.faces = F
        # lattice coordinates per axis as the input floats (cell corners are mesh vertices)
        self.axes = [np.unique(self.vertices[:, a]) for a in range(3)]
        if caps:  # slivers: the surface bulges by at most ``lift``, never inwards
            self.vertices, self.faces = with_caps(self.vertices, self.faces, caps, lift)
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


def with_caps(V: np.ndarray, F: np.ndarray, k: int, lift: float = 0.0):
    """The closed mesh ``(V, F)`` with ``k`` sliver caps: for ``k`` edges (u, v), no two on
    one triangle, a new vertex m at the edge's midpoint moved ``lift`` outwards (along the sum
    of the two faces' normals); the face (u, v, a) becomes (u, m, a), (m, v, a) and the cap
    (v, m, u) closes the surface. With ``lift = 0`` the caps have zero area; with a small lift
    they snap to zero area. The solid only grows (by at most ``lift``), so an exact reference
    of the original body is one whose every collision is a true one."""
    V = np.asarray(V, float)
    F = [list(f) for f in np.asarray(F, np.int64).tolist()]
    owner = {}
    for t, (a, b, c) in enumerate(F):
        for u, v in ((a, b), (b, c), (c, a)):
            owner[(u, v)] = t
    used, new_v, out = set(), [], []
    for t, (a, b, c) in enumerate(list(F)):
        if len(new_v) >= k:
            break
        u, v, w = a, b, c
        other = owner.get((v, u))
        if other is None or t in used or other in used:
            continue
        used |= {t, other}
        n1 = np.cross(V[v] - V[u], V[w] - V[u])
        x = V[[i for i in F[other] if i not in (u, v)][0]]
        n2 = np.cross(V[u] - V[v], x - V[v])
        d = n1 / np.linalg.norm(n1) + n2 / np.linalg.norm(n2)
        m = len(V) + len(new_v)
        new_v.append((V[u] + V[v]) / 2 + lift * d / max(np.linalg.norm(d), 1e-300))
        F[t] = [u, m, w]
        out += [[m, v, w], [v, m, u]]
    return np.vstack([V] + [np.asarray(new_v).reshape(-1, 3)]), np.asarray(F + out, np.int64)


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


def _hull2(points: list) -> list:
    """Counter-clockwise convex hull of 2D rational points (Andrew's monotone chain)."""
    pts = sorted(set(points))
    if len(pts) <= 2:
        return pts

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1]


def _area2(poly: list) -> Fraction:
    """Twice the area of a counter-clockwise polygon (0 when degenerate)."""
    m = len(poly)
    return sum((poly[i][0] * poly[(i + 1) % m][1] - poly[(i + 1) % m][0] * poly[i][1]
                for i in range(m)), Fraction(0)) if m >= 3 else Fraction(0)


def _clip2(subject: list, clip: list) -> list:
    """Intersection of two convex counter-clockwise polygons (Sutherland-Hodgman, exact)."""
    out = list(subject)
    m = len(clip)
    for i in range(m):
        a, b = clip[i], clip[(i + 1) % m]
        if not out:
            break

        def side(p):
            return (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])

        res = []
        for j in range(len(out)):
            p, q = out[j], out[(j + 1) % len(out)]
            sp, sq = side(p), side(q)
            if sp >= 0:
                res.append(p)
            if (sp > 0 > sq) or (sp < 0 < sq):
                t = sp / (sp - sq)
                res.append((p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])))
        out = res
    return out


class TiltCase:
    """A near-coplanar valley: a prism (x in [0, 1], y in [0, 1]) whose top, at height 0.5,
    dips by ``depth`` along the line x = 0.5 (two top faces tilted by about ``2 depth``
    against each other), and a box robot (axis-aligned, centred on its reference point).

    Exact reference for the *float input*: the prism is the union of two convex prisms
    extruded along y, so its C-obstacle is the extrusion over ``[y0 - r_hi, y1 - r_lo]`` of
    the union of two convex polygons in (x, z), each the hull of the sums of a half's corners
    and the robot's; membership is decided on them in rationals.
    """

    def __init__(self, depth: float, robot_size=(0.3, 0.3, 0.3)):
        h = 0.5
        v = h - depth  # rounded once: the float input
        xz = [(0.0, 0.0), (1.0, 0.0), (1.0, h), (0.5, v), (0.0, h)]
        n = len(xz)
        V = np.array([[x, y, z] for y in (0.0, 1.0) for x, z in xz])
        cap = [(0, 1, 2), (0, 2, 3), (0, 3, 4)]  # fan from (0, 0): it sees every corner
        F = [(a, c, b) for a, b, c in cap]  # y = 0 seen from -y
        F += [(a + n, b + n, c + n) for a, b, c in cap]
        for i in range(n):
            j = (i + 1) % n
            F += [(i, j, j + n), (i, j + n, i + n)]
        # the triangles above turn inwards: reversed, every face is wound outwards
        self.vertices, self.faces = V, np.array(F, dtype=np.int64)[:, ::-1].copy()
        half = np.asarray(robot_size, float) / 2
        self.robot = np.array(list(itertools.product(*[(-s, s) for s in half])))
        r = [Fraction(float(s)) for s in half]
        Fr = [[(Fraction(x), Fraction(z)) for x, z in piece]
              for piece in ([xz[0], (0.5, 0.0), xz[3], xz[4]], [(0.5, 0.0), xz[1], xz[2], xz[3]])]
        self.polys = [_hull2([(x + sx * r[0], z + sz * r[2]) for x, z in piece
                              for sx in (-1, 1) for sz in (-1, 1)]) for piece in Fr]
        self.y = (-r[1], 1 + r[1])
        self._float = [np.array([[float(a), float(b)] for a, b in p]) for p in self.polys]

    def contains(self, q: np.ndarray) -> np.ndarray:
        out = np.zeros(len(q), dtype=bool)
        for k, (x, y, z) in enumerate(q.tolist()):
            Y = Fraction(y)
            if not self.y[0] <= Y <= self.y[1]:
                continue
            X, Z = Fraction(x), Fraction(z)
            for poly in self.polys:
                m = len(poly)
                if all((poly[(i + 1) % m][0] - poly[i][0]) * (Z - poly[i][1])
                       - (poly[(i + 1) % m][1] - poly[i][1]) * (X - poly[i][0]) >= 0
                       for i in range(m)):
                    out[k] = True
                    break
        return out

    def distance(self, q: np.ndarray) -> np.ndarray:
        """Float distance to the reference (0 inside; the largest of the y gap and the
        distance in (x, z) to the nearer polygon: a lower bound within a factor sqrt(2))."""
        y0, y1 = float(self.y[0]), float(self.y[1])
        gy = np.maximum(np.maximum(y0 - q[:, 1], q[:, 1] - y1), 0.0)
        best = np.full(len(q), np.inf)
        p = q[:, [0, 2]]
        for P in self._float:
            A, B = P, np.roll(P, -1, axis=0)
            d = B - A
            t = np.clip(np.einsum("kmj,mj->km", p[:, None, :] - A[None], d)
                        / np.einsum("mj,mj->m", d, d), 0.0, 1.0)
            near = A[None] + t[..., None] * d[None]
            dist = np.sqrt(((p[:, None, :] - near) ** 2).sum(axis=2)).min(axis=1)
            side = np.einsum("kmj,mj->km", p[:, None, :] - A[None], d[:, ::-1] * [1, -1])
            inside = (side <= 0).all(axis=1)
            best = np.minimum(best, np.where(inside, 0.0, dist))
        return np.maximum(best, gy)

    def samples(self, n: int, rng) -> np.ndarray:
        """Half uniform around the reference, half near the valley's C-obstacle boundary
        (the top, where the tilt is), moved by 10^U(-15, -1)."""
        uni = rng.uniform([-0.5, -0.5, -0.5], [1.5, 1.5, 1.0], (n // 2, 3))
        m = n - n // 2
        x = rng.uniform(-0.2, 1.2, m)
        top = np.array([max(float(self._top(xi)), 0.0) for xi in x])
        off = 10.0 ** rng.uniform(-15, -1, m) * rng.choice([-1.0, 1.0], m)
        near = np.stack([x, rng.uniform(0.0, 1.0, m), top + off], axis=1)
        return np.vstack([uni, near])

    def volume(self) -> Fraction:
        """Exact volume of the reference: (area(A) + area(B) - area(A ∩ B)) times its y
        length, the intersection clipped in rationals."""
        a, b = self.polys
        return (_area2(a) + _area2(b) - _area2(_clip2(a, b))) / 2 * (self.y[1] - self.y[0])

    def _top(self, x: float) -> float:
        """The reference's upper boundary z at x (the largest z of either polygon)."""
        best = -np.inf
        for P in self._float:
            for (ax, az), (bx, bz) in zip(P, np.roll(P, -1, axis=0)):
                if min(ax, bx) <= x <= max(ax, bx) and ax != bx:
                    best = max(best, az + (bz - az) * (x - ax) / (bx - ax))
        return best
