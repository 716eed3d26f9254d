"""OMPL.app-style planning problems written as OMPL.app ships them: Collada files and a .cfg.

Each builder writes, into a folder, a world ``.dae`` and a robot ``.dae`` (``Z_UP``, unit 1,
one ``<node>`` per body with its own ``<matrix>``, vertices stored as float32 the way a
modelling tool exports them) and the ``.cfg`` OMPL.app's GUI reads (``[problem]`` world,
robot, start/goal position and axis-angle, ``volume.min/max``). The worlds are centred near
``(250, 150, -300)`` (Assimp's frame: ``Z_UP`` turned to +y) with extents of a few hundred
units, like OMPL.app's ``cubicles`` or ``Twistycool``; the robots are non-convex, carry
sliver triangles (long edges split next to their ends) and sit 15 to 50 units off their
file's origin under a node matrix that turns them, so OMPL.app's robot centre (the mean of
Assimp's vertices) is nowhere special.

Geometry is designed in the world frame (after Assimp's up-axis turn and the node matrices)
and written back through the inverse of both, so the numbers below are the ones a reader
of the files sees, up to float32 rounding (about 1e-5 here).

Used only by ``tests/test_real_problems.py``; nothing here checks anything.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from zoo import voxel_solid

#: Assimp's Z_UP turn (file (x, y, z) -> world (x, z, -y)), acting on columns.
Z_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])

CENTRE = np.array([250.0, 150.0, -300.0])

Mesh = tuple[np.ndarray, np.ndarray]


# --------------------------------------------------------------------------------------
# meshes


def lattice_solid(occupancy, *coords) -> Mesh:
    """A closed union of boxes: voxel ``(i, j, k)`` of ``occupancy`` is the box
    ``[x[i], x[i+1]] x [y[j], y[j+1]] x [z[k], z[k+1]]`` for the increasing ``coords``
    ``x, y, z`` (one more than the occupancy's size per axis). Welded, outward, manifold."""
    occ = np.asarray(occupancy, dtype=bool)
    V, F = voxel_solid(occ)
    idx = np.rint(V).astype(np.int64)
    out = np.stack([np.asarray(c, float)[idx[:, a]] for a, c in enumerate(coords)], axis=1)
    return out, F


def box(lo, hi) -> Mesh:
    """The closed box ``[lo, hi]`` (12 triangles, outward)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return lattice_solid(np.ones((1, 1, 1)), *zip(lo, hi))


def tessellated_box(lo, hi, n: int) -> Mesh:
    """The closed box ``[lo, hi]`` with each face an ``n x n`` grid of quads (12 n^2
    triangles); convex, many coplanar triangles."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return lattice_solid(np.ones((n, n, n)), *(np.linspace(a, b, n + 1) for a, b in zip(lo, hi)))


def split_long_edges(mesh: Mesh, fraction: float = 1e-3, count: int = 1000) -> Mesh:
    """Slivers: split up to ``count`` of the longest edges at ``fraction`` of their length
    from one end, each adjacent triangle ``(a, b, c)`` becoming ``(a, p, c), (p, b, c)``
    (no two split edges share a triangle). The surface is unchanged and stays closed."""
    V, F = (np.array(x) for x in mesh)
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    key = np.sort(E, axis=1)
    und, first = np.unique(key, axis=0, return_index=True)
    order = np.argsort(-np.linalg.norm(V[und[:, 0]] - V[und[:, 1]], axis=1), kind="stable")
    tri_of = {}
    for t, (a, b, c) in enumerate(F.tolist()):
        for e in ((a, b), (b, c), (c, a)):
            tri_of.setdefault(tuple(sorted(e)), []).append(t)
    used, chosen = set(), []
    for i in order.tolist():
        e = tuple(und[i].tolist())
        ts = tri_of[e]
        if any(t in used for t in ts):
            continue
        used.update(ts)
        chosen.append(e)
        if len(chosen) == count:
            break
    newV, keep, extra = list(V), np.ones(len(F), bool), []
    for a, b in chosen:
        p = len(newV)
        newV.append(V[a] + fraction * (V[b] - V[a]))
        for t in tri_of[(a, b)]:
            f = F[t].tolist()
            k = next(k for k in range(3) if {f[k], f[(k + 1) % 3]} == {a, b})
            u, v, w = f[k], f[(k + 1) % 3], f[(k + 2) % 3]  # edge (u, v), apex w
            extra += [[u, p, w], [p, v, w]]
            keep[t] = False
    return np.array(newV), np.vstack([F[keep], np.array(extra, np.int64).reshape(-1, 3)])


def double_sided(mesh: Mesh) -> Mesh:
    """An open surface listed with both windings (as exporters write 'double-sided')."""
    V, F = mesh
    return V, np.vstack([F, F[:, ::-1]])


def grid_sheet(corner, u, v, nu: int, nv: int, holes=()) -> Mesh:
    """An open planar sheet ``corner + s u + t v`` (s, t in [0, 1]) as an ``nu x nv`` quad
    strip grid, without the cells listed in ``holes`` ((i, j) pairs)."""
    s, t = np.meshgrid(np.linspace(0, 1, nu + 1), np.linspace(0, 1, nv + 1), indexing="ij")
    V = np.asarray(corner, float) + s.reshape(-1, 1) * u + t.reshape(-1, 1) * v
    idx = np.arange((nu + 1) * (nv + 1)).reshape(nu + 1, nv + 1)
    skip = set(map(tuple, holes))
    F = []
    for i in range(nu):
        for j in range(nv):
            if (i, j) in skip:
                continue
            a, b, c, d = idx[i, j], idx[i + 1, j], idx[i + 1, j + 1], idx[i, j + 1]
            F += [[a, b, c], [a, c, d]]
    return V, np.array(F, np.int64)


def n_triangles(bodies) -> int:
    return int(sum(len(F) for _, (V, F), _ in bodies))


# --------------------------------------------------------------------------------------
# Collada


def matrix(rotvec_deg=(0.0, 0.0, 0.0), translation=(0.0, 0.0, 0.0)) -> np.ndarray:
    """A 4x4 node matrix: a rotation (rotation vector in degrees), then a translation;
    rounded to float32 as a Collada file stores it."""
    m = np.eye(4)
    m[:3, :3] = Rotation.from_rotvec(np.radians(rotvec_deg)).as_matrix()
    m[:3, 3] = translation
    return m.astype(np.float32).astype(np.float64)


def write_dae(path: Path, bodies) -> Path:
    """Write ``bodies``, ``(name, (world_vertices, faces), node_matrix)`` each, as a Z_UP
    Collada file with one node per body; a body whose mesh tuple is the *same object* as an
    earlier body's instances that geometry again (a shared ``<geometry>``). The vertices are
    stored so that Assimp's placement ``Z_UP @ node_matrix @ v`` gives back the world
    vertices (to float32 rounding)."""
    from collada import geometry, scene, source
    from test_meshfile import _doc  # one Collada document with one material

    doc, mat = _doc("Z_UP", 1.0)
    geoms, nodes = {}, []
    for name, mesh, m in bodies:
        V, F = mesh
        m = np.asarray(m, float)
        g = geoms.get(id(mesh))
        if g is None:
            # world = Z_UP @ (A v + t)  =>  v = A^-1 (Z_UP^T world - t)
            local = (Z_UP.T @ np.asarray(V, float).T - m[:3, 3:4])
            local = np.linalg.solve(m[:3, :3], local).T
            gname = f"g{len(geoms)}"
            src = source.FloatSource(f"{gname}-v", local.astype(np.float32).ravel(),
                                     ("X", "Y", "Z"))
            inputs = source.InputList()
            inputs.addInput(0, "VERTEX", f"#{gname}-v")
            g = geometry.Geometry(doc, gname, name, [src])
            g.primitives.append(g.createTriangleSet(np.asarray(F, np.int64).ravel(), inputs,
                                                    "mat"))
            doc.geometries.append(g)
            geoms[id(mesh)] = g
        inst = scene.GeometryNode(g, [scene.MaterialNode("mat", mat, inputs=[])])
        nodes.append(scene.Node(name, children=[inst],
                                transforms=[scene.MatrixTransform(m.astype(np.float32).ravel())]))
    s = scene.Scene("scene0", nodes)
    doc.scenes.append(s)
    doc.scene = s
    doc.write(str(path))
    return path


def write_cfg(path: Path, world: str, robot: str, start, goal, bounds, *,
              start_rotation=((0.0, 0.0, 1.0), 0.0), goal_rotation=((0.0, 0.0, 1.0), 0.0)):
    """OMPL.app's problem file (``[problem]`` as ``gui/ompl_app.py`` reads it)."""
    lines = ["[problem]", f"name = {path.stem}", f"world = {world}", f"robot = {robot}"]
    for which, q, (axis, theta) in (("start", start, start_rotation),
                                    ("goal", goal, goal_rotation)):
        lines += [f"{which}.{a} = {float(v)!r}" for a, v in zip("xyz", q)]
        lines += [f"{which}.axis.{a} = {float(v)!r}" for a, v in zip("xyz", axis)]
        lines.append(f"{which}.theta = {float(theta)!r}")
    lines += [f"volume.{end}.{a} = {float(v)!r}" for end, row in zip(("min", "max"), bounds)
              for a, v in zip("xyz", row)]
    lines += ["", "[benchmark]", "time_limit = 10.0", "", "[planner]", "rrtconnect ="]
    path.write_text("\n".join(lines) + "\n")
    return path


# --------------------------------------------------------------------------------------
# problems


@dataclass
class Problem:
    """A written problem: its files and what the test needs to know about its design."""

    name: str
    cfg: Path
    world: Path
    robot: Path
    world_triangles: int
    robot_triangles: int
    world_nodes: int
    facts: dict = field(default_factory=dict)


def _robot_file(folder: Path, mesh: Mesh, offset, rotvec_deg,
                translation) -> tuple[Path, np.ndarray]:
    """The robot's file: ``mesh`` (designed about the origin) moved by ``offset`` in the world
    frame, stored under a node matrix; returns the path and OMPL.app's centre of it (as
    cspace reads it: the problem's definition, used to write start and goal)."""
    from cspace.mesh.files import read_mesh_file

    V, F = mesh
    path = write_dae(folder / "robot.dae", [("robot", (V + offset, F),
                                             matrix(rotvec_deg, translation))])
    return path, read_mesh_file(path).assimp_centre


def t_robot(sliver_edges: int = 12) -> Mesh:
    """A T of three boxes welded into one closed non-convex solid: a bar 60 long along z
    (6 x 6 across) and a knob 10 long sticking out along +x from its middle; long edges
    split into slivers. Designed about the bar's centre."""
    occ = np.zeros((2, 1, 3), bool)
    occ[0, 0, :] = True
    occ[1, 0, 1] = True
    T = lattice_solid(occ, [-3, 3, 13], [-3, 3], [-30, -3, 3, 30])
    return split_long_edges(T, 1e-3, sliver_edges)


def u_robot(sliver_edges: int = 12) -> Mesh:
    """A U (C) of boxes in the horizontal x-z plane, 8 high (y): a base 6 thick along z and
    two arms 30 long along +x, the slot between them 12 wide (z in [-6, 6]) and 30 deep;
    long edges split into slivers. Designed about the slot's mouth centre."""
    occ = np.zeros((2, 1, 3), bool)
    occ[0, 0, :] = True
    occ[1, 0, 0] = occ[1, 0, 2] = True
    U = lattice_solid(occ, [-36, -30, 0], [-4, 4], [-12, -6, 6, 12])
    return split_long_edges(U, 1e-3, sliver_edges)


def l_robot(sliver_edges: int = 12) -> Mesh:
    """An L of two boxes welded into one closed solid: a leg 40 along x and a leg 30 along
    y, each 8 x 8 across; long edges split into slivers. Designed about the corner."""
    occ = np.zeros((2, 2, 1), bool)
    occ[:, 0, 0] = True
    occ[0, :, 0] = True
    L = lattice_solid(occ, [-4, 4, 36], [-4, 4, 26], [-4, 4])
    return split_long_edges(L, 1e-3, sliver_edges)


def clutter(rng, n: int, region_lo, region_hi, *, keep_out=(), tessellation: int = 1):
    """``n`` small bodies (boxes 4-12 units, some tessellated; open double-sided panels),
    each its own node with its own matrix (a random turn); a few are exact duplicates (the
    same geometry instanced twice with the same matrix) and panels share geometry between
    nodes. Boxes stay out of the ``keep_out`` boxes (``(lo, hi)`` pairs, world frame)."""
    bodies = []
    lo, hi = np.asarray(region_lo, float), np.asarray(region_hi, float)
    panel = double_sided(grid_sheet((-5, -5, 0), np.array([10.0, 0, 0]),
                                    np.array([0, 10.0, 0]), 2, 2))
    while len(bodies) < n:
        c = rng.uniform(lo, hi)
        size = rng.uniform(4, 12, 3)
        r = 0.5 * float(np.linalg.norm(size))
        if any(((c + r > np.asarray(a)) & (c - r < np.asarray(b))).all() for a, b in keep_out):
            continue
        rot = rng.normal(size=3) * 40.0
        m = matrix(rot, (0, 0, 0))
        # design in the body's own frame, then place: world = R (local) + c
        k = len(bodies)
        if k % 5 == 4:
            V, F = panel
            world = (V @ m[:3, :3].T + c, F)
            bodies.append((f"panel{k}", world, matrix(rot, Z_UP.T @ c)))
        else:
            mesh = (tessellated_box(-size / 2, size / 2, tessellation) if k % 3 == 0
                    else box(-size / 2, size / 2))
            V, F = mesh
            world = (V @ m[:3, :3].T + c, F)
            bodies.append((f"box{k}", world, matrix(rot, Z_UP.T @ c)))
            if k % 7 == 0:  # an exact duplicate, the same geometry instanced again
                bodies.append((f"box{k}dup", world, bodies[-1][2]))
    order = rng.permutation(len(bodies))
    return [bodies[i] for i in order]


def slot_wall(folder: Path, *, wall: str = "boxes", cells: int = 30,
              sliver_edges: int = 12) -> Problem:
    """Problem 1: a thick wall (8 units, x in [246, 254]) spanning 300 x 300 across the
    world with a vertical slot 14 wide (z) and 90 tall (y) in its middle. ``wall='boxes'``:
    four tessellated boxes round the slot (``cells`` faces a side along the long axes),
    overlapping at their ends, each its own node and matrix, as OMPL.app's ``cubicles``
    builds walls; ``wall='solid'``: one closed genus-1 solid of ``cells x cells`` faces per
    side, as a modeller exports a holed wall (``Twistycool``); ``wall='sheet'``: the wall's
    mid-plane alone, an open quad strip grid round the slot listed with both windings
    (double-sided, zero thickness). The T robot's bar (60 along
    z) cannot pass the slot; turned 90 degrees about x (the goal's orientation) it stands
    60 tall in the 90-tall slot. The bounds keep the reference point 90 units inside the
    wall's edges, so nothing passes around it."""
    folder.mkdir(parents=True, exist_ok=True)
    if wall in ("solid", "sheet"):
        # lattice coordinates: the slot's edges are lattice lines
        ys = np.unique(np.concatenate([np.linspace(0, 105, cells // 3 + 1),
                                       np.linspace(105, 195, cells // 3 + 1),
                                       np.linspace(195, 300, cells // 3 + 1)]))
        zs = np.unique(np.concatenate([np.linspace(-450, -307, cells // 2 + 1),
                                       [-307.0, -293.0],
                                       np.linspace(-293, -150, cells // 2 + 1)]))
        occ = np.ones((1, len(ys) - 1, len(zs) - 1), bool)
        jy = (ys[:-1] >= 105) & (ys[1:] <= 195)
        jz = (zs[:-1] >= -307) & (zs[1:] <= -293)
        occ[0][np.ix_(jy, jz)] = False
        if wall == "solid":
            mesh = lattice_solid(occ, [246.0, 254.0], ys, zs)
        else:  # the plane x = 250 as a quad strip grid without the slot's cells
            Y, Z = np.meshgrid(ys, zs, indexing="ij")
            V = np.stack([np.full(Y.size, 250.0), Y.ravel(), Z.ravel()], axis=1)
            idx = np.arange(Y.size).reshape(Y.shape)
            i, j = np.nonzero(occ[0])
            a, b, c, d = idx[i, j], idx[i + 1, j], idx[i + 1, j + 1], idx[i, j + 1]
            mesh = double_sided((V, np.concatenate([np.stack([a, b, c], 1),
                                                    np.stack([a, c, d], 1)])))
        world = [("wall", mesh, matrix((0, 0, 30), (5.0, -3.0, 2.0)))]
    elif wall == "boxes":
        def slab(lo, hi):
            n = [1, max(1, cells * int(hi[1] - lo[1]) // 300),
                 max(1, cells * int(hi[2] - lo[2]) // 300)]
            return lattice_solid(np.ones(n), *(np.linspace(a, b, k + 1)
                                               for a, b, k in zip(lo, hi, n)))
        world = [("below", slab((246, 0, -450), (254, 106, -150)), matrix((0, 0, 30), (5, -3, 2))),
                 ("above", slab((246, 194, -450), (254, 300, -150)), matrix((90, 0, 0), (0, 9, 0))),
                 ("left", slab((246, 100, -450), (254, 200, -307)), matrix((0, -45, 0), (1, 1, 1))),
                 ("right", slab((246, 100, -293), (254, 200, -150)), matrix((0, 0, 0), (0, 0, 0)))]
    else:
        raise ValueError(f"wall must be 'boxes', 'solid' or 'sheet', got {wall!r}")
    write_dae(folder / "world.dae", world)
    T = t_robot(sliver_edges)
    offset = np.array([31.0, -18.0, 22.0])
    robot, c = _robot_file(folder, T, offset, (0, 90, 0), (12.0, 7.0, -20.0))
    # reference point q: the robot occupies T + offset - c + q; the bar centred at a point p
    # means q = p + c - offset
    start = np.array([200.0, 150.0, -300.0]) + c - offset
    goal = np.array([300.0, 150.0, -300.0]) + c - offset
    bounds = np.array([[180.0, 90.0, -360.0], [320.0, 210.0, -240.0]])
    cfg = write_cfg(folder / "slot_wall.cfg", "world.dae", "robot.dae", start, goal, bounds,
                    goal_rotation=((1.0, 0.0, 0.0), math.pi / 2))
    return Problem("slot_wall", cfg, folder / "world.dae", robot, n_triangles(world),
                   len(T[1]), len(world),
                   facts={"wall": wall, "wall_x": (246.0, 254.0), "slot_z": (-307.0, -293.0),
                          "slot_y": (105.0, 195.0), "bar_offset": c - offset})


def u_around_post(folder: Path, *, sections: int = 96, sliver_edges: int = 12,
                  n_clutter: int = 12, seed: int = 5) -> Problem:
    """Problem 2: a vertical post (a closed prism of ``sections`` sides, radius 4, y in
    [40, 260], at x = 250, z = -300) inside the U robot's 12-wide slot at the start, with a
    ceiling panel above, a floor below (open double-sided sheets, the floor of a few
    hundred triangles) and ``n_clutter`` small bodies round about. The robot's convex hull
    holds the post: the start is free only because the robot is not convex."""
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    a = 2 * np.pi * (np.arange(sections) + 0.5) / sections
    ring = np.stack([250 + 4 * np.cos(a), np.zeros(sections), -300 + 4 * np.sin(a)], axis=1)
    V = np.vstack([ring + [0, 40, 0], ring + [0, 260, 0], [[250, 40, -300], [250, 260, -300]]])
    i = np.arange(sections)
    j = (i + 1) % sections
    n = sections
    F = np.concatenate([np.stack([i, n + j, j], 1), np.stack([i, n + i, n + j], 1),
                        np.stack([np.full(n, 2 * n), i, j], 1),
                        np.stack([np.full(n, 2 * n + 1), n + j, n + i], 1)])
    post = (V, F)
    floor = double_sided(grid_sheet((100, 30, -450), np.array([300.0, 0, 0]),
                                    np.array([0, 0, 300.0]), 12, 12))
    ceiling = double_sided(grid_sheet((100, 270, -450), np.array([300.0, 0, 0]),
                                      np.array([0, 0, 300.0]), 1, 1))
    keep = [((200, 30, -350), (350, 270, -250)), ((280, 170, -270), (370, 260, -180))]
    world = [("post", post, matrix((0, 0, -20), (-3.0, 4.0, 1.0))),
             ("floor", floor, matrix((10, 0, 0), (0.0, 0.0, 0.0))),
             ("ceiling", ceiling, matrix((0, 0, 0), (7.0, 0.0, 0.0)))]
    world += clutter(rng, n_clutter, (120, 40, -440), (380, 260, -160), keep_out=keep)
    write_dae(folder / "world.dae", world)
    U = u_robot(sliver_edges)
    offset = np.array([-22.0, 35.0, 17.0])
    robot, c = _robot_file(folder, U, offset, (0, 0, 45), (-9.0, 16.0, 3.0))
    # the U's design point (slot mouth centre) at p: q = p + c - offset; the post's axis
    # 15 deep in the slot (x = mouth - 15)
    start = np.array([265.0, 150.0, -300.0]) + c - offset
    goal = np.array([330.0, 215.0, -220.0]) + c - offset
    bounds = np.array([[140.0, 50.0, -420.0], [360.0, 250.0, -180.0]]) + (c - offset)
    cfg = write_cfg(folder / "u_post.cfg", "world.dae", "robot.dae", start, goal, bounds)
    return Problem("u_post", cfg, folder / "world.dae", robot, n_triangles(world),
                   len(U[1]), len(world), facts={})


def thin_wall(folder: Path, *, n_clutter: int = 36, tessellation: int = 1, seed: int = 3,
              sliver_edges: int = 12) -> Problem:
    """Problem 3: one quad 160 x 160 (two triangles, listed with both windings: four), its
    plane through (250, 150, -300) turned 20 degrees about y by its node matrix, start and
    goal 40 units either side of it on its normal; the bounds reach 100 units past its
    edges, so the robot (the L) goes round the edge; ``n_clutter`` small bodies (boxes,
    tessellated boxes, open panels; duplicates; each its own node and matrix) around."""
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    rot = matrix((0, 20, 0))[:3, :3]          # world-frame turn of the wall
    normal = rot @ [1.0, 0.0, 0.0]
    u, v = rot @ [0.0, 0.0, 1.0], np.array([0.0, 1.0, 0.0])
    quad = double_sided(grid_sheet(CENTRE - 80 * u - 80 * v, 160 * u, 160 * v, 1, 1))
    keep = [(CENTRE - 110, CENTRE + 110)]
    world = [("wall", quad, matrix((0, 0, 20), (3.0, 1.0, -2.0)))]
    world += clutter(rng, n_clutter, CENTRE - 240, CENTRE + 240, keep_out=keep,
                     tessellation=tessellation)
    write_dae(folder / "world.dae", world)
    L = l_robot(sliver_edges)
    offset = np.array([18.0, 27.0, -33.0])
    robot, c = _robot_file(folder, L, offset, (30, -60, 0), (6.0, -15.0, 11.0))
    start = CENTRE - 40 * normal + c - offset
    goal = CENTRE + 40 * normal + c - offset
    bounds = np.array([CENTRE - 190, CENTRE + 190])
    cfg = write_cfg(folder / "thin_wall.cfg", "world.dae", "robot.dae", start, goal, bounds)
    return Problem("thin_wall", cfg, folder / "world.dae", robot, n_triangles(world),
                   len(L[1]), len(world),
                   facts={"normal": normal, "u": u, "v": v, "half": 80.0,
                          "design_offset": c - offset,
                          "duplicates": sum(n.endswith("dup") for n, _, _ in world),
                          "duplicate_triangles": sum(len(m[1]) for n, m, _ in world
                                                     if n.endswith("dup")),
                          "panels": sum(n.startswith("panel") for n, _, _ in world)})


def twisting_corner(folder: Path, *, sliver_edges: int = 12, n_clutter: int = 16,
                    seed: int = 11, tessellation: int = 6, width: float = 14.0) -> Problem:
    """Problem 5 (Twistycool's kind: the robot turns *while* it translates): two rooms joined
    by an L-shaped hallway 14 wide and 14 tall, carved out of one closed block (genus 0,
    ``tessellation`` faces a side per lattice cell edge), with open double-sided floor and
    ceiling sheets and ``n_clutter`` bodies in the rooms. The T robot at half size (a bar 30
    long, 3 x 3 across, a knob 5 long; slivers) starts in room A with its bar along z and
    ends in room B the same way. No fixed orientation passes: the hallway's first leg runs
    along x and its second along z, each 14 wide, and the bar's projections on x and on z
    cannot both be below 14 while it stays within the 14-tall layer. Round the corner the
    bar must turn as it moves (a 30 bar fits a 14-wide right-angle turn: 2 sqrt(2) 14 > 39).
    The block's outer cells stay solid and the bounds keep the reference point inside them,
    so nothing goes round it."""
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    h = width / 2
    X = [120.0, 150.0, 210.0, 250 - h, 250 + h, 350.0, 380.0]
    Y = [120.0, 150 - h, 150 + h, 180.0]
    Z = [-480.0, -450.0, -300 - h, -300 + h, -240.0, -150.0, -120.0]
    occ = np.ones((len(X) - 1, len(Y) - 1, len(Z) - 1), bool)
    free = [(1, 1), (1, 2),                  # room A: x in [150, 210], z in [-450, -293]
            (2, 2), (3, 2),                  # hallway along x: z in [-307, -293]
            (3, 3),                          # hallway along z: x in [243, 257]
            (2, 4), (3, 4), (4, 4)]          # room B: x in [210, 350], z in [-240, -150]
    for i, k in free:
        occ[i, 1, k] = False
    # every lattice cell edge cut into ``tessellation`` faces: a heavy, fine mesh
    coords = [np.unique(np.concatenate([np.linspace(a, b, tessellation + 1)
                                        for a, b in zip(c[:-1], c[1:])])) for c in (X, Y, Z)]
    fine = np.repeat(np.repeat(np.repeat(occ, tessellation, 0), tessellation, 1),
                     tessellation, 2)
    block = lattice_solid(fine, *coords)
    floor = double_sided(grid_sheet((150, 150 - h, -450), np.array([200.0, 0, 0]),
                                    np.array([0, 0, 300.0]), 20, 30))
    ceiling = double_sided(grid_sheet((150, 150 + h, -450), np.array([200.0, 0, 0]),
                                      np.array([0, 0, 300.0]), 4, 6))
    world = [("block", block, matrix((0, 0, 15), (4.0, -2.0, 3.0))),
             ("floor", floor, matrix((0, 0, 0), (0.0, 0.0, 0.0))),
             ("ceiling", ceiling, matrix((5, 0, 0), (0.0, 1.0, 0.0)))]
    # clutter on the floor of the rooms, clear of the hallway, the start and the goal
    keep = [((200, 140, -320), (270, 160, -230)), ((160, 140, -380), (200, 160, -320)),
            ((260, 140, -235), (340, 160, -160)), ((150, 140, -240), (350, 160, -230))]
    for name, mesh, m in clutter(rng, 4 * n_clutter, (155, 144.5, -445), (345, 145.5, -155),
                                 keep_out=keep):
        inside = any(all(X[i] + 8 <= x <= X[i + 1] - 8 for x in (mesh[0][:, 0].min(), mesh[0][:, 0].max()))
                     and all(Z[k] + 8 <= z <= Z[k + 1] - 8 for z in (mesh[0][:, 2].min(), mesh[0][:, 2].max()))
                     for i, k in ((1, 1), (4, 4)))
        low = mesh[0][:, 1].max() < 150.0  # below the bar's layer: on the floor
        if inside and low and len(world) < 3 + n_clutter:
            world.append((name, mesh, m))
    write_dae(folder / "world.dae", world)
    V, F = t_robot(sliver_edges)
    T = (V * 0.5, F)
    offset = np.array([-14.0, 21.0, 9.0])
    robot, c = _robot_file(folder, T, offset, (20, 0, -35), (3.0, 8.0, -6.0))
    start = np.array([180.0, 150.0, -400.0]) + c - offset
    goal = np.array([300.0, 150.0, -195.0]) + c - offset
    bounds = np.array([[150.0, 148.0, -450.0], [350.0, 152.0, -150.0]]) + (c - offset)
    cfg = write_cfg(folder / "corner.cfg", "world.dae", "robot.dae", start, goal, bounds)
    return Problem("twisting_corner", cfg, folder / "world.dae", robot, n_triangles(world),
                   len(T[1]), len(world), facts={"design_offset": c - offset})


def piano(sliver_edges: int = 350) -> Mesh:
    """A closed non-convex 'grand piano' of about 1.7k triangles: a case 48 x 30 (x, z) and
    10 tall (y) whose curved side is a staircase of voxels, on three legs 14 tall; its long
    edges split into slivers. Designed about the case's centre."""
    nx, nz = 20, 12
    occ = np.zeros((nx, 4, nz), bool)
    i, k = np.meshgrid(np.arange(nx), np.arange(nz), indexing="ij")
    curve = k < nz - 1 - np.maximum(0, (i - 6)) * 0.65  # the bent side
    occ[:, 2:, :] = curve[:, None, :]
    for a, b in ((1, 1), (1, nz - 3), (nx - 2, 1)):  # legs under the case
        occ[a, :2, b] = True
    x = np.linspace(-24, 24, nx + 1)
    z = np.linspace(-15, 15, nz + 1)
    y = np.array([-19.0, -12.0, -5.0, 0.0, 5.0])
    return split_long_edges(lattice_solid(occ, x, y, z), 1e-3, sliver_edges)


def apartment(folder: Path, *, rooms=(4, 3), wall_cells: int = 1, sheet_cells=(60, 40),
              furniture: int = 12, seed: int = 5, sliver_edges: int = 350,
              door: float = 60.0) -> Problem:
    """An apartment-class world of about 40k triangles in about 180 bodies round
    ``CENTRE``: a floor and a ceiling (open double-sided tessellated sheets), outer walls
    and inner wall segments (open double-sided sheets, each its own node) with a door 60
    wide and 60 tall in every inner segment, and ``furniture`` bodies a room (closed
    tessellated boxes, closed tori, open panels; turned node matrices). The robot is
    :func:`piano`; start and goal are in opposite corner rooms, so a path goes through
    doors. The footprint is 600 x 400 (x, z), 80 tall (y, Assimp's up). ``door``: the doors'
    width (60: the piano, 48 x 30, passes every door as it starts; 40: the doors in walls
    along x only turned 90 degrees about y, so a path must turn it)."""
    from zoo import torus

    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    lo = CENTRE + np.array([-300.0, -40.0, -200.0])
    hi = CENTRE + np.array([300.0, 40.0, 200.0])
    ex, ey, ez = np.eye(3)
    size = hi - lo
    c = wall_cells
    world = []
    # floor and ceiling
    for name, yv in (("floor", lo[1]), ("ceiling", hi[1])):
        world.append((name, double_sided(grid_sheet((lo[0], yv, lo[2]), size[0] * ex,
                                                    size[2] * ez, *sheet_cells)), matrix()))
    # outer walls
    for name, corner, u, n_u in (("wall_s", lo, size[0] * ex, sheet_cells[0]),
                                 ("wall_n", (lo[0], lo[1], hi[2]), size[0] * ex, sheet_cells[0]),
                                 ("wall_w", lo, size[2] * ez, sheet_cells[1]),
                                 ("wall_e", (hi[0], lo[1], lo[2]), size[2] * ez, sheet_cells[1])):
        world.append((name, double_sided(grid_sheet(corner, u, size[1] * ey, n_u, 8 * c)),
                      matrix()))
    nx, nz = rooms
    xs = np.linspace(lo[0], hi[0], nx + 1)
    zs = np.linspace(lo[2], hi[2], nz + 1)
    doors = []

    def segment(name, corner, u, length):
        n_u = max(4, int(round(length / 10.0)) * c)
        mid = n_u // 2
        w = max(1, int(round(door / length * n_u / 2)))   # a door ``door`` wide ...
        h = int(round(60.0 / size[1] * 8 * c))            # ... and 60 tall
        holes = [(i, j) for i in range(mid - w, mid + w) for j in range(h)]
        world.append((name, double_sided(grid_sheet(corner, u, size[1] * ey, n_u, 8 * c,
                                                    holes)), matrix()))
        doors.append(np.asarray(corner, float) + u * 0.5 + ey * 30.0)

    for a in range(1, nx):           # inner walls along z at x = xs[a]
        for b in range(nz):
            segment(f"wall_x{a}_{b}", (xs[a], lo[1], zs[b]), (zs[b + 1] - zs[b]) * ez,
                    zs[b + 1] - zs[b])
    for b in range(1, nz):           # inner walls along x at z = zs[b]
        for a in range(nx):
            segment(f"wall_z{a}_{b}", (xs[a], lo[1], zs[b]), (xs[a + 1] - xs[a]) * ex,
                    xs[a + 1] - xs[a])
    start = np.array([xs[0] + 45.0, lo[1] + 21.0, zs[0] + 45.0])
    goal = np.array([xs[-1] - 45.0, lo[1] + 21.0, zs[-1] - 45.0])
    keep = [(p - 40.0, p + 40.0) for p in doors] + [(p - 45.0, p + 45.0) for p in (start, goal)]
    T = torus(sections=12, ring=6)
    panel = double_sided(grid_sheet((-6, -6, 0), np.array([12.0, 0, 0]),
                                    np.array([0, 12.0, 0]), 2, 2))
    for a in range(nx):
        for b in range(nz):
            room_lo = np.array([xs[a] + 12, lo[1] + 6, zs[b] + 12])
            room_hi = np.array([xs[a + 1] - 12, hi[1] - 20, zs[b + 1] - 12])
            placed, tries = 0, 0
            while placed < furniture and tries < 10000:
                tries += 1
                p = rng.uniform(room_lo, room_hi)
                if any(((p + 12 > k0) & (p - 12 < k1)).all() for k0, k1 in keep):
                    continue
                rot = rng.normal(size=3) * 40.0
                m = matrix(rot, (0, 0, 0))
                k = placed % 4
                if k == 0:
                    s = rng.uniform(4, 10, 3)
                    V, F = tessellated_box(-s / 2, s / 2, 2)
                elif k == 1:
                    V, F = np.asarray(T[0]) * rng.uniform(4, 8), T[1]
                elif k == 2:
                    V, F = panel
                else:
                    s = rng.uniform(4, 10, 3)
                    V, F = box(-s / 2, s / 2)
                name = ("chest", "ring", "panel", "box")[k]
                world.append((f"{name}{a}{b}_{placed}", (np.asarray(V) @ m[:3, :3].T + p, F),
                              matrix(rot, Z_UP.T @ p)))
                placed += 1
    write_dae(folder / "world.dae", world)
    P = piano(sliver_edges)
    offset = np.array([21.0, -17.0, 33.0])
    robot, cr = _robot_file(folder, P, offset, (0, 35, 0), (4.0, 9.0, -6.0))
    # the robot's node turns it 35 degrees about y: start and goal turn it back
    back = ((0.0, 1.0, 0.0), -math.radians(35.0))
    cfg = write_cfg(folder / "apartment.cfg", "world.dae", "robot.dae", start + cr - offset,
                    goal + cr - offset, np.array([lo, hi]), start_rotation=back,
                    goal_rotation=back)
    return Problem("apartment", cfg, folder / "world.dae", robot, n_triangles(world),
                   len(P[1]), len(world), facts={"doors": np.array(doors)})
