"""The independent oracle: a scene's robot against its raw obstacle meshes in FCL.

:class:`SceneOracle` is built from a :class:`cspace.Scene` alone: nothing of the C-space (no
grid, snapped operand, box, piece or model decision). Surface contact comes from FCL's
``DynamicAABBTreeCollisionManager``; containment from one vertex of every connected component
(winding number), with its own published rule for what is solid.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidArgumentError, InvalidMeshError
from .fcl import FclOracle, _components, _fcl, _welded, winding_number

__all__ = ["SceneOracle"]


# --------------------------------------------------------------------------------------
# the independent scene oracle: raw meshes, FCL's broad phase, its own solid semantics


def _balanced(W: np.ndarray, comp: np.ndarray, n_comp: int) -> np.ndarray:
    """(n_comp,) bool: the component is a closed 2-cycle, every edge used as often in one
    direction as in the other (a closed, consistently oriented surface; two solids sharing
    an edge too). Edges from a vertex to itself (welded-away triangles) are ignored."""
    a = W.reshape(-1)
    b = np.roll(W, -1, axis=1).reshape(-1)
    fc = np.repeat(comp, 3)
    keep = a != b
    a, b, fc = a[keep], b[keep], fc[keep]
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    sign = np.where(a < b, 1, -1)
    keys, inv = np.unique(np.stack([lo, hi], axis=1), axis=0, return_inverse=True)
    total = np.bincount(inv.reshape(-1), weights=sign, minlength=len(keys))
    closed = np.ones(n_comp, dtype=bool)
    open_edges = total[inv.reshape(-1)] != 0
    closed[np.unique(fc[open_edges])] = False
    closed[np.setdiff1d(np.arange(n_comp), fc)] = False  # nothing but welded-away triangles
    return closed


class _Mesh:
    """One raw mesh of the scene as :class:`SceneOracle` sees it (see its docstring)."""

    def __init__(self, fcl, name, V, F):
        self.name = name
        self.V = np.ascontiguousarray(V, dtype=np.float64)
        self.F = np.ascontiguousarray(F, dtype=np.int64)
        W = _welded(self.V, self.F)
        comp = _components(W, len(self.V))
        n_comp = int(comp.max()) + 1
        closed = _balanced(W, comp, n_comp)
        self.n_components = n_comp
        self.closed = closed
        # One vertex of every component (the first corner of its first face).
        first = np.unique(comp, return_index=True)[1]
        self.points = self.V[self.F[first, 0]]
        sf = self.F[closed[comp]]  # |winding number| does not depend on the orientation
        self.solid_faces = np.ascontiguousarray(sf)
        used = self.V[np.unique(sf)] if len(sf) else np.zeros((0, 3))
        self.solid_box = (np.stack([used.min(axis=0), used.max(axis=0)]) if len(used) else None)
        self.bvh = fcl.BVHModel()
        self.bvh.beginModel(len(self.F), len(self.V))
        self.bvh.addSubModel(self.V, self.F)
        self.bvh.endModel()

    @property
    def solid(self) -> bool:
        return self.solid_box is not None

    def inside(self, p: np.ndarray) -> np.ndarray:
        """(k,) bool: points inside the solid part (winding number not 0: |w| > 1/2)."""
        out = np.zeros(len(p), dtype=bool)
        if self.solid_box is None or not len(p):
            return out
        lo, hi = self.solid_box
        cand = np.nonzero(((p >= lo) & (p <= hi)).all(axis=1))[0]  # outside the box: w = 0
        if cand.size:
            out[cand] = np.abs(winding_number(self.V, self.solid_faces, p[cand])) > 0.5
        return out

    def describe(self) -> str:
        kinds = ("solid" if self.closed.all() else "surface" if not self.closed.any()
                 else f"{int(self.closed.sum())} of {self.n_components} components solid")
        return f"{self.name}: {len(self.F)} triangles, {self.n_components} components, {kinds}"


class SceneOracle:
    """FCL's verdict on a scene's robot against all its obstacle bodies, from the raw meshes.

    Built from the :class:`cspace.Scene` as loaded and nothing else: ``scene.robot``,
    ``scene.reference_point`` and ``scene.obstacles`` (float64 vertices and faces after the
    scene file's transforms). No grid, snapped coordinate, C-obstacle, box, piece or model
    decision of cspace enters, so a bug in those cannot hide itself here.

    **Semantics (the published rule).** Each mesh (the robot, every obstacle body) is split
    into connected components (triangles sharing a vertex, after welding vertices with
    bit-identical coordinates). A component is *closed* when every edge is used as often in
    one direction as in the other (a closed, consistently oriented surface; solids meeting at
    an edge included). A closed component is **solid**; every other component (open, or
    inconsistently oriented) is a **surface**. A mesh's solid is the region where the
    generalized winding number (:func:`winding_number`) of all its closed components
    together is not zero (``|w| > 1/2``): the inside of a plain closed surface, either way it
    is wound; cavities, wound against their shell, stay holes; a closed surface that meets
    itself (overlapping parts written as one mesh, or folds) holds everything it encloses.
    :mod:`cspace.scene.model` states the same rule (a closed surface whose snapped form bounds no
    valid solid is modelled as its surface and the region it encloses), decided on its own
    grid; it also re-orients inconsistently wound components and splits at non-manifold
    edges, so where the two differ the disagreement is reported, never hidden.

    A pose collides when

    1. FCL finds surface contact between the robot mesh and any body mesh (BVH against BVH:
       the bodies registered once in a ``fcl.DynamicAABBTreeCollisionManager``, the robot the
       query object); touching counts; or
    2. (no surface contact) one vertex of **every** robot component lies inside some body's
       solid, or one vertex of **every** component of every body lies inside the robot's
       solid. Without surface contact a connected component lies wholly inside or wholly
       outside a solid, so one vertex per component decides it. Surfaces get no winding test.

    Poses: :meth:`collides` takes translations ``q`` (the robot occupies
    ``v - reference_point + q``), :meth:`collides_poses` rotations and positions (the robot
    occupies ``R (v - reference_point) + q``).

    **Tolerance.** Everything here is float64: contact is resolved to about ``|x| * 2**-52``
    times a small factor at coordinates of size ``|x|`` (FCL composes the transforms and tests
    the triangles in float64). Measured (``SceneOracle`` itself, against exact rational
    orientation tests): a unit box robot against a unit box body at (X, X, X), moved k ulp of
    X into or out of face contact, k = 1..64, was right every time at X = 1, 10^3, 10^4,
    10^5 and 10^6 (touching: collision); a small tetrahedron's apex moved along the normal of
    a randomly tilted triangle of a body at X (6000 placements per X, offsets 10^-17..10^-8
    times X) was wrong only within 0.62 ulp of X of the exact contact at X = 1, and never at
    X = 10^3..10^6 (where the placements themselves sit on X's ulp grid). :attr:`band` states
    16 ulp of the scene's largest coordinate (``scale * 2**-48``): compare with exact answers
    outside it. Winding numbers decide containment only away from the surfaces (contact
    covers the rest).

    Parameters
    ----------
    scene : Scene
    robot_hull : bool, default False
        The robot's convex hull (scipy's qhull on its vertices) instead of its mesh: the robot
        a C-space built with ``robot_hull=True`` stands for.

    Attributes
    ----------
    robot : the robot's mesh analysis; ``bodies``: one per obstacle body (``describe()``).
    band : float
        FCL's float band at this scene's coordinates: ``2**-48`` times the largest coordinate
        magnitude of the bounds, the bodies and the robot's reach beyond the bounds.
    """

    def __init__(self, scene, *, robot_hull: bool = False):
        fcl = self._fcl = _fcl()
        c = np.asarray(scene.reference_point, dtype=np.float64).reshape(3)
        RV = np.asarray(scene.robot.vertices, dtype=np.float64) - c
        RF = np.asarray(scene.robot.faces, dtype=np.int64)
        if robot_hull:
            RV, RF = _hull(RV)
        self.robot = _Mesh(fcl, scene.robot.name, RV, RF)
        self.bodies = [_Mesh(fcl, b.name, b.vertices, b.faces) for b in scene.obstacles]
        self._robot_obj = fcl.CollisionObject(self.robot.bvh, fcl.Transform())
        self._objects = [fcl.CollisionObject(b.bvh, fcl.Transform()) for b in self.bodies]
        self._manager = fcl.DynamicAABBTreeCollisionManager()
        if self._objects:
            self._manager.registerObjects(self._objects)
        self._manager.setup()
        self._solid_bodies = [b for b in self.bodies if b.solid]
        reach = float(np.abs(RV).max()) if len(RV) else 0.0
        scale = float(np.abs(np.asarray(scene.bounds, dtype=np.float64)).max()) + reach
        for b in self.bodies:
            scale = max(scale, float(np.abs(b.V).max()))
        self.band = scale * 2.0**-48
        # Body component points, all bodies together, for the robot-solid test.
        self._body_points = (np.vstack([b.points for b in self.bodies]) if self.bodies
                             else np.zeros((0, 3)))

    def describe(self) -> str:
        return "\n".join(["robot " + self.robot.describe()] + [b.describe() for b in self.bodies])

    # ---- surface contact (FCL broad and narrow phase) ------------------------------------

    def _contact(self, Rs, Q) -> np.ndarray:
        fcl = self._fcl
        out = np.zeros(len(Q), dtype=bool)
        if not self._objects:
            return out
        rob, mgr = self._robot_obj, self._manager
        cb = fcl.defaultCollisionCallback
        for i in range(len(Q)):
            if Rs is None:
                rob.setTranslation(Q[i])
            else:
                rob.setTransform(fcl.Transform(Rs[i], Q[i]))
            data = fcl.CollisionData(request=fcl.CollisionRequest())
            mgr.collide(rob, data, cb)
            out[i] = data.result.is_collision
        return out

    def _contained(self, Rs, Q, idx) -> np.ndarray:
        """(len(idx),) bool: containment (rule 2) at the poses ``idx``."""
        hit = np.zeros(len(idx), dtype=bool)
        if not idx.size:
            return hit
        Qi = Q[idx]
        Ri = None if Rs is None else Rs[idx]
        # every robot component's vertex, placed, against every solid body
        for p in self.robot.points:
            world = Qi + (p if Ri is None else Ri @ p)
            for b in self._solid_bodies:
                rest = np.nonzero(~hit)[0]
                if not rest.size:
                    return hit
                hit[rest] |= b.inside(world[rest])
        # every body component's vertex, in the robot's frame, against the robot's solid
        if self.robot.solid:
            for p in self._body_points:
                rest = np.nonzero(~hit)[0]
                if not rest.size:
                    break
                d = p - Qi[rest]
                local = d if Ri is None else np.einsum("kji,kj->ki", Ri[rest], d)
                hit[rest] |= self.robot.inside(local)
        return hit

    def _verdict(self, Rs, Q) -> np.ndarray:
        out = self._contact(Rs, Q)
        free = np.nonzero(~out)[0]
        out[free] = self._contained(Rs, Q, free)
        return out

    def collides(self, q) -> np.ndarray:
        """(k,) bool: the robot with its reference point at ``q`` (k, 3) meets some body."""
        return self._verdict(None, FclOracle._q(q))

    def collides_poses(self, rotations, positions) -> np.ndarray:
        """(k,) bool for ``(k, 3, 3)`` rotations about the reference point and ``(k, 3)``
        reference-point positions."""
        Q = FclOracle._q(positions)
        Rs = np.ascontiguousarray(rotations, dtype=np.float64).reshape(-1, 3, 3)
        if len(Rs) != len(Q):
            raise InvalidArgumentError(f"{len(Rs)} rotations but {len(Q)} positions")
        if not np.isfinite(Rs).all():
            from ..errors import NonFiniteError

            raise NonFiniteError("rotations: not finite")
        return self._verdict(Rs, Q)

    def distance(self, q) -> np.ndarray:
        """(k,) float64 FCL distance between the robot at translation ``q`` and the nearest
        body surface (BVH against BVH through the manager); meaningful where the robot is
        free (0 or negative in contact; inside a solid it is the distance to its surface)."""
        fcl, q = self._fcl, FclOracle._q(q)
        out = np.full(len(q), np.inf)
        if not self._objects:
            return out
        rob, mgr = self._robot_obj, self._manager
        for i in range(len(q)):
            rob.setTranslation(q[i])
            data = fcl.DistanceData()
            mgr.distance(rob, data, fcl.defaultDistanceCallback)
            out[i] = data.result.min_distance
        return out


def _hull(V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The convex hull of points as outward triangles (scipy's qhull); flat points: refused."""
    from scipy.spatial import ConvexHull, QhullError

    try:
        h = ConvexHull(V)
    except QhullError as exc:
        raise InvalidMeshError(f"the robot's convex hull is flat or degenerate: {exc}") from None
    F = h.simplices.astype(np.int64)
    T = V[F]
    n = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
    flip = np.einsum("ij,ij->i", n, h.equations[:, :3]) < 0
    F[flip] = F[flip][:, ::-1]
    return np.ascontiguousarray(V), F
