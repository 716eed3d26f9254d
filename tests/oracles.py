"""Independent float membership oracles for C-obstacles (tests only).

- :func:`winding_number`: the generalized winding number of a triangle mesh (or of a
  weighted triangle soup, e.g. a superset with facet multiplicities) at query points.
- :class:`FclSolid`: python-fcl collision with *solid* semantics for a closed obstacle mesh:
  a convex robot translated by ``q`` is in collision when it meets the obstacle's surface
  (FCL) or lies inside the obstacle (winding number of one robot vertex). ``q`` is in the
  C-obstacle ``O ⊕ (-R)`` exactly when it is in collision.
- :func:`membership_disagreements`: compare a membership answer with FCL's, ignoring points
  within a band of the C-obstacle boundary.
- :func:`raw_mesh`, :func:`raw_fcl_oracle`, :func:`raw_scene`: FCL oracles from the *raw
  float input a test gave* ``CSpaceObstacle.build`` (never ``co.obstacle`` / ``co.robot``,
  which are cspace's snapped copies): an :class:`cspace.check.fcl.FclOracle` on the raw
  arrays, or a :class:`cspace.Scene` of them for :class:`cspace.check.oracle.SceneOracle`
  (``cross_check(co, scene=raw_scene(...))``).

Everything is float64. The winding number and the ``fcl.Convex`` builder are
:mod:`cspace.check`'s (one implementation, tested here against known answers).
"""

from __future__ import annotations

from typing import NamedTuple

import fcl
import numpy as np

from cspace.check.fcl import fcl_convex as _convex
from cspace.check.fcl import winding_number

__all__ = [
    "winding_number",
    "FclSolid",
    "FclClassification",
    "membership_disagreements",
    "raw_mesh",
    "raw_fcl_oracle",
    "raw_scene",
    "exact_sum_mesh",
    "exact_sum_volume",
    "mesh_volume",
    "complex_euler",
    "brute_force_sum_distance",
    "VoxelBoxSum",
    "voxel_box_sum",
]


# --------------------------------------------------------------------------------------
# FCL with solid semantics


def fcl_bvh(vertices, faces):
    """FCL's BVH of a raw triangle mesh (a hollow surface)."""
    bvh = fcl.BVHModel()
    bvh.beginModel(len(faces), len(vertices))
    bvh.addSubModel(np.ascontiguousarray(vertices, dtype=np.float64),
                    np.ascontiguousarray(faces, dtype=np.int64))
    bvh.endModel()
    return bvh


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
        bvh = self._bvh = fcl_bvh(self.vertices, self.faces)
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


# ---- exact reference for A ⊕ B: libigl's exact (CGAL) union of convex pieces -----------------


def _grid_ints(a: np.ndarray, b: np.ndarray):
    """The two operands as cspace grid integers (each on its grid of ``Grid.for_operands``,
    as ``minkowski_sum`` snaps them), checking they already lie on those grids."""
    from cspace.geometry.exact import Grid

    grids = Grid.for_operands(a, b)
    out = []
    for arr, grid in zip((a, b), grids):
        k = grid.snap(arr)
        if not (grid.to_float(k) == arr).all():
            raise ValueError(
                "coordinates are not on the cspace grids of the pair: snap them first "
                "(each operand on its grid of Grid.for_operands(A, B))"
            )
        out.append(k)
    return grids, out


def raw_mesh(operand) -> tuple[np.ndarray, np.ndarray]:
    """The raw float mesh of an operand as a test passes it to ``CSpaceObstacle.build``:
    ``(V, F)`` as given, a ``trimesh.Trimesh``'s arrays, or points (a convex body: their
    outward Qhull hull, in float64; nothing snapped). Flat point sets (a panel, a rod, a
    triangle) have no hull: pass them as ``(V, F)``."""
    if isinstance(operand, tuple) and len(operand) == 2:
        V, F = operand
    elif hasattr(operand, "vertices") and hasattr(operand, "faces"):
        V, F = operand.vertices, operand.faces
    else:
        return _outward_hull(np.asarray(operand, dtype=np.float64))
    return np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64)


def raw_fcl_oracle(obstacle, robot, reference_point=(0.0, 0.0, 0.0), **kw):
    """:class:`cspace.check.fcl.FclOracle` on the raw operands (see :func:`raw_mesh`), the
    robot at ``q`` occupying ``robot - reference_point + q``; ``kw`` as FclOracle's."""
    from cspace.check.fcl import FclOracle

    (OV, OF), (RV, RF) = raw_mesh(obstacle), raw_mesh(robot)
    return FclOracle(OV, OF, RV, RF, reference_point, **kw)


def raw_scene(obstacle, robot, reference_point=(0.0, 0.0, 0.0), bounds=None):
    """A :class:`cspace.Scene` of the raw operands (one obstacle body or a list of them), for
    :class:`cspace.check.oracle.SceneOracle` and ``cross_check(co, scene=...)``: the oracle's
    own solid/surface rule on the raw meshes. ``bounds`` default: the raw C-obstacle's box
    grown by 10% (start and goal at its corners; unused by the oracle)."""
    from cspace.scene.scene import Body, Scene

    bodies = obstacle if isinstance(obstacle, list) else [obstacle]
    meshes = [raw_mesh(b) for b in bodies]
    RV, RF = raw_mesh(robot)
    c = np.asarray(reference_point, dtype=np.float64).reshape(3)
    if bounds is None:
        lo = np.min([V.min(axis=0) for V, _ in meshes], axis=0) - (RV.max(axis=0) - c)
        hi = np.max([V.max(axis=0) for V, _ in meshes], axis=0) - (RV.min(axis=0) - c)
        pad = 0.1 * (hi - lo)
        bounds = np.stack([lo - pad, hi + pad])
    bounds = np.asarray(bounds, dtype=np.float64)
    return Scene("raw", None, tuple(Body(f"obstacle-{k}", V, F, "test")
                                    for k, (V, F) in enumerate(meshes)),
                 Body("robot", RV, RF, "test"), c, bounds, bounds[0], bounds[1])


def _outward_hull(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Convex hull (scipy/Qhull) as an outward triangle mesh on its own vertices."""
    from scipy.spatial import ConvexHull

    h = ConvexHull(points)
    F = h.simplices.astype(np.int64)
    n = np.cross(points[F[:, 1]] - points[F[:, 0]], points[F[:, 2]] - points[F[:, 0]])
    flip = np.einsum("ij,ij->i", n, h.equations[:, :3]) < 0
    F[flip] = F[flip][:, ::-1]
    used, inv = np.unique(F, return_inverse=True)
    return points[used], inv.reshape(-1, 3).astype(np.int64)


def _sub(a, b):
    return [x - y for x, y in zip(a, b)]


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def _orient2d(a, b, c) -> int:
    """Sign of the turn a -> b -> c (Python integers: exact)."""
    d = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    return (d > 0) - (d < 0)


def _convex_quads(ints: np.ndarray, faces: np.ndarray) -> list[np.ndarray]:
    """Vertex index sets of convex planar patches covering the faces: pairs of triangles
    sharing an edge, exactly coplanar, whose union is a convex quadrilateral; the rest alone.

    Exact: the oracle's own predicates in Python integers on the grid integers (nothing of
    cspace's kernel). Each patch's convex hull equals the union of its triangles, so
    ``hull(patch ⊕ B)`` is ``∪ (t ⊕ B)`` over its triangles.
    """
    m = len(faces)
    # Directed edge (u, v) of face f at corner k; its twin is (v, u).
    u = faces.reshape(-1)
    v = faces[:, [1, 2, 0]].reshape(-1)
    f = np.repeat(np.arange(m), 3)
    k = np.tile(np.arange(3), m)
    key = {(int(a), int(b)): (int(g), int(c)) for a, b, g, c in zip(u, v, f, k)}
    taken = np.zeros(m, dtype=bool)
    patches = []
    for g in range(m):
        if taken[g]:
            continue
        taken[g] = True
        best = None
        for c in range(3):
            a, b = int(faces[g, c]), int(faces[g, (c + 1) % 3])
            h, hc = key.get((b, a), (-1, -1))
            if h < 0 or taken[h]:
                continue
            x = int(faces[g, (c + 2) % 3])  # apex of g opposite edge (a, b)
            y = int(faces[h, (hc + 2) % 3])  # apex of h opposite edge (b, a)
            P = [[int(c) for c in ints[i]] for i in (a, b, x, y)]
            n = _cross(_sub(P[1], P[0]), _sub(P[2], P[0]))
            if _dot(n, _sub(P[3], P[0])) != 0:  # not coplanar
                continue
            # Quad a-y-b-x (counter-clockwise about g's normal n): convex iff the corners
            # at a and b turn the same way as n: (x, a, y) and (y, b, x).
            ax = max(range(3), key=lambda i: abs(n[i]))
            keep = [i for i in range(3) if i != ax]
            s = 1 if n[ax] > 0 else -1
            q = [[p[i] for i in keep] for p in P]
            if s * _orient2d(q[2], q[0], q[3]) >= 0 and s * _orient2d(q[3], q[1], q[2]) >= 0:
                best = h
                patch = np.array([a, b, x, y])
                break
        if best is None:
            patches.append(faces[g].copy())
        else:
            taken[best] = True
            patches.append(patch)
    return patches


def _spatial_order(centres: np.ndarray) -> np.ndarray:
    """Indices ordered by recursive median splits along the longest axis (a kd order), so
    that neighbours in the order are neighbours in space."""
    idx = np.arange(len(centres))
    out = []
    stack = [idx]
    while stack:
        part = stack.pop()
        if len(part) <= 2:
            out.extend(part.tolist())
            continue
        c = centres[part]
        axis = int(np.argmax(np.ptp(c, axis=0)))
        part = part[np.argsort(c[:, axis], kind="stable")]
        half = len(part) // 2
        stack.append(part[half:])
        stack.append(part[:half])
    return np.array(out, dtype=np.int64)


def exact_sum_mesh(A_vertices, A_faces, B_points) -> tuple[np.ndarray, np.ndarray]:
    """Reference surface of ``A ⊕ B`` from libigl's exact CGAL booleans (tests only).

    ``A ⊕ B = (A + b0) ∪ ⋃_t (t ⊕ B)`` over the triangles ``t`` of A, for any ``b0`` in B:
    for ``a ∈ A`` and ``b ∈ B`` either ``a + b - b0 ∈ A``, or the segment from ``a`` to
    ``a + b - b0`` leaves A at a point ``p`` of some triangle, ``p = a + s (b - b0)``, and then
    ``a + b = p + (s b0 + (1 - s) b) ∈ t ⊕ B``. Each ``t ⊕ B`` is the convex hull of the
    ``3 |B|`` sums (scipy, outward); coplanar triangle pairs forming a convex quadrilateral
    share one piece. The pieces are united by ``igl.copyleft.cgal.mesh_boolean`` in a
    balanced tree over a spatial order (neighbours first).

    Parameters
    ----------
    A_vertices : (n, 3) float64
    A_faces : (m, 3) int64
        A closed, outward-oriented mesh; coordinates already on the cspace grid of the pair.
    B_points : (k, 3) float64
        Points whose convex hull is B (full-dimensional), on the same grid.

    Returns
    -------
    vertices : (p, 3) float64
        CGAL's exact vertices rounded to float64 (also those of intermediate unions).
    faces : (q, 3) int64
        Outward triangles of the union.

    Raises
    ------
    ValueError
        If the coordinates are not on the pair's cspace grid (the sums would not be the
        operands cspace sums).
    ImportError
        Without libigl (the ``peers`` extra).
    """
    import igl.copyleft.cgal as cgal

    AV = np.ascontiguousarray(A_vertices, dtype=np.float64)
    AF = np.ascontiguousarray(A_faces, dtype=np.int64)
    B = np.ascontiguousarray(B_points, dtype=np.float64)
    _, (Ai, _) = _grid_ints(AV, B)
    patches = _convex_quads(Ai, AF)
    centres = np.array([AV[p].mean(axis=0) for p in patches])
    pieces = [(AV + B[0], AF)]
    for i in _spatial_order(centres):
        pieces.append(_outward_hull((AV[patches[i]][:, None, :] + B[None]).reshape(-1, 3)))
    while len(pieces) > 1:
        nxt = []
        for i in range(0, len(pieces) - 1, 2):
            (VA, FA), (VB, FB) = pieces[i], pieces[i + 1]
            V, F, _ = cgal.mesh_boolean(VA, FA, VB, FB, "union")
            nxt.append((np.ascontiguousarray(V), np.ascontiguousarray(F, dtype=np.int64)))
        if len(pieces) % 2:
            nxt.append(pieces[-1])
        pieces = nxt
    return pieces[0]


def sum_support_points(A_vertices, A_faces, B_points, n: int, seed: int) -> np.ndarray:
    """Points of ``A ⊕ B`` of the raw inputs, on its boundary where nothing covers them.

    Each is ``a + b`` with ``a`` on A's surface (a face, an edge or a vertex, a third each)
    and ``b`` the vertex of B supporting a direction of A's normal cone at ``a`` (the face's
    normal; a blend of the two faces' at an edge; of the faces' around a vertex). Every one
    lies in the exact sum by construction (numpy only, no cspace, no FCL); a sum that is
    within ``e`` of the exact one holds each, or has it within ``e`` of its surface.
    """
    V = np.asarray(A_vertices, dtype=np.float64)
    F = np.asarray(A_faces, dtype=np.int64)
    B = np.asarray(B_points, dtype=np.float64).reshape(-1, 3)
    rng = np.random.default_rng(seed)
    tri = V[F]
    nrm = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    nrm /= np.linalg.norm(nrm, axis=1)[:, None]
    k = n // 3
    fi = rng.integers(0, len(F), k)
    faces = np.einsum("ij,ijk->ik", rng.dirichlet([1, 1, 1], k), tri[fi])
    d_faces = nrm[fi]
    # edges: the two faces of each undirected edge
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    owner = np.tile(np.arange(len(F)), 3)
    key = np.minimum(E[:, 0], E[:, 1]) * len(V) + np.maximum(E[:, 0], E[:, 1])
    order = np.argsort(key, kind="stable")
    twin = np.nonzero(key[order][1:] == key[order][:-1])[0]
    e0, e1 = order[twin], order[twin + 1]
    pick = rng.integers(0, len(e0), k)
    t, s = rng.random((2, k, 1))
    edges = V[E[e0[pick], 0]] * (1 - t) + V[E[e0[pick], 1]] * t
    d_edges = nrm[owner[e0[pick]]] * (1 - s) + nrm[owner[e1[pick]]] * s
    # vertices: a random blend of the normals of the faces around each
    m = n - 2 * k
    corner = F.reshape(-1)[rng.integers(0, 3 * len(F), m)]
    incident = [np.nonzero((F == c).any(axis=1))[0] for c in corner]
    d_verts = np.array([nrm[f].T @ rng.dirichlet(np.ones(len(f))) for f in incident])
    a = np.vstack([faces, edges, V[corner]])
    d = np.vstack([d_faces, d_edges, d_verts])
    return a + B[np.argmax(d @ B.T, axis=1)]


def mesh_volume(vertices, faces) -> float:
    """Enclosed volume of a closed outward triangle mesh (float64, about the centroid)."""
    V = np.asarray(vertices, dtype=np.float64)
    F = np.asarray(faces, dtype=np.int64)
    W = V - V.mean(axis=0)  # centring keeps the triple products small
    return float(np.einsum("ij,ij->i", W[F[:, 0]], np.cross(W[F[:, 1]], W[F[:, 2]])).sum() / 6.0)


def exact_sum_volume(A_vertices, A_faces, B_points) -> float:
    """Volume of ``A ⊕ B`` from :func:`exact_sum_mesh` (its rounded vertices).

    Exact up to the float64 rounding of CGAL's constructed vertices and of the volume sum
    (about 1e-15 relative); the test suite compares at 1e-9.
    """
    return mesh_volume(*exact_sum_mesh(A_vertices, A_faces, B_points))


def complex_euler(faces) -> int:
    """``V - E + F`` of a triangle complex: used vertices, distinct undirected edges, faces.

    Unlike ``zoo.euler_characteristic`` (``E = 3F/2``) it counts an edge shared by four
    triangles once, so it is right for non-manifold 2-cycles too.
    """
    F = np.asarray(faces, dtype=np.int64)
    e = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    return int(np.unique(F).size - len(np.unique(e, axis=0)) + len(F))


# ---- exact A ⊕ B for a voxel solid and an axis-aligned box -----------------------------------


class VoxelBoxSum(NamedTuple):
    """Exact ``A ⊕ B`` of a voxel solid A and an axis box B, as a rectilinear voxel set.

    occupancy : (X, Y, Z) bool
        Cells of the rectilinear grid ``breaks`` inside the sum.
    breaks : tuple of three lists of Fraction
        Cell ``(i, j, k)`` is ``[x_i, x_{i+1}] × [y_j, y_{j+1}] × [z_k, z_{k+1}]``.
    volume : Fraction
    n_holes : int
        Bounded components of the complement (face-connected empty cells not reaching the
        outside): the polyhedral holes.
    euler : int
        Euler characteristic of the boundary surface (welded; 2 per sphere-like shell).
    nonmanifold_edges : (k, 2, 3) float64
        Lattice edges where two cells of the sum touch only along the edge.
    nonmanifold_length : Fraction
        Their total length.
    pinch_vertices : (k, 3) float64
        Lattice vertices whose neighbourhood is not a disc and that lie on no non-manifold
        edge (double vertices).
    """

    occupancy: np.ndarray
    breaks: tuple
    volume: "Fraction"
    n_holes: int
    euler: int
    nonmanifold_edges: np.ndarray
    nonmanifold_length: "Fraction"
    pinch_vertices: np.ndarray


def voxel_box_sum(occupancy, lo, hi, *, size=1.0, origin=(0.0, 0.0, 0.0)) -> VoxelBoxSum:
    """The exact Minkowski sum of the voxel solid ``zoo.voxel_solid(occupancy, size, origin)``
    and the box ``[lo, hi]`` (3-vectors, lo < hi): the union of the boxes
    ``[cell + lo, cell + hi]``, decomposed on the rectilinear grid of their coordinates.

    All coordinates are exact Fractions of the given floats; an independent oracle for
    volume, holes, genus and non-manifold contacts of voxel ⊕ box cases.
    """
    from fractions import Fraction

    from scipy import ndimage

    import zoo

    occ = np.asarray(occupancy, dtype=bool)
    if occ.ndim != 3 or not occ.any():
        raise ValueError("occupancy must be a non-empty 3D boolean array")
    s = Fraction(float(size))
    o = [Fraction(float(x)) for x in origin]
    lo = [Fraction(float(x)) for x in lo]
    hi = [Fraction(float(x)) for x in hi]
    if not all(a < b for a, b in zip(lo, hi)):
        raise ValueError(f"box must have lo < hi on every axis, got {lo}, {hi}")
    breaks, start, stop = [], [], []
    for ax in range(3):
        n = occ.shape[ax]
        cuts = sorted({o[ax] + s * k + lo[ax] for k in range(n + 1)} | {o[ax] + s * k + hi[ax] for k in range(n + 1)})
        where = {c: i for i, c in enumerate(cuts)}
        breaks.append(cuts)
        # voxel k covers cells [start[k], stop[k]) of the new grid
        start.append(np.array([where[o[ax] + s * k + lo[ax]] for k in range(n)]))
        stop.append(np.array([where[o[ax] + s * (k + 1) + hi[ax]] for k in range(n)]))
    out = np.zeros(tuple(len(b) - 1 for b in breaks), dtype=bool)
    for i, j, k in np.argwhere(occ):
        out[start[0][i]:stop[0][i], start[1][j]:stop[1][j], start[2][k]:stop[2][k]] = True
    widths = [np.array([b[i + 1] - b[i] for i in range(len(b) - 1)], dtype=object) for b in breaks]
    volume = Fraction(0)
    for i, j in np.argwhere(out.any(axis=2)):
        volume += widths[0][i] * widths[1][j] * sum(widths[2][out[i, j]], Fraction(0))
    pad = np.pad(out, 1)
    labels, count = ndimage.label(~pad)  # 6-connected empty cells
    outside = labels[0, 0, 0]
    n_holes = int(count - 1) if outside else int(count)
    edges, vertices = zoo.voxel_defects(pad)
    fl = [np.array([float(c) for c in b]) for b in breaks]
    segs, length, on_edge = [], Fraction(0), np.zeros_like(vertices)
    for ax, bad in enumerate(edges):
        b, c = [a for a in range(3) if a != ax]
        for idx in np.argwhere(bad):
            cell = int(idx[ax]) - 1  # padded cell -> cell of ``out``
            p0 = np.zeros(3)
            p0[ax], p0[b], p0[c] = fl[ax][cell], fl[b][idx[b]], fl[c][idx[c]]
            p1 = p0.copy()
            p1[ax] = fl[ax][cell + 1]
            segs.append((p0, p1))
            length += breaks[ax][cell + 1] - breaks[ax][cell]
            for end in (cell, cell + 1):
                v = [int(idx[0]), int(idx[1]), int(idx[2])]
                v[ax] = end
                on_edge[tuple(v)] = True
    pinch = np.array([[fl[a][i] for a, i in enumerate(v)] for v in np.argwhere(vertices & ~on_edge)]).reshape(-1, 3)
    _, F = zoo._voxel_surface(out)  # lattice positions only: topology
    return VoxelBoxSum(
        occupancy=out,
        breaks=tuple(breaks),
        volume=volume,
        n_holes=n_holes,
        euler=complex_euler(F),
        nonmanifold_edges=np.array(segs, dtype=np.float64).reshape(-1, 2, 3),
        nonmanifold_length=length,
        pinch_vertices=pinch,
    )


# ---- brute-force distance from q to A ⊕ B (q outside) -----------------------------------------


def _segment_distance(p0, p1, q0, q1) -> np.ndarray:
    """Distances between segments [p0, p1] and [q0, q1] (broadcast (..., 3) arrays), float64.

    The clamped closed form (Ericson, Real-Time Collision Detection 5.1.9), vectorised.
    """
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a = np.einsum("...i,...i->...", d1, d1)
    e = np.einsum("...i,...i->...", d2, d2)
    f = np.einsum("...i,...i->...", d2, r)
    c = np.einsum("...i,...i->...", d1, r)
    b = np.einsum("...i,...i->...", d1, d2)
    denom = a * e - b * b
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(denom > 0, np.clip((b * f - c * e) / denom, 0.0, 1.0), 0.0)
        t = (b * s + f) / e
        s = np.where(t < 0, np.clip(-c / a, 0.0, 1.0), np.where(t > 1, np.clip((b - c) / a, 0.0, 1.0), s))
        t = np.clip(t, 0.0, 1.0)
    gap = (p0 + s[..., None] * d1) - (q0 + t[..., None] * d2)
    return np.sqrt(np.einsum("...i,...i->...", gap, gap))


def _edges(faces: np.ndarray) -> np.ndarray:
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    return np.unique(e, axis=0)


def brute_force_sum_distance(A_vertices, A_faces, B_vertices, B_faces, q) -> np.ndarray:
    """Distance from each ``q`` outside ``A ⊕ B`` to it, by brute force over feature pairs.

    ``dist(q, A ⊕ B) = dist(q - B, ∂A)`` for q outside; the closest pair between the convex
    polytope ``q - B`` and a triangle of A is vertex-triangle, triangle-vertex or edge-edge,
    so the distance is the minimum over those pairs (point-triangle distances by libigl's
    ``point_mesh_squared_distance``, segment pairs in numpy). Independent of FCL and of the
    exact union; float64, for the few points where FCL and our surface disagree.
    """
    import igl

    AV = np.ascontiguousarray(A_vertices, dtype=np.float64)
    AF = np.ascontiguousarray(A_faces, dtype=np.int64)
    BV = np.ascontiguousarray(B_vertices, dtype=np.float64)
    BF = np.ascontiguousarray(B_faces, dtype=np.int64)
    ea, eb = _edges(AF), _edges(BF)
    out = np.zeros(len(q))
    for k, p in enumerate(np.asarray(q, dtype=np.float64).reshape(-1, 3)):
        vf = igl.point_mesh_squared_distance(np.ascontiguousarray(p - BV), AV, AF)[0].min()
        fv = igl.point_mesh_squared_distance(np.ascontiguousarray(p - AV), BV, BF)[0].min()
        ee = _segment_distance(
            AV[ea[:, 0]][:, None], AV[ea[:, 1]][:, None], (p - BV[eb[:, 0]])[None], (p - BV[eb[:, 1]])[None]
        ).min()
        out[k] = min(np.sqrt(vf), np.sqrt(fv), ee)
    return out
