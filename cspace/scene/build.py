"""Building a scene's C-obstacles: one per body (or per robot part and body), through the cache.

:func:`_build_with` runs the builds locally or on an executor in batches
(:func:`build_pair_batch`), each C-obstacle keyed (:func:`_key`, :func:`_pair_key`) and stored in
the disk cache (:mod:`cspace.scene.cache`); :func:`_pair_cos` and :func:`_containment_cos` are the
triangle-pair and containment constructions (a folded closed surface's enclosed region is
a containment term).
"""

from __future__ import annotations

import dataclasses
import multiprocessing as mp
import os
import time
import warnings
from concurrent.futures import FIRST_COMPLETED, wait
from dataclasses import dataclass, field

import numpy as np

from ..cobstacle.margin import Margin
from ..cobstacle.obstacle import CSpaceObstacle, grown_mesh_sum
from ..cobstacle.pairs import (
    PairObstacle,
    _meets,
    component_points,
    containment_meshes,
    is_sum,
    pair_construction,
)
from ..cobstacle.surface import SurfaceMesh
from ..geometry.exact import Grid
from ..mesh.convex import ConvexPolytope
from .cache import COCache, co_key, pack_polytope, unpack_polytope
from .classify import BodyModel, PairModel, RobotPart, _excess

__all__ = ["build_pair_batch"]


# --------------------------------------------------------------------------------------
# step 6: build, through the cache


def _to_arrays(co) -> dict:
    if co.kind == "convex":  # the obstacle's polytope is the body's: not stored again
        out = {"polytope": pack_polytope(co.polytope)}
    else:
        out = {"vertices": np.asarray(co.vertices), "faces": np.asarray(co.faces),
               "facets": np.array([co.n_facets], dtype=np.int64)}  # polygons, for reports
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
    if body.kind == "convex":  # packed (a cache entry), or unpacked (a scene's snapshot)
        poly = a["polytope"]
        if not isinstance(poly, ConvexPolytope):  # named as CVMS names O + (-R) when built
            poly = unpack_polytope(poly, grid, name=f"{body._solid.name}+-{robot.name}")
        return CSpaceObstacle(poly, obstacle=body._solid,
                              robot=robot, reference_point=c, margin=m)
    co = CSpaceObstacle.from_mesh(a["vertices"], a["faces"], obstacle=body._solid,
                                  robot=robot, reference_point=c, grid=grid, name=body.name,
                                  margin=m)
    if "facets" in a:  # (an older entry has none: its report counts triangles)
        co._facets = int(a["facets"][0])
    return co


def _build(body: BodyModel, robot, c, grid, margin: Margin, progress, grown=None, memory=None):
    """The C-obstacle of a body and a convex robot part, grown by ``margin`` (the float64
    surface of a solid body by what also covers its rounding), with that margin.
    ``grown``: ``margin.grow(robot)`` when the caller has it (one hull per robot part);
    ``memory``: the budget a solid body's exact sum is watched against."""
    if body.kind == "solid":
        S, m = grown_mesh_sum(body._solid, robot.reflected(c), margin, progress, memory)
        co = CSpaceObstacle.from_mesh(S.vertices, S.faces, obstacle=body._solid, robot=robot,
                                      reference_point=robot.grid.to_float(robot.grid.snap(c)),
                                      grid=grid, sum=S, name=body.name, margin=m)
        co.excess = robot.excess
        return co
    grown = margin.grow(robot) if grown is None else grown
    # CSpaceObstacle.build(..., conservative=False) without its margin, which is replaced
    # below: the scene's margin is decided once for every body.
    co = CSpaceObstacle._grown(body._solid, grown, np.asarray(c, dtype=np.float64).reshape(3),
                               grid, margin.without_growth())
    co.robot, co.margin = robot, margin
    co.excess = _excess(body) + robot.excess  # the grown robot's hull has lost its excess
    return co


def _key(body: BodyModel, robot, c_ints, grid) -> str:
    """Cache key of a sum (CVMS, NCC-CVMS): a convex or solid body, never a surface. A
    convex one's entry is one packed polytope (:func:`pack_polytope`; older entries, two
    polytopes in twelve arrays, are under other keys)."""
    kind = "convex packed" if body.kind == "convex" else body.kind
    return co_key(kind, grid, body._ints, body.faces, robot.ints, c_ints)


def _pair_key(construction, body: BodyModel, part: RobotPart, c_ints, grid,
              margin: Margin) -> str:
    faces = body.faces[body._keep] if body.kind == "surface" else body.faces
    robot = np.vstack(_part_triangles(part))
    # "trees": triangle pairs are stored as the triangles in reach, not as enumerated pairs
    return co_key(f"{construction} trees robot {len(part.ints)} margin {list(margin.steps)}", grid,
                  body._ints, faces, robot, c_ints)


def _part_triangles(part: RobotPart):
    """The robot part's exact grid vertices and triangles: a convex part's are its polytope's
    facets, fanned (its mesh may be a bent body the polytope stands for); another's its
    welded mesh."""
    if part.kind == "convex":
        return part.operand.ints, part.operand.faces
    return part.ints, part.faces


def _body_operand(body: BodyModel):
    """The obstacle body's exact grid vertices and triangles (a solid's are oriented)."""
    if body.kind == "surface":
        return body._ints, body.faces[body._keep]
    return body._solid.ints, body._solid.faces


def _pair_cos(construction, arrays, body: BodyModel, part: RobotPart, c_ints, grid, bounds_g):
    """C-obstacles of a pair with a non-convex robot part (triangle pairs and containment
    terms), from built or cached arrays."""
    c = part.grid.to_float(c_ints)
    obstacle = (SurfaceMesh(body.vertices, body.faces[body._keep], body.name)
                if body.kind == "surface" else body._solid)
    name = f"{body.name} x {part.name}"
    o_ints, o_faces = _body_operand(body)
    r_ints, r_faces = _part_triangles(part)
    S, T = _pair_operands(o_ints[o_faces], c_ints - r_ints[r_faces], arrays)
    cos = [PairObstacle(S, T, closed=bool(arrays["closed"]), margin=arrays["margin"],
                        obstacle=obstacle, robot=part, reference_point=c,
                        grid=grid)] if len(S) and len(T) else []
    cos += _containment_cos(body, part, c_ints, grid, bounds_g, obstacle, name)
    for co in cos:
        co.semantics = (body.kind != "surface", part.kind)
        co.excess = _excess(body)  # a non-convex robot part is never a hull
    return cos


def _containment_cos(body: BodyModel, part: RobotPart, c_ints, grid, bounds_g, obstacle,
                     name: str) -> list:
    """The containment terms of a pair (module :mod:`cspace.cobstacle.pairs`), as exact mesh
    C-obstacles; terms whose box misses the bounds are left out.

    - a closed robot part (a solid, or a closed surface that encloses a region) holding an
      obstacle component: ``o + c - R`` for one vertex o of each obstacle component;
    - a closed body (a solid against a non-convex part, or a closed surface that encloses a
      region) holding a robot component: ``O + c - r`` for one vertex r of each component.

    A convex side needs none (its pieces are solid), nor does NCC-CVMS (its sum is).
    """
    c = part.grid.to_float(c_ints)
    held_by_robot = (_part_triangles(part) if part.kind in ("solid", "convex") else
                     (part.encloses.ints, part.encloses.faces) if part.encloses is not None
                     else None)
    held_by_body = ((body._solid.ints, body._solid.faces) if body.kind in ("solid", "convex") else
                    (body._encloses.ints, body._encloses.faces)
                    if body.kind == "surface" and body._encloses is not None else None)
    terms = []
    if held_by_robot is not None:  # obstacle components small enough for the robot to hold
        points = component_points(*_body_operand(body), fits_in=np.ptp(held_by_robot[0], axis=0))
        terms += containment_meshes(points, *held_by_robot, c_ints, robot_solid=True)
    if held_by_body is not None:  # robot components small enough for the body to hold
        points = component_points(*_part_triangles(part),
                                  fits_in=np.ptp(held_by_body[0], axis=0))
        terms += containment_meshes(points, *held_by_body, c_ints, robot_solid=False)
    return [CSpaceObstacle.from_mesh(grid.to_float(ints), faces, obstacle=obstacle, robot=part,
                                     reference_point=c, grid=grid, name=f"{name} (containment)")
            for ints, faces in terms if _meets(ints.min(axis=0), ints.max(axis=0), *bounds_g)]


def _build_pair_arrays(construction, body: BodyModel, part: RobotPart, c_ints, grid, bounds_g,
                       margin: Margin, progress) -> dict:
    """Build a pair with a non-convex robot part (triangle pairs, each piece grown by
    ``margin``): arrays for the cache. Nothing is enumerated: the C-obstacle is queried
    through two box trees (PairObstacle). Kept: the triangles whose pieces can meet the
    bounds at all."""
    o_ints, o_faces = _body_operand(body)
    r_ints, r_faces = _part_triangles(part)
    S, T = o_ints[o_faces], c_ints - r_ints[r_faces]
    s_keep, t_keep = _in_reach(S, T, margin.g, bounds_g)
    return {"s_keep": s_keep, "t_keep": t_keep, "margin": margin.g,
            "closed": np.array(body.kind != "surface" or part.kind != "surface"),
            "counts": np.array([int(s_keep.sum()), int(t_keep.sum()),
                                len(S) - int(s_keep.sum())], dtype=np.int64)}


def _in_reach(S, T, g, bounds_g) -> tuple[np.ndarray, np.ndarray]:
    """Exact: the obstacle triangles whose pieces ``s ⊕ T ⊕ box`` can meet the bounds (with
    some robot triangle), and the robot triangles likewise: the others never hold a query."""
    if not len(S) or not len(T):  # a body of what snapping took may hold no triangle
        return np.zeros(len(S), dtype=bool), np.zeros(len(T), dtype=bool)
    s_lo, s_hi = S.min(axis=1) - g, S.max(axis=1) + g
    t_lo, t_hi = T.min(axis=1), T.max(axis=1)
    s_keep = _meets(s_lo + t_lo.min(axis=0), s_hi + t_hi.max(axis=0), *bounds_g)
    t_keep = _meets(t_lo + s_lo.min(axis=0), t_hi + s_hi.max(axis=0), *bounds_g)
    return s_keep, t_keep


def _pair_operands(S, T, arrays):
    """The triangles a triangle-pair C-obstacle keeps (``_in_reach``, from the arrays)."""
    return S[arrays["s_keep"]], T[arrays["t_keep"]]


def _pair_detail(construction, arrays) -> str:
    if "counts" not in arrays:
        return ""
    s, t, out = (int(x) for x in arrays["counts"])  # triangle pairs: the only kind here
    extra = f"; {out} obstacle triangles out of reach of the bounds" if out else ""
    return (f"{s} x {t} triangles, pairs found per query by two box trees "
            f"(none enumerated{extra})")


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
    sums: bool = True    # pair_construction's: NCC-CVMS for a solid body and a convex part
    grown: dict = field(default_factory=dict)  # per robot part: its grown polytope
    memory: object = None  # the build's budget: each NCC-CVMS sum is watched against it


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
    elif is_sum(construction):  # the grown robot names the growth
        key = _key(b, _grown(ctx.grown, ctx.margin, part), ctx.c_ints, ctx.grid)
    else:
        key = _pair_key(construction, b, part, ctx.c_ints, ctx.grid, ctx.margin)
    arrays = store.load(key) if store is not None else None
    pair.cache = "hit" if arrays is not None else ("off" if store is None else "miss")
    return key, arrays


def _assemble(ctx: _Context, construction, b: BodyModel, part: RobotPart, pair: PairModel,
              arrays: dict) -> None:
    """The pair's C-obstacles from built or cached arrays (the one way for both)."""
    if is_sum(construction):
        pair.cos = [_from_arrays(arrays, b, part.operand, ctx.c_snapped, ctx.grid, ctx.margin)]
        return
    pair.cos = _pair_cos(construction, arrays, b, part, ctx.c_ints, ctx.grid, ctx.bounds_g)
    pair.detail = _pair_detail(construction, arrays)
    for co in pair.cos:  # one margin for the pair's union
        co.margin = _margin_from(arrays, ctx.margin)


def _store(ctx: _Context, key, pair: PairModel, arrays) -> None:
    """Write a built pair's arrays to the cache (an unwritable cache only warns)."""
    if ctx.store is not None and pair.cache == "miss":
        try:
            ctx.store.store(key, arrays)
        except OSError as exc:  # an unwritable cache must not fail the build
            warnings.warn(f"C-obstacle cache: cannot write {ctx.store.location}: {exc}",
                          UserWarning, stacklevel=3)


def _failed(ctx: _Context, b: BodyModel, part: RobotPart, pair: PairModel, parts: list,
            error: str) -> None:
    b.error = error if len(parts) == 1 else f"{b.error}; {part.name}: {error}".lstrip("; ")
    pair.cache = "off" if ctx.store is None else "miss"


def _pair_arrays(construction, body: BodyModel, part: RobotPart, c, c_ints, grid, bounds_g,
                 margin: Margin, grown: dict) -> dict:
    """Build one pair: the arrays the cache stores (what :func:`_assemble` reads)."""
    if is_sum(construction):
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
        margin, as :func:`cspace.scene.model.model_scene` has them.

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
        construction = pair_construction(b.kind, part.kind, ctx.sums)
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
