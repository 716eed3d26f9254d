"""OMPL plugin: exact validity/motion checking with real OMPL planners, re-checked with FCL.

No mocks: every run plans with OMPL 2.0.1 on a shipped scene, and every returned path (exact
or approximate) is re-checked exactly (``segment_free``) and with FCL sampled along each
segment at 1e-3 of the scene size, on the raw scene meshes as loaded
(:class:`cspace.check.oracle.SceneOracle`; nothing of the C-space).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("ompl")
pytest.importorskip("fcl")

import cspace  # noqa: E402
from cspace.check.cross_check import path_collisions  # noqa: E402
from cspace.planning.plan import plan
from cspace.planning.ompl_plugin import planner_names, verify_path  # noqa: E402

SCENES = Path(__file__).resolve().parents[1] / "scenes"

# 50 seeded runs: (scene, planner, seed). comb is solved by these planners within about a
# second; window (2% clearance through a 0.05-thick wall), cavity (1.5% clearance entrance) and
# maze (a long serpentine) are rarely solved within such budgets by OMPL's uniform sampling, so
# their runs check only that the returned (approximate) paths are collision-free.
_PLANNERS = ["RRTConnect", "RRT", "PRM", "BITstar", "RRTstar", "KPIECE1", "LBKPIECE1"]
RUNS = (
    [("comb", p, s) for p in _PLANNERS for s in (1, 2, 3, 4)]                       # 28
    + [("cavity", p, 1) for p in _PLANNERS + ["BKPIECE1"]]                          # 8
    + [("window", p, 1) for p in _PLANNERS]                                         # 7
    + [("maze", p, 1) for p in _PLANNERS]                                           # 7
)
TIME = {"comb": 1.0, "cavity": 0.3, "window": 0.3, "maze": 0.3}
MUST_SOLVE = {"comb": 0.7}  # fraction of runs per scene


class _Fcl:
    """FCL re-check of a path on the raw scene, sampled along every segment
    (cspace.check.cross_check.path_collisions of the Scene: SceneOracle)."""

    def __init__(self, scene: cspace.Scene):
        self.scene = scene

    def colliding(self, P: np.ndarray) -> np.ndarray:
        """Sample points along the path where FCL reports a collision."""
        return path_collisions(self.scene, P)[0]


@pytest.fixture(scope="module")
def scenes():
    out = {}
    for name in ("window", "comb", "maze", "cavity"):
        s = cspace.load_scene(SCENES / f"{name}.toml")
        cs = cspace.CSpace.from_scene(s)
        out[name] = (s, cs, _Fcl(s))
    return out


def _check_returned_path(r, cs, fcl, what):
    assert r.path.dtype == np.float64 and r.path.ndim == 2 and r.path.shape[1] == 3
    assert r.n_states == len(r.path)
    if not len(r.path):
        return
    assert bool(np.all(cs.segment_free(r.path[:-1], r.path[1:]))) if len(r.path) > 1 else True
    assert not cs.contains(r.path).any(), what
    assert verify_path(cs, r.path)["valid"], what
    bad = fcl.colliding(r.path)
    assert len(bad) == 0, f"{what}: FCL finds {len(bad)} colliding samples, first {bad[0]}"


@pytest.mark.parametrize("scene_name", ["comb", "cavity", "window", "maze"])
def test_planning_runs_are_collision_free(scenes, scene_name, capsys):
    s, cs, fcl = scenes[scene_name]
    runs = [r for r in RUNS if r[0] == scene_name]
    solved, checked, lines = 0, 0, []
    for _, planner, seed in runs:
        t = time.perf_counter()
        r = plan(s, planner=planner, seed=seed, time=TIME[scene_name])
        what = f"{scene_name}/{planner}/seed={seed}"
        _check_returned_path(r, cs, fcl, what)
        assert r.solved == (r.exact and r.valid)
        assert r.valid or not len(r.path), what  # exact motion validation: never an invalid path
        checked += len(r.path) >= 2
        if r.solved:
            solved += 1
            assert np.array_equal(r.path[0], s.start) and np.array_equal(r.path[-1], s.goal)
        lines.append(f"{what}: {r.status}, {r.n_states} states, {time.perf_counter() - t:.2f}s")
    with capsys.disabled():
        print(f"\n{scene_name}: solved {solved}/{len(runs)}; " + "; ".join(lines))
    # Paths to check, whatever the load: the tree planners return an approximate path from
    # their first samples (five of seven of them did on every scene, in 0.3 s)
    assert checked >= 3, lines
    if scene_name in MUST_SOLVE:
        assert solved >= MUST_SOLVE[scene_name] * len(runs), lines


N_WINDOW = 20
DISCRETE_RESOLUTION = 0.01  # OMPL's default


def test_window_discrete_validation_clips_exact_does_not(scenes, capsys):
    """OMPL's discrete motion validation returns paths through the wall; the exact validator
    never does.

    OMPL's default resolution, 0.01 of the space's extent, is a 0.054 step here, wider than
    the 0.05 wall: RRTConnect's "solutions" step across the wall's rim. When this test was
    written, 6 of 10 runs of 0.5 s returned such paths.
    """
    s, cs, fcl = scenes["window"]
    colliding_discrete = colliding_exact = returned_discrete = 0
    for seed in range(N_WINDOW):
        r = plan(s, planner="RRTConnect", seed=seed, time=0.5, motion="discrete",
                 resolution=DISCRETE_RESOLUTION, simplify=False)
        if r.exact:
            returned_discrete += 1
            free = cs.segment_free(r.path[:-1], r.path[1:])
            colliding_discrete += int(not free.all())
            assert not r.solved or free.all()  # re-proof catches it: not reported solved
    for seed in range(N_WINDOW):
        r = plan(s, planner="RRTConnect", seed=seed, time=0.2, simplify=False)
        if len(r.path) > 1:
            colliding_exact += int(not cs.segment_free(r.path[:-1], r.path[1:]).all())
    with capsys.disabled():
        print(f"\nwindow, {N_WINDOW} runs: discrete validation returned {returned_discrete} "
              f"'exact' paths, {colliding_discrete} colliding; exact validation: "
              f"{colliding_exact} colliding")
    assert colliding_discrete > 0
    assert colliding_exact == 0


# ---- checker and validator units --------------------------------------------------------


def _si(cs, bounds):
    from ompl import base as ob

    from cspace.planning.ompl_plugin import state_space

    space = state_space(bounds)
    return ob.SpaceInformation(space)


def test_checker_and_motion_validator_return_bools(scenes):
    from cspace.planning.ompl_plugin import CSpaceMotionValidator, CSpaceValidityChecker

    s, cs, _ = scenes["window"]
    si = _si(cs, s.bounds)
    chk = CSpaceValidityChecker(si, cs, clearance=True, bounds=s.bounds)
    mv = CSpaceMotionValidator(si, cs, chk)
    si.setStateValidityChecker(chk)
    si.setMotionValidator(mv)
    si.setup()
    a, b, wall, out = (si.allocState() for _ in range(4))
    a[0:3] = s.start.tolist()
    b[0:3] = s.goal.tolist()
    wall[0:3] = [0.0, -1.1275, 1.5]      # inside the left post's C-obstacle
    out[0:3] = [0.0, 0.0, 10.0]          # outside the bounds
    assert chk.isValid(a) is True and chk.isValid(wall) is False and chk.isValid(out) is False
    assert si.isValid(a) is True and si.isValid(wall) is False
    d = chk.clearance(a)
    assert type(d) is float and d == cs.signed_distance(s.start) and d > 0
    assert chk.clearance(wall) < 0
    assert mv.checkMotion(a, b) is False                 # straight through the wall
    assert mv.checkMotion(a, wall) is False              # invalid end state
    assert si.checkMotion(a, b) is False
    c = si.allocState()
    c[0:3] = [-1.5, 0.7, 1.9]
    assert mv.checkMotion(a, c) is True
    # Exactly through the window's centre line: free (the window is 0.01 wider than the robot).
    p, q = si.allocState(), si.allocState()
    p[0:3] = [-1.0, 0.0, 1.5]
    q[0:3] = [1.0, 0.0, 1.5]
    assert mv.checkMotion(p, q) is True
    assert mv.calls >= 5


def test_checker_and_motion_validator_build_a_lazy_cspace_where_they_ask(scenes):
    """A lazy C-space holds no C-obstacle until a query meets one: the checker and motion
    validator must ask the C-space (which builds), not the C-obstacles built so far (none,
    so everything would pass as free)."""
    from cspace.planning.ompl_plugin import CSpaceMotionValidator, CSpaceValidityChecker
    from cspace.scene.model import LazyCSpace, model_scene

    s, _, _ = scenes["window"]
    lazy = LazyCSpace(model_scene(s, build=False))
    si = _si(lazy, s.bounds)
    chk = CSpaceValidityChecker(si, lazy, bounds=s.bounds)
    mv = CSpaceMotionValidator(si, lazy, chk)
    a, b, wall = (si.allocState() for _ in range(3))
    a[0:3] = s.start.tolist()
    b[0:3] = s.goal.tolist()
    wall[0:3] = [0.0, -1.1275, 1.5]      # inside the left post's C-obstacle
    assert not lazy.obstacles
    assert chk.isValid(wall) is False and lazy.obstacles
    assert mv.checkMotion(a, b) is False
    with pytest.raises(cspace.InvalidArgumentError, match="in collision"):
        plan(LazyCSpace(model_scene(s, build=False)), [0.0, -1.1275, 1.5], s.goal,
             bounds=s.bounds)
    r = plan(LazyCSpace(model_scene(s, build=False)), s.start, s.goal, bounds=s.bounds,
             time=2.0, seed=1, sampler="uniform")
    assert not r.exact or r.solved  # an exact OMPL solution is never refused by the re-proof


def test_seed_reproducible(scenes):
    s, _, _ = scenes["comb"]
    r1 = plan(s, seed=7, time=0.5, simplify=False)
    r2 = plan(s, seed=7, time=0.5, simplify=False)
    assert r1.solved and r2.solved
    assert np.array_equal(r1.path, r2.path)


def test_plan_on_cspace_needs_start_goal(scenes):
    s, cs, _ = scenes["comb"]
    with pytest.raises(ValueError, match="start is required"):
        plan(cs, planner="RRTConnect")
    r = plan(cs, s.start, s.goal, bounds=s.bounds, seed=1, time=0.5, planner="RRTConnect")
    assert r.solved and r.planner == "RRTConnect" and r.motion == "exact"
    assert r.length >= float(np.linalg.norm(s.goal - s.start))


def test_invalid_start_goal(scenes):
    s, _, _ = scenes["window"]
    with pytest.raises(ValueError,
                       match=r"start \[0\.0, -1\.1275, 1\.5\] is in collision.*left-post"):
        plan(s, start=[0.0, -1.1275, 1.5])
    with pytest.raises(ValueError, match="goal .* is outside the bounds"):
        plan(s, goal=[0.0, 0.0, 10.0])
    with pytest.raises(ValueError, match="goal .* is in collision"):
        plan(s, goal=[0.0, 0.0, 0.9])  # in the sill's C-obstacle
    with pytest.raises(ValueError, match="start must be a finite"):
        plan(s, start=[0.0, np.nan, 1.0])


def test_unknown_planner_and_motion(scenes):
    s, _, _ = scenes["comb"]
    with pytest.raises(ValueError,
                       match="'RRTconnect' is not a valid planner, must be one of .*RRTConnect"):
        plan(s, planner="RRTconnect")
    with pytest.raises(ValueError, match="must be one of exact, discrete"):
        plan(s, motion="continuous")
    names = planner_names()
    assert {"RRTConnect", "RRT", "PRM", "BITstar", "KPIECE1"} <= set(names)


def test_plan_on_a_scene_builds_through_the_cache(tmp_path):
    from cspace.scene.cache import COCache

    s = cspace.load_scene(SCENES / "comb.toml")
    cache = COCache(tmp_path)
    r1 = plan(s, seed=1, time=1.0, cache=cache)
    r2 = plan(s, seed=1, time=1.0, cache=cache)
    assert (cache.misses, cache.hits) == (11, 11)  # 11 reachable teeth; 6 bodies dropped
    assert r1.solved and r2.solved


def test_narrow_passage_samples_of_triangle_pairs_build_no_hull_of_every_pair():
    # A non-convex robot: its C-obstacles are triangle pairs, with no boundary mesh; the
    # samples come from the hulls of a few random pieces (every hull would cost 0.6 ms a
    # pair), and stay exactly free.
    import trimesh

    from cspace.planning.ompl_plugin import narrow_passage_samples
    from cspace.scene.scene import Body, Scene
    from zoo import l_shape

    V, F = l_shape()
    robot = Body("L", np.asarray(V, float) * 0.1, F, "test")
    boxes = []
    for i, x in enumerate((-0.66, 0.66)):  # a gap 0.02 wider than the robot
        m = trimesh.creation.box(extents=(1.0, 2.0, 2.0))
        boxes.append(Body(f"wall{i}", m.vertices + [x, 0, 0], m.faces, "box"))
    lo, hi = np.array([-1.5, -1.5, -1.5]), np.array([1.5, 1.5, 1.5])
    scene = Scene("gap", None, tuple(boxes), robot, (0.0, 0.0, 0.0), (lo, hi), lo + 0.01,
                  hi - 0.01)
    cs = cspace.CSpace.from_scene(scene)
    pairs = [o for o in cs.obstacles if o.kind == "pairs"]
    assert pairs and all(o.n_pairs > 256 for o in pairs)
    P = narrow_passage_samples(cs, scene.bounds, seed=0)
    assert all(o._mesh is None for o in pairs)  # no hull of every pair was made
    assert len(P) and not cs.contains(P).any()


def test_narrow_passage_samples_are_free_and_in_a_gap(scenes):
    from cspace.planning.ompl_plugin import narrow_passage_samples

    s, cs, _ = scenes["window"]
    P = narrow_passage_samples(cs, s.bounds, seed=0)
    assert len(P) > 5
    assert not cs.contains(P).any() and ((s.bounds[0] <= P) & (P <= s.bounds[1])).all()
    # The window's gaps: every sample is in the wall's slab near the opening (x = 0,
    # y = 0, z = 1.5; the octahedron reaches 0.25 beyond the wall's faces).
    assert (np.abs(P[:, 0]) < 0.3).all()
    assert (np.abs(P[:, 1]) < 0.3).all() and (np.abs(P[:, 2] - 1.5) < 0.3).all()


@pytest.mark.parametrize("scene_name", ["window", "cavity"])
def test_narrow_sampler_solves_the_narrow_scenes_with_prm(scenes, scene_name):
    # With uniform sampling PRM solved neither scene in 3 s (seeds 1-3) when this was written;
    # with the narrow-passage sampler every run solved in about 0.1 s.
    s, cs, fcl = scenes[scene_name]
    for seed in (1, 2, 3):
        r = plan(s, planner="PRM", seed=seed, time=3.0, sampler="narrow")
        assert r.solved, f"{scene_name}/seed={seed}: {r.status}"
        _check_returned_path(r, cs, fcl, f"{scene_name}/PRM/narrow/seed={seed}")
    with pytest.raises(ValueError, match="not a valid sampler"):
        plan(s, sampler="gaussian")
