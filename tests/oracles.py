"""Independent float membership oracles for C-obstacles (tests only).

- :func:`winding_number`: the generalized winding number of a triangle mesh (or of a
  weighted triangle soup, e.g. a superset with facet multiplicities) at query points.
- :class:`FclSolid`: python-fcl collision with *solid* semantics for a closed obstacle mesh:
  a convex robot translated by ``q`` is in collision when it meets the obstacle's surface
  (FCL) or lies inside the obstacle (winding number of one robot vertex). ``q`` is in the
  C-obstacle ``O ⊕ (-R)`` exactly when it is in collision.
- :func:`membership_disagreements`: compare a membership answer with FCL's, ignoring points
  within a band of the C-obstacle boundary.

Everything is float64. The winding number and the ``fcl.Convex`` builder are
:mod:`cspace.fcl_check`'s (one implementation, tested here against known answers).
"""

from __future__ import annotations

from typing import NamedTuple

import fcl
import numpy as np

from cspace.fcl_check import fcl_convex as _convex
from cspace.fcl_check import winding_number

__all__ = ["winding_number", "FclSolid", "FclClassification", "membership_disagreements"]


# --------------------------------------------------------------------------------------
# FCL with solid semantics


class FclClassification(NamedTuple):
    """Per-translation result of :meth:`FclSolid.classify`.

    inside : (k,) bool
        The robot meets the solid obstacle (``q`` in the C-obstacle).
    surface : (k,) bool
        FCL found a contact between the robot and the obstacle's surface.
    contained : (k,) bool
        No surface contact, and the robot is inside the obstacle (winding number).
    distance : (k,) float64
        ``fcl.distance`` where there is no surface contact (robot to surface), NaN elsewhere.
    clearance : (k,) float64 >= 0
        A lower bound on the distance from ``q`` to the C-obstacle boundary: exact (the FCL
        distance) for ``q`` outside; the FCL distance for ``contained`` (moving the robot by
        less than that keeps it strictly inside); for ``surface`` contacts, ``band`` if the
        robot eroded by ``band`` still collides, else 0 (within the band).
    """

    inside: np.ndarray
    surface: np.ndarray
    contained: np.ndarray
    distance: np.ndarray
    clearance: np.ndarray


class FclSolid:
    """FCL membership oracle with solid semantics for a closed obstacle mesh.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
        A closed, outward-oriented obstacle surface (e.g. a ``ClosedMesh``'s arrays).

    Notes
    -----
    ``fcl.BVHModel`` is a hollow triangle surface: a robot entirely inside the obstacle does
    not collide with it. So when FCL finds no surface contact, one robot vertex is tested for
    being inside the obstacle with :func:`winding_number` (a convex robot that does not meet
    the surface is entirely inside or entirely outside). The winding number is chosen over
    ``trimesh.Trimesh.contains`` because it needs no ray acceleration structure (rtree and
    embree are not installed), has no ray-through-edge/vertex failure modes, and is an
    integer up to ~1e-14 for points off the surface; the robot vertex is off the surface
    whenever FCL reports no contact. It also handles cavities (inner shells wound inwards).
    """

    def __init__(self, vertices, faces):
        self.vertices = np.ascontiguousarray(vertices, dtype=np.float64)
        self.faces = np.ascontiguousarray(faces, dtype=np.int64)
        bvh = fcl.BVHModel()
        bvh.beginModel(len(self.faces), len(self.vertices))
        bvh.addSubModel(self.vertices, self.faces)
        bvh.endModel()
        self._bvh = bvh
        self._obstacle = fcl.CollisionObject(bvh, fcl.Transform())

    # -- helpers -------------------------------------------------------------------------

    def contains_points(self, points) -> np.ndarray:
        """(k,) bool: winding number of the obstacle > 1/2 at the points."""
        return winding_number(self.vertices, self.faces, points) > 0.5

    @staticmethod
    def _translations(translations) -> np.ndarray:
        q = np.ascontiguousarray(translations, dtype=np.float64).reshape(-1, 3)
        if not np.isfinite(q).all():
            raise ValueError("translations must be finite")
        return q

    def _robot(self, robot_vertices, robot_faces):
        V = np.ascontiguousarray(robot_vertices, dtype=np.float64)
        geom = _convex(V, robot_faces)
        return V, geom, fcl.CollisionObject(geom, fcl.Transform())

    def surface_contacts(self, robot_vertices, robot_faces, translations) -> np.ndarray:
        """(k,) bool: plain ``fcl.collide`` of the robot (fcl.Convex) at ``q`` with the BVH.

        Surface contacts only: the BVH is hollow, a robot inside the obstacle gives False.
        """
        q = self._translations(translations)
        _, geom, obj = self._robot(robot_vertices, robot_faces)
        out = np.zeros(len(q), dtype=bool)
        obs = self._obstacle
        for i in range(len(q)):
            obj.setTranslation(q[i])  # a float64 numpy row (lists raise in python-fcl)
            out[i] = fcl.collide(obj, obs) > 0  # fresh request/result per call
        del geom
        return out

    # -- the oracle ----------------------------------------------------------------------

    def collides(self, robot_vertices, robot_faces, translations) -> np.ndarray:
        """(k,) bool: the convex robot translated by ``q`` meets the solid obstacle.

        ``robot_vertices`` (r, 3) and ``robot_faces`` (t, 3) describe a convex polytope in
        its own frame (reference point at the origin), e.g. ``R.vertices, R.faces`` of a
        :class:`cspace.ConvexPolytope`. True iff ``q`` is in ``O ⊕ (-R)``.
        """
        q = self._translations(translations)
        V = np.ascontiguousarray(robot_vertices, dtype=np.float64)
        inside = self.surface_contacts(V, robot_faces, q)
        free = ~inside
        if free.any():
            inside[free] = self.contains_points(V[0] + q[free])
        return inside

    def distance(self, robot_vertices, robot_faces, translations) -> np.ndarray:
        """(k,) float64: ``fcl.distance`` of the robot at ``q`` to the obstacle surface.

        Meaningful only without surface contact (FCL returns -1 for a Convex-BVH contact).
        For ``q`` outside the C-obstacle it is the Euclidean distance from ``q`` to it; for a
        robot inside the obstacle it is the distance to the surface.
        """
        q = self._translations(translations)
        _, geom, obj = self._robot(robot_vertices, robot_faces)
        out = np.zeros(len(q))
        obs = self._obstacle
        for i in range(len(q)):
            obj.setTranslation(q[i])
            out[i] = fcl.distance(obj, obs)
        del geom
        return out

    def classify(
        self, robot_vertices, robot_faces, translations, *, band: float = 1e-9
    ) -> FclClassification:
        """Membership of each ``q`` in ``O ⊕ (-R)``, with a lower bound on its boundary distance.

        See :class:`FclClassification`. For surface contacts the depth test collides the
        robot shrunk about its vertex centroid ``c`` by the factor ``1 - band / rho`` (``rho``
        the distance from ``c`` to the nearest robot face plane): every face plane moves
        inwards by at least ``band``, so the shrunk robot lies in the robot eroded by a ball
        of radius ``band``; if it still meets the obstacle at ``q``, the robot meets it at
        every ``q + t`` with ``|t| <= band``. Rounding of the shrunk vertices (about 1e-16
        times their magnitude) is ignored.
        """
        q = self._translations(translations)
        V = np.ascontiguousarray(robot_vertices, dtype=np.float64)
        F = np.asarray(robot_faces, dtype=np.int64)
        surface = self.surface_contacts(V, F, q)
        free = np.nonzero(~surface)[0]
        distance = np.full(len(q), np.nan)
        distance[free] = self.distance(V, F, q[free])
        contained = np.zeros(len(q), dtype=bool)
        if free.size:
            contained[free] = self.contains_points(V[0] + q[free])
        # (A negative FCL distance without a collide contact would be an FCL inconsistency
        # at a touching placement: treat it as within the band.)
        clearance = np.where(surface, 0.0, np.maximum(distance, 0.0))
        hit = np.nonzero(surface)[0]
        if hit.size and band > 0:
            deep = self.collides(_shrunk(V, F, band), F, q[hit])
            clearance[hit[deep]] = band
        return FclClassification(surface | contained, surface, contained, distance, clearance)


def _shrunk(V: np.ndarray, F: np.ndarray, band: float) -> np.ndarray:
    """Robot vertices scaled about their centroid so every face plane moves in by >= band."""
    c = V.mean(axis=0)
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    h = np.einsum("ij,ij->i", n, V[F[:, 0]] - c)
    rho = h.min()
    if not rho > 0:
        raise ValueError("robot is not a convex polytope with outward faces (centroid not inside)")
    if band >= rho:
        raise ValueError(f"band {band} is not smaller than the robot's inner radius {rho}")
    return c + (1.0 - band / rho) * (V - c)


# --------------------------------------------------------------------------------------
# comparing membership answers


def membership_disagreements(our_inside, fcl_inside, fcl_distance, band: float = 1e-9) -> dict:
    """Where two membership answers disagree away from the C-obstacle boundary.

    Parameters
    ----------
    our_inside, fcl_inside : (k,) bool
    fcl_distance : (k,) float >= 0
        A lower bound on the distance from each point to the C-obstacle boundary:
        ``FclSolid.classify(...).clearance``. (Raw ``fcl.distance`` is -1 in collision and
        not a depth; negative values raise ValueError.)
    band : float
        Disagreements at points whose bound is below ``band`` are ignored (counted in
        ``n_in_band``).

    Returns
    -------
    report : dict
        ``n`` points; ``n_disagree`` disagreements beyond the band (``indices`` of them,
        ``false_inside`` where only we say inside, ``false_outside`` where only FCL does,
        ``max_clearance`` the largest bound among them, or 0); ``n_in_band`` disagreements
        ignored; ``ok`` iff ``n_disagree == 0``.
    """
    ours = np.asarray(our_inside, dtype=bool).reshape(-1)
    theirs = np.asarray(fcl_inside, dtype=bool).reshape(-1)
    d = np.asarray(fcl_distance, dtype=np.float64).reshape(-1)
    if not (len(ours) == len(theirs) == len(d)):
        raise ValueError(f"length mismatch: {len(ours)}, {len(theirs)}, {len(d)}")
    if (d < 0).any():
        raise ValueError(
            "fcl_distance must be a non-negative clearance (use FclSolid.classify(...).clearance)"
        )
    differ = ours != theirs
    counted = differ & ~(d < band)  # NaN counts: no bound known
    idx = np.nonzero(counted)[0]
    return {
        "n": int(len(ours)),
        "n_disagree": int(idx.size),
        "indices": idx,
        "false_inside": int((counted & ours).sum()),
        "false_outside": int((counted & theirs).sum()),
        "max_clearance": float(np.nanmax(d[idx])) if np.isfinite(d[idx]).any() else 0.0,
        "n_in_band": int((differ & (d < band)).sum()),
        "ok": bool(idx.size == 0),
    }


# ---- Euler characteristic of A ∩ K for voxel solids (the convolution's winding number) ----


def _hull_meets_box(points: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> bool:
    """Whether conv(points) meets the closed box [lo, hi]: an LP feasibility problem."""
    from scipy.optimize import linprog

    n = len(points)
    # lambda >= 0, sum lambda = 1, lo <= points^T lambda <= hi
    A_ub = np.vstack([points.T, -points.T])
    b_ub = np.concatenate([hi, -lo])
    res = linprog(np.zeros(n), A_ub=A_ub, b_ub=b_ub, A_eq=np.ones((1, n)), b_eq=[1.0],
                  bounds=[(0, None)] * n, method="highs")
    return res.status == 0


def voxel_intersection_euler(occupancy, robot_vertices, translation, *, size=1.0, origin=(0.0, 0.0, 0.0)) -> int:
    """Euler characteristic of A ∩ (R + q) for a voxel solid A and a convex robot R.

    A ∩ K is the union of the closed convex sets ``voxel_i ∩ K``; by the nerve theorem its
    Euler characteristic is ``sum over non-empty index sets S of (-1)^(|S|+1)`` where the
    common intersection of S's voxels (a box, possibly a face, edge or corner) meets K.
    Float LPs decide the meetings: a test oracle, valid away from touching contacts.
    """
    occ = np.asarray(occupancy, dtype=bool)
    K = np.asarray(robot_vertices, dtype=np.float64) + np.asarray(translation, dtype=np.float64)
    origin = np.asarray(origin, dtype=np.float64)
    klo, khi = K.min(0), K.max(0)
    cells = [np.array(c) for c in np.argwhere(occ)]
    boxes = [(origin + size * c, origin + size * (c + 1)) for c in cells]
    live = [b for b in boxes if (b[0] <= khi).all() and (b[1] >= klo).all() and _hull_meets_box(K, *b)]
    chi = 0

    def extend(start: int, lo: np.ndarray, hi: np.ndarray, depth: int) -> None:
        nonlocal chi
        for i in range(start, len(live)):
            nlo, nhi = np.maximum(lo, live[i][0]), np.minimum(hi, live[i][1])
            if (nlo > nhi).any() or not _hull_meets_box(K, nlo, nhi):
                continue
            chi += (-1) ** depth  # depth 0 is a single voxel: +1
            extend(i + 1, nlo, nhi, depth + 1)

    extend(0, np.full(3, -np.inf), np.full(3, np.inf), 0)
    return chi
