"""Benchmark: speed against error, for C-obstacle construction and for planner checks.

Every method answers the same question on the same float input: does the robot R, translated
so that its reference point is at q, touch the obstacle O (q in CO = O ⊕ (-R))?

Construction methods (one table per input, chart ``speed_vs_error_cobstacle.png``):

- *cspace, N bits*: ``CSpaceObstacle.build`` on ``Grid.for_cobstacle(..., bits=N)`` (N from
  12 to 28, the range ``Grid`` accepts is 8..28), conservative (the default a planner gets):
  its stated bound is the C-obstacle's ``error_bound`` and every error must be a false
  collision within it.
- *manifold3d*: ``Manifold.minkowski_sum`` (float), called as ``bench_hard_cases.manifold_sum``
  calls it (a forked child); a speed peer, not a reference.
- *CGAL Nef*: exact ``minkowski_sum_3`` (``benchmarks/peers``, via
  ``bench_hard_cases.cgal_sum``); small inputs only, with a timeout; its output is rounded to
  float64 (its stated bound: that rounding) and its volume is exact.
- *convex hull*: ``hull(O) ⊕ (-R)``, cspace's exact convex sum of the hull (conservative, and
  far from the truth for a non-convex O).
- *CoACD, threshold t*: an approximate convex decomposition of O (CoACD), each piece ⊕ (-R)
  by cspace's convex sum, the C-obstacle their union (no union built, as a planner queries it).
- *voxels, h = S/k*: O and R voxelised at pitch h (trimesh's surface subdivision, interior
  filled), the cell centres of O dilated by those of R (an FFT convolution), a query answered
  by the cell whose centre is nearest. Voxels can be unsafe (false free): measured, not hidden.

Check methods (one table per scene, chart ``speed_vs_error_checks.png``): state validity
and motion validation for a planner on short motions near the obstacles:

- *cspace, N bits*: ``CSpace.contains`` and the exact continuous ``CSpace.segment_free`` (what
  ``cspace.planning.ompl_plugin``'s checker and motion validator call), batched;
- *FCL, discrete r*: ``fcl.collide`` per state on the raw float input (a
  ``cspace.check.fcl.FclOracle`` per obstacle body against the robot mesh: solid semantics,
  behind a bounding-box broad phase; nothing of the C-space), a motion valid when every
  state sampled at spacing ``r × S`` (r = 0.1 ... 0.0001; both ends included) is free;
- *voxels, h = S/k*: one look-up per state; a motion valid when every state sampled at spacing
  h/4 is free.

Errors, against an exact answer:

- Truth for a state q: the exact rational reference of ``tests/hard.py`` (``VoxelCase``,
  ``TiltCase``) where there is one; otherwise FCL (``cspace.check.fcl.FclOracle`` on the float
  input: collide, and distance where free). A point within ``BAND × S`` of the boundary
  (FCL's distance where FCL says free, the finest cspace C-obstacle's signed distance where it
  says collision) is undecidable and excluded; the report gives how many.
- *false free*: declared free, truly colliding (UNSAFE for a planner); *false collision*:
  declared colliding, truly free. On N states (10^5; ``--quick`` 2000), three quarters on the
  boundary of the finest cspace C-obstacle moved along its normal by ``±S × 10^U(-12,-1)``,
  one quarter uniform in its box grown by 10%.
- Hausdorff distance (two-sided estimate, a lower bound from samples): points on the method's
  boundary, each one's distance to the true C-obstacle (the reference's distance for a
  ``VoxelCase``, else FCL's distance, 0 inside); and points on the true boundary (the boundary
  of the finest cspace C-obstacle, 28 bits, ``conservative=False``: within its own bound of
  the truth), each one's distance to the method's set (cspace's exact-sign ``signed_distance``
  on the method's surface, 0 inside; for voxels the distance to the nearest boundary cells'
  cubes). Reported relative to S.
- Volume error: relative to the exact volume (the reference's in rationals, else
  ``volume_exact`` of the finest cspace C-obstacle, the exact sum of the 28-bit snapped input).
- Motions (M = 10^4, ``--quick`` 10^3): start on or near a C-obstacle boundary (three
  quarters) or uniform in the bounds, random direction, length ``S × 10^U(-3,-0.5)``, clipped to
  the bounds. Truth: the exact ``segment_free`` of the finest cspace C-space (28 bits),
  cross-checked on a subset with FCL: the robot's swept volume ``hull(R + a ∪ R + b)`` (exact
  for a convex robot translating, see the API notes) collided with each obstacle, plus the start
  state. *unsafe*: declared valid, truly colliding; *false invalid*: declared invalid, truly
  free.

Cost: build seconds (in process, after one warm-up build; manifold3d's time is measured in
its child, CGAL's by the binary); peak memory of a second, traced build (``tracemalloc``:
Python and numpy allocations; C++ allocations inside manifold3d, CGAL, CoACD and FCL are not
seen); seconds per 10^6 checks (batched calls on the N states or M motions).

S (scene size): the largest side of the finest C-obstacle's bounding box (construction) or of
the planning bounds (scenes).

Usage::

    python benchmarks/bench_speed_error.py [--quick] [--no-cgal] [--out DIR] [--json PATH]

writes ``DIR/speed_vs_error.md``, ``DIR/speed_vs_error_cobstacle.png``,
``DIR/speed_vs_error_checks.png`` and the numbers as JSON (default ``DIR/speed_vs_error.json``).
DIR defaults to ``benchmarks/reports`` (``--quick``: ``out/speed_vs_error_quick``). Needs the
``bench`` extra (matplotlib, coacd) and the ``peers`` extra (manifold3d).
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import sys
import time
import tracemalloc
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Callable

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # hard.py and zoo.py live with the tests
sys.path.insert(0, str(ROOT / "benchmarks"))

import bench_hard_cases as bhc  # noqa: E402
import hard  # noqa: E402
import zoo  # noqa: E402

import cspace  # noqa: E402
from cspace import CSpace, CSpaceObstacle, Grid  # noqa: E402
from cspace.check.fcl import FclOracle
from cspace.check.cross_check import near_surface  # noqa: E402

REPORTS = ROOT / "benchmarks" / "reports"
SHARED = ROOT.parent / "shared" / "data"
BAND = 1e-9  # undecidable band, relative to S
FLOOR = 1e-17  # where a measured 0 is drawn on log axes (relative errors)
BITS = (12, 16, 20, 24, 26, 28)
FINE_BITS = 28  # the finest grid Grid accepts: the reference C-obstacle
FCL_RES = (1e-1, 1e-2, 1e-3, 1e-4)
ENDPOINT_BAND = 1e-6  # motion ends this close to a boundary (relative to S) are redrawn
CGAL_TIMEOUT = 300.0


# --------------------------------------------------------------------------------------
# geometry helpers


def on_surface(V: np.ndarray, F: np.ndarray, n: int, rng) -> np.ndarray:
    """(n, 3) points uniform by area on the triangles ``V[F]``."""
    T = V[F]
    area = np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    k = rng.choice(len(F), n, p=area / area.sum())
    w = rng.dirichlet(np.ones(3), n)
    return np.einsum("ki,kij->kj", w, T[k])


def mesh_volume(V: np.ndarray, F: np.ndarray) -> float:
    """Enclosed volume of a closed, outward float surface (centred to limit cancellation)."""
    T = V[F] - V.mean(axis=0)
    return float(np.einsum("kj,kj->k", T[:, 0], np.cross(T[:, 1], T[:, 2])).sum() / 6.0)


def hull_mesh(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The convex hull of points as an outward triangle mesh (input coordinates kept)."""
    import trimesh

    h = trimesh.convex.convex_hull(np.asarray(points, dtype=np.float64))
    return np.asarray(h.vertices, dtype=np.float64), np.asarray(h.faces, dtype=np.int64)


def co_volume(co: CSpaceObstacle) -> float | None:
    if co.kind == "convex":
        return float(co.polytope.volume)
    if co.kind == "mesh":
        return mesh_volume(co.vertices, co.faces)
    return None  # a union of pieces: overlapping, no volume without a union


def traced_peak_mb(fn: Callable[[], object]) -> float:
    """Peak traced memory of ``fn()`` in MB (Python and numpy allocations)."""
    tracemalloc.start()
    try:
        fn()
        return tracemalloc.get_traced_memory()[1] / 2**20
    finally:
        tracemalloc.stop()


def timed(fn: Callable[[], object]) -> tuple[object, float]:
    t = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t


# --------------------------------------------------------------------------------------
# voxel C-space


class VoxelCSpace:
    """Voxel C-obstacle: O's and R's cells (pitch ``h``, centres on multiples of ``h``)
    dilated: occupied centres ``i - j`` for O's cells ``i`` and R's ``j``; a query is answered
    by the cell of the nearest centre (the declared set is the union of those cubes)."""

    def __init__(self, bodies, robot_V: np.ndarray, robot_F: np.ndarray, h: float):
        import trimesh
        from scipy.signal import fftconvolve

        def cells(V, F):
            vg = trimesh.Trimesh(V, F, process=False).voxelized(h).fill()
            return np.rint(np.asarray(vg.points) / h).astype(np.int64)

        o_cells = np.vstack([cells(V, F) for V, F in bodies])
        r_cells = cells(robot_V, robot_F)
        self.h = h
        o_lo, r_lo, r_hi = o_cells.min(axis=0), r_cells.min(axis=0), r_cells.max(axis=0)
        a = np.zeros(o_cells.max(axis=0) - o_lo + 1, dtype=np.float32)
        a[tuple((o_cells - o_lo).T)] = 1.0
        b = np.zeros(r_hi - r_lo + 1, dtype=np.float32)
        b[tuple((r_cells - r_lo).T)] = 1.0
        # Dilation as one FFT convolution (a direct one costs cells x robot cells): with R
        # flipped, index p of the full result is the centre o_lo - r_hi + p.
        self.occ = fftconvolve(a, b[::-1, ::-1, ::-1], mode="full") > 0.5
        self.offset = o_lo - r_hi
        pad = np.pad(self.occ, 1)
        inner = pad[1:-1, 1:-1, 1:-1]
        boundary = np.zeros_like(self.occ)
        self._faces = []  # (cell index, axis, side) of boundary faces, for surface samples
        for axis in range(3):
            for side in (-1, 1):
                nb = np.roll(pad, -side, axis=axis)[1:-1, 1:-1, 1:-1]
                f = inner & ~nb
                boundary |= f
                idx = np.argwhere(f)
                self._faces.append((idx, axis, side))
        from scipy.spatial import cKDTree

        self._centres = (np.argwhere(boundary) + self.offset) * h
        self._tree = cKDTree(self._centres)
        self.volume = float(self.occ.sum()) * h**3

    def contains(self, q: np.ndarray) -> np.ndarray:
        k = np.rint(q / self.h).astype(np.int64) - self.offset
        ok = ((k >= 0) & (k < self.occ.shape)).all(axis=1)
        out = np.zeros(len(q), dtype=bool)
        out[ok] = self.occ[tuple(k[ok].T)]
        return out

    def distance(self, q: np.ndarray) -> np.ndarray:
        """Distance to the union of cubes (0 inside), from the 16 nearest boundary cells
        (an estimate: a nearer cube farther down the list is possible but rare)."""
        out = np.zeros(len(q))
        free = ~self.contains(q)
        if free.any() and len(self._centres):
            kk = min(16, len(self._centres))
            _, idx = self._tree.query(q[free], k=kk)
            idx = idx.reshape(len(idx), -1)
            gap = np.maximum(np.abs(q[free][:, None, :] - self._centres[idx]) - self.h / 2, 0.0)
            out[free] = np.sqrt((gap**2).sum(axis=2)).min(axis=1)
        return out

    def surface(self, n: int, rng) -> np.ndarray:
        counts = np.array([len(f[0]) for f in self._faces])
        pick = rng.choice(len(counts), n, p=counts / counts.sum())
        out = np.zeros((n, 3))
        for g, (idx, axis, side) in enumerate(self._faces):
            m = pick == g
            if not m.any():
                continue
            c = (idx[rng.integers(0, len(idx), m.sum())] + self.offset) * self.h
            p = c + rng.uniform(-0.5, 0.5, (m.sum(), 3)) * self.h
            p[:, axis] = c[:, axis] + side * self.h / 2
            out[m] = p
        return out

    def motions_free(self, q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
        return sampled_motions_free(self.contains, q0, q1, self.h / 4)


def sampled_motions_free(collides: Callable, q0: np.ndarray, q1: np.ndarray,
                         step: float) -> np.ndarray:
    """Discrete motion validation: every state at spacing ``step`` (ends included) free."""
    n = np.maximum(1, np.ceil(np.linalg.norm(q1 - q0, axis=1) / step).astype(np.int64))
    owner = np.repeat(np.arange(len(q0)), n + 1)
    start = np.repeat(np.cumsum(n + 1) - (n + 1), n + 1)
    t = (np.arange(owner.size) - start) / n[owner]
    states = q0[owner] + t[:, None] * (q1[owner] - q0[owner])
    hit = collides(states)
    bad = np.zeros(len(q0), dtype=bool)
    np.logical_or.at(bad, owner, hit)
    return ~bad


# --------------------------------------------------------------------------------------
# FCL checker (solid semantics, one oracle per raw obstacle body, box broad phase)


class FclChecker:
    """FCL on a check scene's raw float input (``sc.bodies``, ``sc.robot_V``/``robot_F``,
    reference point at 0), never the C-space's snapped operands: one :class:`FclOracle` per
    body, behind the box of the translations where the robot's box meets the body's."""

    def __init__(self, sc: "CheckScene"):
        RV = np.ascontiguousarray(sc.robot_V, dtype=np.float64)
        RF = np.asarray(sc.robot_F, dtype=np.int64)
        self.robot_V = RV
        self.parts = []
        for V, F in sc.bodies:
            V, F = np.ascontiguousarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64)
            box = np.stack([V.min(axis=0) - RV.max(axis=0), V.max(axis=0) - RV.min(axis=0)])
            self.parts.append((FclOracle(V, F, RV, RF).collides, box, (V, F)))

    def collides(self, q: np.ndarray) -> np.ndarray:
        out = np.zeros(len(q), dtype=bool)
        for collide, (lo, hi), _ in self.parts:
            near = np.nonzero(~out & ((lo <= q) & (q <= hi)).all(axis=1))[0]
            if near.size:
                out[near] = collide(q[near])
        return out

    def swept_collides(self, q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
        """FCL's answer for straight motions of a convex robot: its swept hull
        ``hull(R + a ∪ R + b)`` against each obstacle surface, or the start state colliding."""
        import fcl
        from scipy.spatial import ConvexHull

        out = self.collides(q0)
        objs = []
        for _, box, (V, F) in self.parts:
            m = fcl.BVHModel()
            m.beginModel(len(F), len(V))
            m.addSubModel(V, F)
            m.endModel()
            objs.append((fcl.CollisionObject(m, fcl.Transform()), box))
        Rv = self.robot_V
        for i in np.nonzero(~out)[0]:
            P = np.vstack([Rv + q0[i], Rv + q1[i]])
            H = ConvexHull(P)
            geom = fcl.Convex(P, len(H.simplices),
                              np.hstack([np.full((len(H.simplices), 1), 3), H.simplices]).ravel())
            sw = fcl.CollisionObject(geom, fcl.Transform())
            lo_s, hi_s = np.minimum(q0[i], q1[i]), np.maximum(q0[i], q1[i])
            for obj, (lo, hi) in objs:
                if (hi_s < lo).any() or (lo_s > hi).any():
                    continue
                if fcl.collide(sw, obj, fcl.CollisionRequest(), fcl.CollisionResult()) > 0:
                    out[i] = True
                    break
        return out


# --------------------------------------------------------------------------------------
# inputs, truth


@dataclass
class Input:
    """One construction input: obstacle (float), robot points (reference point at 0)."""

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    robot: np.ndarray
    case: object = None  # hard.VoxelCase / TiltCase: exact membership and volume
    cgal: bool = False
    coacd: tuple = (0.2, 0.05)

    def __post_init__(self):
        # Every tool gets the obstacle wound outwards (an inward-wound input makes
        # manifold3d sum another solid, and FCL's containment test miss).
        if mesh_volume(self.vertices, self.faces) < 0:
            self.faces = np.ascontiguousarray(self.faces[:, ::-1])


def construction_inputs(quick: bool) -> list[Input]:
    L = hard.VoxelCase(hard.l_cells(), (0.5, 0.5, 0.5), (0.3, 0.3, 0.3))
    k = 6 if quick else 9
    tilt = hard.TiltCase(10.0**-k)
    out = [Input("L bracket ⊕ box (hard.VoxelCase)", L.vertices, L.faces, L.robot, L, cgal=True,
                 coacd=(0.05,)),
           Input(f"tilt 10^-{k} ⊕ box (hard.TiltCase)", tilt.vertices, tilt.faces, tilt.robot,
                 tilt, cgal=True, coacd=(0.05,))]
    if quick:
        return out
    stairs = hard.VoxelCase(zoo.stairs_occupancy(4, 1), (0.5, 0.5, 0.5), (0.3, 0.3, 0.3))
    out.append(Input("stairs (4 steps) ⊕ box (hard.VoxelCase)", stairs.vertices, stairs.faces,
                     stairs.robot, stairs, cgal=True, coacd=(0.2, 0.05)))
    for mesh, robot in (("bunny-128", "box"), ("bumpy-528", "hull20")):
        path = SHARED / zoo.SHARED_CLOSED_MESHES[mesh]
        if not path.exists():
            continue
        from cspace.mesh.closed import ClosedMesh

        m = ClosedMesh.load(path)
        # writable copies: manifold3d's binding rejects read-only arrays
        V, F = np.array(m.vertices, np.float64), np.array(m.faces, np.int64)
        rob = zoo.scaled_robots(float(np.ptp(V, axis=0).max()))[robot]
        out.append(Input(f"{mesh} ⊕ {robot} (../shared/data)", V, F, rob, None, cgal=False))
    return out


class Truth:
    """The true C-obstacle of one input: membership, distance, boundary samples, volume."""

    def __init__(self, inp: Input):
        self.inp = inp
        V, F, R = inp.vertices, inp.faces, inp.robot
        grid = Grid.for_cobstacle(V, R, np.zeros(3), bits=FINE_BITS)
        self.fine = CSpaceObstacle.build((V, F), R, grid=grid, conservative=False)
        lo, hi = self.fine.bounds
        self.size = float((hi - lo).max())
        self.band = BAND * self.size
        RV, RF = hull_mesh(R)
        self.oracle = FclOracle(V, F, RV, RF)
        case = inp.case
        if case is not None:
            self.volume = case.volume()
            self.reference = ("exact rational reference (tests/hard.py): membership, volume"
                              + (", distance" if isinstance(case, hard.VoxelCase) else
                                 "; distance: FCL"))
        else:
            self.volume = self.fine.sum.volume_exact
            self.reference = ("FCL (membership, distance; band " f"{BAND:g} S undecidable); "
                              f"volume: volume_exact of the {FINE_BITS}-bit cspace C-obstacle")

    def membership(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(inside, decided)."""
        if self.inp.case is not None:
            return self.inp.case.contains(q), np.ones(len(q), dtype=bool)
        hit = self.oracle.collides(q)
        decided = np.ones(len(q), dtype=bool)
        free = np.nonzero(~hit)[0]
        decided[free] = self.oracle.distance(q[free]) >= self.band
        inside = np.nonzero(hit)[0]
        decided[inside] = np.abs(self.fine.signed_distance(q[inside])) >= self.band
        return hit, decided

    def distance(self, q: np.ndarray) -> np.ndarray:
        """Distance to the true C-obstacle (0 inside)."""
        if isinstance(self.inp.case, hard.VoxelCase):
            return self.inp.case.distance(q)
        out = np.zeros(len(q))
        free = np.nonzero(~self.oracle.collides(q))[0]
        out[free] = np.maximum(self.oracle.distance(q[free]), 0.0)
        return out

    def states(self, n: int, rng) -> np.ndarray:
        near = near_surface(self.fine, n - n // 4, rng, self.size)
        lo, hi = self.fine.bounds
        pad = 0.1 * (hi - lo)
        return np.vstack([near, rng.uniform(lo - pad, hi + pad, (n // 4, 3))])


# --------------------------------------------------------------------------------------
# construction methods: each returns a Built


@dataclass
class Built:
    method: str
    family: str  # 'exact', 'peer' or 'approx'
    param: str = ""
    result: str = "ok"
    seconds: float | None = None
    peak_mb: float | None = None
    bound: float | None = None  # stated (absolute)
    contains: Callable | None = None
    distance: Callable | None = None  # to the declared set, 0 inside
    surface: Callable | None = None  # (n, rng) -> points on its boundary
    volume: float | Fraction | None = None
    extra: dict = field(default_factory=dict)


def _co_built(method, family, param, co, seconds, peak, bound) -> Built:
    return Built(method, family, param, seconds=seconds, peak_mb=peak, bound=bound,
                 contains=co.contains,
                 distance=lambda q: np.maximum(co.signed_distance(q), 0.0),
                 surface=lambda n, rng: on_surface(co.vertices, co.faces, n, rng),
                 volume=co_volume(co))


def build_cspace(inp: Input, bits: int) -> Built:
    V, F, R = inp.vertices, inp.faces, inp.robot
    grid = Grid.for_cobstacle(V, R, np.zeros(3), bits=bits)

    def make():
        return CSpaceObstacle.build((V, F), R, grid=grid)

    try:
        co, dt = timed(make)
    except cspace.CspaceError as exc:
        return Built("cspace", "exact", f"{bits} bits",
                     result=f"{type(exc).__name__}: {str(exc)[:80]}")
    return _co_built("cspace", "exact", f"{bits} bits", co, dt, traced_peak_mb(make),
                     co.error_bound)


def build_manifold(inp: Input) -> Built:
    try:
        import manifold3d  # noqa: F401
    except ImportError:
        return Built("manifold3d", "peer", result="not installed (pip install -e '.[peers]')")
    kind, got = bhc.manifold_sum(inp.vertices, inp.faces, inp.robot)
    if kind != "ok":
        return Built("manifold3d", "peer", result=got)
    V, F, dt = got
    try:
        co = CSpaceObstacle.from_mesh(V, F)
    except cspace.CspaceError as exc:
        return Built("manifold3d", "peer", result=f"invalid output ({type(exc).__name__})",
                     seconds=dt)
    return _co_built("manifold3d", "peer", "", co, dt, None, None)


def build_cgal(inp: Input, enabled: bool) -> Built | None:
    if not enabled or not inp.cgal:
        return None
    if not bhc.CGAL["binary"]:
        return Built("CGAL Nef", "exact", result=f"skipped: {bhc.CGAL['status']}")
    kind, got = bhc.cgal_sum(inp.vertices, inp.faces, inp.robot, CGAL_TIMEOUT)
    if kind != "ok":
        return Built("CGAL Nef", "exact", result=got)
    V, F, dt, vol = got
    try:
        co = CSpaceObstacle.from_mesh(V, F)
    except cspace.CspaceError as exc:
        return Built("CGAL Nef", "exact", result=f"invalid after rounding ({type(exc).__name__})",
                     seconds=dt)
    b = _co_built("CGAL Nef", "exact", "", co, dt, None,
                  math.sqrt(3) * 2.0**-53 * float(np.abs(V).max()))  # rounding to float64
    b.volume = vol
    return b


def build_hull(inp: Input) -> Built:
    def make():
        return CSpaceObstacle.build(inp.vertices, inp.robot)  # points: hulled

    co, dt = timed(make)
    return _co_built("convex hull", "approx", "", co, dt, traced_peak_mb(make), None)


def build_coacd(inp: Input, threshold: float) -> Built:
    try:
        import coacd
    except ImportError:
        return Built("CoACD", "approx", f"t={threshold:g}",
                     result="not installed (pip install -e '.[bench]')")
    coacd.set_log_level("error")

    def make():
        parts = coacd.run_coacd(coacd.Mesh(inp.vertices, inp.faces), threshold=threshold,
                                seed=0)
        return CSpace([CSpaceObstacle.build(np.asarray(v, np.float64), inp.robot)
                       for v, _ in parts])

    cs, dt = timed(make)
    peak = traced_peak_mb(make)
    import manifold3d

    # measurement only: the union's volume (a planner never builds it)
    union = manifold3d.Manifold.batch_boolean(
        [manifold3d.Manifold.hull_points(np.ascontiguousarray(co.vertices))
         for co in cs.obstacles], manifold3d.OpType.Add)
    V = np.vstack([co.vertices for co in cs.obstacles])
    sizes = np.array([len(co.vertices) for co in cs.obstacles])
    F = np.vstack([co.faces + o for co, o in zip(cs.obstacles,
                                                  np.cumsum(sizes) - sizes)])
    return Built("CoACD", "approx", f"t={threshold:g}, {len(cs)} pieces", seconds=dt,
                 peak_mb=peak, contains=cs.contains,
                 distance=lambda q: np.maximum(cs.signed_distance(q), 0.0),
                 surface=lambda n, rng: on_surface(V, F, n, rng), volume=union.volume())


def build_voxel(bodies, robot_V, robot_F, size: float, k: int) -> Built:
    def make():
        return VoxelCSpace(bodies, robot_V, robot_F, size / k)

    vx, dt = timed(make)
    return Built("voxels", "approx", f"h = S/{k}", seconds=dt, peak_mb=traced_peak_mb(make),
                 contains=vx.contains, distance=vx.distance, surface=vx.surface,
                 volume=vx.volume, extra={"voxel": vx})


# --------------------------------------------------------------------------------------
# construction: evaluate every method on one input


def evaluate(b: Built, truth: Truth, q, inside, decided, true_surface, n_h, rng) -> dict:
    row = {"method": b.method, "family": b.family, "param": b.param, "result": b.result,
           "build_s": b.seconds, "peak_mb": b.peak_mb, "bound": b.bound,
           "bound_rel": None if b.bound is None else b.bound / truth.size}
    if b.result != "ok":
        return row
    declared, dt = timed(lambda: b.contains(q))
    ffm, fcm = ~declared & inside & decided, declared & ~inside & decided
    ff, fc, nd = int(ffm.sum()), int(fcm.sum()), int(decided.sum())
    # how wrong: the deepest false free (into the finest C-obstacle) and the farthest false
    # collision (from the true C-obstacle)
    deep = float(np.max(-truth.fine.signed_distance(q[ffm]), initial=0.0))
    far = float(np.max(truth.distance(q[fcm]), initial=0.0))
    h_out = float(truth.distance(b.surface(n_h, rng)).max())  # method's boundary -> truth
    h_in = float(b.distance(true_surface).max())  # true boundary -> method's set
    H = max(h_out, h_in)
    vol_ref = truth.volume
    if b.volume is None:
        verr = None
    elif isinstance(b.volume, Fraction):
        verr = abs(float((b.volume - vol_ref) / vol_ref))
    else:
        verr = abs(b.volume - float(vol_ref)) / float(vol_ref)
    row.update({"n": int(len(q)), "n_decided": nd, "false_free": ff, "false_coll": fc,
                "false_free_rate": ff / nd, "false_coll_rate": fc / nd,
                "deepest_false_free_rel": deep / truth.size,
                "farthest_false_coll_rel": far / truth.size,
                "hausdorff": H, "hausdorff_rel": H / truth.size,
                "h_method_to_true_rel": h_out / truth.size,
                "h_true_to_method_rel": h_in / truth.size,
                "vol_err": verr, "s_per_1e6_checks": dt / len(q) * 1e6})
    return row


def run_construction(inp: Input, n: int, n_h: int, voxel_ks, cgal: bool, rng) -> dict:
    truth = Truth(inp)
    q = truth.states(n, rng)
    inside, decided = truth.membership(q)
    true_surface = on_surface(truth.fine.vertices, truth.fine.faces, n_h, rng)
    RV, RF = hull_mesh(inp.robot)  # R's cells j are subtracted from O's cells i
    builders: list[Callable[[], Built | None]] = [
        *(lambda b=b: build_cspace(inp, b) for b in BITS),
        lambda: build_manifold(inp),
        lambda: build_cgal(inp, cgal),
        lambda: build_hull(inp),
        *(lambda t=t: build_coacd(inp, t) for t in inp.coacd),
        *(lambda k=k: build_voxel([(inp.vertices, inp.faces)], RV, RF, truth.size, k)
          for k in voxel_ks),
    ]
    rows = []
    for make in builders:
        b = make()
        if b is None:
            continue
        rows.append(evaluate(b, truth, q, inside, decided, true_surface, n_h, rng))
        r = rows[-1]
        print(f"  {r['method']:12s} {r['param']:22s} {r['result'][:40]:40s} "
              f"build {_f(r['build_s'], '.3f')} s  H/S {_f(r.get('hausdorff_rel'))}  "
              f"ff {r.get('false_free')}  fc {r.get('false_coll')}", flush=True)
    return {"input": inp.name, "size": truth.size, "reference": truth.reference,
            "n": int(len(q)), "n_excluded": int((~decided).sum()),
            "n_inside": int((inside & decided).sum()), "n_hausdorff": n_h,
            "reference_bound_rel": truth.fine.error_bound / truth.size, "rows": rows}


# --------------------------------------------------------------------------------------
# checks on scenes


@dataclass
class CheckScene:
    name: str
    build: Callable[[int], CSpace]  # bits -> the cspace C-space
    bodies: list  # [(V, F)] obstacle meshes (float input)
    robot_V: np.ndarray  # robot mesh, reference point at 0
    robot_F: np.ndarray
    bounds: np.ndarray
    case: object = None  # exact state reference (hard.VoxelCase)


def check_scenes(quick: bool) -> list[CheckScene]:
    out = []
    names = ["window"] if quick else ["window", "comb"]
    for name in names:
        scene = cspace.load_scene(ROOT / "scenes" / f"{name}.toml")
        out.append(CheckScene(
            f"{name} (scenes/{name}.toml)",
            lambda bits, s=scene: CSpace.from_scene(s, grid=s.grid(bits=bits)),
            [(b.vertices, b.faces) for b in scene.obstacles],
            scene.robot.vertices - scene.reference_point, scene.robot.faces, scene.bounds))
    L = hard.VoxelCase(hard.l_cells(), (0.5, 0.5, 0.5), (0.3, 0.3, 0.3))
    singles = [("L bracket ⊕ box (hard.VoxelCase)", L.vertices, L.faces, L.robot, L)]
    path = SHARED / zoo.SHARED_CLOSED_MESHES["bunny-128"]
    if not quick and path.exists():
        from cspace.mesh.closed import ClosedMesh

        m = ClosedMesh.load(path)
        # writable copies: manifold3d's binding rejects read-only arrays
        V, F = np.array(m.vertices, np.float64), np.array(m.faces, np.int64)
        singles.append(("bunny-128 ⊕ box (../shared/data)", V, F,
                        zoo.scaled_robots(float(np.ptp(V, axis=0).max()))["box"], None))
    for name, V, F, R, case in singles:
        fine = CSpaceObstacle.build((V, F), R)
        lo, hi = fine.bounds
        bounds = np.stack([lo - 0.1 * (hi - lo), hi + 0.1 * (hi - lo)])

        def build(bits, V=V, F=F, R=R, bounds=bounds):
            g = Grid.for_cobstacle(V, R, np.zeros(3), bits=bits)
            return CSpace([CSpaceObstacle.build((V, F), R, grid=g)], bounds=bounds)

        RV, RF = hull_mesh(R)
        out.append(CheckScene(name, build, [(V, F)], RV, RF, bounds, case))
    return out


def near_states(fine: CSpace, n: int, size: float, rng) -> np.ndarray:
    """Three quarters on the C-obstacles' boundaries moved along the normal by
    ``±size × 10^U(-12,-1)``, one quarter uniform; all in the bounds."""
    lo, hi = fine.bounds
    parts, need = [rng.uniform(lo, hi, (n // 4, 3))], n - n // 4
    while need > 0:
        per = need // len(fine.obstacles) + 1
        p = np.vstack([near_surface(co, per, rng, size) for co in fine.obstacles])
        p = p[((lo <= p) & (p <= hi)).all(axis=1)][:need]
        parts.append(p)
        need -= len(p)
    return np.vstack(parts)


def motions(fine: CSpace, m: int, size: float, rng) -> tuple[np.ndarray, np.ndarray]:
    """Short straight motions near the obstacles: starts drawn by :func:`near_states`, a
    random direction, length ``size × 10^U(-3,-0.5)``, clipped to the bounds. Motions with an
    end within ``ENDPOINT_BAND × size`` of a C-obstacle boundary are redrawn: there the
    truth (the finest C-space, grown by its bound) cannot decide, and states that close are
    measured by the state checks."""
    lo, hi = fine.bounds
    band = ENDPOINT_BAND * size
    q0s, q1s, got = [], [], 0
    while got < m:
        q0 = near_states(fine, m, size, rng)
        d = rng.normal(size=(m, 3))
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        q1 = np.clip(q0 + d * (size * 10.0 ** rng.uniform(-3, -0.5, m))[:, None], lo, hi)
        ok = ((np.abs(fine.signed_distance(q0)) >= band)
              & (np.abs(fine.signed_distance(q1)) >= band))
        q0s.append(q0[ok][: m - got])
        q1s.append(q1[ok][: m - got])
        got += len(q0s[-1])
    return np.vstack(q0s), np.vstack(q1s)


def run_checks(sc: CheckScene, n: int, m: int, voxel_ks, fcl_res, n_cross: int, rng) -> dict:
    fine, fine_s = timed(lambda: sc.build(FINE_BITS))
    lo, hi = sc.bounds
    size = float((hi - lo).max())
    band = BAND * size
    fclc = FclChecker(sc)
    q = near_states(fine, n, size, rng)
    # state truth: exact reference, else FCL outside the band of the finest C-space
    fcl_hit, fcl_state_s = timed(lambda: fclc.collides(q))
    if sc.case is not None:
        inside, decided = sc.case.contains(q), np.ones(len(q), dtype=bool)
        truth_distance = sc.case.distance
    else:
        inside = fcl_hit
        decided = np.abs(fine.signed_distance(q)) >= band

        def truth_distance(x):  # the finest C-space's (within its bound of the truth)
            return np.maximum(fine.signed_distance(x), 0.0)
    q0, q1 = motions(fine, m, size, rng)
    truth_free, truth_s = timed(lambda: fine.segment_free(q0, q1))
    # cross-check of the motion truth: FCL's swept hull on a subset
    sub = rng.choice(m, min(n_cross, m), replace=False)
    swept_free = ~fclc.swept_collides(q0[sub], q1[sub])
    cross = {"n": int(len(sub)), "disagree": int((swept_free != truth_free[sub]).sum())}
    rows = []

    def add(method, family, param, build_s, peak, bound, s_state, declared_state,
            s_motion, declared_free):
        ffm = ~declared_state & inside & decided
        fcm = declared_state & ~inside & decided
        ff, fc, nd = int(ffm.sum()), int(fcm.sum()), int(decided.sum())
        deep = float(np.max(-fine.signed_distance(q[ffm]), initial=0.0))
        far = float(np.max(truth_distance(q[fcm]), initial=0.0))
        unsafe = int((declared_free & ~truth_free).sum())
        finv = int((~declared_free & truth_free).sum())
        rows.append({"method": method, "family": family, "param": param, "build_s": build_s,
                     "peak_mb": peak, "bound": bound,
                     "bound_rel": None if bound is None else bound / size,
                     "state_s_per_1e6": s_state / len(q) * 1e6,
                     "state_false_free": ff, "state_false_coll": fc,
                     "state_false_free_rate": ff / nd, "state_false_coll_rate": fc / nd,
                     "state_deepest_false_free_rel": deep / size,
                     "state_farthest_false_coll_rel": far / size,
                     "motion_s_per_1e6": s_motion / m * 1e6, "motion_unsafe": unsafe,
                     "motion_false_invalid": finv, "motion_unsafe_rate": unsafe / m,
                     "motion_false_invalid_rate": finv / m})
        r = rows[-1]
        print(f"  {method:10s} {param:14s} state ff {ff} fc {fc}  motion unsafe {unsafe} "
              f"false invalid {finv}  {r['motion_s_per_1e6']:.3g} s/1e6 motions", flush=True)

    sc.build(26)  # warm-up (first build in a process pays one-off costs)
    for bits in BITS:
        try:
            cs, dt = timed(lambda: sc.build(bits))
        except cspace.CspaceError as exc:
            rows.append({"method": "cspace", "family": "exact", "param": f"{bits} bits",
                         "result": f"{type(exc).__name__}: {str(exc)[:80]}"})
            continue
        peak = traced_peak_mb(lambda: sc.build(bits))
        bound = max(co.error_bound for co in cs.obstacles)
        st, s_st = timed(lambda: cs.contains(q))
        mv, s_mv = timed(lambda: cs.segment_free(q0, q1))
        add("cspace", "exact", f"{bits} bits", dt, peak, bound, s_st, st, s_mv, mv)
    for r in fcl_res:
        mv, s_mv = timed(lambda: sampled_motions_free(fclc.collides, q0, q1, r * size))
        add("FCL", "approx", f"discrete {r:g} S", None, None, None, fcl_state_s, fcl_hit,
            s_mv, mv)
    for k in voxel_ks:
        b = build_voxel(sc.bodies, sc.robot_V, sc.robot_F, size, k)
        vx = b.extra["voxel"]
        st, s_st = timed(lambda: vx.contains(q))
        mv, s_mv = timed(lambda: vx.motions_free(q0, q1))
        add("voxels", "approx", f"h = S/{k}", b.seconds, b.peak_mb, None, s_st, st, s_mv, mv)
    return {"scene": sc.name, "size": size, "n": int(len(q)), "n_excluded": int((~decided).sum()),
            "state_reference": ("exact rational reference (tests/hard.py)" if sc.case is not None
                                else f"FCL, band {BAND:g} S (finest cspace signed distance)"),
            "m": m, "motion_truth_free": int(truth_free.sum()),
            "motion_truth": f"segment_free of the {FINE_BITS}-bit cspace C-space",
            "motion_truth_bound_rel": max(co.error_bound for co in fine.obstacles) / size,
            "truth_seconds": truth_s, "fine_build_s": fine_s, "cross_check": cross,
            "rows": rows}


# --------------------------------------------------------------------------------------
# report


_f = bhc._fmt  # a number as the reports print it ('–' for none)


def _rate(k, n) -> str:
    return f"{k} ({100.0 * k / n:.2g}%)" if n else "–"


def pareto(points: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """Points not dominated (lower cost and lower error), sorted by cost."""
    front, best = [], math.inf
    for x, y in sorted(points):
        if y < best:
            front.append((x, y))
            best = y
    return front


def construction_table(res: dict) -> list[str]:
    S = res["size"]
    lines = [f"### {res['input']}", "",
             f"S = {S:.4g}; truth: {res['reference']}; {res['n']} states "
             f"({res['n_excluded']} undecidable, excluded; {res['n_inside']} truly colliding), "
             f"{res['n_hausdorff']} boundary samples per side for the Hausdorff estimate. "
             f"The true boundary is sampled on the {FINE_BITS}-bit cspace C-obstacle "
             f"(within {res['reference_bound_rel']:.2g} S of the truth).", "",
             "| method | parameter | result | build s | peak MB | stated bound / S | "
             "Hausdorff / S (method→true, true→method) | volume error | false free (UNSAFE) | "
             "deepest false free / S | false collision | farthest false collision / S | "
             "s / 10^6 checks |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in res["rows"]:
        nd = r.get("n_decided", 0)
        haus = ("–" if "hausdorff_rel" not in r else
                f"{r['hausdorff_rel']:.2g} ({r['h_method_to_true_rel']:.2g}, "
                f"{r['h_true_to_method_rel']:.2g})")
        ff = "–" if "false_free" not in r else _rate(r["false_free"], nd)
        fc = "–" if "false_coll" not in r else _rate(r["false_coll"], nd)
        lines.append(f"| {r['method']} | {r['param']} | {r['result']} | "
                     f"{_f(r['build_s'], '.3g')} | {_f(r['peak_mb'], '.3g')} | "
                     f"{_f(r['bound_rel'])} | {haus} | {_f(r.get('vol_err'))} | {ff} | "
                     f"{_f(r.get('deepest_false_free_rel'))} | {fc} | "
                     f"{_f(r.get('farthest_false_coll_rel'))} | "
                     f"{_f(r.get('s_per_1e6_checks'), '.3g')} |")
    return lines + [""]


def checks_table(res: dict) -> list[str]:
    cc = res["cross_check"]
    lines = [f"### {res['scene']}", "",
             f"S = {res['size']:.4g}; {res['n']} states, truth: {res['state_reference']} "
             f"({res['n_excluded']} undecidable, excluded); {res['m']} motions "
             f"({res['motion_truth_free']} truly free), truth: {res['motion_truth']} "
             f"(bound {res['motion_truth_bound_rel']:.2g} S, {res['truth_seconds']:.2f} s), "
             f"cross-checked with FCL's swept hull on {cc['n']} motions: "
             f"{cc['disagree']} disagree. The {FINE_BITS}-bit cspace row's motion answers are "
             "the motion truth"
             + (", and FCL's state answers the state truth (their zeros say nothing)."
                if res["state_reference"].startswith("FCL") else "."), "",
             "| method | parameter | build s | peak MB | stated bound / S | s / 10^6 states | "
             "states false free (UNSAFE) | deepest / S | states false collision | farthest / S | "
             "s / 10^6 motions | motions unsafe | motions false invalid |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    nd = res["n"] - res["n_excluded"]
    for r in res["rows"]:
        if "result" in r:
            lines.append(f"| {r['method']} | {r['param']} | {r['result']} |" + " – |" * 10)
            continue
        lines.append(
            f"| {r['method']} | {r['param']} | {_f(r['build_s'], '.3g')} | "
            f"{_f(r['peak_mb'], '.3g')} | {_f(r['bound_rel'])} | "
            f"{r['state_s_per_1e6']:.3g} | {_rate(r['state_false_free'], nd)} | "
            f"{_f(r['state_deepest_false_free_rel'])} | {_rate(r['state_false_coll'], nd)} | "
            f"{_f(r['state_farthest_false_coll_rel'])} | {r['motion_s_per_1e6']:.3g} | "
            f"{_rate(r['motion_unsafe'], res['m'])} | "
            f"{_rate(r['motion_false_invalid'], res['m'])} |")
    return lines + [""]


STYLE = {"cspace": ("*", "tab:red"), "CGAL Nef": ("P", "tab:purple"),
         "manifold3d": ("D", "tab:blue"), "convex hull": ("s", "tab:gray"),
         "CoACD": ("^", "tab:green"), "voxels": ("o", "tab:orange"), "FCL": ("v", "tab:brown")}


def _axes(n: int):
    import matplotlib

    matplotlib.use("Agg")  # no display: files only
    import matplotlib.pyplot as plt

    cols = min(n, 2)
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(7.0 * cols, 5.2 * rows), squeeze=False)
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    return plt, fig, axes.ravel()


def _short(param: str) -> str:
    """The sweep parameter as a point label: '12', 'S/8', 't=0.05', '0.01 S'."""
    return (param.replace(" bits", "").replace("h = ", "").replace("discrete ", "")
            .split(",")[0])


def _plot(ax, groups: dict, exact_label: str, front_of: list, front_label: str) -> None:
    """One curve per method (points in sweep order, labelled with the parameter); exact
    methods as hollow markers; points with unsafe answers ringed; the Pareto front dashed."""
    ringed = False
    for method, g in groups.items():
        marker, colour = STYLE.get(method, ("x", "k"))
        exact = g["exact"]
        ax.plot(g["x"], g["y"], marker=marker, color=colour, ms=11 if exact else 7,
                mfc="white" if exact else colour, mew=2 if exact else 1, lw=0.8, alpha=0.9,
                ls="-" if len(g["x"]) > 1 else "none",
                label=f"{method} ({exact_label})" if exact else method)
        for x, y, t, bad in zip(g["x"], g["y"], g["labels"], g["unsafe"]):
            if t:
                ax.annotate(t, (x, y), textcoords="offset points", xytext=(5, 4), fontsize=6,
                            color=colour)
            if bad:
                ax.plot([x], [y], "o", ms=16, mfc="none", mec="red", mew=1.2,
                        label=None if ringed else "has UNSAFE answers (false free)")
                ringed = True
    front = pareto(front_of)
    if front:
        fx, fy = zip(*front)
        ax.step(fx, fy, where="post", color="k", ls="--", lw=1, alpha=0.6, label=front_label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    from matplotlib.ticker import NullFormatter

    ax.xaxis.set_minor_formatter(NullFormatter())  # minor labels collide on short ranges
    ax.grid(True, which="major", alpha=0.3)


def chart_cobstacle(results: list[dict], path: Path) -> None:
    plt, fig, axes = _axes(len(results))
    for ax, res in zip(axes, results):
        groups: dict = {}
        pts = []
        for r in res["rows"]:
            if r["result"] != "ok" or r["build_s"] is None:
                continue
            exact = r["family"] == "exact"
            # exact methods at their stated bound (their measured error is at most that)
            y = r["bound_rel"] if exact else max(r["hausdorff_rel"], FLOOR)
            g = groups.setdefault(r["method"], {"x": [], "y": [], "labels": [], "unsafe": [],
                                                "exact": exact})
            g["x"].append(max(r["build_s"], 1e-4))
            g["y"].append(y)
            g["labels"].append(_short(r["param"]))
            g["unsafe"].append(r["false_free"] > 0)
            pts.append((g["x"][-1], y))
        _plot(ax, groups, "drawn at stated bound", pts, "Pareto front")
        ax.axhline(FLOOR, color="k", lw=0.5, ls=":")
        ax.set_title(res["input"], fontsize=10)
        ax.set_xlabel("build seconds")
        ax.set_ylabel(f"Hausdorff error / S (measured 0: drawn at {FLOOR:g})")
        ax.legend(fontsize=7, loc="best")
    fig.suptitle("C-obstacle construction: cost against error (log-log; lower left is better)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def chart_checks(results: list[dict], path: Path) -> None:
    plt, fig, axes = _axes(len(results))
    for ax, res in zip(axes, results):
        groups: dict = {}
        floor = 1.0 / res["m"]
        safe = []
        for r in res["rows"]:
            if "result" in r:
                continue
            wrong = r["motion_unsafe"] + r["motion_false_invalid"]
            y = wrong / res["m"] if wrong else floor
            g = groups.setdefault(r["method"], {"x": [], "y": [], "labels": [], "unsafe": [],
                                                "exact": r["family"] == "exact"})
            g["x"].append(r["motion_s_per_1e6"])
            g["y"].append(y)
            g["labels"].append(_short(r["param"]))
            g["unsafe"].append(r["motion_unsafe"] > 0)
            if not r["motion_unsafe"]:
                safe.append((g["x"][-1], y))
        _plot(ax, groups, "never unsafe; errors are false invalid", safe,
              "Pareto front of the methods without unsafe answers")
        ax.axhline(floor, color="k", lw=0.5, ls=":")
        ax.set_title(res["scene"], fontsize=10)
        ax.set_xlabel("seconds per 10^6 motion checks (batched)")
        ax.set_ylabel("wrong motion answers / M (0: drawn at 1/M)")
        ax.legend(fontsize=7, loc="best")
    fig.suptitle("Motion validation: cost against wrong answers (unsafe + false invalid; "
                 "log-log; lower left is better)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def versions() -> dict:
    from importlib.metadata import PackageNotFoundError, version

    out = {"cspace": cspace.__version__, "numpy": np.__version__,
           "python": platform.python_version()}
    for pkg in ("manifold3d", "coacd", "python-fcl", "trimesh", "scipy", "matplotlib"):
        try:
            out[pkg] = version(pkg)
        except PackageNotFoundError:
            out[pkg] = "absent"
    out["CGAL"] = bhc.CGAL["status"]
    return out


def provenance() -> str:
    """Which cspace ran: this checkout's (with its last commit touching ``cspace/`` and
    whether ``cspace/`` has uncommitted changes), or a package imported from elsewhere."""
    import subprocess

    where = Path(cspace.__file__).resolve().parent
    if where != ROOT / "cspace":
        return f"cspace imported from {where}, outside this checkout"
    try:
        def git(*a):
            return subprocess.run(["git", "-C", str(ROOT), *a], capture_output=True, text=True,
                                  timeout=30).stdout.strip()

        commit = git("log", "-1", "--format=%h %s", "--", "cspace")[:80]
        dirty = " (with uncommitted changes)" if git("status", "--porcelain", "cspace") else ""
    except (OSError, subprocess.TimeoutExpired):
        commit, dirty = "unknown", ""
    return f"cspace from this checkout{dirty}, last commit touching cspace/: {commit}"


def write_report(out: Path, data: dict) -> None:
    v = data["versions"]
    la0, la1 = data["load_start"], data["load_end"]
    head = [
        "# Speed against error: C-obstacle construction and planner checks",
        "",
        f"Generated by `{data['command']}` on {data['date']} in {data['seconds']:.0f} s; "
        + ", ".join(f"{k} {val}" for k, val in v.items() if k != "CGAL")
        + f"; CGAL: {v['CGAL']}; {os.cpu_count()} CPUs shared with other jobs, load average "
        f"(1/5/15 min) {la0[0]:.2f} / {la0[1]:.2f} / {la0[2]:.2f} at the start, "
        f"{la1[0]:.2f} / {la1[1]:.2f} / {la1[2]:.2f} at the end.",
        "",
        data["provenance"] + ".",
        "",
        "Methods, error definitions and sampling: the docstring of "
        "`benchmarks/bench_speed_error.py`. The numbers are also in the JSON sidecar "
        f"(`{data['json_name']}`).",
        "",
        "![Construction: build seconds against Hausdorff error / S]"
        "(speed_vs_error_cobstacle.png)",
        "",
        "![Motion validation: seconds per 10^6 motions against wrong answers]"
        "(speed_vs_error_checks.png)",
        "",
        "Charts: log-log, one curve per method (points labelled with the swept parameter: "
        "bits, voxel pitch, CoACD threshold, FCL sampling step). Construction: exact methods "
        "(hollow markers) are drawn at their stated bound, the others at their measured "
        "Hausdorff error; points with unsafe answers (false free) are ringed in red; the "
        "dashed line is the Pareto front. Checks: wrong motion answers (unsafe + false "
        "invalid) per motion, 0 drawn at 1/M; the Pareto front is that of the methods without "
        "unsafe answers.",
        "",
        "## Columns",
        "",
        "- *S*: the scene size (largest side of the true C-obstacle's box, or of the planning "
        "bounds); errors are given relative to it.",
        "- *stated bound / S*: what the method promises. cspace: the C-obstacle's "
        "`error_bound` (conservative build: every error a false collision within it); CGAL: the "
        "rounding of its exact output to float64. On the charts exact methods are drawn at "
        "this bound (their measured error is at most that, and is often 0).",
        "- *Hausdorff / S*: two-sided estimate from boundary samples (a lower bound), with "
        "its two sides: the method's boundary to the true C-obstacle, and the true boundary to "
        "the method's set. A large first side is over-approximation (false collisions), a large "
        "second side under-approximation (unsafe).",
        "  Values below about 1e-15 are the float64 noise of the measurement itself (the "
        "distances are evaluated in float64): an exact method's output rounded to float64 can "
        "measure slightly above its stated bound.",
        "- *volume error*: |V - V_true| / V_true; '–' for cspace C-obstacles held as a union "
        "of pieces.",
        "- *false free (UNSAFE)*: states declared free that truly collide; *false collision*: "
        "declared colliding, truly free; counts among the decidable states, with rates.",
        "- *build s*: seconds in this process (manifold3d: in its child; CGAL: the binary's "
        "own timer); *peak MB*: tracemalloc peak of a second build (Python and numpy "
        "allocations only; '–' for work done outside Python).",
        "- *s / 10^6 checks*: batched `contains` on the states; manifold3d's and CGAL's outputs "
        "are queried with cspace's exact mesh queries, so that column is cspace's speed on "
        "their surfaces.",
        "- Checks: *s / 10^6 states* and *s / 10^6 motions* per batched call (`CSpace.contains`"
        ", `CSpace.segment_free`; FCL: a Python loop of `fcl.collide` behind a box broad "
        "phase, the same state check for every resolution); *motions unsafe*: declared valid, "
        "truly colliding; *motions false invalid*: declared invalid, truly free.",
        "",
    ]
    body = ["## C-obstacle construction", ""]
    for res in data["construction"]:
        body += construction_table(res)
    body += ["## Planner checks (state validity and motion validation)", ""]
    for res in data["checks"]:
        body += checks_table(res)
    body += summary(data)
    (out / "speed_vs_error.md").write_text("\n".join(head + body) + "\n")


def summary(data: dict) -> list[str]:
    """Totals per method family over all inputs: unsafe answers and worst errors."""
    out = ["## Summary", "",
           "| method | construction rows | states false free (all inputs) | worst Hausdorff / S | "
           "check rows | motions unsafe (all scenes) |", "|---|---|---|---|---|---|"]
    names = []
    for res in data["construction"] + data["checks"]:
        for r in res["rows"]:
            if r["method"] not in names:
                names.append(r["method"])
    for name in names:
        crow = [r for res in data["construction"] for r in res["rows"]
                if r["method"] == name and r.get("result") == "ok"]
        krow = [r for res in data["checks"] for r in res["rows"]
                if r["method"] == name and "result" not in r]
        ff = sum(r["false_free"] for r in crow) + sum(r["state_false_free"] for r in krow)
        worst = max((r["hausdorff_rel"] for r in crow), default=None)
        unsafe = sum(r["motion_unsafe"] for r in krow)
        out.append(f"| {name} | {len(crow)} | {ff} | {_f(worst)} | {len(krow)} | {unsafe} |")
    return out + [""]


def _jsonable(x):
    if isinstance(x, dict):
        return {k: _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (np.floating,)):
        return float(x)
    if isinstance(x, Fraction):
        return float(x)
    return x


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true",
                    help="tiny inputs, few samples, no CGAL (under a minute)")
    ap.add_argument("--out", type=Path, help="report folder (default benchmarks/reports)")
    ap.add_argument("--json", type=Path, help="numbers as JSON (default OUT/speed_vs_error.json)")
    ap.add_argument("--no-cgal", action="store_true", help="skip the CGAL peer")
    args = ap.parse_args(argv)
    out = args.out or (ROOT / "out" / "speed_vs_error_quick" if args.quick else REPORTS)
    out.mkdir(parents=True, exist_ok=True)
    json_path = args.json or out / "speed_vs_error.json"
    load_start = os.getloadavg()
    t0 = time.perf_counter()
    rng = np.random.default_rng(0)
    quick = args.quick
    n, n_h, m = (2000, 300, 1000) if quick else (100_000, 4000, 10_000)
    cgal = not (quick or args.no_cgal)
    if cgal:
        bhc._build_cgal()
    else:
        bhc.CGAL["status"] = "skipped (--quick)" if quick else "skipped (--no-cgal)"
    voxel_ks = (8, 16, 32) if quick else (8, 16, 32, 64, 128)
    fcl_res = FCL_RES
    bv, bf = hull_mesh(zoo.box_points(1.0, 1.0, 1.0))
    VoxelCSpace([(bv, bf)], bv, bf, 0.25)  # one-off costs (imports, first calls) not timed
    construction = []
    for inp in construction_inputs(quick):
        print(inp.name, flush=True)
        construction.append(run_construction(inp, n, n_h, voxel_ks, cgal, rng))
    checks = []
    for sc in check_scenes(quick):
        print(sc.name, flush=True)
        checks.append(run_checks(sc, n, m, voxel_ks, fcl_res, 50 if quick else 500, rng))
    cmd = "python benchmarks/bench_speed_error.py" + (" --quick" if quick else "") + (
        " --no-cgal" if args.no_cgal else "")
    data = {"command": cmd, "mode": "quick" if quick else "full",
            "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "versions": versions(), "load_start": list(load_start),
            "load_end": list(os.getloadavg()), "seconds": time.perf_counter() - t0,
            "json_name": json_path.name if json_path.parent == out else str(json_path),
            "provenance": provenance(), "n_states": n, "n_motions": m, "band_rel": BAND,
            "bits": list(BITS),
            "construction": construction, "checks": checks}
    chart_cobstacle(construction, out / "speed_vs_error_cobstacle.png")
    chart_checks(checks, out / "speed_vs_error_checks.png")
    write_report(out, data)
    json_path.parent.mkdir(parents=True, exist_ok=True)
    json_path.write_text(json.dumps(_jsonable(data), indent=1))
    print(f"wrote {out / 'speed_vs_error.md'}, the charts and {json_path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
