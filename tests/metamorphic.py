"""Metamorphic checks: the same scene moved, scaled, rotated and permuted must give answers
that an independent oracle accepts, for every construction cspace has.

Shared by ``tests/test_metamorphic.py`` (a small grid in ``make test``, a randomized sweep in
``make test-slow``) and ``benchmarks/bench_metamorphic.py`` (the counts in
``benchmarks/reports/hard_cases.md``).

The oracle is :class:`cspace.check.oracle.SceneOracle` on the transformed scene's raw float
meshes: FCL's own broad phase and BVHs, containment by winding numbers per connected
component. Nothing of the C-space (grids, snapped integers, boxes, pieces) reaches it; the
C-space only chooses where samples are *not* drawn (nowhere: samples come from the raw
meshes too).

What is asserted (principle 2):

- **false free**: cspace says free, FCL says the robot meets an obstacle. Always a failure.
- **false collision**: cspace says in collision, FCL says free. Allowed only within the
  model's stated ``error_bound`` (FCL's distance from the robot to the obstacles at most
  ``error_bound`` plus FCL's float band at the scene's coordinates).

Invariance follows: where the clearance exceeds ``error_bound`` both the original and the
moved scene must agree with the oracle, hence with each other (a gap of exactly the
robot's width may flip under a non-dyadic scale; that is within the bound).
"""

from __future__ import annotations

import contextlib
import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation
from test_robot_parts import _box, _open, _u_robot
from zoo import comb, grate, l_shape, pierced_box, torus

from cspace.scene.scene import Body, Scene

Mesh = tuple  # (vertices (n, 3) float64, faces (m, 3) int64)


@dataclass(frozen=True)
class Case:
    """A small scene that exercises one construction (the name says which)."""

    name: str
    obstacles: tuple          # of Mesh, world frame
    robot: Mesh               # robot frame
    reference_point: tuple = (0.0, 0.0, 0.0)
    half: float = 2.0         # bounds: the cube of this half-size about the origin


def _shifted(mesh: Mesh, by) -> Mesh:
    return np.asarray(mesh[0], float) + np.asarray(by, float), np.asarray(mesh[1], np.int64)


def _scaled(mesh: Mesh, by: float) -> Mesh:
    return np.asarray(mesh[0], float) * by, np.asarray(mesh[1], np.int64)


def _two_part_robot() -> Mesh:
    """Two disjoint boxes: a robot of two convex parts (each its own C-obstacle)."""
    a, b = _box((0.3, 0.2, 0.2), (-0.35, 0, 0)), _box((0.2, 0.3, 0.2), (0.35, 0.1, 0))
    return np.vstack([a[0], b[0]]), np.vstack([a[1], np.asarray(b[1]) + len(a[0])])


def _folded_l(size: float = 1.0) -> Mesh:
    """A closed L with eight sliver caps 1e-12 off its edges, turned: its snapped surface
    meets itself (the caps fold), so it bounds no valid solid on the grid."""
    from hard import VoxelCase, l_cells

    R = Rotation.random(random_state=0).as_matrix()
    case = VoxelCase(l_cells(), (0.5 * size,) * 3, (0.1, 0.1, 0.1), caps=8, lift=1e-12,
                     transform=lambda x: (x - x.mean(axis=0)) @ R.T)
    return case.vertices, case.faces


def _centred(mesh: Mesh, span: float) -> Mesh:
    """``mesh`` scaled so that its longest side is ``span`` and centred on the origin."""
    V = np.asarray(mesh[0], float)
    V = (V - (V.min(axis=0) + V.max(axis=0)) / 2) * (span / np.ptp(V, axis=0).max())
    return V, np.asarray(mesh[1], np.int64)


L_BRACKET = l_shape(arm=2)
POST = _box((0.3, 0.3, 2.0))
SMALL_BOX = _box((0.5, 0.3, 0.4))
OPEN_BOX = _open(_box((1.0, 1.0, 1.0)))

#: One case per construction (``cspace.cobstacle.pairs.CONSTRUCTIONS``), plus robot parts, a robot
#: far from its own frame's origin, and a scene of several bodies.
CASES = {c.name: c for c in [
    Case("CVMS", (_box((1.0, 1.0, 1.0)),), SMALL_BOX),
    Case("NCC-CVMS", (L_BRACKET,), SMALL_BOX),
    Case("convex obstacle x solid robot", (POST,), _u_robot()),
    Case("open obstacle x convex robot", (OPEN_BOX,), SMALL_BOX),
    Case("convex obstacle x open robot", (POST,), _open(_u_robot())),
    Case("triangle pairs", (L_BRACKET,), _u_robot(0.4)),
    Case("triangle pairs, open obstacle", (OPEN_BOX,), _u_robot(0.4)),
    Case("flat pieces", (OPEN_BOX,), _open(_u_robot(0.4), side=-1)),
    Case("robot parts", (L_BRACKET,), _two_part_robot()),
    # The robot's vertices 16.6 units from its frame's origin, the reference point beside
    # them (as OMPL.app's robots are in their files).
    Case("robot off its origin", (torus(0.8, 0.3, 12, 8),),
         _shifted(_u_robot(0.4), (16.6, -3.0, 5.0)), reference_point=(16.7, -3.0, 5.0)),
    Case("convex robot off its origin", (L_BRACKET, _shifted(OPEN_BOX, (1.2, 1.2, 0.0)),
                                         _shifted(POST, (-1.5, 1.5, 0.0))),
         _shifted(SMALL_BOX, (16.6, -3.0, 5.0)), reference_point=(16.5, -3.1, 5.0)),
    # Closed meshes whose snapped surface meets itself: a surface and what it encloses.
    Case("folded closed body", (_folded_l(),), SMALL_BOX),
    Case("folded closed robot", (L_BRACKET, _shifted(POST, (-1.5, 1.5, 0.0))), _folded_l(0.4)),
    Case("several bodies", (L_BRACKET, _shifted(OPEN_BOX, (1.2, 1.2, 0.0)),
                            _shifted(POST, (-1.5, 1.5, 0.0))), _u_robot(0.4)),
    # Features thinner than the grid step (issue #51): a needle through a box snaps to
    # segments, a box cut through by a sheet to open halves whose inside must stay, and a
    # robot's needle is the robot's too.
    Case("needle through a box", (pierced_box("needle", 1e-9),), SMALL_BOX),
    Case("box cut by a sheet", (pierced_box("cut", 1e-9),), SMALL_BOX),
    Case("robot with a needle", (POST,), _scaled(pierced_box("needle", 1e-9), 0.3)),
    # Many parallel slots and holes exactly one voxel wide, turned by the moves (issue #51:
    # a turned comb's sum once missed the stated bound): combs of 4 and 16 teeth and a grate
    # of 4 x 4 holes, with a robot about a slot's width.
    Case("comb, 4 teeth", (_centred(comb(4, 2), 2.4),), _box((0.25, 0.3, 0.2))),
    Case("comb, 16 teeth", (_centred(comb(16, 2), 3.0),), _box((0.08, 0.1, 0.12))),
    Case("grate, 4 x 4 holes", (_centred(grate(4), 2.7),), _box((0.2, 0.25, 0.3))),
]}


@dataclass(frozen=True)
class Move:
    """A similarity ``x -> scale * rotation x + shift`` of the world, and a permutation of
    bodies and triangles. The robot's frame turns and scales with it (not shifted): the
    same physical problem in other coordinates."""

    label: str
    scale: float = 1.0
    rotation: np.ndarray = dataclasses.field(default_factory=lambda: np.eye(3))
    shift: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    permute: int | None = None  # seed of the permutation; None keeps the order

    @property
    def matrix(self) -> np.ndarray:
        return self.scale * np.asarray(self.rotation, float)

    def point(self, x) -> np.ndarray:
        return np.asarray(x, float) @ self.matrix.T + self.shift

    def vector(self, v) -> np.ndarray:
        return np.asarray(v, float) @ self.matrix.T


def random_moves(n: int, seed: int) -> list[Move]:
    """Randomized moves: shifts up to 10^6 in random directions, scales by powers of two and
    by non-dyadic factors, random rotations, permuted bodies and triangles."""
    rng = np.random.default_rng(seed)
    scales = [1.0, 2.0**-5, 2.0**7, 3.7, 0.013, 1000.0 / 3.0]
    out = []
    for k in range(n):
        d = rng.normal(size=3)
        shift = d / np.linalg.norm(d) * 10.0 ** rng.uniform(0.0, 6.0)
        s = scales[k % len(scales)]
        R = Rotation.random(random_state=int(rng.integers(1 << 31))).as_matrix()
        out.append(Move(f"random {k}: scale {s:.4g}, shift {np.round(shift, 1).tolist()}",
                        s, R if k % 2 else np.eye(3), shift, permute=int(rng.integers(1 << 31))))
    return out


#: The fixed grid of ``make test``: each kind of move once.
GRID_MOVES = [
    Move("as given"),
    Move("shifted to (250, 150, -300)", shift=np.array([250.0, 150.0, -300.0])),
    Move("shifted by 10^6", shift=np.array([6e5, -6e5, 5.2915e5])),
    Move("scaled by 2^-5 and 2^7 apart: 2^7", scale=2.0**7, permute=1),
    Move("non-dyadic scale 3.7, rotated, shifted", scale=3.7,
         rotation=Rotation.random(random_state=4).as_matrix(),
         shift=np.array([250.0, 150.0, -300.0]), permute=2),
]


def moved_scene(case: Case, move: Move, name: str = "metamorphic") -> Scene:
    """The case as a :class:`cspace.Scene` in the moved coordinates."""
    rng = np.random.default_rng(move.permute) if move.permute is not None else None
    bodies = []
    for i, (V, F) in enumerate(case.obstacles):
        F = np.asarray(F, np.int64)
        if rng is not None:
            F = F[rng.permutation(len(F))]
        bodies.append(Body(f"body {i}", move.point(V), F, "metamorphic"))
    if rng is not None:
        bodies = [bodies[i] for i in rng.permutation(len(bodies))]
    robot = Body("robot", move.vector(case.robot[0]), np.asarray(case.robot[1], np.int64),
                 "metamorphic")
    c = move.vector(case.reference_point)
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)],
                       float) * case.half
    P = move.point(corners)
    lo, hi = P.min(axis=0), P.max(axis=0)
    return Scene(name, None, tuple(bodies), robot, c, np.stack([lo, hi]),
                 lo + 0.01 * (hi - lo), lo + 0.02 * (hi - lo))


def samples(scene: Scene, n: int, seed: int) -> np.ndarray:
    """``(k, 3)`` translations in the bounds: a third uniform, two thirds near contact
    (a point of an obstacle's surface minus a point of the robot's, moved by
    ``10**U(-9, -1)`` of the scene size), drawn from the raw meshes only."""
    rng = np.random.default_rng(seed)
    lo, hi = scene.bounds
    size = float(np.linalg.norm(hi - lo))

    def on_surface(V, F, k):
        tri = np.asarray(V, float)[np.asarray(F)[rng.integers(0, len(F), k)]]
        return np.einsum("ki,kij->kj", rng.dirichlet(np.ones(3), k), tri)

    k = 2 * n // 3
    which = rng.integers(0, len(scene.obstacles), k)
    po = np.zeros((k, 3))
    for i, b in enumerate(scene.obstacles):
        m = which == i
        po[m] = on_surface(b.vertices, b.faces, int(m.sum()))
    pr = on_surface(scene.robot.vertices, scene.robot.faces, k) - scene.reference_point
    near = po - pr + rng.normal(size=(k, 3)) * size * 10.0 ** rng.uniform(-9, -1, (k, 1))
    Q = np.vstack([rng.uniform(lo, hi, (n - k, 3)), near])
    return Q[((Q >= lo) & (Q <= hi)).all(axis=1)]


@dataclass
class Verdict:
    """Our answers against the oracle's on one set of translations."""

    n: int
    inside: int              # ours
    inside_oracle: int
    false_free: int
    false_collision: int     # all of them
    beyond_bound: int        # false collisions farther than error_bound (+ FCL's band)
    error_bound: float
    false_free_at: np.ndarray

    @property
    def ok(self) -> bool:
        return self.false_free == 0 and self.beyond_bound == 0


def judge(ours: np.ndarray, Q: np.ndarray, oracle, error_bound: float) -> Verdict:
    """Compare our membership answers at ``Q`` with the oracle's (see the module)."""
    truth = oracle.collides(Q)
    false_free = ~ours & truth
    false_coll = ours & ~truth
    beyond = 0
    if false_coll.any():
        d = oracle.distance(Q[false_coll])
        beyond = int((d > error_bound + oracle.band).sum())
    return Verdict(len(Q), int(ours.sum()), int(truth.sum()), int(false_free.sum()),
                   int(false_coll.sum()), beyond, float(error_bound), Q[false_free])


@contextlib.contextmanager
def without_what_snapping_took():
    """Re-introduce the bug of issue #51 while inside: what snapping takes from a body or the
    robot (segments and points thinner than the step, a closed body's inside) is dropped again,
    as it was before ``classify._snapped_body``."""
    import cspace.scene.model as model

    body, robot = model._snapped_body, model.snapping_losses
    model._snapped_body = lambda *a, **k: None  # the bodies'
    model.snapping_losses = lambda n, welded, F: (np.zeros((0, 3), np.int64), None)  # robot's
    try:
        yield
    finally:
        model._snapped_body, model.snapping_losses = body, robot


@contextlib.contextmanager
def shifted_piece_boxes():
    """Re-introduce the bug of issue #27 while inside: triangle-pair boxes (the obstacle's box
    tree's k-DOPs) shifted by the grid's origin (added twice). A check that passes with it is a check that cannot fail."""
    import cspace.cobstacle.pairs as pairs

    from cspace.geometry.boxes import BoxTree

    init = pairs._TreePairsCO.__init__

    def shifted(self, S, T, grid, *, closed, margin=(0, 0, 0)):
        init(self, S, T, grid, closed=closed, margin=margin)
        o = (np.asarray(grid.origin, dtype=np.int64) @ self.directions.T).astype(np.float64)
        self._set = self._pair_set(BoxTree(self.tree_s.box_lo + o, self.tree_s.box_hi + o),
                                   self.tree_r)

    pairs._TreePairsCO.__init__ = shifted
    try:
        yield
    finally:
        pairs._TreePairsCO.__init__ = init
