"""What each body of a scene becomes, and why: the classification rules.

:class:`BodyModel` records one obstacle body's kind (``convex``, ``solid``, ``surface``,
``dropped``; :data:`KINDS`) with its reason; :class:`RobotPart` and :class:`PairModel` the robot's
parts and the pairs built between them. :func:`_classify` / :func:`_closed_kind` decide a body
exactly (closed and valid → solid, convex within the stated bound → convex, a folded closed
surface → surface plus what it encloses (:class:`Enclosing`), open → surface), and
:func:`_without_far_parts` drops what lies beyond the planning bounds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from ..cobstacle.obstacle import CSpaceObstacle
from ..cobstacle.pairs import _meets
from ..errors import InvalidMeshError
from ..geometry.exact import Grid
from ..geometry.graphs import component_labels
from ..mesh.closed import ClosedMesh
from ..mesh.components import edge_uses
from ..mesh.convex import ConvexPolytope, convex_within_bound

__all__ = ["KINDS", "BodyModel", "RobotPart", "PairModel"]


KINDS = ("convex", "solid", "surface", "dropped")


@dataclass(eq=False)
class BodyModel:
    """One obstacle body of a scene after modelling.

    Attributes
    ----------
    name : str
        ``<scene body>`` or ``<scene body>#<k>`` when the scene body was split.
    source : str
        The scene body's name.
    kind : {'convex', 'solid', 'surface', 'dropped'}
    reason : str
        Why this kind, in words.
    vertices : (n, 3) float64
        Welded, snapped vertices (world frame).
    faces : (m, 3) int64
        Deduplicated triangles of this body.
    pieces : int
        Surface: triangles whose piece can meet the bounds (built); else 0.
    co : CSpaceObstacle or None
        The built C-obstacle when the robot is one convex part (None if dropped, not built,
        failed, or the robot has several parts: see ``pairs``).
    pairs : list of PairModel
        One per robot part: the construction it got and its C-obstacles.
    seconds : float
        Build (or cache load) time.
    cache : {'hit', 'miss', 'off', ''}
        '' when not built.
    error : str
        Why the build failed ('' if it did not).
    changed : str
        How modelling changed what the body means ('' when it did not): a closed body whose
        snapped surface bounds no valid solid, modelled as its surface and the region it
        encloses (non-zero winding number); a closed but inconsistently wound body modelled
        as its surface (its inside counts as free); or a bent convex body modelled by its hull
        (within a stated excess, counted in ``error_bound``). Announced in the normal output
        of ``cspace build``/``plan`` and in :meth:`cspace.scene.model.SceneModel.explain` alike.
    """

    name: str
    source: str
    kind: str
    reason: str
    vertices: np.ndarray
    faces: np.ndarray
    pieces: int = 0
    co: CSpaceObstacle | None = None
    pairs: list = field(default_factory=list)
    seconds: float = 0.0
    cache: str = ""
    error: str = ""
    changed: str = ""
    _ints: np.ndarray | None = field(default=None, repr=False)
    _solid: object = field(default=None, repr=False)
    _keep: np.ndarray | None = field(default=None, repr=False)
    _encloses: object = field(default=None, repr=False)  # Enclosing of a closed surface
    _sheet: bool = field(default=False, repr=False)  # every triangle listed with both windings
    _kept: bool = field(default=False, repr=False)  # what snapping took, kept (_snapped_body)

    def __repr__(self) -> str:
        return (f"BodyModel({self.name!r}, kind={self.kind!r}, vertices={len(self.vertices)}, "
                f"faces={len(self.faces)}, C-obstacles={len(self.cos)}"
                + (f", error={self.error!r}" if self.error else "") + ")")

    @property
    def cos(self) -> list:
        """Every C-obstacle built for this body (over all robot parts)."""
        return [co for p in self.pairs for co in p.cos]

    def line(self) -> str:
        """One report line: name, kind, sizes, reason, build time and cache."""
        size = f"{len(self.faces)} triangles"
        if self.co is not None:
            size += f" -> CO {self.co.n_facets} facets"
            if self.kind == "surface":
                size += f" in {self.pieces} pieces"
        built = ""
        if self.cache:
            built = f"; built in {self.seconds:.3f} s (cache {self.cache})"
        if self.error:
            built = f"; BUILD FAILED: {self.error}"
        return f"{self.name}: {self.kind} ({size}): {self.reason}{built}"


@dataclass(eq=False)
class RobotPart:
    """One part of the robot after modelling (robot frame, reference point not subtracted).

    Attributes
    ----------
    name : str
        ``<robot>`` or ``<robot>#<k>`` when the robot was split.
    kind : {'convex', 'solid', 'surface'}
    reason : str
    ints : (n, 3) int64
        Welded grid vertices (for ``solid``: the validated mesh's, oriented outwards).
    faces : (m, 3) int64
    grid : Grid
    operand : ConvexPolytope, ClosedMesh, Enclosing or None
        The exact operand: the polytope (convex), the closed mesh (solid), the closed 2-cycle
        of a surface that encloses a region (:class:`Enclosing`) or none (open surface).
    """

    name: str
    kind: str
    reason: str
    ints: np.ndarray
    faces: np.ndarray
    grid: Grid
    operand: object = None

    @property
    def encloses(self):
        """The :class:`Enclosing` cycle of a closed surface part, else None."""
        return self.operand if isinstance(self.operand, Enclosing) else None

    @property
    def vertices(self) -> np.ndarray:
        """(n, 3) float64: the snapped vertices, exactly ``grid.to_float(ints)``."""
        return self.grid.to_float(self.ints)

    def line(self) -> str:
        return f"{self.name}: {self.kind} ({len(self.faces)} triangles): {self.reason}"


@dataclass(eq=False)
class PairModel:
    """An (obstacle body, robot part) pair: its construction and C-obstacles.

    Attributes
    ----------
    part : str
        The robot part's name.
    construction : str
        A key of :data:`cspace.cobstacle.pairs.CONSTRUCTIONS`.
    cos : list of CSpaceObstacle
        Its C-obstacles (convex pieces and containment terms for triangle pairs).
    detail : str
        Sizes: pieces or pairs built, and those left out (flat, out of the bounds).
    seconds : float
    cache : {'hit', 'miss', 'off', ''}
    """

    part: str
    construction: str
    cos: list = field(default_factory=list)
    detail: str = ""
    seconds: float = 0.0
    cache: str = ""

    def line(self) -> str:
        built = f"; {self.seconds:.3f} s (cache {self.cache})" if self.cache else ""
        return (f"x {self.part}: {self.construction}"
                f"{'; ' + self.detail if self.detail else ''}{built}")


# --------------------------------------------------------------------------------------
# steps 1-3: weld, deduplicate, split


# in cspace.mesh.components: weld_dedupe, split_parts (shared with CSpaceObstacle.build)


# --------------------------------------------------------------------------------------
# steps 4-5: drop and classify


def _excess(body) -> float:
    """How far a convex body's (or robot part's) hull may exceed its snapped mesh (0 for the
    others); counted in each C-obstacle's ``excess`` and so in ``error_bound``."""
    return float(getattr(body._solid, "excess", 0.0) or 0.0) if body.kind == "convex" else 0.0


@dataclass(frozen=True, eq=False)
class Enclosing:
    """A closed 2-cycle that bounds no valid solid on the grid (it meets itself, or slivers
    that snapping flattened cannot be repaired): grid vertices and triangles, every directed
    edge balanced by its reverse. The region it encloses is where its winding number is
    non-zero (:class:`cspace.mesh.query.MeshCO`, exact)."""

    ints: np.ndarray
    faces: np.ndarray


def _sheet_kind(P, F):
    """``('surface', why, None)`` for a closed part every triangle of which was listed with
    both windings, else None.

    Such a part is a sheet with two sides, not the boundary of a solid: the winding numbers of
    its two listings cancel (0 everywhere, so it encloses nothing), and FCL's mesh collision
    reads it as a surface. An apartment whose double-sided walls, floor and ceiling happen to
    close up is a set of walls with free space inside, not a solid block.
    """
    edge, count = edge_uses(F, len(P))
    if (count == 1).any():
        return None  # open: the usual reason says so
    return ("surface", "closed, but every triangle is listed with both windings (a double-sided "
            "sheet: winding number 0, it encloses nothing)", None)


def _closed_kind(name, P, F, grid):
    """Kind of a welded part, without bounds: ``(kind, reason, operand)``.

    ``('convex', reason, ConvexPolytope)``, ``('solid', reason, ClosedMesh)``,
    ``('surface', why, Enclosing)`` (closed and oriented, but its snapped surface bounds no
    valid solid: it is modelled as its surface and the region it encloses) or
    ``('surface', why, None)`` (open, or not consistently oriented).

    A closed body whose snapped surface meets itself is never left as a bare surface: that
    would count its inside as free. Snapping moves every point of the surface by at most the
    snapping bound, so away from the surface the snapped winding number is the input's; near
    it, the (grown) triangle pairs hold every contact.
    """
    from ..mesh.query import unbalanced_edge

    # Most bodies of a real scene are exactly convex: one compiled call proves it (what the
    # steps below would conclude, without their Python and numpy per body).
    poly = ConvexPolytope.from_convex_mesh(P, F, grid=grid, name=name)
    if poly is not None:
        return "convex", f"closed and convex ({poly.n_facets} facets)", poly
    edge, count = edge_uses(F, len(P))
    n_boundary = int((count == 1).sum())
    if n_boundary:
        return "surface", f"open: {n_boundary} boundary edges", None
    cycle = Enclosing(P, F) if unbalanced_edge(F, len(P)) is None else None
    V = grid.to_float(P)
    try:
        solid = ClosedMesh.from_arrays(V, F, grid=grid, name=name)
    except InvalidMeshError as exc:
        return "surface", (f"closed but not a valid solid ({type(exc).__name__}: "
                           f"{str(exc).split(': ', 1)[-1]})"), cycle
    from ..mesh.self_intersection import self_intersections

    crossing = self_intersections(solid)
    if len(crossing):
        i, j = crossing[0].tolist()
        return "surface", (f"closed but intersecting itself (triangles {i} and {j} cross; "
                           f"{len(crossing)} pairs), so it bounds no valid solid"), Enclosing(
                               solid.ints, solid.faces)
    shells = int(solid.components.max()) + 1
    chi = len(solid.ints) - len(F) * 3 // 2 + len(F)
    poly, why = convex_within_bound(solid)  # the one definition of "convex"
    if poly is None:
        genus = f", genus {1 - chi // 2}" if shells == 1 else ""
        return "solid", (f"closed 2-manifold, not convex ({shells} shell"
                         f"{'s' if shells > 1 else ''}, Euler characteristic {chi}{genus})"), solid
    if poly.excess:
        return "convex", f"closed and {why}; modelled by its hull ({poly.n_facets} facets)", poly
    return "convex", f"closed and convex ({poly.n_facets} facets)", poly


def _classify(name, source, ints, F, minus_r_box, bounds_g, grid,
              convex_robot: bool = True, memo: dict | None = None,
              sheet: bool = False) -> BodyModel:
    used, local = np.unique(F, return_inverse=True)
    P, F = ints[used], local.reshape(-1, 3)
    V = grid.to_float(P)
    r_lo, r_hi = minus_r_box  # the box of c - R, grid units
    lo, hi = P.min(axis=0) + r_lo, P.max(axis=0) + r_hi
    body = BodyModel(name, source, "dropped", "", V, F, _ints=P, _sheet=bool(sheet))
    if not _meets(lo, hi, *bounds_g):
        body.reason = (f"its C-obstacle's bounding box {grid.to_float(np.stack([lo, hi])).tolist()} "
                       "misses the planning bounds: the robot can never touch it")
        return body
    sheet_kind = _sheet_kind(P, F) if sheet else None
    if sheet_kind is not None:
        kind, why, operand = sheet_kind
    elif memo is None:
        kind, why, operand = _closed_kind(name, P, F, grid)
    else:  # the kind depends only on these, exactly (bytes compare exactly on a collision)
        key = (name, grid.exponent, grid.bits, tuple(int(x) for x in grid.origin),
               P.shape, P.tobytes(), F.tobytes())
        if key not in memo:
            memo[key] = _closed_kind(name, P, F, grid)
        kind, why, operand = memo[key]
    if kind != "surface":
        body.kind, body._solid = kind, operand
        if kind == "convex" and operand.excess:
            body.changed = (f"modelled by its convex hull, which exceeds the snapped body by at "
                            f"most {operand.excess:.3g} (counted in the error bound)")
        # With a convex robot the body's kind names its algorithm; else each pair's line does.
        body.reason = why + ((": CVMS" if kind == "convex" else ": NCC-CVMS") if convex_robot
                             else "")
        return body
    # Surface semantics; leave out triangles whose piece cannot meet the bounds.
    body._encloses = operand
    if operand is not None:
        body.changed = (f"a closed body modelled as its surface and the region it encloses "
                        f"(non-zero winding number of its snapped surface): {why}")
    elif why.startswith("closed"):
        body.changed = f"a closed body modelled as its surface (its inside counts as free): {why}"
    tri = P[F]
    keep = _meets(tri.min(axis=1) + r_lo, tri.max(axis=1) + r_hi, *bounds_g)
    body.kind, body._keep, body.pieces = "surface", keep, int(keep.sum())
    inside = (" and containment terms for what it encloses (non-zero winding number)"
              if operand is not None else "")
    body.reason = (f"{why}: surface semantics, the union of triangle ⊕ (-R) over "
                   f"{int(keep.sum())} triangles" + (f" ({int((~keep).sum())} more cannot "
                                                     "reach the bounds)" if (~keep).any() else "")
                   + inside)
    if not convex_robot:
        body.reason = (f"{why}: surface semantics (FCL's mesh collision), "
                       f"{int(keep.sum())} triangles can reach the bounds" + inside)
    return body


def _lost_inside(parts: list) -> bool:
    """Whether a part of a body is modelled as a bare surface (its inside would count as free)
    though it is neither open by itself nor a double-sided sheet: a closed body that
    de-duplication or splitting left without an inside of its own."""
    return any(b.kind == "surface" and b._encloses is None and not b._sheet for b in parts)


def _kept_from_snapping(ints, thin, chain, grid: Grid):
    """``(P, T, enclosing, why)``: the grid points, the thin features as degenerate triangles
    ``T`` (indices into ``P``), the :class:`Enclosing` of ``chain`` (or None) and the words for
    what snapping took (:func:`cspace.mesh.components.snapping_losses`), for a body or a robot
    part that keeps it."""
    rows = [thin] + ([chain] if chain is not None else [])
    used, local = np.unique(np.concatenate(rows), return_inverse=True)
    local = local.reshape(-1, 3)
    P = ints[used]
    n_seg = int((thin[:, 0] != thin[:, 1]).sum())
    said = []
    if len(thin):
        said.append(f"{n_seg} segments and {len(thin) - n_seg} points left by triangles that "
                    f"collapse on the grid (features thinner than its step 2**{grid.exponent}),"
                    " kept as segments and points")
    if chain is not None:
        said.append(f"the region its {len(chain)} welded triangles enclose (non-zero winding "
                    "number of a closed 2-cycle), which de-duplication or splitting left "
                    "without an inside of its own")
    enclosing = None if chain is None else Enclosing(P, local[len(thin):])
    return P, local[:len(thin)], enclosing, "kept from snapping: " + "; and ".join(said)


def _snapped_body(source: str, ints, welded, F, parts: list, minus_r_box, bounds_g,
                  grid: Grid) -> BodyModel | None:
    """What snapping took from the scene body ``source``, as one more surface body: its
    features thinner than the grid step (segments and points, each summed with ``-R`` as any
    triangle is) and, when a part lost its inside (:func:`_lost_inside`) and the body's
    welded triangles are a closed 2-cycle, the region that cycle encloses (a containment
    term, non-zero winding number). None when snapping took nothing (most bodies).

    ``ints``, ``welded``, ``F``: the body's welded grid integers, every input triangle
    welded, and the triangles kept (:func:`cspace.mesh.components.weld_dedupe`); ``parts``:
    the body's modelled parts. The segments' and points' pieces are grown by the scene's
    margin like every piece, so they hold the thin feature of the float input
    (:mod:`cspace.cobstacle.margin`).
    """
    from ..mesh.components import snapping_losses

    thin, chain = snapping_losses(len(ints), welded, F)
    if not _lost_inside(parts):
        chain = None
    if not len(thin) and chain is None:
        return None
    P, T, enclosing, why = _kept_from_snapping(ints, thin, chain, grid)
    return _snapped_model(source, P, T, enclosing, why, minus_r_box, bounds_g, grid)


def _snapped_model(source: str, P, T, enclosing, why: str, minus_r_box, bounds_g,
                   grid: Grid) -> BodyModel:
    """The body of :func:`_snapped_body` from its parts (grid points ``P``, degenerate
    triangles ``T``, the :class:`Enclosing` or None, the reason), as a build makes it and a
    snapshot restores it: its pieces are those that can meet the bounds."""
    r_lo, r_hi = minus_r_box
    tri = P[T].reshape(-1, 3, 3)
    keep = _meets(tri.min(axis=1) + r_lo, tri.max(axis=1) + r_hi, *bounds_g)
    return BodyModel(f"{source} (snapped)", source, "surface", why, grid.to_float(P), T,
                     pieces=int(keep.sum()), changed=why.replace("kept from snapping",
                                                                 "what snapping took, kept"),
                     _ints=P, _keep=keep, _kept=True, _encloses=enclosing)


def _without_far_parts(scene):
    """The scene without the parts of its obstacle bodies that cannot reach the bounds and
    would coarsen the grid, and per scene body ``(count, box)`` of what was left out.

    Precision follows the size of what is modelled, not where everything lies: an obstacle
    far away that the robot can never touch must not set the grid step for the rest. Parts
    are the components of triangles sharing a vertex (exact float positions); a part is far
    when its C-obstacle's bounding box ``[lo(P) + lo(c - R), hi(P) + hi(c - R)]`` misses the
    planning bounds (decided with exact rationals on the float input) and it reaches beyond
    the extent of everything else; parts are left out only when that changes the grid step.
    Other unreachable parts are dropped later, on the grid, as usual.
    """
    from dataclasses import replace

    from .scene import Body

    rel = scene.robot.vertices - scene.reference_point
    # c - R as a box of exact rationals (the reference point minus the robot's box): a part
    # reaches the bounds when lo + c - r_hi <= b_hi and b_lo <= hi + c - r_lo on every axis,
    # that is lo <= the largest float not above b_hi - c + r_hi (and hi >= the smallest float
    # not below b_lo - c + r_lo): exact comparisons of floats.
    c = [Fraction(float(x)) for x in scene.reference_point]
    r_lo = [Fraction(float(x)) for x in scene.robot.vertices.min(axis=0)]
    r_hi = [Fraction(float(x)) for x in scene.robot.vertices.max(axis=0)]
    b_lo = [Fraction(float(x)) for x in scene.bounds[0]]
    b_hi = [Fraction(float(x)) for x in scene.bounds[1]]
    lo_max = np.array([_float_at_most(b_hi[i] - c[i] + r_hi[i]) for i in range(3)])
    hi_min = np.array([_float_at_least(b_lo[i] - c[i] + r_lo[i]) for i in range(3)])
    # Parts of every body at once: components of triangles sharing a vertex (exact float
    # positions, per body), their boxes over the vertices their triangles use.
    sizes = np.array([len(b.vertices) for b in scene.obstacles], dtype=np.int64)
    n_faces = np.array([len(b.faces) for b in scene.obstacles], dtype=np.int64)
    if not len(sizes) or not n_faces.sum():
        return scene, {}
    base = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    body_of_face = np.repeat(np.arange(len(sizes)), n_faces)
    V_all = np.concatenate([b.vertices for b in scene.obstacles])
    F_all = np.concatenate([b.faces for b in scene.obstacles]) + base[body_of_face][:, None]
    body_of_vertex = np.repeat(np.arange(len(sizes)), sizes)
    keyed = np.concatenate([body_of_vertex[:, None].astype(np.float64), V_all], axis=1)
    _, inverse = np.unique(keyed, axis=0, return_inverse=True)
    F = inverse.reshape(-1)[F_all]
    _, label = component_labels(int(F.max()) + 1, F.reshape(-1), np.repeat(F[:, 0], 3))
    _, part = np.unique(label[F[:, 0]], return_inverse=True)  # parts numbered by body, then
    part = part.reshape(-1)                                     # by lowest welded vertex
    n_parts = int(part.max()) + 1
    corners = V_all[F_all]  # (m, 3, 3)
    p_lo = np.full((n_parts, 3), np.inf)
    p_hi = np.full((n_parts, 3), -np.inf)
    np.minimum.at(p_lo, part, corners.min(axis=1))
    np.maximum.at(p_hi, part, corners.max(axis=1))
    reach_all = ((p_lo <= lo_max) & (p_hi >= hi_min)).all(axis=1)
    box_lo = np.minimum(p_lo, p_lo - rel.max(axis=0))
    box_hi = np.maximum(p_hi, p_hi - rel.min(axis=0))
    part_body = np.zeros(n_parts, dtype=np.int64)
    part_body[part] = body_of_face
    split = [[] for _ in scene.obstacles]
    for k in range(n_parts):
        split[part_body[k]].append(k)
    # The box of what is near: the bounds with the robot at their corners, and the parts
    # that can reach them (each with its C-obstacle's box).
    near = np.concatenate([
        np.stack([scene.bounds[0] + rel.min(axis=0), scene.bounds[1] + rel.max(axis=0)]),
        scene.bounds, box_lo[reach_all], box_hi[reach_all]])
    n_lo, n_hi = near.min(axis=0), near.max(axis=0)
    r_far = max(float(np.abs(scene.robot.vertices).max()),
                float(np.abs(scene.reference_point).max()))
    near_grid = Grid.for_box(n_lo, n_hi, reach=float(np.abs(rel).max()), far=r_far)
    if near_grid.exponent >= scene.grid().exponent:
        return scene, {}  # nothing far enough to coarsen the grid: model everything as is

    def outside(box) -> bool:  # beyond the near box: it would widen the grid
        return bool((box[0] < n_lo).any() or (box[1] > n_hi).any())

    faces_of = np.split(np.argsort(part, kind="stable"), np.cumsum(np.bincount(part))[:-1])
    first_face = np.concatenate([[0], np.cumsum(n_faces)[:-1]])
    split = [[(faces_of[k] - first_face[b], bool(reach_all[k]),
               np.stack([box_lo[k], box_hi[k]]), p_lo[k], p_hi[k]) for k in ks]
             for b, ks in enumerate(split)]
    far, bodies = {}, []
    for body, parts in zip(scene.obstacles, split):
        gone = [p for p in parts if not p[1] and outside(p[2])]
        if not gone:
            bodies.append(body)
            continue
        lo = np.min([p[3] for p in gone], axis=0) - rel.max(axis=0)
        hi = np.max([p[4] for p in gone], axis=0) - rel.min(axis=0)
        far[body.name] = (len(gone), [lo.tolist(), hi.tolist()])
        kept = np.sort(np.concatenate([p[0] for p in parts if p[1] or not outside(p[2])]
                                      + [np.zeros(0, np.int64)]))
        if len(kept):  # only the vertices the kept triangles use (the body's box shrinks)
            used, faces = np.unique(body.faces[kept], return_inverse=True)
            bodies.append(Body(body.name, body.vertices[used], faces.reshape(-1, 3),
                               body.source))
    if not far:
        return scene, far
    return replace(scene, obstacles=tuple(bodies)), far


def _float_at_most(t) -> float:
    """The largest float64 not above the rational ``t``."""
    f = float(t)
    return math.nextafter(f, -math.inf) if Fraction(f) > t else f


def _float_at_least(t) -> float:
    """The smallest float64 not below the rational ``t``."""
    f = float(t)
    return math.nextafter(f, math.inf) if Fraction(f) < t else f


def _far_body(name: str, n_far: int, box) -> BodyModel:
    return BodyModel(f"{name} (far parts)", name, "dropped",
                     f"{n_far} connected part{'s' if n_far > 1 else ''} far from the bounds "
                     f"(C-obstacle bounding box {box} misses them, decided exactly before the "
                     "grid was chosen, so they do not coarsen it)",
                     np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
