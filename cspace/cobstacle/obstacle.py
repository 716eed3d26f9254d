"""Translational C-space obstacles ``CO = O ⊕ (-R)``: build once, query many.

Queries take translations of the robot's reference point as ``(k, 3)`` float64 arrays
(``(3,)`` also accepted), in scene units, world frame.

A :class:`CSpaceObstacle` holds one C-obstacle in one of two representations behind the same
four queries. The *convex path* (``kind='convex'``, :mod:`cspace.cobstacle.convex`): obstacle and robot convex,
CO their exact Minkowski sum (:func:`cspace.convex_minkowski_sum`) stored as its exact facet
planes ``n . k <= d`` (``n`` primitive int64, ``d`` a Python int, ``k`` in grid units,
``x = step * k`` in scene units). The *mesh path* (``kind='mesh'``, :mod:`cspace.mesh.query`):
a non-convex closed obstacle's C-obstacle ``cspace.minkowski_sum(O, R.reflected(c))``, or any
closed triangle surface (:meth:`CSpaceObstacle.from_mesh`), queried exactly on its float64
coordinates.

Exactness
---------
The queries are exact for the *stored* C-obstacle and arbitrary float64 translations (no
snapping of the queries): a float64 ``q`` is a dyadic rational, so ``n . q - d * step`` has
an exact sign. It is evaluated by a float filter (one matrix product with a rigorous error
bound, semi-static: ``16 eps`` times the same sum on absolute values) and, where the filter
cannot decide, with Python integers (every float is an integer times a power of two). No
tolerance decides anything. The stored C-obstacle is the exact one of the *snapped* inputs
grown by the least box that covers how far snapping moved them (and the float64 rounding of a
stored surface): :mod:`cspace.cobstacle.margin`. It therefore holds the true ``O ⊕ (c - R)`` of the float
input, so a collision is never reported free, and a reported collision is within
``error_bound`` of a true one (``conservative=False``: no growth, two-sided error).
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidQueryError, NonFiniteError, NotConvexError
from ..geometry.exact import Grid
from ..mesh.convex import ConvexPolytope
from ..mesh.operands import (
    _FlatOperand,
    _Mesh,
    _as_convex,
    _closed_2cycle,
    _flat_convex_mesh,
    _hull_excess,
    _is_mesh,
    _mesh_arrays,
    _vertices_of,
    _wider_somewhere,
)
from ..minkowski.cvms import convex_minkowski_sum
from .convex import _ConvexCO, _translations
from .margin import Margin
from .union import _UnionOf

__all__ = ["CSpaceObstacle", "grown_mesh_sum"]


def _flat_operands(obstacle, robot, c, grid, rgrid, margin: Margin):
    """``(C-obstacle polytope, O, R, margin)`` when an operand is a flat convex point set (a
    polygon or a segment): ``O ⊕ (c - R)`` is the hull of the pairwise sums of their points
    (exact on the grid), grown by ``margin``'s box. When both are flat in parallel planes the
    sum is flat too; it is then grown by at least one grid step on every axis (a solid within
    the returned margin's bound: an error that can only add collisions). None when both
    operands have volume, or the obstacle is not a point set or convex mesh."""
    from ..errors import DegenerateError, DuplicateFaceError, NonManifoldError

    def points(obj, name, grid):
        try:
            return _as_convex(obj, grid, name), None
        except (DegenerateError, DuplicateFaceError):
            P = grid.snap(_vertices_of(obj))
            if _is_mesh(obj) and not _flat_convex_mesh(P, _mesh_arrays(obj)[1]):
                raise  # a thin non-convex mesh (a flat L) is not its hull
            return None, P
        except (NotConvexError, NonManifoldError):
            return None, None

    O, o_pts = points(obstacle, "obstacle", grid)
    R, r_pts = points(robot, "robot", rgrid)
    if o_pts is None and r_pts is None:
        return None
    if (O is None and o_pts is None) or (R is None and r_pts is None):
        return None  # a non-convex mesh with a flat operand: NCC-CVMS takes solids only
    A = O.ints if O is not None else o_pts
    B = rgrid.snap(c) - (R.ints if R is not None else r_pts)  # vectors: sums in grid's frame
    sums = (A[:, None, :] + B[None, :, :]).reshape(-1, 3)
    try:
        co = ConvexPolytope.from_ints(margin.grow_ints(sums), grid=grid, name="cobstacle")
    except DegenerateError:
        margin = margin.at_least(1)
        co = ConvexPolytope.from_ints(margin.grow_ints(sums), grid=grid, name="cobstacle")
    return (co, O if O is not None else _FlatOperand(o_pts, grid),
            R if R is not None else _FlatOperand(r_pts, rgrid), margin)


def grown_mesh_sum(A, B, margin: Margin, progress=None, memory=None):
    """``minkowski_sum(A, B ⊕ box)`` with the box of ``margin`` (chosen for the snapping
    deviation alone), and the margin that holds for the float64 surface returned.

    ``B`` is a ConvexPolytope or ``(n, 3)`` grid ints of a convex set of vectors (``c - r``)
    on ``margin.grid``'s step; a
    flat one (a panel, a rod) is grown by at least one step on every axis, so that the sum has
    a solid operand (an error that only adds collisions, within the returned bound).

    The surface's vertices are rounded to float64 (at most half an ulp per coordinate, which
    the sum measures). When the box also covers that rounding the sum is returned as is;
    otherwise (rare: a deviation just below a whole number of steps, or none at all with
    inexact vertices) it is built once more with the box that covers the a-priori rounding
    bound, so that the stored surface holds the true C-obstacle.

    ``memory``: the budget the sum is watched against (:func:`cspace.minkowski_sum`).

    Returns ``(SumPolyhedron, Margin)``.
    """
    from ..errors import DegenerateError
    from ..minkowski.sum import minkowski_sum

    def grown(m: Margin) -> ConvexPolytope:
        if isinstance(B, ConvexPolytope):
            return m.grow(B)
        return ConvexPolytope.from_ints(m.grow_ints(B), grid=m.grid.vectors, name="B")

    try:
        Bg = grown(margin)
    except DegenerateError:  # flat: give it volume
        margin = margin.at_least(1)
        Bg = grown(margin)
    S = minkowski_sum(A, Bg, progress=progress, memory=memory)
    m = margin.with_rounding(S.rounding)
    if not margin.conservative or m.holds_true:
        return S, m
    wider = Margin.for_deviation(margin.deviation, margin.grid, rounded=True)
    wider = Margin(tuple(max(a, b) for a, b in zip(wider.steps, margin.steps)),
                   wider.deviation, wider.grid, wider.rounding)
    S = minkowski_sum(A, grown(wider), progress=progress, memory=memory)
    return S, wider.with_rounding(S.rounding)


class CSpaceObstacle:
    """One translational C-obstacle ``CO = O ⊕ (-R)``, exact, with vectorised queries.

    Build with :meth:`build` (or wrap a closed C-obstacle surface with :meth:`from_mesh`).
    The robot with its reference point at ``q`` meets the obstacle (touching counts) exactly
    when ``q`` is in the closed set CO.

    Attributes
    ----------
    polytope : ConvexPolytope or None
        The C-obstacle (convex path), exact grid vertices and primitive integer normals;
        None on the mesh path.
    obstacle : ConvexPolytope, ClosedMesh or None
        The snapped obstacle (a ClosedMesh when non-convex).
    robot : ConvexPolytope or None
        The snapped robot (in its own frame, reference point not subtracted).
    reference_point : (3,) float64
        The robot's reference point, snapped to the grid.
    grid : Grid
    kind : {'convex', 'mesh', 'union'}
        The representation: exact facet planes, a closed triangle surface
        (:class:`cspace.mesh.query.MeshCO`) for non-convex C-obstacles, or the union of
        several (``parts``; an obstacle whose pieces meet at non-manifold edges or vertices).
    margin : Margin
        The outward rounding it was grown by (:mod:`cspace.cobstacle.margin`); ``error_bound``.
    excess : float
        How far the hulls standing for operands that snapping bent may exceed the snapped
        operands (the obstacle's and the robot's :attr:`ConvexPolytope.excess`, from
        :func:`cspace.mesh.convex.convex_within_bound`); a hull holds its body, so this only adds
        collisions. Counted in ``error_bound``; 0 when no hull stands for a bent body.
    sum : SumPolyhedron or None
        The ``cspace.minkowski_sum`` result a mesh C-obstacle was built from (provenance,
        holes, non-manifold features), when built by :meth:`build`.

    Notes
    -----
    Every query validates its input once: ``(3,)`` or ``(k, 3)`` float64, and raises
    :class:`~cspace.errors.NonFiniteError` naming the first row with a NaN or inf.

    Examples
    --------
    >>> import numpy as np
    >>> cube = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    >>> co = CSpaceObstacle.build(cube, 0.5 * cube, reference_point=(0.25, 0.25, 0.25))
    >>> co.bounds.tolist()
    [[-0.25, -0.25, -0.25], [1.25, 1.25, 1.25]]
    >>> co.contains([1.25, 0.5, 0.5]), co.contains([np.nextafter(1.25, 2), 0.5, 0.5])
    (True, False)
    >>> co.segment_free([-1, 1.25, 0.5], [2, 1.25, 0.5])  # slides along a facet: touches
    False
    >>> co.first_contact([-1, 0.5, 0.5], [2, 0.5, 0.5]), co.signed_distance([2, 0.5, 0.5])
    (0.25, 0.75)

    Measured here (numpy, one core, a 103-facet CO, batches of 10^5 to 10^6): ``contains``
    about 6e6 queries/s (7.7e4/s when every query is exactly on the boundary, all exact
    fallback); ``signed_distance`` 1.5e5/s; ``segment_free`` 5.5e5 segments/s, about 40 us
    for one segment per call (numpy call overhead; 30 us on a box CO); ``first_contact``
    3.7e5/s; one ``contains`` per call about 20 us. Mesh path (12848 and 3816 triangles,
    ``benchmarks/reports/queries.md``): ``contains`` 6e6 to 8.7e6/s, ``signed_distance``
    2.8e5 to 3.9e5/s, ``segment_free`` 1e6 to 1.5e6/s, one ``contains`` call about 4 us.
    """

    excess = 0.0  # hulls of bent operands (each construction that uses one sets it)

    def __init__(
        self, polytope: ConvexPolytope, *, obstacle=None, robot=None, reference_point=None,
        margin: Margin | None = None,
    ):
        self.polytope = polytope
        self.margin = margin if margin is not None else Margin.none(polytope.grid)
        self.obstacle = obstacle
        self.robot = robot
        self.reference_point = (
            np.zeros(3)
            if reference_point is None
            else np.asarray(reference_point, dtype=np.float64)
        )
        self.grid = polytope.grid
        self.kind = "convex"
        self.sum = None
        self._engine = None  # made on the first query (most of a scene's are never asked)

    @property
    def _impl(self):
        """The query engine (a convex C-obstacle's plane tests are made when first asked)."""
        if self._engine is None:
            self._engine = _ConvexCO(self.polytope)
        return self._engine

    @_impl.setter
    def _impl(self, engine) -> None:
        self._engine = engine

    @classmethod
    def from_mesh(
        cls, vertices, faces, *, obstacle=None, robot=None, reference_point=(0.0, 0.0, 0.0),
        grid: Grid | None = None, sum=None, name: str = "cobstacle", margin: Margin | None = None,
    ) -> "CSpaceObstacle":
        """Wrap a closed triangle surface as a C-obstacle (``kind='mesh'``).

        Parameters
        ----------
        vertices : (n, 3) float64
        faces : (m, 3) int64
            A closed 2-cycle (every directed edge balanced by its reverse), counter-clockwise
            seen from outside; several shells (holes facing inwards) and non-manifold edges
            are allowed. Queries are exact on these float64 coordinates.
        obstacle, robot : optional
            The operands it is the C-obstacle of (used by :func:`cspace.check.cross_check.cross_check`).
        reference_point : (3,) float64
        grid : Grid, optional
            Default ``Grid.for_points(vertices)`` (kept for reference; queries do not snap).
        sum : SumPolyhedron, optional
        name : str
            Used in error messages.
        margin : Margin, optional
            How the surface was grown from its operands (default: not at all).

        Raises
        ------
        InvalidMeshError, OpenMeshError, NonFiniteError, EmptyMeshError
            Bad arrays, named (see :class:`cspace.mesh.query.MeshCO`).
        """
        from ..mesh.query import MeshCO

        impl = MeshCO(vertices, faces, name=name)
        self = cls.__new__(cls)
        self.polytope = None
        self.obstacle = obstacle
        self.robot = robot
        self.reference_point = np.asarray(reference_point, dtype=np.float64).reshape(3)
        self.grid = grid if grid is not None else Grid.for_points(impl.vertices)
        self.margin = margin if margin is not None else Margin.none(self.grid)
        self.kind = "mesh"
        self.sum = sum
        self._impl = impl
        self._facets = None  # polygon facets when known without the sum (a cached sum's)
        return self

    @classmethod
    def build(
        cls, obstacle, robot, reference_point=(0.0, 0.0, 0.0), *, grid: Grid | None = None,
        progress=None, conservative: bool = True,
    ) -> "CSpaceObstacle":
        """Compute ``CO = O ⊕ (c - R)`` exactly, grown just enough to hold the true one.

        A convex obstacle gives a convex C-obstacle (``kind='convex'``, CVMS); a non-convex
        closed mesh gives ``cspace.minkowski_sum(O, R.reflected(c))`` held as a closed
        surface (``kind='mesh'``, exact queries by :mod:`cspace.mesh.query`).

        Parameters
        ----------
        obstacle : ConvexPolytope, (n, 3) float64 points, or a closed mesh
            Points are hulled; a mesh (ClosedMesh, trimesh, ``(vertices, faces)``, path)
            may be non-convex, and may touch itself at edges or vertices (two boxes sharing
            an edge: split there, the C-obstacle is the union of the pieces'). Coplanar or
            collinear points (a panel, a rod) are a flat convex operand.
        robot : ConvexPolytope, (n, 3) float64 points, or a closed convex mesh
            In its own frame; flat points (a panel, a rod) too: against a convex obstacle the
            C-obstacle is the hull of the pairwise sums, against a non-convex one the robot
            is thickened by at least one grid step (within ``error_bound``).
        reference_point : (3,) float64
            The robot point whose position ``q`` is planned (robot frame).
        grid : Grid, optional
            The obstacle's (and the C-obstacle's) snapping grid; default
            ``Grid.for_cobstacle``: centred on the C-obstacle when that is finer, so that
            precision follows its size, not its distance from the origin. The robot is
            snapped on the same step (about its reference point when far from the grid).
        progress : callable, optional
            ``progress(fraction, stage)`` during a non-convex build (see ``minkowski_sum``).
        conservative : bool, default True
            Grow the C-obstacle of the snapped operands by the least box (:mod:`cspace.cobstacle.margin`)
            that makes it hold the C-obstacle of the float input, so that no translation is
            ever reported free that is not (every error is a false collision within
            :attr:`error_bound`). Inputs on the grid get no growth where the result is stored
            exactly (convex path). False: the exact C-obstacle of the snapped operands, whose
            error is two-sided.

        Returns
        -------
        CSpaceObstacle
            ``margin`` says by how much it was grown; ``error_bound`` how far a reported
            collision can be from a true one.

        Raises
        ------
        NotConvexError
            The robot mesh is not convex.
        NonFiniteError, EmptyMeshError, DegenerateError, OpenMeshError
            Bad operands.
        """
        c = np.asarray(reference_point, dtype=np.float64).reshape(3)
        if not np.isfinite(c).all():
            raise NonFiniteError(f"reference_point is not finite: {c.tolist()}")
        if grid is None:
            grid = Grid.for_cobstacle(_vertices_of(obstacle), _vertices_of(robot), c)
        m = Margin.for_operands(grid, _vertices_of(obstacle), _vertices_of(robot), c[None, :],
                                rounded=False)
        return cls._grown(obstacle, robot, c, grid, m if conservative else m.without_growth(),
                          progress)

    @classmethod
    def _grown(cls, obstacle, robot, c, grid: Grid, margin: Margin, progress=None):
        """:meth:`build` with the margin decided (from the float operands)."""
        from ..errors import DegenerateError, NonManifoldError, SelfIntersectionError
        from ..mesh.closed import as_mesh

        rgrid = grid.for_robot(_vertices_of(robot), c)
        c_snapped = rgrid.to_float(rgrid.snap(c))
        try:
            flat = _flat_operands(obstacle, robot, c, grid, rgrid, margin)
        except DegenerateError as exc:  # a non-convex mesh flat on the grid (a thin L plate)
            return cls._thin(obstacle, robot, c, grid, rgrid, margin, exc)
        if flat is not None:
            co, O, R, m = flat
            out = cls(co, obstacle=O, robot=R, reference_point=c_snapped, margin=m)
            out.excess = _hull_excess(O, R)
            # FCL's view: each operand a solid where it has volume, a surface where flat.
            o_flat, r_flat = isinstance(O, _FlatOperand), isinstance(R, _FlatOperand)
            out.semantics = (not o_flat, "surface" if r_flat else "convex")
            return out
        try:
            R = _as_convex(robot, rgrid, "robot")
        except DegenerateError:  # flat, against a non-convex obstacle: NCC-CVMS thickens it
            R = _FlatOperand(rgrid.snap(_vertices_of(robot)), rgrid)
        try:
            O = _as_convex(obstacle, grid, "obstacle")
        except (NotConvexError, NonManifoldError):
            try:
                O = as_mesh(obstacle, grid=grid, name="obstacle")
            except NonManifoldError as exc:  # pieces meeting at edges or vertices: one CO each
                return cls._of_parts(obstacle, robot, c, grid, margin, progress, exc)
            except DegenerateError as exc:  # thinner than a grid step somewhere
                return cls._thin(obstacle, robot, c, grid, rgrid, margin, exc)
            B = R.reflected(c) if isinstance(R, ConvexPolytope) else rgrid.snap(c) - R.ints
            try:
                S, m = grown_mesh_sum(O, B, margin, progress)
            except SelfIntersectionError as exc:  # snapping folded it: its surface and inside
                return cls._thin(obstacle, robot, c, grid, rgrid, margin, exc)
            out = cls.from_mesh(S.vertices, S.faces, obstacle=O, robot=R,
                                reference_point=c_snapped, grid=grid, sum=S, margin=m)
            out.excess = _hull_excess(R)
            if isinstance(R, _FlatOperand):
                out.semantics = (True, "surface")
            return out
        co = convex_minkowski_sum(O, margin.grow(R).reflected(c)).polytope
        out = cls(co, obstacle=O, robot=R, reference_point=c_snapped, margin=margin)
        out.excess = _hull_excess(O, R)
        return out

    @classmethod
    def _thin(cls, obstacle, robot, c, grid: Grid, rgrid: Grid, margin: Margin, why):
        """A closed obstacle whose snapped solid does not exist (features thinner than a grid
        step, a plate 1e-9 thick; or a surface that snapping folds through itself) while its
        surface does. The C-obstacle of a closed solid is that of its surface, ``union over
        triangles t of t ⊕ (c - R)`` (each piece grown by ``margin``: ``kind='union'``, one
        convex piece per triangle), plus the positions where the robot lies wholly inside it:
        when the robot fits in the obstacle's box, the containment term ``O + c - r`` for one
        robot vertex r, a mesh C-obstacle on the snapped closed 2-cycle whose inside is its
        non-zero winding number (exact). Snapping moves the surface by at most the snapping
        bound, so away from it the snapped winding number is the input's, and a robot nearer
        to it meets the grown pieces. Not a closed 2-cycle: ``why`` (the named error the
        snapped solid gave) stands.
        """
        from ..errors import DegenerateError

        if not _is_mesh(obstacle):
            raise why
        V, F = _mesh_arrays(obstacle)
        cycle = (_closed_2cycle(V, F) if F.ndim == 2 and F.shape[1:] == (3,) and len(F)
                 else None)
        if cycle is None:
            raise why  # not a closed surface: the snapped solid's error is the answer
        Rv = np.asarray(_vertices_of(robot), dtype=np.float64).reshape(-1, 3)
        try:
            hull = _as_convex(robot, rgrid, "robot")
            excess, R = _hull_excess(hull), margin.grow(hull)
        except DegenerateError:  # a flat robot: give it volume
            excess = 0.0
            margin = margin.at_least(1)
            R = ConvexPolytope.from_ints(margin.grow_ints(rgrid.snap(Rv)), grid=rgrid, name="robot")
        B = R.reflected(c)
        T = grid.snap(V)[np.asarray(F, np.int64)]
        c_snapped = rgrid.to_float(rgrid.snap(c))
        cos = []
        for k, t in enumerate(T):
            piece = ConvexPolytope.from_ints((t[:, None, :] + B.ints[None]).reshape(-1, 3),
                                             grid=grid.plus(B.grid), name=f"triangle {k}")
            co = cls(piece, obstacle=_FlatOperand(t, grid), robot=R, reference_point=c_snapped,
                     margin=margin)
            co.excess = excess
            co.semantics = (False, "convex")  # FCL: the obstacle's triangles, as a surface
            cos.append(co)
        U, G = cycle
        if not _wider_somewhere(Rv, U):  # the robot may lie wholly inside: what O encloses
            ints = grid.snap(U) + (rgrid.snap(c) - rgrid.snap(Rv[0]))  # O + c - r, exact
            co = cls.from_mesh(grid.to_float(ints), G, obstacle=_Mesh(U, G, "obstacle"),
                               robot=R, reference_point=c_snapped, grid=grid, margin=margin,
                               name="containment")
            co.excess = excess
            co.semantics = (True, "convex")  # FCL: the obstacle as the solid it encloses
            cos.append(co)
        out = cls.union(cos)
        out.thin = str(why)
        return out

    @classmethod
    def _of_parts(cls, obstacle, robot, c, grid: Grid, margin: Margin, progress=None,
                  why=None):
        """A closed obstacle whose pieces meet at non-manifold edges or vertices (two boxes
        sharing an edge): split there into closed manifold pieces (exactly, as scenes are,
        :func:`cspace.mesh.components.split_mesh`); the C-obstacle is the union of theirs. One
        part (a surface pinched at a vertex, not split apart): ``why`` stands."""
        from ..mesh.components import split_mesh
        from ..errors import NonManifoldError

        parts = split_mesh(*_mesh_arrays(obstacle), grid)
        if len(parts) < 2 and why is not None:
            raise why
        cos = []
        for k, piece in enumerate(parts):
            try:
                cos.append(cls._grown(piece, robot, c, grid, margin, progress))
            except NonManifoldError as exc:  # a part pinched at a vertex
                raise NonManifoldError(f"obstacle: piece {k} of {len(parts)}: {exc}") from None
        return cls.union(cos)

    @classmethod
    def union(cls, cos: list) -> "CSpaceObstacle":
        """One C-obstacle answering for several (their union, not built): ``contains`` and
        ``segment_free`` over all, ``first_contact`` the earliest, ``signed_distance`` the
        least (inside: minus the deepest containing one's depth, a lower bound on the union's).
        ``kind='union'``; ``parts`` holds them."""
        if len(cos) == 1:
            return cos[0]
        self = cls.__new__(cls)
        self.parts = list(cos)
        first = cos[0]
        self.polytope, self.sum, self.kind = None, None, "union"
        self.obstacle = _Mesh.join([co.obstacle for co in cos])
        self.robot, self.reference_point, self.grid = first.robot, first.reference_point, first.grid
        self.margin = max((co.margin for co in cos), key=lambda m: m.error_bound)
        self.semantics = getattr(first, "semantics", None)
        self._impl = _UnionOf(cos)
        return self

    # ---- properties ---------------------------------------------------------------------

    @property
    def n_facets(self) -> int:
        """Polygon facets (mesh path: of the SumPolyhedron if known, else triangles)."""
        if self.polytope is not None:
            return self.polytope.n_facets
        if self.sum is not None and len(self.sum.face_facet):
            return int(self.sum.face_facet.max()) + 1
        if getattr(self, "_facets", None) is not None:
            return self._facets
        return len(self._impl.faces)

    @property
    def vertices(self) -> np.ndarray:
        """(n, 3) float64 vertices of the C-obstacle (exact on the convex path; the stored
        float64 surface, on which queries are exact, on the mesh path)."""
        if self.polytope is None:
            return self._impl.vertices
        return self.polytope.vertices

    @property
    def faces(self) -> np.ndarray:
        """(m, 3) int64 triangles of the C-obstacle's boundary, counter-clockwise from outside."""
        if self.polytope is None:
            return self._impl.faces
        return self.polytope.faces

    @property
    def bounds(self) -> np.ndarray:
        """(2, 3) float64 bounding box of the C-obstacle."""
        if self.polytope is not None:  # exact: to_float is monotone and exact on grid points
            k = self.polytope.ints
            return self.grid.to_float(np.stack([k.min(axis=0), k.max(axis=0)]))
        V = self.vertices
        return np.stack([V.min(axis=0), V.max(axis=0)])

    @property
    def error_bound(self) -> float:
        """How far (scene units) a translation reported in collision can be from the true
        C-obstacle of the float input: :attr:`margin`'s bound plus :attr:`excess` (a hull
        standing for a body that snapping bent); a union's is the largest of its parts'.
        Built with ``conservative=True`` the error is one-sided: every true collision is
        reported."""
        parts = getattr(self, "parts", None)
        if self.kind == "union" and parts:
            return max(co.error_bound for co in parts)
        return self.margin.error_bound + self.excess

    def __repr__(self) -> str:
        return (
            f"CSpaceObstacle(kind={self.kind!r}, facets={self.n_facets}, "
            f"vertices={len(self.vertices)})"
        )

    def to_trimesh(self):
        """The C-obstacle's boundary triangles as a ``trimesh.Trimesh`` (float64, not
        re-processed; for a union of pieces, their overlapping boundaries)."""
        import trimesh

        return trimesh.Trimesh(self.vertices, self.faces, process=False)

    # ---- queries ------------------------------------------------------------------------

    def contains(self, q) -> np.ndarray | bool:
        """Is the robot at translation ``q`` in collision (``q`` in the closed CO)?

        Exact for every float64 ``q`` (no snapping, no tolerance); the boundary counts as
        inside (touching is a collision). Convex path: one ``(k, 4) x (4, f)`` product and a
        max; rows within the filter's bound of a facet plane are decided with Python integers.
        Mesh path: on a triangle, or a non-zero winding number from a symbolically perturbed
        ray (see :mod:`cspace.mesh.query`).

        Parameters
        ----------
        q : (k, 3) or (3,) float64

        Returns
        -------
        inside : (k,) bool, or a Python bool for a ``(3,)`` input
        """
        q, single = _translations(q)
        out = self._impl.contains(q)
        return bool(out[0]) if single else out

    def plane_signs(self, q) -> np.ndarray:
        """Exact ``(k, f)`` int8 side of each ``q`` against each facet plane (+1 outside it)."""
        if self.kind != "convex":
            raise TypeError(f"plane_signs is defined for a convex C-obstacle, not kind {self.kind!r}")
        q, _ = _translations(q)
        return self._impl.plane_signs(q)

    def signed_distance(self, q) -> np.ndarray | float:
        """Euclidean distance from ``q`` to the CO boundary, negative inside.

        The sign is exact (:meth:`contains`; boundary points give ``-0.0`` or ``0.0``).
        Outside: the distance to the nearest point of the polytope, the minimum over facets
        whose projection holds ``q`` (plane distance) and over all edges (segment distance).
        Inside: ``-min_j (d_j - n_j . q) / |n_j|``, the exact translational penetration depth
        of a convex C-obstacle (the shortest translation that frees the robot).

        The magnitude is computed in float64 on coordinates centred on the CO: its error is
        a few ulps of ``r + |q - centre|`` (``r`` the CO's radius); the a-priori bound used
        in the tests is ``64 eps (r + |q - centre|)`` (checked against FCL, see
        :mod:`cspace.check`). Mesh path: the distance to the nearest triangle, outside
        and inside alike (inside, the translational penetration depth of the C-obstacle).

        Parameters
        ----------
        q : (k, 3) or (3,) float64

        Returns
        -------
        distance : (k,) float64, or a float for a ``(3,)`` input
        """
        q, single = _translations(q)
        out = self._signed_distance(q)
        return float(out[0]) if single else out

    def _signed_distance(self, q: np.ndarray) -> np.ndarray:
        return self._impl.signed_distance(q)

    def segment_free(self, q0, q1) -> np.ndarray | bool:
        """Does the straight translation from ``q0`` to ``q1`` stay out of CO?

        An exact continuous check, no sampling. Mesh path: the closed segment meets CO iff it
        meets a triangle (exact segment-triangle tests, coplanar and touching included) or
        ``q0`` is inside. Convex path: the closed segment misses the closed convex
        CO iff no ``t`` in ``[0, 1]`` satisfies every facet inequality. The parameter interval
        is clipped facet by facet; each clip is a ratio of two plane values whose signs are
        exact (float filter), the interval test uses ratios with rigorous error bounds, and
        segments the filter cannot decide (touching, lying in a facet plane, ...) are redone
        with Python integers and fractions. Touching counts as a collision (not free). A
        zero-length segment is free iff ``not contains(q0)``.

        Parameters
        ----------
        q0, q1 : (k, 3) or (3,) float64
            Start and end translations (broadcast to a common ``(k, 3)``).

        Returns
        -------
        free : (k,) bool, or a Python bool if both inputs are ``(3,)``
        """
        q0, q1, single = self._pair(q0, q1)
        hit, _ = self._impl.segments(q0, q1, want_t=False)
        return bool(not hit[0]) if single else ~hit

    def first_contact(self, q0, q1) -> np.ndarray | float:
        """Parameter ``t`` in ``[0, 1]`` of the first contact along ``q0 + t (q1 - q0)``.

        The exact entry parameter (a rational) rounded to the nearest float64; ``0.0`` when
        ``q0`` is in CO (touching included); NaN when the segment stays free.

        Parameters
        ----------
        q0, q1 : (k, 3) or (3,) float64

        Returns
        -------
        t : (k,) float64, or a float if both inputs are ``(3,)``

        Notes
        -----
        Free segments are decided by the float filter; each colliding segment is resolved
        exactly with Python integers (about ``f`` fraction operations).
        """
        q0, q1, single = self._pair(q0, q1)
        _, t = self._impl.segments(q0, q1, want_t=True)
        return float(t[0]) if single else t

    @staticmethod
    def _pair(q0, q1):
        a, s0 = _translations(q0, "q0")
        b, s1 = _translations(q1, "q1")
        if len(a) != len(b):
            if len(a) == 1:
                a = np.broadcast_to(a, b.shape)
            elif len(b) == 1:
                b = np.broadcast_to(b, a.shape)
            else:
                raise InvalidQueryError(f"q0 and q1 have {len(a)} and {len(b)} rows")
        return np.ascontiguousarray(a), np.ascontiguousarray(b), s0 and s1
