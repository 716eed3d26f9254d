"""The ``cspace`` command line; each subcommand mirrors a Python function.

- ``cspace convex-sum A B`` — :func:`cspace.convex_minkowski_sum` of two convex shapes
  (mesh files, hulled), optionally as a C-obstacle ``A ⊕ (−(B − c))`` with ``--reflect-b``.
- ``cspace superset A B`` — :func:`cspace.minkowski_superset` of a closed mesh A and a convex
  shape B (hulled), with the same ``--reflect-b``.
- ``cspace sum A B`` — :func:`cspace.minkowski_sum`: the exact sum of a closed mesh A (any
  genus, non-convex) and a convex shape B (hulled), with holes and non-manifold contacts
  reported; ``--reflect-b`` as above; per-stage times with ``--stats``; ``--workers N``
  processes for the large stages.
- ``cspace check SCENE`` — :func:`cspace.check.cross_check.cross_check` of the scene's C-obstacles
  against FCL (membership and distance on random translations).
- ``cspace build SCENE`` — :func:`cspace.scene.model.model_scene`: model the scene (which bodies
  are convex, solid, surface or dropped, and why: ``--explain``) and build the C-obstacles
  through the disk cache (:mod:`cspace.scene.cache`; ``--no-cache``); progress on stderr
  (``--quiet``); ``-o`` writes the C-obstacle meshes. ``--workers N`` builds in N processes,
  ``--scheduler tcp://host:8786`` on a Dask cluster (:func:`cspace.planning.scale.executor_for`).
- ``cspace plan SCENE`` — the same modelling, then :func:`cspace.planning.plan.plan`: an OMPL
  planner with the exact validity checker and motion validator; the path is re-proved
  exactly and written out. ``--explain`` prints the model first. ``--slices N`` (turns about
  one axis) or ``--orientations N`` (free flying) let the robot turn, every translation and
  turn in place certified (:func:`cspace.planning.plan.plan_turning`). Without ``--planner``,
  ``auto``: RRTConnect, the decision (the exact free space, then certified cells:
  :mod:`cspace.planning.decide`), then the robot turns while it moves (RRTConnect in SE(3)
  and passages at fixed orientations, every motion certified by clearance:
  :mod:`cspace.planning.se3`), within ``--time`` (``plan(..., planner='auto')``); a scene whose
  goal orientation differs from the start's goes to SE(3) at once (``--no-turns`` keeps the
  start's). Exit status 3 when no path exists, proved, as the robot may move: at the start's
  orientation with ``--no-turns``; a robot that may turn freely gets 1 when nothing is found.
  ``--workers`` / ``--scheduler`` build through an executor, as for ``build``.
- ``cspace free-space SCENE`` — :func:`cspace.planning.free_space.free_space` at the start's
  orientation: its components, which hold start and goal, the proof when they differ;
  ``-o`` writes the union's surface.
- ``cspace view SCENE`` — :func:`cspace.viz.draw.draw_scene`: an offline HTML page of a scene
  (default ``<scene>.html``), or a live meshcat server with ``--live``; ``--free-space`` adds
  the components of :func:`cspace.planning.free_space.free_space`.

Length: one module holds every subcommand's parser and its few lines of glue, so that each
mirrors its function in one place; splitting it would only scatter them.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence

from ._version import __version__
from .output import MESH_FORMATS, write_atomic


def _operands(args: argparse.Namespace, a_points):
    """The grid, and B (hulled, optionally reflected), for the subcommands taking A and B files."""

    from .mesh.convex import ConvexPolytope
    from .geometry.exact import Grid

    b = _load_points(args.b)
    if args.reflect_b is not None:  # B is the robot: the grid of the C-obstacle A ⊕ (c - B)
        grid = Grid.for_cobstacle(a_points, b, args.reflect_b, bits=args.grid_bits)
        rgrid = grid.for_robot(b, args.reflect_b)
        B = ConvexPolytope.from_points(b, grid=rgrid, name=args.b).reflected(args.reflect_b)
    else:
        grid, gb = Grid.for_operands(a_points, b, bits=args.grid_bits)
        B = ConvexPolytope.from_points(b, grid=gb, name=args.b)
    return grid, B


def _closed_operands(args: argparse.Namespace):
    """A (a validated closed mesh), the grid and B for the subcommands on a closed mesh A."""
    from .mesh.closed import ClosedMesh

    A0 = ClosedMesh.load(args.a)
    grid, B = _operands(args, A0.vertices)
    return A0.on_grid(grid), grid, B


def _load_points(path: str):
    """The vertices of a mesh file (the frame the file means), or a SceneError naming it."""
    from .mesh.files import read_mesh_file

    return read_mesh_file(path, f"mesh {path!r}").vertices


def _out(path, formats, what):
    """The checked output path (before any work), or None."""
    from .output import output_path

    return None if path is None else output_path(path, formats, what)


def _timed(fn, *operands, **options):
    t = time.perf_counter()
    out = fn(*operands, **options)
    return out, time.perf_counter() - t


def _convex_sum(args: argparse.Namespace) -> int:
    # Heavy imports here so that `cspace --help` stays fast.

    from .minkowski.cvms import FACET_KINDS, convex_minkowski_sum
    from .mesh.convex import ConvexPolytope

    out = _out(args.output, MESH_FORMATS, "-o")
    a = _load_points(args.a)
    grid, B = _operands(args, a)
    A = ConvexPolytope.from_points(a, grid=grid, name=args.a)
    S, dt = _timed(convex_minkowski_sum, A, B)
    kinds = ", ".join(f"{int((S.kind == k).sum())} {name}" for k, name in enumerate(FACET_KINDS))
    print(f"A: {A.n_facets} facets, {len(A.ints)} vertices ({args.a})")
    print(f"B: {B.n_facets} facets, {len(B.ints)} vertices ({args.b}){' reflected' if args.reflect_b is not None else ''}")
    print(f"A ⊕ B: {S.polytope.n_facets} facets ({kinds}), {len(S.vertices)} vertices, volume {S.volume:.9g}")
    print(f"grid step {grid.step:.3g}; snapping moved each input point by at most {S.error_bound:.3g}")
    print(f"time {dt * 1e3:.2f} ms")
    if out:
        write_atomic(out, lambda p: S.polytope.to_trimesh().export(p))
        print(f"wrote {out}")
    return 0


def _sum(args: argparse.Namespace) -> int:
    from .minkowski.sum import minkowski_sum

    out = _out(args.output, MESH_FORMATS, "-o")
    A, grid, B = _closed_operands(args)

    progress = _Progress(args.quiet, args.progress)
    try:
        S, dt = _timed(minkowski_sum, A, B, progress=progress, workers=args.workers)
    finally:
        progress.close()
    print(f"A: {len(A.faces)} triangles ({args.a}); B: {B.n_facets} facets ({args.b})")
    print(f"A ⊕ B: {len(S.faces)} triangles, {len(S.vertices)} vertices, volume {S.volume:.9g}, "
          f"{S.n_holes} hole(s), {len(S.nonmanifold_edges)} non-manifold edge(s), "
          f"{len(S.nonmanifold_vertices)} non-manifold vertex(es) ({'CVMS' if S.convex else 'NCC-CVMS'})")
    if len(S.rounding_self_intersections):
        print(f"warning: rounding to float64 made {len(S.rounding_self_intersections)} triangle pairs "
              "intersect (see SumPolyhedron.rounding_self_intersections)")
    print(f"grid step {grid.step:.3g}; error bound {S.error_bound:.3g}; time {dt:.3f} s")
    if args.stats:
        for k, v in S.stats.items():
            print(f"  {k}: {v:.4f} s" if isinstance(v, float) else f"  {k}: {v}")
    if out:
        write_atomic(out, lambda p: S.to_trimesh().export(p))
        print(f"wrote {out}")
    return 0


def _superset(args: argparse.Namespace) -> int:
    import trimesh

    from .minkowski.superset import SUPERSET_KINDS, minkowski_superset

    out = _out(args.output, MESH_FORMATS, "-o")
    A, grid, B = _closed_operands(args)
    S, dt = _timed(minkowski_superset, A, B)
    kinds = ", ".join(f"{int((S.kind == k).sum())} {name}" for k, name in enumerate(SUPERSET_KINDS))
    corner = S.multiplicity[S.kind == SUPERSET_KINDS.index("corner")]
    print(f"A: {len(A.faces)} triangles ({args.a}); B: {B.n_facets} facets ({args.b})")
    print(f"superset: {S.n_facets} facets ({kinds}), {len(S.triangles()[0])} triangles, closed: {S.is_closed()}")
    if corner.size:
        print(f"corner multiplicities from {int(corner.min())} to {int(corner.max())}")
    print(f"grid step {grid.step:.3g}; time {dt * 1e3:.1f} ms")
    if out:
        faces, _, _ = S.triangles()
        write_atomic(out, lambda p: trimesh.Trimesh(S.vertices, faces, process=False).export(p))
        print(f"wrote {out} (triangle soup; multiplicities are not stored)")
    return 0


def _check(args: argparse.Namespace) -> int:
    from .check.cross_check import cross_check
    from .scene.files import load_scene

    scene = load_scene(args.scene)
    m = _model(args, scene)
    if args.explain:
        print(m.explain())
    cs = m.cspace()
    # FCL's verdict from the raw scene (every body, its own solid rule), not from the C-space.
    r = cross_check(cs, n=args.n, seed=args.seed, band=args.band, scene=scene,
                    robot_hull=args.robot_hull)
    print(f"{scene.name}: {r['n']} translations, {r['n_inside']} in collision (FCL: {r['n_inside_fcl']})")
    print(f"membership disagreements beyond {args.band:g} of the surface: {r['n_disagree']} "
          f"({r['n_in_band']} within the band ignored)")
    print(f"in margin (ours in collision, FCL free within the error bound "
          f"{r['error_bound']:.3g}): {r['n_in_margin']}; false free: {r['n_false_free']}")
    print(f"max |distance - FCL distance| outside: {r['max_distance_error']:.3g} "
          f"(scene size {r['scene_size']:.3g})")
    print(f"time per query: ours {r['seconds_per_query_ours'] * 1e6:.2f} us, "
          f"FCL {r['seconds_per_query_fcl'] * 1e6:.2f} us")
    for q in r["disagreements"][:10]:
        print(f"  disagreement at {q.tolist()}")
    return 0 if r["ok"] else 1


class _Progress:
    """One progress style for every long command, ``progress(fraction, message)``.

    On a terminal: one status line on stderr, ``[ 45%] message``, rewritten in place.
    Elsewhere (a pipe, a log): quiet, unless ``--progress`` asks for a line whenever the
    message changes or another tenth is done. ``--quiet``: nothing.
    """

    def __init__(self, quiet: bool, lines: bool = False):
        self.live = not quiet and sys.stderr.isatty()
        self.lines = not quiet and not self.live and lines
        self.message = None
        self.shown = -1
        self.width = 0

    def __call__(self, fraction: float, message: str) -> None:
        tenth = int(fraction * 10)
        if self.live:
            text = f"[{fraction:4.0%}] {message}"[:100]
            print("\r" + text.ljust(self.width), end="", file=sys.stderr, flush=True)
            self.width = len(text)
        elif self.lines and (message != self.message or tenth > self.shown):
            sys.stderr.write(f"[{fraction:4.0%}] {message}\n")  # one write: whole lines
            sys.stderr.flush()
        self.message, self.shown = message, tenth

    def close(self) -> None:
        """End the status line (before anything else is printed)."""
        if self.live and self.width:
            print(file=sys.stderr, flush=True)
            self.width = 0


def _executor(args: argparse.Namespace):
    """The executor ``--scheduler`` / ``--workers`` name (None: build here)."""
    if getattr(args, "scheduler", None) or getattr(args, "workers", None):
        from .planning.scale import executor_for

        return executor_for(args.scheduler, args.workers)
    return None


def _model(args: argparse.Namespace, scene=None):
    """Load the scene (unless given) and model it (build its C-obstacles, through the cache
    unless --no-cache)."""
    from .scene.model import model_scene
    from .scene.files import load_scene

    scene = load_scene(args.scene) if scene is None else scene
    cache = None if args.no_cache else (args.cache_dir or True)
    if args.robot_hull:
        print(f"cspace: note: robot {scene.robot.name!r} is replaced by its convex hull "
              "(--robot-hull): collisions may be reported where the real robot is free",
              file=sys.stderr)
    progress = _Progress(args.quiet, args.progress)
    executor = None
    try:
        executor = _executor(args)
        return model_scene(scene, cache=cache, progress=progress, robot_hull=args.robot_hull,
                           executor=executor, memory=args.memory)
    finally:
        if executor is not None:  # all done (or interrupted): stop the pool, close the client
            executor.shutdown(wait=False, cancel_futures=True)
        progress.close()


def _build(args: argparse.Namespace) -> int:
    import numpy as np

    out = _out(args.output, ("npz",), "-o")
    m = _model(args)
    built = [(f"{b.name} x {p.part}" if len(m.robot_parts) > 1 else b.name, b.kind, co, p.cache)
             for b in m.bodies for p in b.pairs for co in p.cos]
    hits = sum(cache == "hit" for _, _, _, cache in built)
    if args.explain:
        print(m.explain())
    else:
        c = m.counts()
        print(f"{m.scene.name}: {len(m.bodies)} bodies: " + ", ".join(f"{c[k]} {k}" for k in c))
        for line in m.meaning_changes(limit=10):  # the same lines as --explain's
            print(line)
    where = ""
    if args.scheduler:
        where = (" on a local Dask cluster" if args.scheduler == "local"
                 else f" on the Dask cluster at {args.scheduler}")
    elif args.workers and args.workers > 1:
        where = f" in {args.workers} processes"
    print(f"built {len(built)} C-obstacles in {m.seconds['build']:.2f} s{where} "
          f"({hits} from the cache)")
    failed = [b for b in m.bodies if b.error]
    for b in failed:
        print(f"cspace: error: body {b.name!r} ({b.kind}): {b.error}", file=sys.stderr)
    if out and failed:
        print(f"cspace: error: {out} not written: {len(failed)} bodies failed to build",
              file=sys.stderr)
    elif out:
        arrays = {"names": np.array([name for name, _, _, _ in built]),
                  "kinds": np.array([kind for _, kind, _, _ in built])}
        for i, (_, _, co, _) in enumerate(built):
            if co.kind == "pairs":
                # A union over every triangle pair has no boundary mesh worth writing (one
                # hull a pair): its operands define it, in scene coordinates.
                arrays[f"obstacle_triangles_{i}"] = co.grid.to_float(co.S.reshape(-1, 3)).reshape(-1, 3, 3)
                arrays[f"robot_vectors_{i}"] = co.grid.vectors.to_float(co.T.reshape(-1, 3)).reshape(-1, 3, 3)
            else:
                arrays[f"vertices_{i}"] = co.vertices
                arrays[f"faces_{i}"] = co.faces
        write_atomic(out, lambda p: np.savez_compressed(p, **arrays))
        print(f"wrote {out} (per C-obstacle: vertices_<i>, faces_<i>; for triangle pairs "
              "obstacle_triangles_<i>, robot_vectors_<i> (c - t): the union of every "
              "s + (c - t); names, kinds)")
    return 1 if failed else 0


def _plan(args: argparse.Namespace) -> int:
    import numpy as np

    from .planning.plan import AUTO, DEFAULT_TIME, plan

    if args.time is None:  # one default with Python's plan()
        args.time = DEFAULT_TIME
    path_out = _out(args.output, ("txt", "csv", "npy", "path"), "-o")
    result_out = _out(args.result, ("json",), "--result")
    html_out = _out(args.html, ("html",), "--html")
    from .scene.files import load_scene

    scene = load_scene(args.scene)
    if args.slices is not None or args.orientations is not None:
        return _plan_turning(args, scene, path_out, result_out, html_out)
    turn = not np.array_equal(scene.goal_rotation, scene.start_rotation)
    if turn and not args.no_turns and args.planner != AUTO:
        return _plan_se3(args, scene, path_out, result_out, html_out)
    m = _model(args, scene)
    if args.explain:
        print(m.explain())
    else:
        for line in m.meaning_changes(limit=10):  # the same lines as --explain's
            print(line)
    scene = m.scene
    cs = m.cspace()
    auto = args.planner == AUTO
    if auto and args.sampler != "uniform":
        args.planner = "PRM"  # a sampler asked for: the planner that uses it, as before
        auto = False
    r = plan(cs, scene.start, scene.goal, bounds=scene.bounds, planner=args.planner,
             time=args.time, seed=args.seed, sampler=args.sampler,
             cache=None if args.no_cache else (args.cache_dir or True),
             robot_hull=args.robot_hull, memory=args.memory, turns=not args.no_turns)
    for t in r.tried or ():
        how = ("decision for the ball inside the robot, at every orientation"
               if t.get("robot") == "inscribed ball" else
               "decision (exact free space, cells)" if t["planner"] == "decide" else
               "passages at fixed orientations, turns where there is room (SE(3))"
               if t["planner"] == "bridge" else
               "a tunnel along the ball's path, joined to start and goal (SE(3))"
               if t["planner"] == "tunnel" else
               f"{t['planner']} in SE(3), certified motions" if t.get("space") == "SE3"
               else f"{t['planner']} ({t['sampler']} sampler)")
        said = t.get("answer") or ("solved" if t["solved"] else "not found")
        print(f"  auto: {how}: {said} in {t['seconds']:.2f} s of {t['time']:.2f} s")
    if (d := r.decision) is not None and d.answer == "no path":
        wall = ("the separating surface is the certificate" if d.separation is not None else
                f"a wall of {int(d.wall.sum())} cells inside the C-obstacles or near them")
        where = ("at any orientation" if any(t.get("robot") == "inscribed ball" and
                                             t["answer"] == "no path" for t in r.tried or ())
                 else "at the start's orientation")
        print(f"  no path {where}, proved: {d.reason} ({wall}; for clearances above "
              f"{d.clearance:.3g})")
    everywhere = any(t.get("robot") == "inscribed ball" and t["answer"] == "no path"
                     for t in r.tried or ())
    if d is not None and d.answer == "no path" and not r.solved and (args.no_turns or everywhere):
        print(f"{scene.name}: no path, proved: " + (
            "none at any orientation (even the ball inside the robot that no turn changes "
            "cannot pass)" if everywhere else "none at the start's orientation"))
        _finish({**_result_head(args, scene, r), "path": None}, result_out, html_out, scene,
                None, decision=d)
        return EXIT_NO_PATH
    if r.certified is not None:  # auto turned the robot
        return _report_se3(args, scene, r, path_out, result_out, html_out)
    status = "solved" if r.solved else f"NOT solved ({r.status})"
    name = f"auto ({r.planner})" if auto else args.planner
    if r.solved:
        print(f"{scene.name}: {name} {status} in {r.time:.2f} s; {len(r.path)} waypoints, "
              f"length {r.length:.4g}; exact re-check: {'valid' if r.valid else 'INVALID'}")
    else:  # no path: nothing was re-checked (an approximate one, if any, is not written)
        print(f"{scene.name}: {name} {status} in {r.time:.2f} s: no path found (not a proof "
              "that none exists)")
    fcl = None
    if args.fcl_check and r.solved:
        from .check.cross_check import path_collisions

        bad, n = path_collisions(cs, r.path, scene=scene, robot_hull=args.robot_hull)
        fcl = {"colliding_samples": int(len(bad)), "samples": n}
        print(f"FCL re-check: {len(bad)} colliding of {n} samples along the path")
    proved = r.solved and not (fcl and fcl["colliding_samples"])
    # A path file is a solution: written only for a solved, proved path.
    written = None
    if path_out and proved:
        _write_path(path_out, r.path, _quaternions(scene.start_rotation, len(r.path)))
        written = str(path_out)
        print(f"wrote {path_out}")
    elif path_out:
        print(f"no path written to {path_out}: the problem was not solved", file=sys.stderr)
    if not r.solved and not auto and (args.planner, args.sampler) != ("PRM", "narrow"):
        print("hint: for narrow passages try --planner PRM --sampler narrow (samples in the gaps "
              "between C-obstacles), or a longer --time", file=sys.stderr)
    result = None
    if result_out:
        result = {
            **_result_head(args, scene, r),
            "path": r.path.tolist() if proved else None,
            "approximate_path": None if proved else r.path.tolist(),
            "path_file": written, "fcl_recheck": fcl,
            "model": {"counts": m.counts(), "model_seconds": m.seconds["model"],
                      "build_seconds": m.seconds["build"], "robot_hull": m.robot_hull,
                      "robot_parts": [{"name": p.name, "kind": p.kind} for p in m.robot_parts],
                      "bodies": [{"name": b.name, "kind": b.kind, "reason": b.reason,
                                  "constructions": [p.construction for p in b.pairs],
                                  "cache": b.cache, "seconds": b.seconds} for b in m.bodies]},
        }
    return _finish(result, result_out, html_out, scene, r.path if proved else None)


def _result_head(args: argparse.Namespace, scene, r) -> dict:
    """The fields every ``plan --result`` JSON starts with."""
    return {"scene": scene.name, "scene_file": str(args.scene), "planner": args.planner,
            "seed": args.seed, "time_budget": args.time, "solved": r.solved, "exact": r.exact,
            "valid_exact_recheck": r.valid, "status": r.status, "seconds": r.time,
            "length": r.length, "tried": r.tried, "decision": None if r.decision is None else
            {k: getattr(r.decision, k) for k in ("answer", "reason", "depth", "clearance")}}


def _finish(result, result_out, html_out, scene, path, decision=None, rotations=None) -> int:
    """Write ``plan``'s JSON summary and HTML page (the scene, and ``path`` when proved, or
    the cells of a proof that there is none); exit status 0 when there is a proved path."""
    import json

    if result_out:
        write_atomic(result_out, lambda p: p.write_text(json.dumps(result, indent=1)))
        print(f"wrote {result_out}")
    if html_out:
        from .viz.draw import draw_scene
        from .viz.scene_view import SceneView

        view = SceneView()
        draw_scene(view, scene, path=path, decision=decision, rotations=rotations)
        write_atomic(html_out, lambda p: view.save(p))
        print(f"wrote {html_out}" + ("" if path is not None else " (the cells that prove no "
                                     "path exists)" if decision is not None else
                                     " (the scene only: no solution)"))
    return 0 if path is not None else 1


def _quaternions(rotation, n: int):
    """``(n, 4)`` copies of a rotation's quaternion ``(x, y, z, w)``."""
    import numpy as np
    from scipy.spatial.transform import Rotation

    return np.tile(Rotation.from_matrix(np.asarray(rotation)).as_quat(), (n, 1))


def _write_path(path_out, positions, orientations) -> None:
    """A path file: ``.path`` is OMPL.app's (``x y z qx qy qz qw`` per line); ``.txt``,
    ``.csv`` and ``.npy`` hold the positions (n x 3), or n x 7 with the orientations when the
    robot turns along the path."""
    import numpy as np

    P = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    Q = np.asarray(orientations, dtype=np.float64).reshape(-1, 4)
    turns = len(Q) > 1 and not np.array_equal(Q, np.tile(Q[0], (len(Q), 1)))
    suffix = path_out.suffix.lower()
    table = (np.hstack([P, Q]) if suffix == ".path" or turns else P) + 0.0  # no "-0.0"
    if suffix == ".npy":
        write_atomic(path_out, lambda p: np.save(p, table))
    else:
        delimiter = "," if suffix == ".csv" else " "
        # shortest round-trip text of each float64 (the path proved is the path read back)
        text = "".join(delimiter.join(repr(float(x)) for x in row) + "\n" for row in table)
        write_atomic(path_out, lambda p: p.write_text(text))



def _plan_se3(args: argparse.Namespace, scene, path_out, result_out, html_out) -> int:
    """``cspace plan --planner X`` on a scene whose goal turns the robot: X in SE(3)."""
    from .planning.se3.plan import plan_se3

    r = plan_se3(scene, planner=args.planner, time=args.time, seed=args.seed)
    return _report_se3(args, scene, r, path_out, result_out, html_out)


def _posed_path_out(args: argparse.Namespace, scene, r, rel, path_out, what: str):
    """A turning path's FCL re-check (``--fcl-check``: every pose along its motions, ``rel``
    the rotations relative to the start) and path file: ``(fcl, proved, written)``."""
    import numpy as np

    fcl = None
    if args.fcl_check and r.solved:
        from .check.cross_check import pose_path_collisions

        size = float(np.linalg.norm(np.ptp(np.asarray(scene.bounds), axis=0))) or 1.0
        bad, n = pose_path_collisions(scene, r.path, rel, per_metre=1e3 / size, per_degree=100)
        fcl = {"colliding_samples": bad, "samples": n}
        print(f"FCL re-check: {bad} colliding of {n} poses along {what}")
    proved = r.solved and not (fcl and fcl["colliding_samples"])
    written = None
    if path_out and proved:
        _write_path(path_out, r.path, r.orientations)
        written = str(path_out)
        print(f"wrote {path_out}")
    elif path_out:
        print(f"no path written to {path_out}: the problem was not solved", file=sys.stderr)
    return fcl, proved, written


def _report_se3(args: argparse.Namespace, scene, r, path_out, result_out, html_out) -> int:
    """Print, check, write and summarise a path planned in SE(3) (``plan_se3``'s result, or
    the auto planner's turning stage)."""
    import numpy as np
    from scipy.spatial.transform import Rotation

    name = f"auto ({r.planner})" if r.tried else args.planner
    status = "solved" if r.solved else f"NOT solved ({r.status})"
    c = r.certified
    print(f"{scene.name}: {name} in SE(3) {status} in {r.time:.2f} s; {len(r.path)} poses, "
          f"length {r.length:.4g}; certified: {c['motions']} motions "
          f"({'valid' if r.valid else 'NOT certified'}), {c['queries']} clearance queries, "
          f"bisection depth up to {c['max_depth']}; clearance error bound "
          f"{c['error_bound']:.3g}, robot radius {c['rho']:.4g}")
    if not r.solved and r.tried:
        print(f"  {scene.name}: no path found within --time {args.time:g} (not a proof: the "
              "robot may turn)")
    rel = (Rotation.from_quat(r.orientations)
           * Rotation.from_matrix(np.asarray(scene.start_rotation)).inv()).as_matrix()
    fcl, proved, written = _posed_path_out(args, scene, r, rel, path_out, "the motions")
    result = None
    if result_out:
        result = {**_result_head(args, scene, r), "space": "SE3", "certified": c,
                  "path": r.path.tolist() if proved else None,
                  "orientations": r.orientations.tolist() if proved else None,
                  "path_file": written, "fcl_recheck": fcl}
    return _finish(result, result_out, html_out, scene, r.path if proved else None,
                   rotations=rel if proved else None)


def _plan_turning(args: argparse.Namespace, scene, path_out, result_out, html_out) -> int:
    """``cspace plan --slices N``: translations and certified turns over orientation slices."""
    import numpy as np

    from .errors import InvalidArgumentError
    from .planning.plan import default_slices, plan_turning
    from .planning.orientations import Orientations

    if args.slices is not None and args.orientations is not None:
        raise InvalidArgumentError("--slices and --orientations are alternatives: give one")
    cache = None if args.no_cache else (args.cache_dir or True)
    if args.slices is not None:
        slices = default_slices(scene, args.slices)
    else:
        rel = np.asarray(scene.goal_rotation) @ np.asarray(scene.start_rotation).T
        slices = Orientations.uniform(args.orientations, goal_rotation=rel)
    executor = _executor(args)
    if args.planner == "auto":  # turns asked for (or needed): the turning planner's default
        args.planner = "RRTConnect"
    try:
        r = plan_turning(scene, slices, planner=args.planner, time=args.time, seed=args.seed,
                         cache=cache, robot_hull=args.robot_hull, executor=executor,
                         memory=args.memory)
    finally:
        if executor is not None:
            executor.shutdown(wait=False, cancel_futures=True)
    return _report_turning(args, scene, slices, r, path_out, result_out, html_out)


def _report_turning(args: argparse.Namespace, scene, slices, r, path_out, result_out,
                    html_out) -> int:
    """Print, check, write and summarise a path with turns (``plan_turning``'s result)."""
    import numpy as np

    if r.tried:
        args.planner = f"auto ({r.planner})"
    status = "solved" if r.solved else f"NOT solved ({r.status})"
    turns = int((np.diff(r.slices) != 0).sum()) if len(r.slices) else 0
    if r.solved:
        print(f"{scene.name}: {args.planner} with {len(slices)} orientations {status} in "
              f"{r.time:.2f} s; {len(r.path)} waypoints ({turns} turns between neighbouring "
              f"orientations), length {r.length:.4g}; exact re-check: "
              f"{'valid' if r.valid else 'INVALID'}")
    else:
        print(f"{scene.name}: {args.planner} with {len(slices)} orientations {status} in "
              f"{r.time:.2f} s: no path found")
    first = r.built.get("start_orientation_only")
    if first is not None:
        print("  start and goal share an orientation: "
              + ("translations at it found the path" if first else
                 "translations at it found no path; the turning planner had the rest of the time"))
    if args.explain:
        print(f"  {slices!r}")
        print(f"  built lazily: {r.built['slices']} of {r.built['of'][0]} orientations' "
              f"C-spaces, {r.built['turns']} of {r.built['of'][1]} turns'")
    rel = [slices.rotation(k) for k in r.slices]
    fcl, proved, written = _posed_path_out(args, scene, r, rel, path_out,
                                           "the translations and turns")
    result = None
    if result_out:
        result = {
            **_result_head(args, scene, r), "slices": len(slices), "built": r.built,
            "path": r.path.tolist() if proved else None,
            "orientations": r.orientations.tolist() if proved else None,
            "slice_ids": r.slices.tolist() if proved else None,
            "path_file": written, "fcl_recheck": fcl,
        }
    return _finish(result, result_out, html_out, scene, r.path if proved else None,
                   rotations=np.asarray(rel) if proved else None)


def _view(args: argparse.Namespace) -> int:
    from pathlib import Path

    import numpy as np

    from .scene.files import load_scene
    from .viz.draw import draw_scene
    from .viz.scene_view import SceneView
    from .viz.browser import screenshot

    _out(args.output or f"{Path(args.scene).stem}.html", ("html",), "-o")
    _out(args.screenshot, ("png",), "--screenshot")
    scene = load_scene(args.scene)
    path = None
    if args.path:
        p = Path(args.path)
        path = np.load(p) if p.suffix == ".npy" else np.loadtxt(p, delimiter="," if p.suffix == ".csv" else None)
        path = np.asarray(path, dtype=np.float64).reshape(-1, 3)
    view = SceneView(live=args.live)
    cache = None if args.no_cache else (args.cache_dir or True)
    fs = None
    if args.free_space:  # the exact free space's components (where it takes the scene)
        from .errors import MemoryBudgetError, UnsupportedError
        from .planning.free_space import free_space
        from .scene.model import model_scene

        try:
            fs = free_space(model_scene(scene, cache=cache).cspace(), scene.bounds)
        except (UnsupportedError, MemoryBudgetError) as e:  # the scene is drawn all the same
            print(f"free space: not drawn: {e}")
    progress = _Progress(args.quiet, args.progress)
    try:
        report = draw_scene(view, scene, path=path, superset=args.superset, cache=cache,
                            free_space=fs, progress=progress, memory=args.memory)
    finally:
        progress.close()
    for name, what in report.items():
        print(f"{name}: {what}")
    if args.live:
        print(f"meshcat is serving the scene at {view.url}; press Enter (or Ctrl-C) to stop")
        try:
            input()
        except (EOFError, KeyboardInterrupt, OSError):  # no terminal: stop at once
            pass
        finally:
            view.close()
        return 0
    out = Path(args.output or f"{Path(args.scene).stem}.html")
    write_atomic(out, lambda p: view.save(p))
    print(f"wrote {out} (self-contained; open it in a browser)")
    if args.screenshot:
        print(f"wrote {screenshot(out, args.screenshot)}")
    failed = [name for name, what in report.items() if "failed to build" in what]
    if failed:
        print(f"cspace: error: the C-obstacles of {', '.join(failed)} failed to build; the page "
              "shows those obstacles without them", file=sys.stderr)
        return 1
    return 0


def _benchmark(args: argparse.Namespace) -> int:
    import sqlite3
    import subprocess
    import tempfile
    from pathlib import Path

    from .planning.benchmark import benchmark
    from .scene.files import load_scene

    out = _out(args.output, ("log",), "-o")
    db = _out(args.db, ("db",), "--db")
    scene = load_scene(args.scene)
    planners = [p.strip() for p in args.planners.split(",") if p.strip()]
    logs = benchmark(scene, out, planners=planners, runs=args.runs, time=args.time,
                     memory_mb=args.max_mem, seed=args.seed, sampled=args.sampled)
    written = [str(p) for p in logs.values() if p is not None]
    print(f"wrote {', '.join(written)} (OMPL's benchmark log format)")
    # OMPL's own statistics script reads them into its database (Planner Arena's input)
    with tempfile.TemporaryDirectory() as tmp:
        target = str(db) if db is not None else str(Path(tmp) / "results.db")
        r = subprocess.run([sys.executable, "-m", "ompl.ompl_benchmark_statistics", *written,
                            "-d", target], capture_output=True, text=True)
        if r.returncode != 0:
            print(f"cspace: error: ompl_benchmark_statistics could not read the logs: "
                  f"{r.stderr.strip()[-300:]}", file=sys.stderr)
            return 1
        with sqlite3.connect(target) as c:
            rows = c.execute("SELECT e.name, p.name, COUNT(*), SUM(r.solved), AVG(r.time) "
                             "FROM runs r JOIN plannerConfigs p ON r.plannerid = p.id "
                             "JOIN experiments e ON r.experimentid = e.id "
                             "GROUP BY e.name, p.name ORDER BY e.name, p.name").fetchall()
    for exp, planner, n, solved, t in rows:
        print(f"  {exp}: {planner.removeprefix('geometric_')}: solved {int(solved or 0)} of "
              f"{n} runs, mean {t:.3g} s")
    if db is not None:
        print(f"wrote {db} (OMPL's benchmark database: plannerarena.org plots it)")
    else:
        print(f"  OMPL's database: ompl_benchmark_statistics {' '.join(written)} -d results.db")
    return 0


def _free_space(args: argparse.Namespace) -> int:
    from .planning.free_space import free_space
    from .scene.files import load_scene
    from .scene.model import model_scene

    out = _out(args.output, MESH_FORMATS, "-o")
    scene = load_scene(args.scene)
    cache = None if args.no_cache else (args.cache_dir or True)
    progress = _Progress(args.quiet, args.progress)
    try:
        model = model_scene(scene, cache=cache, progress=progress, memory=args.memory)
    finally:
        progress.close()
    try:
        fs = free_space(model.cspace(), scene.bounds, time=args.time, memory=args.memory)
    except TimeoutError as e:  # unknown within the budget, as cspace plan's exit status 1
        print(f"{scene.name}: {e}")
        return 1
    print(f"{scene.name}: {fs!r}")
    a, b = fs.component_of(scene.start), fs.component_of(scene.goal)
    print(f"  start in component {a}, goal in component {b} (None: not strictly free)")
    sep = fs.separation(scene.start, scene.goal)
    if sep is not None:
        print(f"  separated: the start's component's boundary ({len(sep.faces)} triangles) "
              f"winds {sep.winding[0]} about the start and {sep.winding[1]} about the goal: no "
              f"path with a clearance above {fs.error_bound:.3g}")
    elif fs.joined(scene.start, scene.goal):
        print("  one component: a path exists (the grown union holds the C-obstacles)")
    elif a is not None and a == b:
        print("  one component of the bounds snapped outward (a step larger at most)")
    if out is not None:
        write_atomic(out, lambda p: fs.to_trimesh().export(p))
        print(f"wrote {out} (the union's surface, with the frame around the bounds)")
    return 0


def _executor_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--workers", type=_positive_int, default=None, metavar="N",
                   help="build in N processes here (default: this process); with "
                        "--scheduler local, the local Dask cluster's worker processes")
    p.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="build on a Dask cluster: its scheduler's address (tcp://host:8786), "
                        "or 'local' for a Dask LocalCluster started here; the cache folder is "
                        "the shared store (needs dask[distributed])")


def _model_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--explain", action="store_true",
                   help="report what was modelled and why, per body (kind, reason, sizes, "
                        "build time, cache hit or miss)")
    p.add_argument("--no-cache", action="store_true", help="do not read or write the disk cache")
    p.add_argument("--robot-hull", action="store_true",
                   help="build against the robot's convex hull instead of its exact parts "
                        "(faster for a non-convex robot; conservative: it can only add "
                        "collisions); default: the robot exactly")
    p.add_argument("--cache-dir", help="cache folder (default $CSPACE_CACHE or ~/.cache/cspace)")
    _memory_option(p, "the build")
    _progress_options(p)


def _memory_option(p: argparse.ArgumentParser, what: str) -> None:
    p.add_argument("--memory", type=_size, default=None, metavar="SIZE",
                   help=f"memory budget of {what}, e.g. 6G (default $CSPACE_MEMORY, else half "
                        "of the memory available); a build over it stops before it starts, "
                        f"exit status {EXIT_MEMORY}")


def _progress_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    p.add_argument("--progress", action="store_true",
                   help="progress lines on stderr even when it is not a terminal (a log)")


def _operand_arguments(p: argparse.ArgumentParser, a_help: str, output_help: str) -> None:
    """The operands A and B, ``-o``, ``--reflect-b`` and ``--grid-bits`` of the sum commands."""
    p.add_argument("a", help=a_help)
    p.add_argument("b", help="mesh file of B (its convex hull is used)")
    p.add_argument("-o", "--output", help=output_help)
    p.add_argument(
        "--reflect-b", nargs=3, type=float, metavar=("X", "Y", "Z"),
        help="use -(B - c) for this reference point c: the C-obstacle of robot B around obstacle A",
    )
    p.add_argument("--grid-bits", type=int, default=26, help="snapped coordinates satisfy |k| <= 2**bits")


def _number(kind, test, what):
    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not {what}") from None
        if not test(value):
            raise argparse.ArgumentTypeError(f"{text!r} is not {what}")
        return value
    return parse


_positive_int = _number(int, lambda v: v >= 1, "a whole number >= 1")
_count = _number(int, lambda v: v >= 0, "a whole number >= 0")
_slices = _number(int, lambda v: v >= 2, "a whole number of slices >= 2")
_seed = _number(int, lambda v: 0 <= v < 2**31, "a seed (a whole number from 0 to 2**31 - 1)")
_positive = _number(float, lambda v: 0 < v < float("inf"), "a positive number")
_non_negative = _number(float, lambda v: 0 <= v < float("inf"), "a number >= 0")


def _size(text: str) -> int:
    from .memory import parse_size

    try:
        return parse_size(text, "--memory")
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


# Exit status of a build that would not fit in its memory budget (2 is bad input).
EXIT_MEMORY = 4
EXIT_NO_PATH = 3  # plan: proved that no path exists (at the orientations allowed)


class _Formatter(argparse.RawDescriptionHelpFormatter):
    """Help that shows an option's default when it has one (not None or False)."""

    def _get_help_string(self, action):
        text = action.help or ""
        if (action.option_strings and "%(default)" not in text
                and action.default not in (None, False, argparse.SUPPRESS)):
            text += " (default: %(default)s)"
        return text


def _help(example: str, one: str = "", status: str | None = None) -> dict:
    """Subcommand help: defaults shown, one example, the exit statuses (``one``: what 1
    means for this command, besides an internal error; ``status``: the whole list)."""
    status = status or (f"0 done; 1 {one + ' or ' if one else ''}an internal error (a bug: "
                        f"--debug shows it); 2 bad input or an unwritable output (one line on "
                        f"stderr); {EXIT_MEMORY} over the memory budget; 130 interrupted")
    return {"formatter_class": _Formatter,
            "epilog": f"example:\n  {example}\n\nexit status: {status}"}


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``cspace`` command line; returns the exit status."""
    from .errors import CspaceError, MemoryBudgetError

    parser = argparse.ArgumentParser(
        prog="cspace", description="Exact C-space obstacles, and OMPL planning that trusts them.")
    parser.add_argument("--debug", action="store_true",
                        help="show Python tracebacks (for reporting a bug in cspace)")
    parser.add_argument("--version", action="version", version=f"cspace {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("convex-sum", help="exact Minkowski sum of two convex shapes (CVMS)", **_help(
        "cspace convex-sum obstacle.stl robot.stl --reflect-b 0 0 0 -o cobstacle.stl"))
    _operand_arguments(p, "mesh file of A (its convex hull is used)", "write the sum as a mesh file")
    p.set_defaults(func=_convex_sum)
    p = sub.add_parser("superset", help="NCC-CVMS superset (convolution) of a closed mesh and a convex shape", **_help(
        "cspace superset bunny.obj robot.stl --reflect-b 0 0 0 -o superset.ply"))
    _operand_arguments(p, "closed mesh file of A (validated)", "write the superset's triangles as a mesh file")
    p.set_defaults(func=_superset)
    p = sub.add_parser("sum", help="exact Minkowski sum of a closed (non-convex) mesh and a convex shape", **_help(
        "cspace sum bunny.obj robot.stl --reflect-b 0 0 0 -o cobstacle.stl --stats"))
    _operand_arguments(p, "closed mesh file of A (validated; any genus, non-convex)",
                       "write the sum as a mesh file (any format trimesh exports)")
    p.add_argument("--stats", action="store_true", help="print the time of each stage")
    p.add_argument("--workers", type=_positive_int, default=None, metavar="N",
                   help="processes for the large stages (default: $CSPACE_WORKERS, else the CPUs)")
    _progress_options(p)
    p.set_defaults(func=_sum)
    p = sub.add_parser("check", help="cross-check a scene's C-obstacles against FCL", **_help(
        "cspace check scenes/window.toml -n 2000", one="FCL disagreed"))
    p.add_argument("scene", help="scene file: .toml, OMPL.app .cfg, Parasol .env/.query")
    p.add_argument("-n", type=_positive_int, default=10000,
                   help="number of random translations")
    p.add_argument("--seed", type=_seed, default=0, help="random seed")
    p.add_argument("--band", type=_non_negative, default=1e-9,
                   help="ignore points this close to the surface")
    _model_options(p)
    _executor_options(p)
    p.set_defaults(func=_check)
    p = sub.add_parser("build", help="model a scene and build its C-obstacles (cached)", **_help(
        "cspace build scenes/maze.toml --explain -o maze_cobstacles.npz",
        one="a body's C-obstacles could not be built"))
    p.add_argument("scene", help="scene file: .toml, OMPL.app .cfg, Parasol .env/.query")
    p.add_argument("-o", "--output", help="write the C-obstacles' meshes to an .npz file")
    _model_options(p)
    _executor_options(p)
    p.set_defaults(func=_build)
    p = sub.add_parser("plan", help="plan a path with OMPL and exact C-obstacles", **_help(
        "cspace plan scenes/comb.toml --seed 1 -o path.txt --html comb.html", status=(
            "0 a proved path; 1 none found in the time given (not a proof); 2 bad input; "
            f"{EXIT_NO_PATH} proved that none exists as the robot may move (--no-turns: at the "
            "start's orientation; --slices N: over those slices, said so; a robot that may "
            "turn: the ball inside it that no turn changes cannot pass either); "
            f"{EXIT_MEMORY} over the memory budget; 130 interrupted")))
    p.add_argument("scene", help="scene file: .toml, OMPL.app .cfg, Parasol .env/.query")
    _model_options(p)
    p.add_argument("--planner", default="auto",
                   help="any bound OMPL geometric planner, or 'auto' (default): RRTConnect, "
                        "then a decision by certified cells (a path through free cells, or a "
                        "proof that none exists), then the robot turns while it moves: "
                        "RRTConnect in SE(3) and passages at fixed orientations, every motion "
                        "certified by clearance (with --no-turns: PRM with the narrow-passage "
                        "sampler and the decision again), within --time. A given planner "
                        "plans in SE(3) when the goal's orientation differs from the start's, "
                        "else translations")
    p.add_argument("--time", type=_positive, default=None,
                   help="planning time budget in seconds (default: Python plan()'s, "
                        "cspace.planning.plan.DEFAULT_TIME, 10 s; the auto planner stops at its "
                        "first answer, a path or a proof)")
    p.add_argument("--seed", type=_seed, default=None, help="OMPL random seed (none: a new one each run)")
    p.add_argument("-o", "--output", help="write the path when solved: .txt, .csv or .npy (n x 3, "
                   "n x 7 with quaternions x y z w when it turns), or OMPL.app's .path "
                   "(x y z qx qy qz qw per line)")
    p.add_argument("--slices", type=_slices, default=None, metavar="N",
                   help="let the robot turn: plan over N orientation slices about the axis of "
                        "the goal's rotation (z when the goal keeps the start's), every "
                        "translation and turn in place certified")
    p.add_argument("--orientations", type=_count, default=None, metavar="N",
                   help="let a free-flying robot turn: plan over the 24 axis-aligned "
                        "orientations, N near-uniform ones of SO(3) and the goal's, each "
                        "linked to its nearest, every motion certified (0: the 24 alone)")
    p.add_argument("--no-turns", action="store_true",
                   help="keep the start's orientation (the goal's is then ignored) and do not "
                        "let --planner auto turn the robot")
    _executor_options(p)
    p.add_argument("--html", help="also write an offline meshcat page of the scene and the path")
    p.add_argument("--sampler", default="uniform", choices=("uniform", "narrow"),
                   help="valid-state sampler of PRM-like planners: 'narrow' draws half its "
                        "samples from gaps between C-obstacles (narrow passages)")
    p.add_argument("--fcl-check", action="store_true",
                   help="re-check the path with FCL sampled every 1e-3 of the scene size")
    p.add_argument("--result", help="write a JSON summary (model, plan, path, checks)")
    p.set_defaults(func=_plan)
    p = sub.add_parser("benchmark", help="OMPL benchmark log of planners on a scene, every "
                       "motion certified (and OMPL.app's sampled way beside it)", **_help(
                           "cspace benchmark scenes/comb.toml --planners RRTConnect,PRM "
                           "--runs 20 --time 5 --sampled -o comb.log --db comb.db",
                           one="OMPL's statistics script could not read the log"))
    p.add_argument("scene", help="scene file: .toml, OMPL.app .cfg, Parasol .env/.query")
    p.add_argument("-o", "--output", required=True,
                   help="the .log to write, in OMPL's benchmark format (ompl_benchmark_statistics "
                        "reads it; with --sampled also <stem>-sampled.log)")
    p.add_argument("--planners", default="RRTConnect",
                   help="comma-separated OMPL geometric planners (poses in SE(3); the robot "
                        "may turn)")
    p.add_argument("--runs", type=_positive_int, default=10, help="runs per planner")
    p.add_argument("--time", type=_positive, default=10.0, help="seconds per run")
    p.add_argument("--max-mem", type=_positive, default=4096.0, metavar="MB",
                   help="OMPL's memory limit per run, megabytes")
    p.add_argument("--seed", type=_seed, default=None, help="OMPL random seed")
    p.add_argument("--sampled", action="store_true",
                   help="also run OMPL.app's way (FCL at each pose, motions sampled every 1%% "
                        "of the extent, nothing proved between) into <stem>-sampled.log")
    p.add_argument("--db", help="also write OMPL's benchmark database (.db, sqlite) of the logs")
    p.set_defaults(func=_benchmark)
    p = sub.add_parser("free-space", help="the exact free space at the start's orientation: "
                       "components, start and goal, the union's surface", **_help(
                           "cspace free-space scenes/cage.toml -o cage_union.stl",
                           one="not done within --time"))
    p.add_argument("scene", help="scene file: .toml, OMPL.app .cfg, Parasol .env/.query")
    p.add_argument("-o", "--output", help="write the union's surface (any format trimesh exports)")
    p.add_argument("--time", type=_positive, default=None, metavar="SECONDS",
                   help="give up after this long (exit status 1); default: no limit")
    _memory_option(p, "the build and the union")
    p.add_argument("--no-cache", action="store_true", help="do not read or write the disk cache")
    p.add_argument("--cache-dir", help="cache folder (default $CSPACE_CACHE or ~/.cache/cspace)")
    _progress_options(p)
    p.set_defaults(func=_free_space)
    p = sub.add_parser("view", help="draw a scene with its C-obstacles in meshcat (offline HTML by default)", **_help(
        "cspace view scenes/window.toml -o window.html",
        one="a body's C-obstacles could not be built (the page is written all the same)"))
    p.add_argument("scene", help="scene file: .toml, OMPL.app .cfg, Parasol .env/.query")
    p.add_argument("-o", "--output", help="HTML file to write (default: <scene name>.html)")
    p.add_argument("--live", action="store_true", help="serve the scene with a live meshcat server instead")
    p.add_argument("--path", help="a path of reference-point positions: .npy or text with 3 columns")
    p.add_argument("--superset", action="store_true",
                   help="draw the superset of a body whose C-obstacle could not be built")
    p.add_argument("--free-space", action="store_true",
                   help="draw the exact free space's components (where it takes the scene: "
                        "convex pieces, triangle pairs, solid bodies against a convex robot)")
    p.add_argument("--no-cache", action="store_true", help="do not read or write the disk cache")
    p.add_argument("--cache-dir", help="cache folder (default $CSPACE_CACHE or ~/.cache/cspace)")
    _memory_option(p, "the build")
    _progress_options(p)
    p.add_argument("--screenshot", metavar="PNG", help="also render the HTML with headless Chromium")
    p.set_defaults(func=_view)
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except KeyboardInterrupt:
        print("cspace: interrupted", file=sys.stderr)
        return 130
    except MemoryBudgetError as e:  # would not fit: said before anything was allocated
        if args.debug:
            raise
        print(f"cspace: error: {e}", file=sys.stderr)
        return EXIT_MEMORY
    except (CspaceError, ValueError, OSError) as e:  # bad input, paths, files: one line
        if args.debug:
            raise
        print(f"cspace: error: {e}", file=sys.stderr)
        return 2
    except Exception as e:  # a bug of cspace's: say so, traceback with --debug
        if args.debug:
            raise
        print(f"cspace: internal error: {type(e).__name__}: {e} (run with --debug for the "
              "traceback)", file=sys.stderr)
        return 1
