"""OMPL adapter: exact C-space validity and motion checking for translational planning.

The robot's configuration is the ``(3,)`` float64 translation of its reference point, an OMPL
``RealVectorStateSpace(3)`` state bounded by the scene's ``(2, 3)`` bounds.

- :class:`CSpaceValidityChecker`: a state is valid iff it is inside the bounds and not in any
  closed C-obstacle (:meth:`cspace.CSpace.contains`, exact; touching is invalid).
- :class:`CSpaceMotionValidator`: a motion is valid iff its end state is valid and the
  straight segment misses every closed C-obstacle (:meth:`cspace.CSpace.segment_free`, an
  exact continuous check, no sampling resolution).
- :func:`cspace.planning.plan.plan` → :class:`~cspace.planning.plan.PlanResult`: solve with any bound geometric planner, simplify, and
  re-prove the returned path exactly (every waypoint and every segment) before reporting it.

This is the only module of cspace that imports ``ompl`` (imported here, at use of
the planners in :mod:`cspace.planning.plan` or the classes; OMPL 2.0.1 nanobind bindings). Callbacks return real Python
``bool`` (OMPL 2.0.1 raises on ``np.bool_``). ``solve()`` holds the GIL.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidArgumentError
from ..scene.model import CSpace

__all__ = ["state_space", "planner_names", "verify_path", "narrow_passage_samples"]


def _ompl():
    try:
        from ompl import base as ob, geometric as og, util as ou
    except ImportError as exc:  # pragma: no cover
        raise ImportError("cspace.planning.ompl_plugin needs OMPL's Python bindings (ompl>=2.0)") from exc
    return ob, og, ou


def planner_names() -> tuple[str, ...]:
    """Names of the geometric planners bound in ``ompl.geometric`` (sorted)."""
    ob, og, _ = _ompl()
    return tuple(sorted(
        n for n in dir(og)
        if isinstance(getattr(og, n), type) and issubclass(getattr(og, n), ob.Planner)
    ))


def _vec(state) -> np.ndarray:
    return np.array([state[0], state[1], state[2]], dtype=np.float64)


def _bounds(bounds) -> np.ndarray:
    b = np.array(bounds, dtype=np.float64)
    if b.shape != (2, 3):
        raise InvalidArgumentError(f"bounds must be (2, 3), got shape {b.shape}")
    # A flat axis (lower == upper) fixes that coordinate: a planar problem in 3D (OMPL.app's
    # 2D problems have z bounds [0, 0]). At least one axis must be free.
    if not np.isfinite(b).all() or (b[0] > b[1]).any() or not (b[0] < b[1]).any():
        raise InvalidArgumentError("bounds must be finite with lower <= upper on every axis and "
                         f"lower < upper on at least one, got {b.tolist()}")
    return b


def _in_bounds(q: np.ndarray, b: np.ndarray) -> np.ndarray:
    q = np.atleast_2d(q)
    return ((b[0] <= q) & (q <= b[1])).all(axis=1)


# --------------------------------------------------------------------------------------
# checker classes (built lazily: the base classes come from ompl)

_CLASSES: dict[str, type] = {}


def _classes() -> dict[str, type]:
    if _CLASSES:
        return _CLASSES
    ob, _, _ = _ompl()

    class CSpaceValidityChecker(ob.StateValidityChecker):
        """Exact state validity: inside ``bounds`` and ``not cspace.contains(q)``.

        Parameters
        ----------
        si : ompl.base.SpaceInformation
            Over a ``RealVectorStateSpace(3)``.
        cspace : CSpace
        clearance : bool, default False
            Whether :meth:`clearance` reports ``cspace.signed_distance(q)`` (exact sign;
            float64 magnitude) instead of OMPL's default.
        bounds : (2, 3) float64, optional
            Default ``cspace.bounds``.

        Attributes
        ----------
        calls : int
            Number of :meth:`isValid` calls (OMPL's own counters miss Python checkers).
        """

        def __init__(self, si, cspace: CSpace, *, clearance: bool = False, bounds=None):
            super().__init__(si)
            self.cspace = cspace
            b = _bounds(cspace.bounds if bounds is None else bounds)
            self._lo, self._hi = b[0].tolist(), b[1].tolist()
            self._clearance = bool(clearance)
            self.calls = 0

        def isValid(self, state) -> bool:
            self.calls += 1
            lo, hi = self._lo, self._hi
            x, y, z = state[0], state[1], state[2]
            if not (lo[0] <= x <= hi[0] and lo[1] <= y <= hi[1] and lo[2] <= z <= hi[2]):
                return False
            # The C-space's own broad phase (a box tree over its C-obstacles), which also
            # builds a lazy C-space's pairs where the state meets them.
            return not self.cspace.contains(np.array((x, y, z)))

        def clearance(self, state) -> float:
            if not self._clearance:
                return 0.0
            return float(self.cspace.signed_distance(_vec(state)))

    class CSpaceMotionValidator(ob.MotionValidator):
        """Exact motion validity: the end state is valid and the segment is free.

        ``checkMotion(s1, s2)`` is ``checker.isValid(s2)`` and ``cspace.segment_free(q1, q2)``:
        a continuous check with no resolution (touching counts as a collision). Bounds are
        convex, so a segment between in-bounds states stays in bounds. Only the two-argument
        form reaches Python in OMPL 2.0.1.

        Parameters
        ----------
        si : ompl.base.SpaceInformation
        cspace : CSpace
        checker : CSpaceValidityChecker, optional
            Decides the end state; default a new one on ``cspace`` (its bounds).

        Attributes
        ----------
        calls : int
            Number of :meth:`checkMotion` calls.
        """

        def __init__(self, si, cspace: CSpace, checker=None):
            super().__init__(si)
            # Holding ``si`` here would make a reference cycle through C++ (a leak).
            self.checker = checker if checker is not None else CSpaceValidityChecker(si, cspace)
            self.cspace = cspace
            self.calls = 0

        def checkMotion(self, s1, s2, *last_valid) -> bool:
            self.calls += 1
            if not self.checker.isValid(s2):
                return False
            return bool(self.cspace.segment_free(np.array((s1[0], s1[1], s1[2])),
                                                 np.array((s2[0], s2[1], s2[2]))))

    _CLASSES["CSpaceValidityChecker"] = CSpaceValidityChecker
    _CLASSES["CSpaceMotionValidator"] = CSpaceMotionValidator
    return _CLASSES


def __getattr__(name: str):
    # CSpaceValidityChecker / CSpaceMotionValidator subclass ompl classes: import ompl on use.
    if name in ("CSpaceValidityChecker", "CSpaceMotionValidator"):
        return _classes()[name]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


# --------------------------------------------------------------------------------------
# exact path verification


def _box_bounds(ob, lo, hi):
    """OMPL ``RealVectorBounds`` of the box ``[lo, hi]`` (one entry per axis)."""
    rb = ob.RealVectorBounds(len(lo))
    for k, (a, b) in enumerate(zip(lo, hi)):
        rb.setLow(k, float(a))
        rb.setHigh(k, float(b))
    return rb


def state_space(bounds):
    """An OMPL ``RealVectorStateSpace(3)`` of translations bounded by ``(2, 3)`` ``bounds``
    (scene units): the space the checker and motion validator work on."""
    ob = _ompl()[0]
    b = _bounds(bounds)
    space = ob.RealVectorStateSpace(3)
    space.setBounds(_box_bounds(ob, b[0], b[1]))
    return space


def verify_path(cspace: CSpace, path, bounds=None) -> dict:
    """Re-prove a piecewise-linear path exactly.

    Parameters
    ----------
    cspace : CSpace
    path : (n, 3) float64
        Waypoints (translations of the reference point).
    bounds : (2, 3) float64, optional
        Default ``cspace.bounds``.

    Returns
    -------
    report : dict
        ``valid`` (bool: every waypoint in bounds and outside every closed C-obstacle, every
        segment ``segment_free``); ``bad_waypoints`` and ``bad_segments``, ``(j,) int64``
        indices (segment ``i`` joins waypoints ``i`` and ``i + 1``).
    """
    P = np.asarray(path, dtype=np.float64).reshape(-1, 3)
    b = _bounds(cspace.bounds if bounds is None else bounds)
    bad_w = np.nonzero(~_in_bounds(P, b) | cspace.contains(P))[0].astype(np.int64)
    if len(P) > 1:
        bad_s = np.nonzero(~cspace.segment_free(P[:-1], P[1:]))[0].astype(np.int64)
    else:
        bad_s = np.zeros(0, dtype=np.int64)
    return {"valid": bool(len(P) > 0 and not bad_w.size and not bad_s.size),
            "bad_waypoints": bad_w, "bad_segments": bad_s}


# --------------------------------------------------------------------------------------
# narrow passages


def narrow_passage_samples(cspace: CSpace, bounds=None, *, per_obstacle: int = 40000,
                           gap: float = 0.01, seed: int | None = 0,
                           total: int = 400_000) -> np.ndarray:
    """Free translations in narrow gaps between C-obstacles, found on their boundaries.

    Points are drawn on each C-obstacle's boundary triangles (area-weighted) and moved out
    along the triangle's normal by ``1e-4`` of the bounds' diagonal. A point is kept when it
    is in the bounds and free, and the point ``gap`` times the diagonal further along the
    normal is in collision: it lies in a gap narrower than that (a window, a slot, a cavity's
    entrance). Both tests are the exact :meth:`CSpace.contains`; only the positions are float.

    Parameters
    ----------
    cspace : CSpace
    bounds : (2, 3) float64, optional
        Default ``cspace.bounds``.
    per_obstacle : int
        Boundary points drawn per C-obstacle, at most.
    gap : float
        Widest gap kept, as a fraction of the bounds' diagonal.
    seed : int, optional
    total : int, default 400000
        Boundary points drawn in all, at most (a scene of many C-obstacles draws fewer on
        each, at least 100): two exact ``contains`` per point, so the pool's cost is bounded.

    Notes
    -----
    Triangle-pair C-obstacles (``kind='pairs'``, a non-convex robot part) have no boundary
    mesh, only overlapping pieces whose hulls cost about 0.6 ms a pair to make: points are
    drawn on the hulls of at most 256 random pieces of each (``PairObstacle.sample_mesh``).

    Returns
    -------
    (k, 3) float64
        Valid states (exactly collision-free, in bounds); possibly none.
    """
    b = _bounds(cspace.bounds if bounds is None else bounds)
    rng = np.random.default_rng(seed)
    diag = float(np.linalg.norm(b[1] - b[0]))
    out = []
    per_obstacle = min(per_obstacle, max(100, total // max(1, len(cspace.obstacles))))
    for o in cspace.obstacles:
        V, F = o.sample_mesh(rng) if o.kind == "pairs" else (o.vertices, o.faces)
        T = V[F]
        normal = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
        area = np.linalg.norm(normal, axis=1)
        ok = area > 0
        if not ok.any():
            continue
        T, normal, area = T[ok], normal[ok] / area[ok, None], area[ok]
        pick = rng.choice(len(T), per_obstacle, p=area / area.sum())
        w = rng.dirichlet(np.ones(3), per_obstacle)
        P = np.einsum("ki,kij->kj", w, T[pick]) + 1e-4 * diag * normal[pick]
        keep = _in_bounds(P, b)
        P, n = P[keep], normal[pick][keep]
        free = ~cspace.contains(P)
        P, n = P[free], n[free]
        out.append(P[cspace.contains(P + gap * diag * n)])
    return np.vstack(out) if out else np.zeros((0, 3))


def _pool_sampler(si, pool: np.ndarray, seed: int | None):
    """A ValidStateSampler: half the time a pool state, else OMPL's uniform valid sampler."""
    ob, _, _ = _ompl()
    rng = np.random.default_rng(seed)
    rows = pool.tolist()

    class PoolSampler(ob.ValidStateSampler):
        def __init__(self, si_):
            super().__init__(si_)
            self.uniform = ob.UniformValidStateSampler(si_)

        def sample(self, state) -> bool:
            if rows and rng.random() < 0.5:
                x, y, z = rows[int(rng.integers(len(rows)))]
                state[0], state[1], state[2] = x, y, z
                return True
            return bool(self.uniform.sample(state))

        def sampleNear(self, state, near, distance) -> bool:
            return bool(self.uniform.sampleNear(state, near, distance))

    return PoolSampler(si)
