"""Model only what a scene needs: per obstacle body, what to build and why.

:func:`model_scene` turns a :class:`~cspace.scene.scene.Scene` into a :class:`SceneModel`. Each
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
   (open, or closed but not a valid solid, e.g. non-manifold: triangle pairs, the union of
   ``s ⊕ (c - t)`` over its triangles s and the robot's t, :class:`~cspace.cobstacle.pairs.PairObstacle`;
   triangles whose pieces cannot meet the bounds are left out), or ``dropped``. Each decision carries a
   human-readable reason.
6. **Build** (``build=True``) each kept body's C-obstacle, through the disk cache
   (:mod:`cspace.scene.cache`) when one is given. A build with a cache also leaves the
   scene's *snapshot* (:mod:`cspace.scene.snapshot`): the next build of the same input
   restores steps 1-6 from it instead of modelling each body again.

The robot goes through steps 1-3 and 5 too (nothing of it is dropped): its parts
(:class:`RobotPart`) are ``convex``, ``solid`` or ``surface``, and every (kept body, robot
part) pair gets the construction :func:`cspace.cobstacle.pairs.pair_construction` names for its kinds
(:class:`PairModel`). A convex robot is one convex part and steps 5-6 are as described above;
``robot_hull=True`` makes the robot's convex hull its one part instead.

Surface semantics equals FCL's mesh collision: a robot wholly inside an unclosed surface
meets nothing.

Length: the model (its steps and report) and the C-space it builds (eager and lazy, with
the queries planners and users ask of it) share the bodies' bookkeeping; split, each half
would reach into the other's.
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, field
from fractions import Fraction
from typing import NamedTuple

import numpy as np

from ..cobstacle.convex import _translations
from ..cobstacle.margin import Margin
from ..cobstacle.obstacle import CSpaceObstacle
from ..cobstacle.pairs import CONSTRUCTIONS, is_sum, pair_construction, pairs_memory
from ..cobstacle.union import _UnionOf
from ..errors import BuildError, InvalidArgumentError, InvalidMeshError, MemoryBudgetError
from ..geometry.exact import Grid
from ..geometry.snapping import snap_deviation
from ..memory import budget_and_source, format_size
from ..mesh.components import snapping_losses, weld_split
from ..mesh.convex import ConvexPolytope
from .build import (
    _Context,
    _assemble,
    _body_operand,
    _build,
    _build_pair_arrays,
    _build_with,
    _failed,
    _grown,
    _lookup,
    _part_triangles,
    _store,
    _to_arrays,
)
from .cache import COCache
from .snapshot import Snapshot, snapshot_arrays, snapshot_key
from .classify import (
    BodyModel,
    KINDS,
    PairModel,
    RobotPart,
    _classify,
    _closed_kind,
    _kept_from_snapping,
    _lost_inside,
    _sheet_kind,
    _snapped_body,
    _far_body,
    _without_far_parts,
)

__all__ = ["SceneModel", "model_scene", "CSpace"]


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
        The outward rounding (:mod:`cspace.cobstacle.margin`): the snapping deviation of the scene and
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
    memory: int = 0  # bytes its C-obstacles hold, as estimated before the build (_memory_check)

    def __repr__(self) -> str:
        kinds: dict = {}
        for b in self.bodies:
            kinds[b.kind] = kinds.get(b.kind, 0) + 1
        parts = ", ".join(f"{n} {k}" for k, n in kinds.items()) or "none"
        return (f"SceneModel({getattr(self.scene, 'name', '?')!r}, bodies: {parts}, "
                f"robot parts={len(self.robot_parts)}, robot_hull={self.robot_hull}, "
                f"grid step=2**{self.grid.exponent})")

    @property
    def error_bound(self) -> float:
        """How far (scene units) a translation reported in collision can be from the scene's
        true C-obstacles (the largest over the built ones); with ``conservative=True`` no true
        collision is ever missed."""
        built = [co.error_bound for b in self.bodies for co in b.cos]  # excess included
        return max(built + [self.margin.error_bound if self.margin else 0.0])

    def meaning_changes(self, limit: int | None = None) -> list[str]:
        """One line per body whose meaning modelling changed (:attr:`BodyModel.changed`),
        the first ``limit`` of them and a count of the rest, and one per robot part that is
        not a solid (an open surface: it collides only where its surface meets an obstacle,
        and what it would enclose is free unless it closes up); empty when nothing changed."""
        lines = [f"robot {p.name}: modelled as a surface, not a solid ({p.reason}): it "
                 "collides where its surface meets an obstacle"
                 + ("" if p.encloses is not None else ", an obstacle wholly inside it does not")
                 for p in self.robot_parts if p.kind == "surface"]
        changed = [b for b in self.bodies if b.changed]
        if not changed:
            return lines
        lines += [f"meaning changed for {len(changed)} of {len(self.bodies)} bodies:"]
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
        """The :class:`CSpace` of the built bodies (dropped ones cannot matter).

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
        cos = [co for b in kept for co in b.cos]
        owners = [(b.name, b.source) for b in kept for _ in b.cos]
        return CSpace(cos, bounds=self.scene.bounds, name=self.scene.name, scene=self.scene,
                      owners=owners,
                      robot_hull=self.robot_hull, memory=self.memory)

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


def _model_robot(scene, grid: Grid, hull: ConvexPolytope, robot_hull: bool) -> list[RobotPart]:
    """The robot's exact parts (steps 1-3 and 5 of the obstacles, without dropping), or the
    hull alone when asked for."""
    if robot_hull:
        return [RobotPart(scene.robot.name, "convex", "the convex hull of its vertices "
                          "(robot_hull: an approximation that can only add collisions)",
                          hull.ints, hull.faces, grid, hull)]
    ints, F, _, two_sided, parts, welded = weld_split(scene.robot, grid)
    # (a robot whose every triangle collapses is its segments and points: nothing is empty)
    thin, chain = snapping_losses(len(ints), welded, F)
    out, lost = [], False
    for k, faces in enumerate(parts):
        name = scene.robot.name if len(parts) == 1 else f"{scene.robot.name}#{k}"
        used, local = np.unique(F[faces], return_inverse=True)
        P, Fk = ints[used], local.reshape(-1, 3)
        sheet = bool(two_sided[faces].all())
        kind, why, operand = (_sheet_kind(P, Fk) if sheet else None) or \
            _closed_kind(name, P, Fk, grid)
        if kind == "solid":  # the validated mesh: oriented outwards
            P, Fk = operand.ints, operand.faces
        lost |= kind == "surface" and operand is None and not sheet
        out.append(RobotPart(name, kind, why, P, Fk, grid, operand))
    # What snapping took from the robot, as one more part (as for an obstacle body:
    # classify._snapped_body): its segments and points, and the region its closed 2-cycle
    # encloses when a part lost its inside.
    chain = chain if lost else None
    if len(thin) or chain is not None:
        P, T, enclosing, why = _kept_from_snapping(ints, thin, chain, grid)
        out.append(RobotPart(f"{scene.robot.name} (snapped)", "surface", why, P, T, grid,
                             enclosing))
    return out


def _robot_polytope(r_ints, rgrid: Grid, name: str, parts) -> ConvexPolytope:
    """The hull of the robot's snapped vertices: its one part's polytope when that part is
    exactly convex on the same points (the hull of the same points; no Qhull call), else
    the exact hull."""
    if parts is not None and len(parts) == 1 and parts[0].kind == "convex":
        poly = parts[0].operand
        if not poly.excess and np.array_equal(np.unique(r_ints, axis=0),
                                              np.unique(parts[0].ints, axis=0)):
            return poly
    return ConvexPolytope.from_ints(r_ints, grid=rgrid, name=name)


def model_scene(scene, *, build: bool = True, cache=None, progress=None,
                grid: Grid | None = None, robot_hull: bool = False,
                conservative: bool = True, executor=None,
                memo: dict | None = None, memory=None, sums: bool = True) -> SceneModel:
    """Decide, per obstacle body, what to build and why; build it.

    Parameters
    ----------
    scene : Scene
    build : bool, default True
        Build the C-obstacles (else only steps 1-5: cheap, for reports).
    cache : COCache, path, True, or None/False
        A :class:`~cspace.scene.cache.COCache` (or its folder; True: the default folder,
        ``$CSPACE_CACHE`` or ``~/.cache/cspace``); None or False: no disk cache.
    progress : callable, optional
        ``progress(fraction, message)`` with the overall fraction in ``[0, 1]``: once per
        body, and per stage of a non-convex (NCC-CVMS) build.
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
        scene's float input (:mod:`cspace.cobstacle.margin`): errors are then false collisions within
        ``error_bound``, never false free. False: the exact C-obstacles of the snapped
        input, whose error is two-sided (for measuring, not for planning).
    executor : concurrent.futures.Executor, optional
        Build the (body, robot part) pairs there: a ``ProcessPoolExecutor``, a Dask
        ``Client(...).get_executor()`` (:func:`cspace.planning.scale.executor_for`), any Executor.
        Modelling (steps 1-5), cache look-ups and writes stay in this process: cache hits
        are never submitted; misses go out as :func:`cspace.scene.build.build_pair_batch` tasks (picklable
        arrays and grid objects in, the arrays the cache stores out), and this process
        makes the C-obstacles from those arrays as it makes them from a cache hit, so the
        answers are those of the local build. ``progress`` is called as tasks complete;
        an error in a task (or a lost worker) becomes that body's error, as locally.
        None (default): build here, one pair after the other.
    memo : dict, optional
        Shared by calls on scenes with the same obstacle bodies (orientation slices,
        :func:`cspace.planning.scale.build_slices`): steps 1-3 of a body and step 5's classification
        depend only on the body and the grid, and are made once per grid. Such builds leave
        no snapshot (each would repeat the shared model) and read none.
    memory : int or str, optional
        The memory budget of the build (bytes or a size such as ``"6G"``; default
        ``$CSPACE_MEMORY``, else half of the memory available: :mod:`cspace.memory`). The
        triangle-pair C-obstacles are estimated before anything is built (per triangle:
        :data:`cspace.cobstacle.pairs.TRIANGLE_BYTES`); a build over the budget raises
        :class:`~cspace.errors.MemoryBudgetError` saying what it needed.
    sums : bool, default True
        Build a solid body against a convex robot part as one NCC-CVMS sum (an exact mesh,
        drawable and exportable). False: as triangle pairs, the same set with nothing built,
        for a C-space asked only a few queries (:class:`cspace.planning.turning.TurningCSpace`'s
        turns in place).

    Returns
    -------
    SceneModel
        Build failures are recorded per body (``body.error``) and raised as
        :class:`~cspace.errors.BuildError` by :meth:`SceneModel.cspace`.
    """
    t0 = time.perf_counter()
    store = COCache.of(cache)
    # A build of the same input before left a snapshot: the model and the convex C-obstacles
    # are restored from it (cspace.scene.snapshot), not made again per body. Not for scenes
    # sharing their obstacles (memo: orientation slices), whose obstacles are modelled once
    # for all of them already: a snapshot per slice would hold the same model once per slice.
    skey = (snapshot_key(scene, grid, robot_hull, conservative, sums)
            if build and store is not None and memo is None else None)
    snap = Snapshot.read(store.load(skey, count=False)) if skey is not None else None
    far: dict = {}
    modelled = scene
    if snap is not None:
        grid = snap.grid
    elif grid is None:
        modelled, far = _without_far_parts(scene)
        grid = modelled.grid()
    c = np.asarray(scene.reference_point, dtype=np.float64)
    # The robot is snapped on the scene's step, about its reference point when far from the
    # grid's origin (Grid.for_robot): c - r are vectors, every C-obstacle is in grid's frame.
    rgrid = grid.for_robot(scene.robot.vertices, c)
    c_ints = rgrid.snap(c)
    margin = snap.margin if snap is not None else _margin(modelled, grid, conservative)
    # The box of c - R, grown by the widest margin a build may take (one more step for a
    # float64 surface's rounding), decides what is dropped, exactly, whatever the robot's parts.
    r_ints = rgrid.snap(scene.robot.vertices[np.unique(scene.robot.faces)])
    g = margin.g + 1
    minus_r_box = (c_ints - r_ints.max(axis=0) - g, c_ints - r_ints.min(axis=0) + g)
    parts = None if robot_hull else _model_robot(scene, rgrid, None, False)
    try:
        robot = _robot_polytope(r_ints, rgrid, scene.robot.name, parts)
    except InvalidMeshError as exc:  # a flat robot has no hull polytope
        if robot_hull:
            raise BuildError(f"scene {scene.name!r}: robot {scene.robot.name!r} has no convex "
                             f"hull to stand in for it ({exc})") from exc
        robot = None
    if robot_hull:
        parts = _model_robot(scene, rgrid, robot, True)
    bounds_g = grid.inner_box(*np.asarray(scene.bounds, dtype=np.float64))
    convex_robot = sums and len(parts) == 1 and parts[0].kind == "convex"
    bodies, sources, restored = [], {}, {}
    if snap is not None:
        bodies, restored = snap.bodies(minus_r_box, bounds_g, convex_robot,
                                       parts[0].operand.name if convex_robot else "", memo)
        sources = snap.sources
    kept = {sb.name: sb for sb in modelled.obstacles}
    for sb in scene.obstacles if snap is None else ():
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
            ints, F, counts, two_sided, split, all_welded = weld_split(sb, grid)
            if memo is not None:  # the body is kept in the value: its id stays its own
                memo[("weld", id(sb), grid.exponent, grid.bits,
                      tuple(int(x) for x in grid.origin))] = (sb, ints, F, counts, split,
                                                               two_sided, all_welded)
        else:
            _, ints, F, counts, split, two_sided, all_welded = welded
        counts = dict(counts)
        counts["parts"] = len(split)
        sources[sb.name] = counts
        modelled_parts = []
        for k, faces in enumerate(split):
            name = sb.name if len(split) == 1 else f"{sb.name}#{k}"
            modelled_parts.append(_classify(name, sb.name, ints, F[faces], minus_r_box,
                                            bounds_g, grid, convex_robot, memo,
                                            sheet=bool(two_sided[faces].all())))
        # what snapping took (features thinner than the step, a closed body's inside)
        snapped = (_snapped_body(sb.name, ints, all_welded, F, modelled_parts, minus_r_box,
                                 bounds_g, grid)
                   if counts["collapsed"] or _lost_inside(modelled_parts) else None)
        bodies += modelled_parts + ([snapped] if snapped is not None else [])
        if sb.name in far:
            bodies.append(_far_body(sb.name, *far[sb.name]))
    t1 = time.perf_counter()
    held = 0
    if build:
        todo = [(b, p) for b in bodies if b.kind != "dropped" for p in parts]
        held = _memory_check(scene, todo, memory, sums)
        ctx = _context(scene, grid, rgrid, margin, store, sums, memory)
        if restored:  # their convex C-obstacles, as from their own cache entries
            for b, part in todo:
                if id(b) in restored:
                    _restore_pair(ctx, b, part, restored[id(b)])
            todo = [(b, p) for b, p in todo if id(b) not in restored]
        if executor is not None:
            _build_with(executor, todo, parts, ctx, progress)
        for i, (b, part) in enumerate(todo if executor is None else ()):
            def sub(f, stage=None, i=i, b=b, part=part):
                if progress is not None:
                    progress((i + f) / len(todo), f"{b.name} ({b.kind})"
                             + (f" x {part.name}" if len(parts) > 1 else "")
                             + (f": {stage}" if stage else ""))
            sub(0.0)
            _build_one(ctx, b, part, parts, sub)
        for b in bodies:  # one convex part: the body's one C-obstacle, as before parts
            if (len(parts) == 1 and b.pairs and b.pairs[0].cos
                    and is_sum(b.pairs[0].construction)):
                b.co = b.pairs[0].cos[0]
        if skey is not None and snap is None:
            kept_arrays = snapshot_arrays(bodies, sources, grid, margin, convex_robot)
            if kept_arrays is not None:
                store.store(skey, kept_arrays)
        _flush(store)
        if progress is not None:
            progress(1.0, f"{len(todo)} C-obstacles" if len(parts) == 1
                     else f"{len(todo)} (body, robot part) pairs")
    t2 = time.perf_counter()
    return SceneModel(scene=scene, grid=grid, robot=robot, bodies=bodies, sources=sources,
                      seconds={"model": t1 - t0, "build": t2 - t1}, robot_parts=parts,
                      robot_hull=robot_hull, margin=margin, memory=held)


def _context(scene, grid: Grid, rgrid: Grid, margin: Margin, store, sums: bool,
             memory=None) -> _Context:
    """What every pair of one scene's build shares (:class:`cspace.scene.build._Context`)."""
    c = np.asarray(scene.reference_point, dtype=np.float64)
    c_ints = rgrid.snap(c)
    bounds_g = grid.inner_box(*np.asarray(scene.bounds, dtype=np.float64))
    return _Context(c, c_ints, rgrid.to_float(c_ints), grid, bounds_g, margin, store, sums,
                    memory=memory)


def _flush(store) -> None:
    """Write what a build kept in the cache as one pack (an unwritable cache only warns: the
    build stands, its entries are not kept)."""
    if store is None:
        return
    try:
        store.flush()
    except OSError as exc:
        warnings.warn(f"C-obstacle cache: cannot write {store.location}: {exc}", UserWarning,
                      stacklevel=3)


def _build_one(ctx: _Context, b: BodyModel, part: RobotPart, parts: list, sub=None) -> PairModel:
    """Build (or read from the cache) the C-obstacles of one (body, robot part) pair; a
    failure is recorded on the body (:meth:`SceneModel.cspace` raises it)."""
    construction = pair_construction(b.kind, part.kind, ctx.sums)
    t = time.perf_counter()
    pair = PairModel(part.name, construction)
    b.pairs.append(pair)
    try:
        key, arrays = _lookup(ctx, construction, b, part, pair)
        if is_sum(construction) and arrays is None:
            pair.cos = [_build(b, part.operand, ctx.c, ctx.grid, ctx.margin, sub,
                               _grown(ctx.grown, ctx.margin, part), ctx.memory)]
            arrays = _to_arrays(pair.cos[0]) if ctx.store is not None else None
        else:
            if arrays is None:
                arrays = _build_pair_arrays(construction, b, part, ctx.c_ints, ctx.grid,
                                            ctx.bounds_g, ctx.margin, sub)
            _assemble(ctx, construction, b, part, pair, arrays)
        _store(ctx, key, pair, arrays)
    except MemoryBudgetError as exc:  # the build stops: no later body would fit either
        raise MemoryBudgetError(f"body {b.name!r} x robot part {part.name!r}: {exc}",
                                exc.needed, exc.budget) from None
    except Exception as exc:  # recorded per body; SceneModel.cspace() raises it
        _failed(ctx, b, part, pair, parts, f"{type(exc).__name__}: {exc}")
    pair.seconds = time.perf_counter() - t
    b.seconds += pair.seconds
    b.cache = pair.cache if not b.cache or b.cache == pair.cache else "mixed"
    return pair


def _restore_pair(ctx: _Context, b: BodyModel, part: RobotPart, arrays: dict) -> None:
    """A restored convex body's C-obstacle from its snapshot's arrays (those of its own
    cache entry: :func:`cspace.scene.build._assemble` makes it the one way)."""
    pair = PairModel(part.name, "CVMS", cache="hit")
    b.pairs.append(pair)
    _assemble(ctx, "CVMS", b, part, pair, arrays)
    b.cache = "hit"
    ctx.store.hits += 1  # a C-obstacle read from the cache, as through its own entry


def _memory_check(scene, todo, memory, sums: bool = True) -> int:
    """Bytes the C-obstacles of ``todo`` will hold; raises :class:`MemoryBudgetError` before
    anything is built when they, and the largest construction's own peak, exceed the budget.

    Counted: the triangle-pair C-obstacles (:func:`cspace.cobstacle.pairs.pairs_memory`, per
    triangle of each side: a body's triangles once per pair, a robot part's once, since every
    body of the build shares its side). The other constructions are linear in a body's
    triangles."""
    items = [(b, part, len(_body_operand(b)[1]) + len(_part_triangles(part)[1]))
             for b, part in todo
             if pair_construction(b.kind, part.kind, sums) == "triangle pairs"]
    if not items:
        return 0
    budget, source = budget_and_source(memory)
    ns = [n for _, _, n in items]
    parts = {id(part): len(_part_triangles(part)[1]) for _, part, _ in items}
    n_held = sum(len(_body_operand(b)[1]) for b, _, _ in items) + sum(parts.values())
    held = pairs_memory(n_held)[0]
    needed = held + max(pairs_memory(n)[1] - pairs_memory(n)[0] for n in ns)
    if needed > budget:
        k = max(range(len(ns)), key=ns.__getitem__)
        raise MemoryBudgetError(
            f"scene {scene.name!r}: building its C-obstacles needs about "
            f"{format_size(needed)} ({len(items):,} triangle-pair C-obstacles over "
            f"{n_held:,} triangles; the largest: body {items[k][0].name!r} x robot part "
            f"{items[k][1].name!r}, {ns[k]:,} triangles), over the memory budget of "
            f"{format_size(budget)} ({source}); nothing was built. Use the robot's convex hull "
            "(robot_hull=True, --robot-hull: conservative), a smaller scene or bounds, or a "
            "larger budget (memory=, --memory, $CSPACE_MEMORY)",
            needed=needed, budget=budget)
    return held


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


_NON_CONVEX = "non-convex C-obstacles need cspace.minkowski_sum (issue #4)"


class CSpace:
    """Several C-obstacles answering the same queries over all of them (no union built).

    Parameters
    ----------
    obstacles : sequence of CSpaceObstacle
    bounds : (2, 3) float64, optional
        The box translations are planned in (used by sampling checks); default the bounding
        box of the C-obstacles.
    scene : Scene, optional
        The scene the C-obstacles were built from: checks against FCL use its raw meshes.
    robot_hull : bool, default False
        The C-obstacles are of the robot's convex hull (checks use the hull too).
    memory : int, default 0
        Bytes the C-obstacles hold, as the build estimated them (``SceneModel.memory``):
        what a set of orientation slices counts against its budget.
    owners : sequence of (str, str), optional
        Per C-obstacle, the modelled body it belongs to and that body's scene body (as
        :meth:`SceneModel.cspace` gives them): what :meth:`contact` names. Default
        ``("obstacle-<k>", None)``.
    """

    def __init__(self, obstacles, *, bounds=None, name: str = "cspace", scene=None,
                 robot_hull: bool = False, memory: int = 0, owners=None):
        self.obstacles = tuple(obstacles)
        self.owners = (tuple(tuple(o) for o in owners) if owners is not None
                       else tuple((f"obstacle-{k}", None) for k in range(len(self.obstacles))))
        if len(self.owners) != len(self.obstacles):
            raise InvalidArgumentError(f"{len(self.owners)} owners for "
                                       f"{len(self.obstacles)} C-obstacles")
        self._union = _UnionOf(self.obstacles)
        self.name = name
        # The scene as loaded (set by SceneModel.cspace): FCL cross-checks judge on its raw
        # meshes (cspace.check.oracle.SceneOracle), never on anything built here.
        self.scene = scene
        self.robot_hull = bool(robot_hull)
        self.memory = int(memory)
        if bounds is None:
            if not self.obstacles:
                raise InvalidArgumentError("a CSpace without obstacles needs bounds")
            b = np.stack([o.bounds for o in self.obstacles])
            bounds = np.stack([b[:, 0].min(axis=0), b[:, 1].max(axis=0)])
        self.bounds = np.asarray(bounds, dtype=np.float64).reshape(2, 3)

    @classmethod
    def from_scene(cls, scene, *, grid: Grid | None = None, cache=None,
                   progress=None, robot_hull: bool = False, executor=None,
                   memory=None) -> "CSpace":
        """The C-obstacles a scene needs, built: :func:`cspace.scene.model.model_scene` decides per
        body (split, deduplicated; convex, solid, surface or dropped) and builds each.

        Parameters
        ----------
        scene : Scene
        grid : Grid, optional
            Default ``scene.grid()`` (centred on the scene).
        cache : COCache, path, True, or None
            Disk cache of C-obstacles (:mod:`cspace.scene.cache`); None: none.
        progress : callable, optional
            ``progress(fraction, message)``, see :func:`cspace.scene.model.model_scene`.
        robot_hull : bool, default False
            Use the robot's convex hull instead of its exact parts (see ``model_scene``).
        executor : concurrent.futures.Executor, optional
            Build the C-obstacles there (a process pool, a Dask cluster:
            :func:`cspace.planning.scale.executor_for`); same answers as the local build.
        memory : int or str, optional
            The build's memory budget (see :func:`model_scene`).

        Raises
        ------
        BuildError
            A body's C-obstacle could not be built; the message names the body and why.
        MemoryBudgetError
            The build would exceed the memory budget; nothing was built.
        """

        return model_scene(scene, grid=grid, cache=cache, progress=progress,
                           robot_hull=robot_hull, executor=executor, memory=memory).cspace()

    def __len__(self) -> int:
        return len(self.obstacles)

    def __repr__(self) -> str:
        return f"CSpace(name={self.name!r}, obstacles={len(self.obstacles)})"

    def contains(self, q) -> np.ndarray | bool:
        """In collision with any obstacle (exact, touching counts).

        See :meth:`CSpaceObstacle.contains`.
        """
        x = _one_point(q)
        if x is not None:  # one state, as a planner asks: three floats, no arrays
            return self._union.contains_point(x)
        q, single = _translations(q)
        out = self._union.contains(q)
        return bool(out[0]) if single else out

    def signed_distance(self, q) -> np.ndarray | float:
        """Minimum of the obstacles' signed distances.

        Outside every C-obstacle this is the exact clearance (distance to the union).
        Inside, it is ``-max`` of the penetration depths of the C-obstacles containing ``q``:
        a lower bound on the penetration depth of the union (overlapping C-obstacles can
        make the true depth larger); the sign is exact either way.
        """
        q, single = _translations(q)
        out = self._union.signed_distance(q)
        return float(out[0]) if single else out

    def segment_free(self, q0, q1) -> np.ndarray | bool:
        """Free of every obstacle (exact); see :meth:`CSpaceObstacle.segment_free`."""
        a, b, single = CSpaceObstacle._pair(q0, q1)
        free = ~self._union.segments(a, b, want_t=False)[0]
        return bool(free[0]) if single else free

    def first_contact(self, q0, q1) -> np.ndarray | float:
        """Smallest first-contact parameter over the obstacles (NaN if the segment is free)."""
        a, b, single = CSpaceObstacle._pair(q0, q1)
        t = self._union.segments(a, b, want_t=True)[1]
        return float(t[0]) if single else t

    def build(self, lo=None, hi=None) -> None:
        """Nothing to do: every C-obstacle is built (:class:`LazyCSpace` builds those that may
        meet the box ``[lo, hi]``)."""

    def contact(self, q0, q1=None) -> Contact:
        """What the robot meets first moving straight from ``q0`` to ``q1`` (or standing at
        ``q0``), as FCL users ask it: where, which obstacle body, and a witness pair.

        Parameters
        ----------
        q0, q1 : (3,) float64
            Reference-point positions, world frame; ``q1`` omitted: the robot at ``q0``.

        Returns
        -------
        Contact
            ``t`` the first-contact parameter (exact, as :meth:`first_contact`; 0 when the
            robot at ``q0`` already collides; NaN when the motion is free), ``position`` the
            reference point there, ``body`` the modelled obstacle body whose C-obstacle it
            meets first (``name#k`` for a part of a scene body split into several), and, when
            the scene is known, ``robot_point`` and ``obstacle_point``: the closest points of
            the robot's and that body's raw triangles with the robot at ``position`` (world
            frame, float), ``gap`` their distance. The contact itself is exact; the witness
            pair is a float search on the raw meshes: ``gap`` is 0 where they cross and at
            most about ``error_bound`` where the margin made the contact (a false collision
            within the bound).
        """
        from ..geometry.distance import closest_points

        a = np.asarray(q0, dtype=np.float64).reshape(3)
        b = a if q1 is None else np.asarray(q1, dtype=np.float64).reshape(3)
        self.build(np.minimum(a, b), np.maximum(a, b))  # (lazy: what the motion may meet)
        ts = np.array([co.first_contact(a, b) if q1 is not None else
                       (0.0 if co.contains(a) else np.nan) for co in self.obstacles], float)
        if not len(ts) or np.isnan(ts).all():
            return Contact(float("nan"), None, None, None, None, float("nan"))
        k = int(np.nanargmin(ts))
        t = float(ts[k])
        p = a + t * (b - a)
        name, source = self.owners[k]
        if self.scene is None or source is None:
            return Contact(t, p, name, None, None, float("nan"))
        body = next(o for o in self.scene.obstacles if o.name == source)
        robot = self.scene.robot
        R = (robot.vertices - self.scene.reference_point + p)[robot.faces]
        O = body.vertices[body.faces]
        # the triangles near each other: boxes within a little more than the error bound
        slack = 4.0 * self.obstacles[k].error_bound + 1e-12 * float(np.abs(p).max() + 1.0)
        lo, hi = R.reshape(-1, 3).min(axis=0) - slack, R.reshape(-1, 3).max(axis=0) + slack
        near_o = O[((O.max(axis=1) >= lo) & (O.min(axis=1) <= hi)).all(axis=1)]
        if len(near_o):
            olo = near_o.reshape(-1, 3).min(axis=0) - slack
            ohi = near_o.reshape(-1, 3).max(axis=0) + slack
            near_r = R[((R.max(axis=1) >= olo) & (R.min(axis=1) <= ohi)).all(axis=1)]
        if not len(near_o) or not len(near_r):  # (a hull or a containment made the contact)
            near_o, near_r = O, R
        gap, x_r, x_o = closest_points(near_r, near_o)
        return Contact(t, p, name, x_r, x_o, gap)


class Contact(NamedTuple):
    """:meth:`CSpace.contact`'s answer (world frame, scene units; None or NaN when free)."""

    t: float
    position: np.ndarray | None
    body: str | None
    robot_point: np.ndarray | None
    obstacle_point: np.ndarray | None
    gap: float


def _one_point(q) -> list | None:
    """``q`` as three finite floats when it is one float64 state ``(3,)`` (a planner's
    question), else None: the general path then checks and answers it."""
    if type(q) is np.ndarray and q.shape == (3,) and q.dtype == np.float64:
        x = q.tolist()
        if math.isfinite(x[0]) and math.isfinite(x[1]) and math.isfinite(x[2]):
            return x
    return None


class LazyCSpace(CSpace):
    """A scene's :class:`CSpace` whose C-obstacles are built the first time a query comes near
    them: the same constructions, cache and answers as ``model_scene(...).cspace()``, built only
    where asked (a planner that visits a few places of an orientation slice builds the bodies
    there, not the scene).

    Made from a model without builds (``model_scene(scene, build=False)``). Each (body, robot
    part) pair's C-obstacles lie in the exact grid box ``O ⊕ (c - R)`` grown by the widest
    margin (as step 4 drops bodies); a query meeting that box builds the pair (through the disk
    cache). ``obstacles`` holds what is built so far; ``signed_distance`` and drawing build
    everything. ``memory`` is the estimate for all pairs, as for the eager build.

    Raises
    ------
    BuildError
        From the query that first needs a pair whose build fails (it names the body).
    MemoryBudgetError
        At construction, when all pairs together would not fit the budget.
    """

    def __init__(self, model: SceneModel, *, cache=None, sums: bool = True, memory=None):
        scene, parts = model.scene, model.robot_parts
        rgrid = parts[0].grid
        self.model = model
        self._ctx = _context(scene, model.grid, rgrid, model.margin, COCache.of(cache), sums,
                             memory)
        self._todo = [(b, p) for b in model.bodies if b.kind != "dropped" for p in parts]
        held = _memory_check(scene, self._todo, memory, sums)
        super().__init__((), bounds=scene.bounds, name=scene.name, scene=scene,
                         robot_hull=model.robot_hull, memory=held)
        # Boxes in grid integers, exact: the body's box plus the box of c - R, grown by the
        # margin and one step (a float64 surface's rounding), as minus_r_box in model_scene.
        g = model.margin.g + 1
        lo, hi = np.zeros((len(self._todo), 3)), np.zeros((len(self._todo), 3))
        for k, (b, part) in enumerate(self._todo):
            o_ints, o_faces = _body_operand(b)
            o = o_ints[np.unique(o_faces)]
            r_ints, _ = _part_triangles(part)
            v_lo = self._ctx.c_ints - r_ints.max(axis=0) - g  # vectors: robot grid's step
            v_hi = self._ctx.c_ints - r_ints.min(axis=0) + g
            lo[k] = model.grid.to_float(o.min(axis=0)) + np.ldexp(v_lo.astype(float),
                                                                   rgrid.exponent)
            hi[k] = model.grid.to_float(o.max(axis=0)) + np.ldexp(v_hi.astype(float),
                                                                   rgrid.exponent)
        # each sum rounded once: widened by 2**-40 of its size, far beyond an ulp
        pad = np.ldexp(np.maximum(np.abs(lo), np.abs(hi)).max(axis=1, initial=0.0), -40)[:, None]
        lo, hi = lo - pad - 1e-300, hi + pad + 1e-300
        self._union = _UnionOf((), lazy=(lo, hi, self._make))
        self._pair_lo, self._pair_hi = lo, hi
        #: (2, 3): the box every C-obstacle of this C-space lies in
        self.box = (np.stack([lo.min(axis=0), hi.max(axis=0)]) if len(lo)
                    else np.zeros((2, 3)))
        self._built = 0

    def build(self, lo=None, hi=None) -> None:
        """Build now every pair whose C-obstacles may meet the box ``[lo, hi]`` (scene units;
        default: all), as queries there would: ``obstacles`` then holds them all."""
        lo = np.full(3, -np.inf) if lo is None else np.asarray(lo, dtype=np.float64)
        hi = np.full(3, np.inf) if hi is None else np.asarray(hi, dtype=np.float64)
        meet = ((self._pair_lo <= hi) & (lo <= self._pair_hi)).all(axis=1)
        for k in np.nonzero(meet)[0].tolist():
            self._union._engine(k)

    def has_sums(self) -> bool:
        """Whether some (body, robot part) pair is built as one non-convex sum (NCC-CVMS)."""
        return any(pair_construction(b.kind, p.kind, self._ctx.sums) == "NCC-CVMS"
                   for b, p in self._todo)

    def _make(self, k: int) -> _UnionOf:
        b, part = self._todo[k]
        pair = _build_one(self._ctx, b, part, self.model.robot_parts)
        if b.error:
            raise BuildError(f"scene {self.name!r}: cannot build the C-obstacle of body "
                             f"{b.name!r} ({b.kind}: {b.reason}): {b.error}")
        self.obstacles += tuple(pair.cos)
        self.owners += tuple((b.name, b.source) for _ in pair.cos)
        self._built += 1
        return _UnionOf(pair.cos)

    def __repr__(self) -> str:
        return (f"LazyCSpace(name={self.name!r}, pairs={len(self._todo)}, "
                f"built={self._built})")
