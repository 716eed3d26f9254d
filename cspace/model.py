"""Model only what a scene needs: per obstacle body, what to build and why.

:func:`model_scene` turns a :class:`~cspace.scene.Scene` into a :class:`SceneModel`. Each
obstacle body (a mesh as its file gives it) goes through these steps, all exact on the
scene grid (``scene.grid()``, centred on the scene):

1. **Weld** vertices by exact snapped position; triangles whose corners weld to fewer than
   three points are dropped (they have no area), and counted.
2. **Duplicates**: triangles on the same three welded vertices are one surface patch. The
   first (in file order) is kept and later copies are dropped, counted as *double-sided*
   (opposite winding: the two sides of a zero-thickness sheet) or *repeated* (same
   winding). A sheet modelled with both sides becomes the single open surface it is; a
   closed surface modelled double-sided becomes closed.
3. **Split** into connected parts (triangles sharing an edge that no third triangle uses:
   at a non-manifold edge the parts meeting there are split apart). A closed part (no boundary
   edge) that lies inside another closed part's solid (a vertex of it, decided exactly) is
   kept with it: a cavity; every other part is its own body, named ``<body>#<k>``.
4. **Drop** a part whose C-obstacle cannot meet the planning bounds: its bounding box is
   exactly ``[lo(O) + lo(c - R), hi(O) + hi(c - R)]`` in grid integers, compared exactly
   with the bounds, before anything is built.
5. **Classify**: ``convex`` (a closed convex mesh: CVMS), ``solid`` (closed, oriented
   2-manifold, not convex: NCC-CVMS through :meth:`CSpaceObstacle.build`), ``surface``
   (open, or closed but not a valid solid, e.g. non-manifold: the union of the pieces
   ``t ⊕ (c - R)`` of its triangles, :class:`~cspace.surface.SurfaceObstacle`; triangles
   whose piece cannot meet the bounds are left out), or ``dropped``. Each decision carries a
   human-readable reason.
6. **Build** (``build=True``) each kept body's C-obstacle, through the disk cache
   (:mod:`cspace.cache`) when one is given.

The robot goes through steps 1-3 and 5 too (nothing of it is dropped): its parts
(:class:`RobotPart`) are ``convex``, ``solid`` or ``surface``, and every (kept body, robot
part) pair gets the construction :func:`cspace.pairs.pair_construction` names for its kinds
(:class:`PairModel`). A convex robot is one convex part and steps 5-6 are as described above;
``robot_hull=True`` makes the robot's convex hull its one part instead.

Surface semantics equals FCL's mesh collision: a robot wholly inside an unclosed surface
meets nothing.
"""

from __future__ import annotations

import dataclasses
import multiprocessing as mp
import os
import time
import warnings
from concurrent.futures import FIRST_COMPLETED, wait
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from .cache import COCache, co_key, pack_polytopes, unpack_polytopes
from .components import edge_uses, split_parts, weld_dedupe
from .convex import ConvexPolytope, convex_within_bound
from .errors import BuildError, InvalidMeshError
from .exact import Grid
from .graphs import component_labels
from .margin import Margin, snap_deviation
from .mesh import ClosedMesh
from .obstacle import CSpace, CSpaceObstacle, grown_mesh_sum
from .pairs import (
    CONSTRUCTIONS,
    PairObstacle,
    TrianglePairs,
    _meets,
    component_points,
    containment_meshes,
    convex_triangle_pieces,
    pair_construction,
    triangle_pairs,
)
from .surface import SurfaceMesh, SurfaceObstacle

__all__ = ["KINDS", "BodyModel", "RobotPart", "PairModel", "SceneModel", "model_scene",
           "build_pair_batch"]

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
        of ``cspace build``/``plan`` and in :meth:`SceneModel.explain` alike.
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
        A key of :data:`cspace.pairs.CONSTRUCTIONS`.
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


@dataclass(eq=False)
class SceneModel:
    """What :func:`model_scene` decided and built for a scene.

    Attributes
    ----------
    scene : Scene
    grid : Grid
    robot : ConvexPolytope or None
        The robot's hull on ``grid`` (its frame); None for a flat robot.
    robot_parts : list of RobotPart
        What the C-obstacles are built from: the robot's exact parts, or its hull alone when
        ``robot_hull=True`` was asked for.
    robot_hull : bool
        Whether the hull stands in for the robot (an explicit choice, never a silent one).
    bodies : list of BodyModel
    sources : dict
        Per scene body: ``triangles`` (input), ``collapsed``, ``double_sided``, ``repeated``
        (dropped in steps 1-2) and ``parts`` (after splitting).
    seconds : dict
        ``model`` (steps 1-5) and ``build`` (step 6) wall seconds.
    margin : Margin or None
        The outward rounding (:mod:`cspace.margin`): the snapping deviation of the scene and
        the box every C-obstacle is grown by (a float64 surface's may be one step wider, to
        cover its rounding: its own ``margin`` says). With ``conservative=True`` every
        C-obstacle holds the true one of the scene's float input.
    """

    scene: object
    grid: Grid
    robot: ConvexPolytope | None
    bodies: list
    sources: dict
    seconds: dict
    robot_parts: list = field(default_factory=list)
    robot_hull: bool = False
    margin: Margin | None = None

    @property
    def error_bound(self) -> float:
        """How far (scene units) a translation reported in collision can be from the scene's
        true C-obstacles (the largest over the built ones); with ``conservative=True`` no true
        collision is ever missed."""
        built = [co.error_bound for b in self.bodies for co in b.cos]  # excess included
        return max(built + [self.margin.error_bound if self.margin else 0.0])

    def meaning_changes(self, limit: int | None = None) -> list[str]:
        """One line per body whose meaning modelling changed (:attr:`BodyModel.changed`),
        the first ``limit`` of them and a count of the rest; empty when none did."""
        changed = [b for b in self.bodies if b.changed]
        if not changed:
            return []
        lines = [f"meaning changed for {len(changed)} of {len(self.bodies)} bodies:"]
        shown = changed if limit is None else changed[:limit]
        lines += [f"  {b.name}: {b.changed}" for b in shown]
        if len(shown) < len(changed):
            lines.append(f"  ... and {len(changed) - len(shown)} more (--explain lists them)")
        return lines

    def of_kind(self, kind: str) -> list[BodyModel]:
        return [b for b in self.bodies if b.kind == kind]

    def counts(self) -> dict:
        """Number of bodies of each kind."""
        return {k: len(self.of_kind(k)) for k in KINDS}

    def cspace(self) -> CSpace:
        """The :class:`CSpace` of the built bodies (dropped ones cannot matter); the surface
        bodies' C-obstacles are joined into one (:meth:`SurfaceObstacle.union`).

        Raises
        ------
        BuildError
            If the model was made with ``build=False`` or a body's build failed.
        """
        failed = [b for b in self.bodies if b.error]
        if failed:
            raise BuildError(f"scene {self.scene.name!r}: " + "; ".join(
                f"cannot build the C-obstacle of body {b.name!r} ({b.kind}: {b.reason}): "
                f"{b.error}" for b in failed))
        kept = [b for b in self.bodies if b.kind != "dropped"]
        missing = [b.name for b in kept if not b.pairs]
        if missing:
            raise BuildError(f"scene {self.scene.name!r}: bodies {missing} were modelled "
                             "without building (build=False)")
        # Surface pieces of one robot part share one broad phase (one cell lookup per query
        # for all of them); every other C-obstacle stands alone.
        cos, surfaces = [], {}
        for b in kept:
            for p in b.pairs:
                for co in p.cos:
                    if isinstance(co, SurfaceObstacle) and p.construction == "surface pieces":
                        surfaces.setdefault(p.part, []).append(co)
                    else:
                        cos.append(co)
        cos += [SurfaceObstacle.union(group) for group in surfaces.values()]
        return CSpace(cos, bounds=self.scene.bounds, name=self.scene.name, scene=self.scene,
                      robot_hull=self.robot_hull)

    def _margin_line(self) -> str:
        m = self.margin
        if m is None:
            return "error bound: unknown"
        steps = sorted({co.margin.steps for b in self.bodies for co in b.cos} | {m.steps})
        grown = ("not grown" if steps == [(0, 0, 0)] else
                 "grown by " + " or ".join(str(list(s)) for s in steps) + " grid steps per axis")
        one_sided = m.conservative and all(co.margin.holds_true for b in self.bodies
                                           for co in b.cos)
        return (f"error bound {self.error_bound:.3g}: snapping moved the input by at most "
                f"{[float(f'{d:.3g}') for d in m.deviation]} per axis; C-obstacles {grown}: "
                + ("every error is a false collision, never a false free" if one_sided else
                   "the error is two-sided (conservative=False)"))

    def explain(self) -> str:
        """A human-readable report: per scene body and per modelled body."""
        c = self.counts()
        lines = [f"scene {self.scene.name!r}: {len(self.scene.obstacles)} obstacle bodies -> "
                 f"{len(self.bodies)} modelled: " + ", ".join(f"{c[k]} {k}" for k in KINDS),
                 f"robot {self.scene.robot.name!r}: " + (
                     f"its convex hull ({self.robot.n_facets} facets, {len(self.robot.ints)} "
                     "vertices), as asked (robot_hull)" if self.robot_hull else
                     f"{len(self.robot_parts)} part{'s' if len(self.robot_parts) != 1 else ''}, "
                     "modelled exactly") + f"; grid step 2**{self.grid.exponent}; bounds "
                 f"{self.scene.bounds.tolist()}", self._margin_line()]
        lines += ["  " + p.line() for p in self.robot_parts]
        for name, s in self.sources.items():
            extra = [f"{s[k]} {k.replace('_', '-')}" for k in ("collapsed", "double_sided",
                                                                 "repeated") if s[k]]
            lines.append(f"  {name}: {s['triangles']} triangles, {s['parts']} parts"
                         + (f"; dropped triangles: {', '.join(extra)}" if extra else ""))
        for b in self.bodies:
            lines.append("    " + b.line())
            if len(self.robot_parts) > 1 or any(p.kind != "convex" for p in self.robot_parts):
                lines += ["      " + p.line() for p in b.pairs]
        used = sorted({p.construction for b in self.bodies for p in b.pairs})
        if len(self.robot_parts) > 1 or any(p.kind != "convex" for p in self.robot_parts):
            lines += ["constructions:"] + [f"  {c}: {CONSTRUCTIONS[c]}" for c in used]
        lines += self.meaning_changes()
        lines.append(f"modelling {self.seconds['model']:.3f} s, building "
                     f"{self.seconds['build']:.3f} s")
        return "\n".join(lines)


# --------------------------------------------------------------------------------------
# steps 1-3: weld, deduplicate, split


# in cspace.components: weld_dedupe, split_parts (shared with CSpaceObstacle.build)


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
    non-zero (:class:`cspace.meshquery.MeshCO`, exact)."""

    ints: np.ndarray
    faces: np.ndarray


def _closed_kind(name, P, F, grid):
    """Kind of a welded part, without bounds: ``(kind, reason, operand)``.

    ``('convex', reason, ConvexPolytope)``, ``('solid', reason, ClosedMesh)``,
    ``('surface', why, Enclosing)`` (closed and oriented, but its snapped surface bounds no
    valid solid: it is modelled as its surface and the region it encloses) or
    ``('surface', why, None)`` (open, or not consistently oriented).

    A closed body whose snapped surface meets itself is never left as a bare surface: that
    would count its inside as free. Snapping moves every point of the surface by at most the
    snapping bound, so away from the surface the snapped winding number is the input's; near
    it, the (grown) surface pieces hold every contact.
    """
    from .meshquery import unbalanced_edge

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
    from .trim import self_intersections

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
              convex_robot: bool = True, memo: dict | None = None) -> BodyModel:
    used, local = np.unique(F, return_inverse=True)
    P, F = ints[used], local.reshape(-1, 3)
    V = grid.to_float(P)
    r_lo, r_hi = minus_r_box  # the box of c - R, grid units
    lo, hi = P.min(axis=0) + r_lo, P.max(axis=0) + r_hi
    body = BodyModel(name, source, "dropped", "", V, F, _ints=P)
    if not _meets(lo, hi, *bounds_g):
        body.reason = (f"its C-obstacle's bounding box {grid.to_float(np.stack([lo, hi])).tolist()} "
                       "misses the planning bounds: the robot can never touch it")
        return body
    if memo is None:
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


# --------------------------------------------------------------------------------------
# step 6: build, through the cache


def _to_arrays(co) -> dict:
    if co.kind == "convex":
        out = pack_polytopes([co.polytope, co.obstacle], "p_")
    elif co.kind == "surface":
        out = pack_polytopes(co.pieces, "p_")
    else:
        out = {"vertices": np.asarray(co.vertices), "faces": np.asarray(co.faces)}
    return out | _margin_arrays(co.margin)


def _margin_arrays(m: Margin) -> dict:
    """The box and rounding a C-obstacle was grown by (a surface's may be wider than asked)."""
    return {"margin": np.array(m.steps, dtype=np.int64), "rounding": np.array([m.rounding])}


def _margin_from(a: dict, margin: Margin) -> Margin:
    """The margin stored with built or cached arrays (same deviation as the scene's)."""
    if "margin" not in a:
        return margin
    rounding = float(a["rounding"][0]) if "rounding" in a else 0.0
    return Margin(tuple(int(x) for x in a["margin"]), margin.deviation, margin.grid,
                  rounding, margin.conservative)


def _from_arrays(a: dict, body: BodyModel, robot, c, grid, margin: Margin):
    co = _from_arrays_of(a, body, robot, c, grid, margin)
    co.excess = _excess(body) + robot.excess  # hulls standing for bent bodies
    return co


def _from_arrays_of(a: dict, body: BodyModel, robot, c, grid, margin: Margin):
    m = _margin_from(a, margin)
    if body.kind == "convex":
        co, obs = unpack_polytopes(a, "p_", grid)
        return CSpaceObstacle(co, obstacle=obs, robot=robot, reference_point=c, margin=m)
    if body.kind == "surface":
        F = body.faces[body._keep]
        co = SurfaceObstacle(unpack_polytopes(a, "p_", grid),
                             obstacle=SurfaceMesh(body.vertices, F, body.name), robot=robot,
                             reference_point=c, grid=grid)
        co.margin = m
        return co
    return CSpaceObstacle.from_mesh(a["vertices"], a["faces"], obstacle=body._solid,
                                    robot=robot, reference_point=c, grid=grid, name=body.name,
                                    margin=m)


def _build(body: BodyModel, robot, c, grid, margin: Margin, progress, grown=None):
    """The C-obstacle of a body and a convex robot part, grown by ``margin`` (the float64
    surface of a solid body by what also covers its rounding), with that margin.
    ``grown``: ``margin.grow(robot)`` when the caller has it (one hull per robot part)."""
    if body.kind == "solid":
        S, m = grown_mesh_sum(body._solid, robot.reflected(c), margin, progress)
        co = CSpaceObstacle.from_mesh(S.vertices, S.faces, obstacle=body._solid, robot=robot,
                                      reference_point=robot.grid.to_float(robot.grid.snap(c)),
                                      grid=grid, sum=S, name=body.name, margin=m)
        co.excess = robot.excess
        return co
    grown = margin.grow(robot) if grown is None else grown
    if body.kind == "surface":
        F = body.faces[body._keep]
        co = SurfaceObstacle.build((body.vertices, F), grown, c, grid=grid, name=body.name,
                                   progress=progress)
    else:
        co = CSpaceObstacle.build(body._solid, grown, c, grid=grid, conservative=False)
    co.robot, co.margin = robot, margin
    co.excess = _excess(body) + robot.excess  # the grown robot's hull has lost its excess
    return co


def _key(body: BodyModel, robot, c_ints, grid) -> str:
    faces = body.faces[body._keep] if body.kind == "surface" else body.faces
    return co_key(body.kind, grid, body._ints, faces, robot.ints, c_ints)


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
    from fractions import Fraction

    from .scene import Body

    rel = scene.robot.vertices - scene.reference_point
    # c - R as a box of exact rationals (the reference point minus the robot's box)
    c = [Fraction(float(x)) for x in scene.reference_point]
    r_lo = [Fraction(float(x)) for x in scene.robot.vertices.min(axis=0)]
    r_hi = [Fraction(float(x)) for x in scene.robot.vertices.max(axis=0)]
    b_lo = [Fraction(float(x)) for x in scene.bounds[0]]
    b_hi = [Fraction(float(x)) for x in scene.bounds[1]]
    split = []
    for body in scene.obstacles:
        _, inverse = np.unique(body.vertices, axis=0, return_inverse=True)
        F = inverse.reshape(-1)[body.faces]
        n = int(F.max()) + 1
        _, label = component_labels(n, F.reshape(-1), np.repeat(F[:, 0], 3))
        part = label[F[:, 0]]
        parts = []
        for k in np.unique(part):
            faces = np.nonzero(part == k)[0]
            V = body.vertices[np.unique(body.faces[faces])]
            lo, hi = V.min(axis=0), V.max(axis=0)
            reach = all(Fraction(float(lo[i])) + c[i] - r_hi[i] <= b_hi[i]
                        and b_lo[i] <= Fraction(float(hi[i])) + c[i] - r_lo[i] for i in range(3))
            box = np.stack([np.minimum(lo, lo - rel.max(axis=0)),
                            np.maximum(hi, hi - rel.min(axis=0))])
            parts.append((faces, reach, box, lo, hi))
        split.append(parts)
    # The box of what is near: the bounds with the robot at their corners, and the parts
    # that can reach them (each with its C-obstacle's box).
    near = [np.stack([scene.bounds[0] + rel.min(axis=0), scene.bounds[1] + rel.max(axis=0)]),
            scene.bounds] + [box for parts in split for _, reach, box, _, _ in parts if reach]
    near = np.concatenate(near)
    n_lo, n_hi = near.min(axis=0), near.max(axis=0)
    r_far = max(float(np.abs(scene.robot.vertices).max()),
                float(np.abs(scene.reference_point).max()))
    near_grid = Grid.for_box(n_lo, n_hi, reach=float(np.abs(rel).max()), far=r_far)
    if near_grid.exponent >= scene.grid().exponent:
        return scene, {}  # nothing far enough to coarsen the grid: model everything as is

    def outside(box) -> bool:  # beyond the near box: it would widen the grid
        return bool((box[0] < n_lo).any() or (box[1] > n_hi).any())

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


def _far_body(name: str, n_far: int, box) -> BodyModel:
    return BodyModel(f"{name} (far parts)", name, "dropped",
                     f"{n_far} connected part{'s' if n_far > 1 else ''} far from the bounds "
                     f"(C-obstacle bounding box {box} misses them, decided exactly before the "
                     "grid was chosen, so they do not coarsen it)",
                     np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))


def _model_robot(scene, grid: Grid, hull: ConvexPolytope, robot_hull: bool) -> list[RobotPart]:
    """The robot's exact parts (steps 1-3 and 5 of the obstacles, without dropping), or the
    hull alone when asked for."""
    if robot_hull:
        return [RobotPart(scene.robot.name, "convex", "the convex hull of its vertices "
                          "(robot_hull: an approximation that can only add collisions)",
                          hull.ints, hull.faces, grid, hull)]
    ints, F, _ = weld_dedupe(scene.robot, grid)
    parts = split_parts(ints, F) if len(F) else []
    if not parts:
        raise BuildError(f"scene {scene.name!r}: robot {scene.robot.name!r}: all "
                         f"{len(scene.robot.faces)} triangles collapse when welded on the grid "
                         f"(step 2**{grid.exponent})")
    out = []
    for k, faces in enumerate(parts):
        name = scene.robot.name if len(parts) == 1 else f"{scene.robot.name}#{k}"
        used, local = np.unique(F[faces], return_inverse=True)
        P, Fk = ints[used], local.reshape(-1, 3)
        kind, why, operand = _closed_kind(name, P, Fk, grid)
        if kind == "solid":  # the validated mesh: oriented outwards
            P, Fk = operand.ints, operand.faces
        out.append(RobotPart(name, kind, why, P, Fk, grid, operand))
    return out


def _pair_key(construction, body: BodyModel, part: RobotPart, c_ints, grid,
              margin: Margin) -> str:
    faces = body.faces[body._keep] if body.kind == "surface" else body.faces
    robot = np.vstack([part.ints, part.faces])
    return co_key(f"{construction} robot {len(part.ints)} margin {list(margin.steps)}", grid,
                  body._ints, faces, robot, c_ints)


def _body_operand(body: BodyModel):
    """The obstacle body's exact grid vertices and triangles (a solid's are oriented)."""
    if body.kind == "surface":
        return body._ints, body.faces[body._keep]
    return body._solid.ints, body._solid.faces


def _pair_cos(construction, arrays, body: BodyModel, part: RobotPart, c_ints, grid, bounds_g):
    """C-obstacles of a pair with a non-convex robot part, from built or cached arrays."""
    c = part.grid.to_float(c_ints)
    obstacle = (SurfaceMesh(body.vertices, body.faces[body._keep], body.name)
                if body.kind == "surface" else body._solid)
    name = f"{body.name} x {part.name}"
    if construction == "NCC-CVMS swapped":
        cos = [CSpaceObstacle.from_mesh(arrays["vertices"], arrays["faces"], obstacle=obstacle,
                                        robot=part, reference_point=c, grid=grid, name=name)]
    elif construction == "triangle pairs":
        o_ints, o_faces = _body_operand(body)
        S = o_ints[o_faces]
        T = c_ints - part.ints[part.faces]
        tp = TrianglePairs(S, T, arrays["pairs"], arrays["flat"], margin=arrays["margin"])
        cos = [PairObstacle(tp, obstacle=obstacle, robot=part, reference_point=c,
                            grid=grid)] if len(tp.pairs) else []
    else:
        pieces = unpack_polytopes(arrays, "p_", grid)
        cos = [SurfaceObstacle(pieces, obstacle=obstacle, robot=part, reference_point=c,
                               grid=grid)] if pieces else []
    if construction in ("triangle pairs", "convex ⊕ robot triangles"):
        cos += _containment_cos(body, part, c_ints, grid, bounds_g, obstacle, name)
    for co in cos:
        co.semantics = (body.kind != "surface", part.kind)
        co.excess = _excess(body)  # a non-convex robot part is never a hull
    return cos


def _containment_cos(body: BodyModel, part: RobotPart, c_ints, grid, bounds_g, obstacle,
                     name: str) -> list:
    """The containment terms of a pair (module :mod:`cspace.pairs`), as exact mesh
    C-obstacles; terms whose box misses the bounds are left out.

    - a closed robot part (a solid, or a closed surface that encloses a region) holding an
      obstacle component: ``o + c - R`` for one vertex o of each obstacle component;
    - a closed body (a solid against a non-convex part, or a closed surface that encloses a
      region) holding a robot component: ``O + c - r`` for one vertex r of each component.

    A convex side needs none (its pieces are solid), nor does NCC-CVMS (its sum is).
    """
    c = part.grid.to_float(c_ints)
    held_by_robot = ((part.ints, part.faces) if part.kind == "solid" else
                     (part.encloses.ints, part.encloses.faces) if part.encloses is not None
                     else None)
    held_by_body = ((body._solid.ints, body._solid.faces) if body.kind == "solid" else
                    (body._encloses.ints, body._encloses.faces)
                    if body.kind == "surface" and body._encloses is not None else None)
    terms = []
    if held_by_robot is not None:  # obstacle components small enough for the robot to hold
        points = component_points(*_body_operand(body), fits_in=np.ptp(held_by_robot[0], axis=0))
        terms += containment_meshes(points, *held_by_robot, c_ints, robot_solid=True)
    if held_by_body is not None:  # robot components small enough for the body to hold
        points = component_points(part.ints, part.faces, fits_in=np.ptp(held_by_body[0], axis=0))
        terms += containment_meshes(points, *held_by_body, c_ints, robot_solid=False)
    return [CSpaceObstacle.from_mesh(grid.to_float(ints), faces, obstacle=obstacle, robot=part,
                                     reference_point=c, grid=grid, name=f"{name} (containment)")
            for ints, faces in terms if _meets(ints.min(axis=0), ints.max(axis=0), *bounds_g)]


def _build_pair_arrays(construction, body: BodyModel, part: RobotPart, c_ints, grid, bounds_g,
                       margin: Margin, progress) -> dict:
    """Build a pair with a non-convex robot part, grown by ``margin`` (the convex obstacle,
    or each triangle pair's piece): arrays for the cache."""
    if construction == "NCC-CVMS swapped":
        moved = ClosedMesh.from_arrays(grid.vectors.to_float(part.ints - c_ints), part.faces,
                                       grid=grid.vectors, name=part.name)
        S, m = grown_mesh_sum(moved, body._solid.reflected((0.0, 0.0, 0.0)), margin)
        # -(A ⊕ B): negating floats is exact; reversing the triangles keeps them outward.
        return {"vertices": -np.asarray(S.vertices) + 0.0,
                "faces": np.ascontiguousarray(np.asarray(S.faces)[:, ::-1]),
                "margin": np.array(m.steps, dtype=np.int64), "rounding": np.array([m.rounding])}
    if construction == "convex ⊕ robot triangles":
        made = convex_triangle_pieces(margin.grow_ints(body._solid.ints), part.ints, part.faces,
                                      c_ints, grid, bounds_g)
    else:
        o_ints, o_faces = _body_operand(body)
        tp = triangle_pairs(o_ints, o_faces, part.ints, part.faces, c_ints, bounds_g,
                            closed=body.kind == "solid" or part.kind == "solid", margin=margin.g)
        return {"pairs": tp.pairs, "flat": tp.flat, "margin": margin.g,
                "counts": np.array([len(tp.pairs), tp.flat_skipped, tp.out_of_bounds],
                                   dtype=np.int64)}
    arrays = pack_polytopes(made.pieces, "p_")
    arrays["counts"] = np.array([len(made.pieces), made.flat_skipped,
                                 made.out_of_bounds], dtype=np.int64)
    return arrays


def _pair_detail(construction, arrays) -> str:
    if "counts" not in arrays:
        return ""
    n, flat, out = (int(x) for x in arrays["counts"])  # built, flat left out, out of bounds
    what = "triangle pairs" if construction == "triangle pairs" else "robot-triangle pieces"
    extra = [f"{out} out of the bounds"] if out else []
    extra += [f"{flat} flat left out (an operand is closed)"] if flat else []
    return f"{n} {what}" + (f" ({', '.join(extra)})" if extra else "")


@dataclass(frozen=True, eq=False)
class _Context:
    """What every pair of one scene's build shares."""

    c: np.ndarray        # the reference point as given
    c_ints: np.ndarray   # ... snapped on the robot's grid
    c_snapped: np.ndarray
    grid: Grid
    bounds_g: tuple
    margin: Margin
    store: COCache | None
    grown: dict = field(default_factory=dict)  # per robot part: its grown polytope


def _grown(memo: dict, margin: Margin, part: RobotPart):
    """``margin.grow`` of a convex robot part, made once per part (an exact hull)."""
    if id(part) not in memo:
        memo[id(part)] = (part, margin.grow(part.operand))  # the part pins its id
    return memo[id(part)][1]


def _lookup(ctx: _Context, construction, b: BodyModel, part: RobotPart, pair: PairModel):
    """The pair's cache key and its cached arrays (None: a miss or no cache); sets
    ``pair.cache``."""
    store = ctx.store
    if store is None:
        key = None
    elif part.kind == "convex":  # the grown robot names the growth
        key = _key(b, _grown(ctx.grown, ctx.margin, part), ctx.c_ints, ctx.grid)
    else:
        key = _pair_key(construction, b, part, ctx.c_ints, ctx.grid, ctx.margin)
    arrays = store.load(key) if store is not None else None
    pair.cache = "hit" if arrays is not None else ("off" if store is None else "miss")
    return key, arrays


def _assemble(ctx: _Context, construction, b: BodyModel, part: RobotPart, pair: PairModel,
              arrays: dict) -> None:
    """The pair's C-obstacles from built or cached arrays (the one way for both)."""
    if part.kind == "convex":
        pair.cos = [_from_arrays(arrays, b, part.operand, ctx.c_snapped, ctx.grid, ctx.margin)]
        _add_enclosed(ctx, b, part, pair)
        return
    pair.cos = _pair_cos(construction, arrays, b, part, ctx.c_ints, ctx.grid, ctx.bounds_g)
    pair.detail = _pair_detail(construction, arrays)
    for co in pair.cos:  # one margin for the pair's union
        co.margin = _margin_from(arrays, ctx.margin)


def _add_enclosed(ctx: _Context, b: BodyModel, part: RobotPart, pair: PairModel) -> None:
    """A closed surface body that encloses a region holds a convex robot part there too:
    its containment term beside the surface pieces (built, never cached: one mesh)."""
    if b._encloses is not None and pair.cos:
        terms = _containment_cos(b, part, ctx.c_ints, ctx.grid, ctx.bounds_g,
                                 pair.cos[0].obstacle, f"{b.name} x {part.name}")
        for co in terms:
            co.margin = pair.cos[0].margin
        pair.cos += terms


def _store(ctx: _Context, key, pair: PairModel, arrays) -> None:
    """Write a built pair's arrays to the cache (an unwritable cache only warns)."""
    if ctx.store is not None and pair.cache == "miss":
        try:
            ctx.store.store(key, arrays)
        except OSError as exc:  # an unwritable cache must not fail the build
            warnings.warn(f"C-obstacle cache: cannot write {ctx.store.path(key)}: {exc}",
                          UserWarning, stacklevel=3)


def _failed(ctx: _Context, b: BodyModel, part: RobotPart, pair: PairModel, parts: list,
            error: str) -> None:
    b.error = error if len(parts) == 1 else f"{b.error}; {part.name}: {error}".lstrip("; ")
    pair.cache = "off" if ctx.store is None else "miss"


def _pair_arrays(construction, body: BodyModel, part: RobotPart, c, c_ints, grid, bounds_g,
                 margin: Margin, grown: dict) -> dict:
    """Build one pair: the arrays the cache stores (what :func:`_assemble` reads)."""
    if part.kind == "convex":
        return _to_arrays(_build(body, part.operand, c, grid, margin, None,
                                 _grown(grown, margin, part)))
    return _build_pair_arrays(construction, body, part, c_ints, grid, bounds_g, margin, None)


def build_pair_batch(jobs: list, c, c_ints, grid: Grid, bounds_g, margin: Margin) -> list:
    """Build (body, robot part) pairs in an executor's worker; a top-level function, so that
    any Executor (processes, Dask) can pickle it by name.

    Parameters
    ----------
    jobs : list of (construction, BodyModel, RobotPart)
        Bodies without their pairs (only what modelling made: grid integers, triangles and
        the exact operand).
    c, c_ints, grid, bounds_g, margin
        The scene's reference point (float and snapped), grid, bounds in grid integers and
        margin, as :func:`model_scene` has them.

    Returns
    -------
    list of (ok, value, seconds)
        Per job: ``(True, arrays, s)`` with the arrays the cache stores, or
        ``(False, "ErrorName: message", s)``: one pair's failure does not fail the others.
    """
    if mp.parent_process() is not None and not os.environ.get("CSPACE_WORKERS", "").strip():
        os.environ["CSPACE_WORKERS"] = "1"  # a worker is one unit: do not fork more
    out, grown = [], {}
    for construction, body, part in jobs:
        t = time.perf_counter()
        try:
            arrays = _pair_arrays(construction, body, part, c, c_ints, grid, bounds_g, margin,
                                  grown)
            out.append((True, arrays, time.perf_counter() - t))
        except Exception as exc:  # noqa: BLE001 - returned, recorded per body by the caller
            out.append((False, f"{type(exc).__name__}: {exc}", time.perf_counter() - t))
    return out


# Pairs of two convex operands per task (cheap: milliseconds); every other pair is a task.
_BATCH = 16


def _build_with(executor, todo: list, parts: list, ctx: _Context, progress) -> None:
    """Step 6 through an Executor: cache hits here, misses submitted as
    :func:`build_pair_batch` tasks, results assembled here (in ``todo``'s order: the same
    pairs, C-obstacles and reports as the local loop)."""
    n = len(todo)
    done = 0
    pairs, keys, pending = [], [], []
    errors = {}  # pair index -> error text, recorded in todo's order at the end (as locally)
    for i, (b, part) in enumerate(todo):
        construction = pair_construction(b.kind, part.kind)
        pair = PairModel(part.name, construction)
        b.pairs.append(pair)
        pairs.append(pair)
        t = time.perf_counter()
        key = None
        try:
            key, arrays = _lookup(ctx, construction, b, part, pair)
            if arrays is not None:
                _assemble(ctx, construction, b, part, pair, arrays)
                done += 1
            else:
                pending.append(i)
        except Exception as exc:
            errors[i] = f"{type(exc).__name__}: {exc}"
            done += 1
        keys.append(key)
        pair.seconds = time.perf_counter() - t

    def report(i):
        if progress is not None:
            b, part = todo[i]
            progress(done / n, f"{b.name} ({b.kind})"
                     + (f" x {part.name}" if len(parts) > 1 else ""))

    # Expensive pairs first (each its own task), then the convex ones in batches.
    cheap = [i for i in pending if pairs[i].construction == "CVMS"]
    dear = sorted((i for i in pending if pairs[i].construction != "CVMS"),
                  key=lambda i: -len(todo[i][0].faces) * len(todo[i][1].faces))
    size = max(1, min(_BATCH, len(cheap) // 64))
    tasks = [[i] for i in dear] + [cheap[k:k + size] for k in range(0, len(cheap), size)]
    slim = {}  # one pickled copy per body: no pairs, no C-obstacles

    def job(i):
        b, part = todo[i]
        if id(b) not in slim:
            slim[id(b)] = dataclasses.replace(b, pairs=[], co=None)
        return pairs[i].construction, slim[id(b)], part

    futures = {}
    try:
        for task in tasks:
            f = executor.submit(build_pair_batch, [job(i) for i in task], ctx.c, ctx.c_ints,
                                ctx.grid, ctx.bounds_g, ctx.margin)
            futures[f] = task
        waiting = set(futures)
        while waiting:
            finished, waiting = wait(waiting, return_when=FIRST_COMPLETED)
            for f in finished:
                task = futures.pop(f)
                try:
                    results = f.result()
                except Exception as exc:  # the task itself failed: a lost worker, pickling
                    results = [(False, f"{type(exc).__name__}: {exc}", 0.0)] * len(task)
                for i, (ok, value, seconds) in zip(task, results):
                    b, part = todo[i]
                    t = time.perf_counter()
                    try:
                        if not ok:
                            raise _TaskError(value)
                        _assemble(ctx, pairs[i].construction, b, part, pairs[i], value)
                        _store(ctx, keys[i], pairs[i], value)
                    except _TaskError as exc:
                        errors[i] = str(exc)
                    except Exception as exc:
                        errors[i] = f"{type(exc).__name__}: {exc}"
                    pairs[i].seconds += seconds + time.perf_counter() - t
                    done += 1
                    report(i)
    finally:
        for f in futures:  # only left on an interrupt or a bug here: cancel the rest
            f.cancel()
    for i in sorted(errors):
        _failed(ctx, *todo[i], pairs[i], parts, errors[i])
    for (b, part), pair in zip(todo, pairs):
        b.seconds += pair.seconds
        b.cache = pair.cache if not b.cache or b.cache == pair.cache else "mixed"


class _TaskError(Exception):
    """An error a worker reported as text (already ``ErrorName: message``)."""


def model_scene(scene, *, build: bool = True, cache=None, progress=None,
                grid: Grid | None = None, robot_hull: bool = False,
                conservative: bool = True, executor=None,
                memo: dict | None = None) -> SceneModel:
    """Decide, per obstacle body, what to build and why; build it.

    Parameters
    ----------
    scene : Scene
    build : bool, default True
        Build the C-obstacles (else only steps 1-5: cheap, for reports).
    cache : COCache, path, True, or None/False
        A :class:`~cspace.cache.COCache` (or its folder; True: the default folder,
        ``$CSPACE_CACHE`` or ``~/.cache/cspace``); None or False: no disk cache.
    progress : callable, optional
        ``progress(fraction, message)`` with the overall fraction in ``[0, 1]``: once per
        body, during long surface builds, and per stage of a non-convex (NCC-CVMS) build.
    grid : Grid, optional
        Default ``Scene.grid`` of what is modelled: obstacle parts that cannot reach the
        bounds and lie beyond everything else are dropped first, so that an obstacle far away
        does not coarsen the grid for the rest.
    robot_hull : bool, default False
        Build against the robot's convex hull instead of its exact parts: faster for a
        non-convex robot, and conservative (the hull holds the robot, so it can only add
        collisions), but not the robot the scene gave. ``explain()`` says which was used.
    conservative : bool, default True
        Grow every C-obstacle by the least box that makes it hold the true C-obstacle of the
        scene's float input (:mod:`cspace.margin`): errors are then false collisions within
        ``error_bound``, never false free. False: the exact C-obstacles of the snapped
        input, whose error is two-sided (for measuring, not for planning).
    executor : concurrent.futures.Executor, optional
        Build the (body, robot part) pairs there: a ``ProcessPoolExecutor``, a Dask
        ``Client(...).get_executor()`` (:func:`cspace.scale.executor_for`), any Executor.
        Modelling (steps 1-5), cache look-ups and writes stay in this process: cache hits
        are never submitted; misses go out as :func:`build_pair_batch` tasks (picklable
        arrays and grid objects in, the arrays the cache stores out), and this process
        makes the C-obstacles from those arrays as it makes them from a cache hit, so the
        answers are those of the local build. ``progress`` is called as tasks complete;
        an error in a task (or a lost worker) becomes that body's error, as locally.
        None (default): build here, one pair after the other.
    memo : dict, optional
        Shared by calls on scenes with the same obstacle bodies (orientation slices,
        :func:`cspace.scale.build_slices`): steps 1-3 of a body and step 5's classification
        depend only on the body and the grid, and are made once per grid.

    Returns
    -------
    SceneModel
        Build failures are recorded per body (``body.error``) and raised as
        :class:`~cspace.errors.BuildError` by :meth:`SceneModel.cspace`.
    """
    t0 = time.perf_counter()
    far: dict = {}
    modelled = scene
    if grid is None:
        modelled, far = _without_far_parts(scene)
        grid = modelled.grid()
    c = np.asarray(scene.reference_point, dtype=np.float64)
    # The robot is snapped on the scene's step, about its reference point when far from the
    # grid's origin (Grid.for_robot): c - r are vectors, every C-obstacle is in grid's frame.
    rgrid = grid.for_robot(scene.robot.vertices, c)
    c_ints = rgrid.snap(c)
    margin = _margin(modelled, grid, conservative)
    # The box of c - R, grown by the widest margin a build may take (one more step for a
    # float64 surface's rounding), decides what is dropped, exactly, whatever the robot's parts.
    r_ints = rgrid.snap(scene.robot.vertices[np.unique(scene.robot.faces)])
    g = margin.g + 1
    minus_r_box = (c_ints - r_ints.max(axis=0) - g, c_ints - r_ints.min(axis=0) + g)
    try:
        robot = ConvexPolytope.from_ints(r_ints, grid=rgrid, name=scene.robot.name)
    except InvalidMeshError as exc:  # a flat robot has no hull polytope
        if robot_hull:
            raise BuildError(f"scene {scene.name!r}: robot {scene.robot.name!r} has no convex "
                             f"hull to stand in for it ({exc})") from exc
        robot = None
    parts = _model_robot(scene, rgrid, robot, robot_hull)
    bounds_g = grid.inner_box(*np.asarray(scene.bounds, dtype=np.float64))
    bodies, sources = [], {}
    kept = {sb.name: sb for sb in modelled.obstacles}
    for sb in scene.obstacles:
        if sb.name not in kept:  # every part of it far away
            n_far, box = far[sb.name]
            sources[sb.name] = {"triangles": len(sb.faces), "collapsed": 0, "double_sided": 0,
                                "repeated": 0, "parts": n_far}
            bodies.append(_far_body(sb.name, n_far, box))
            continue
        sb = kept[sb.name]
        welded = None if memo is None else memo.get(
            ("weld", id(sb), grid.exponent, grid.bits, tuple(int(x) for x in grid.origin)))
        if welded is None:  # steps 1-3 depend only on the body and the grid
            ints, F, counts = weld_dedupe(sb, grid)
            split = split_parts(ints, F) if len(F) else []
            if memo is not None:  # the body is kept in the value: its id stays its own
                memo[("weld", id(sb), grid.exponent, grid.bits,
                      tuple(int(x) for x in grid.origin))] = (sb, ints, F, counts, split)
        else:
            _, ints, F, counts, split = welded
        counts = dict(counts)
        counts["parts"] = len(split)
        sources[sb.name] = counts
        for k, faces in enumerate(split):
            name = sb.name if len(split) == 1 else f"{sb.name}#{k}"
            bodies.append(_classify(name, sb.name, ints, F[faces], minus_r_box, bounds_g, grid,
                                    len(parts) == 1 and parts[0].kind == "convex", memo))
        if sb.name in far:
            bodies.append(_far_body(sb.name, *far[sb.name]))
        if not split and sb.name not in far:
            bodies.append(BodyModel(sb.name, sb.name, "dropped",
                                    f"empty: all {len(sb.faces)} triangles collapse when welded "
                                    f"on the grid (step 2**{grid.exponent})",
                                    np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)))
    t1 = time.perf_counter()
    if isinstance(cache, COCache):
        store = cache
    elif cache is None or cache is False:
        store = None
    else:
        store = COCache(None if cache is True else cache)
    if build:
        todo = [(b, p) for b in bodies if b.kind != "dropped" for p in parts]
        ctx = _Context(c, c_ints, rgrid.to_float(c_ints), grid, bounds_g, margin, store)
        if executor is not None:
            _build_with(executor, todo, parts, ctx, progress)
        for i, (b, part) in enumerate(todo if executor is None else ()):
            construction = pair_construction(b.kind, part.kind)

            def sub(f, stage=None, i=i, b=b, part=part):
                if progress is not None:
                    progress((i + f) / len(todo), f"{b.name} ({b.kind})"
                             + (f" x {part.name}" if len(parts) > 1 else "")
                             + (f": {stage}" if stage else ""))
            sub(0.0)
            t = time.perf_counter()
            pair = PairModel(part.name, construction)
            b.pairs.append(pair)
            try:
                key, arrays = _lookup(ctx, construction, b, part, pair)
                if part.kind == "convex" and arrays is None:
                    pair.cos = [_build(b, part.operand, c, grid, margin, sub,
                                       _grown(ctx.grown, margin, part))]
                    arrays = _to_arrays(pair.cos[0]) if store is not None else None
                    _add_enclosed(ctx, b, part, pair)
                else:
                    if arrays is None:
                        arrays = _build_pair_arrays(construction, b, part, c_ints, grid,
                                                    bounds_g, margin, sub)
                    _assemble(ctx, construction, b, part, pair, arrays)
                _store(ctx, key, pair, arrays)
            except Exception as exc:  # recorded per body; SceneModel.cspace() raises it
                _failed(ctx, b, part, pair, parts, f"{type(exc).__name__}: {exc}")
            pair.seconds = time.perf_counter() - t
            b.seconds += pair.seconds
            b.cache = pair.cache if not b.cache or b.cache == pair.cache else "mixed"
        for b in bodies:  # one convex part: the body's one C-obstacle, as before parts
            if len(parts) == 1 and parts[0].kind == "convex" and b.pairs and b.pairs[0].cos:
                b.co = b.pairs[0].cos[0]
        if progress is not None:
            progress(1.0, f"{len(todo)} C-obstacles" if len(parts) == 1
                     else f"{len(todo)} (body, robot part) pairs")
    t2 = time.perf_counter()
    return SceneModel(scene=scene, grid=grid, robot=robot, bodies=bodies, sources=sources,
                      seconds={"model": t1 - t0, "build": t2 - t1}, robot_parts=parts,
                      robot_hull=robot_hull, margin=margin)


def _margin(scene, grid: Grid, conservative: bool) -> Margin:
    """The scene's outward rounding: the obstacles' largest snapping move per axis (over all
    bodies), plus the robot's, plus the reference point's, exact. Float64 surfaces may widen
    it by a step to cover their rounding (each C-obstacle's ``margin`` says)."""
    dev_o = np.zeros(3)
    for body in scene.obstacles:
        dev_o = np.maximum(dev_o, snap_deviation(body.vertices, grid))
    parts = (dev_o, snap_deviation(scene.robot.vertices, grid),
             snap_deviation(np.asarray(scene.reference_point, np.float64), grid))
    dev = [sum((Fraction(float(p[i])) for p in parts), Fraction(0)) for i in range(3)]
    out = Margin.for_deviation(dev, grid, rounded=False)
    return out if conservative else out.without_growth()
