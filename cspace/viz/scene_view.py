"""Draw translational C-space scenes in meshcat and save them as offline HTML.

Works on ``(n, 3) float64`` vertex arrays, ``(m, 3) int64`` triangle faces (counter-clockwise
seen from outside) and ``(k, 3) float64`` paths of the robot's reference point, all in the
world frame and scene units. :class:`SceneView` wraps a ``meshcat.Visualizer``; by default it
starts nothing (no server, no port, no browser) and :meth:`SceneView.save` writes one
self-contained HTML file that opens offline (the three.js viewer is inlined; no CDN).
:func:`cspace.viz.browser.screenshot` renders such a file to PNG with headless Chromium.

Scene tree
----------
Every drawing is a node the meshcat UI can toggle ("Open Controls" → Scene → meshcat)::

    /meshcat/obstacles/<name>             obstacle (+ /edges)
    /meshcat/robot/<name>                 robot, placed by its transform (animated)
    /meshcat/cobstacles/<name>            C-obstacle O ⊕ (−R) (+ /edges)
    /meshcat/superset/<name>/<kind>       superset facets, one node per kind in
                                          SUPERSET_KINDS = translated, corner, edge
    /meshcat/path/<name>/line             polyline of the reference point
    /meshcat/path/<name>/waypoints        small spheres at the waypoints

Colours
-------
meshcat draws no text, so the legend is this table (sRGB, 0–255; module constants):

=====================  ===============  =======  =====================================
constant               RGB              hex      drawn as
=====================  ===============  =======  =====================================
``BACKGROUND_COLOR``   (255, 255, 255)  #ffffff  background (white)
``OBSTACLE_COLOR``     (91, 117, 154)   #5b759a  obstacles, opaque grey-blue
``ROBOT_COLOR``        (245, 138, 7)    #f58a07  robot, opaque orange
``COBSTACLE_COLOR``    (208, 28, 91)    #d01c5b  C-obstacles, crimson at opacity 0.35
``PATH_COLOR``         (11, 110, 46)    #0b6e2e  path line and waypoints, dark green
``SUPERSET_COLORS``    (31, 119, 180)   #1f77b4  superset "translated" facets, blue
                       (44, 160, 44)    #2ca02c  superset "corner" facets, green
                       (240, 192, 0)    #f0c000  superset "edge" facets, yellow
``GRID_COLOR``         (200, 200, 200)  #c8c8c8  floor grid lines, light grey
=====================  ===============  =======  =====================================

Facet outlines (``edges=True``) use the same hue, darker (``EDGE_SHADE`` times the colour).
Shading by meshcat's lights scales a colour's brightness but keeps its hue, and the
translucent C-obstacle keeps its hue over the white background (light pink); an obstacle,
always inside its C-obstacle, is seen through it as violet. Tests match on hue.

Notes
-----
meshcat 0.3.2's orbit controls always orbit, and point the camera at, the world origin
(``OrbitControls.target`` is not exposed, and a transform on ``/Cameras/default`` moves the
camera without moving the point it looks at). :meth:`SceneView.frame` therefore puts the
camera at ``/Cameras/default/rotated/<object>`` (``position``, in the Y-up camera frame) and
moves the *scene*: the ``/meshcat`` root gets the translation ``−centre``. ``/Axes`` is moved
with it, so the axes still mark the data origin, and ``/Grid`` is redrawn as a floor under
the scene. Coordinates read in the meshcat UI are therefore relative to the scene's centre.

meshcat is imported lazily: ``import cspace.viz`` costs nothing until a view is made.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np

from ..errors import EmptyMeshError, InvalidArgumentError, InvalidMeshError, NonFiniteError
from .browser import _OfflineWindow, log

__all__ = [
    "SceneView",
    "BACKGROUND_COLOR",
    "OBSTACLE_COLOR",
    "ROBOT_COLOR",
    "COBSTACLE_COLOR",
    "PATH_COLOR",
    "SUPERSET_COLORS",
    "EDGE_SHADE",
    "GRID_COLOR",
    "KINDS",
]


#: Colours, sRGB 0–255 (see the module docstring).
BACKGROUND_COLOR = (255, 255, 255)


OBSTACLE_COLOR = (91, 117, 154)


ROBOT_COLOR = (245, 138, 7)


COBSTACLE_COLOR = (208, 28, 91)


PATH_COLOR = (11, 110, 46)


#: Superset facet colours by kind name (the names of ``cspace.minkowski.superset.SUPERSET_KINDS``).
SUPERSET_COLORS = {
    "translated": (31, 119, 180),
    "corner": (44, 160, 44),
    "edge": (240, 192, 0),
}


#: Cells of a decision (:meth:`SceneView.add_cells`): translucent teal.
CELLS_COLOR = (0, 150, 136)


#: Floor grid lines drawn by :meth:`SceneView.frame`: light grey, no hue.
GRID_COLOR = (200, 200, 200)


#: Facet outlines are drawn in the surface colour times this factor (same hue, darker).
EDGE_SHADE = 0.6


#: Kind names, indexed like ``Superset.kind`` (same as ``cspace.minkowski.superset.SUPERSET_KINDS``).
KINDS = ("translated", "corner", "edge")


_CAMERA_FOV = 45.0  # vertical field of view, degrees (meshcat's default is 75)


_FRONT_SIDE, _DOUBLE_SIDE = 0, 2  # three.js material sides


# --------------------------------------------------------------------------------------
# input checks


def _name(name) -> str:
    if not isinstance(name, str) or not name or "/" in name or name.strip() != name:
        raise InvalidArgumentError(
            f"name must be a non-empty string without '/' or surrounding spaces, got {name!r}"
        )
    return name


def _points(x, what: str, *, min_rows: int = 1) -> np.ndarray:
    """Coerce to (n, 3) float64 and check it is finite and has at least ``min_rows`` rows."""
    try:
        a = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise InvalidMeshError(f"{what} must be an (n, 3) array of numbers: {e}") from None
    if a.ndim != 2 or a.shape[1] != 3:
        raise InvalidMeshError(f"{what} must be (n, 3), got shape {a.shape}")
    if len(a) < min_rows:
        raise EmptyMeshError(f"{what} needs at least {min_rows} row(s), got {len(a)}")
    bad = ~np.isfinite(a).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise NonFiniteError(
            f"{what} has {int(bad.sum())} non-finite row(s); first is row {i}: {a[i]}"
        )
    return a


def _vector(x, what: str) -> np.ndarray:
    a = np.asarray(x, dtype=np.float64)
    if a.shape != (3,):
        raise InvalidMeshError(f"{what} must be a (3,) vector, got shape {a.shape}")
    if not np.isfinite(a).all():
        raise NonFiniteError(f"{what} must be finite, got {a}")
    return a


def _faces(f, n_vertices: int, what: str) -> np.ndarray:
    """Coerce to (m, 3) int64 indices into ``n_vertices`` vertices."""
    a = np.asarray(f)
    if a.ndim != 2 or a.shape[1] != 3:
        raise InvalidMeshError(f"{what} must be (m, 3) triangle indices, got shape {a.shape}")
    if len(a) == 0:
        raise EmptyMeshError(f"{what} has no triangles")
    if a.dtype.kind not in "iu":
        if a.dtype.kind != "f" or not np.isfinite(a).all() or (a != np.round(a)).any():
            raise InvalidMeshError(f"{what} must hold integer vertex indices, got dtype {a.dtype}")
    a = a.astype(np.int64)
    if a.min() < 0 or a.max() >= n_vertices:
        raise InvalidMeshError(
            f"{what} indices must lie in [0, {n_vertices - 1}], got range [{a.min()}, {a.max()}]"
        )
    return a


def _mesh(vertices, faces, what: str) -> tuple[np.ndarray, np.ndarray]:
    """Arrays, or an object with ``.vertices`` and ``.faces`` passed as ``vertices`` alone."""
    if faces is None:
        if not (hasattr(vertices, "vertices") and hasattr(vertices, "faces")):
            raise InvalidMeshError(
                f"{what}: pass vertices and faces, or one object with .vertices and .faces"
            )
        vertices, faces = vertices.vertices, vertices.faces
    v = _points(vertices, f"{what} vertices", min_rows=3)
    return v, _faces(faces, len(v), f"{what} faces")


def _rotation(R) -> np.ndarray:
    """A (3, 3) rotation matrix, or :class:`InvalidArgumentError`."""
    R = np.asarray(R, dtype=np.float64)
    if R.shape != (3, 3) or not np.isfinite(R).all() or not np.allclose(R @ R.T, np.eye(3),
                                                                         atol=1e-6):
        raise InvalidArgumentError(f"rotation must be a (3, 3) rotation matrix, got {R.tolist()}")
    return R


def _pose_matrix(t: np.ndarray, R: np.ndarray) -> np.ndarray:
    """The 4x4 transform turning by ``R`` and then moving by ``t``."""
    m = np.eye(4)
    m[:3, :3] = R
    m[:3, 3] = t
    return m


def _opacity(x) -> float:
    x = float(x)
    if not 0.0 < x <= 1.0:
        raise InvalidArgumentError(f"opacity must be in (0, 1], got {x}")
    return x


# --------------------------------------------------------------------------------------
# geometry helpers (drawing only: the float threshold below decides nothing but looks)


def _hex(rgb, shade: float = 1.0) -> int:
    r, g, b = (min(255, max(0, int(round(c * shade)))) for c in rgb)
    return (r << 16) | (g << 8) | b


def _flat(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unshared corners, so meshcat computes face normals as vertex normals (flat shading)."""
    v = vertices[faces].reshape(-1, 3)
    return v, np.arange(len(v), dtype=np.int64).reshape(-1, 3)


def _crease_edges(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(e, 2, 3) segments of the edges between non-coplanar faces, and of boundary edges.

    The diagonals of a fan-triangulated polygon facet are left out, so a polytope shows its
    polygon facets. Coplanarity here is a drawing choice (normals within 1e-9), not a decision
    about the geometry.
    """
    a, b, c = (vertices[faces[:, i]] for i in range(3))
    n = np.cross(b - a, c - a)
    length = np.linalg.norm(n, axis=1, keepdims=True)
    n = np.divide(n, length, out=np.zeros_like(n), where=length > 0)
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    owner = np.tile(np.arange(len(faces)), 3)
    key = np.sort(e, axis=1)
    order = np.lexsort((key[:, 1], key[:, 0]))
    key, owner = key[order], owner[order]
    starts = np.flatnonzero(np.r_[True, (key[1:] != key[:-1]).any(axis=1)])
    counts = np.diff(np.r_[starts, len(key)])
    keep = np.zeros(len(starts), dtype=bool)
    keep[counts != 2] = True  # boundary or non-manifold edges: always draw
    two = counts == 2
    f0, f1 = owner[starts[two]], owner[starts[two] + 1]
    keep[two] = (n[f0] * n[f1]).sum(axis=1) < 1.0 - 1e-9
    edges = key[starts[keep]]
    return vertices[edges]


def _icosphere() -> tuple[np.ndarray, np.ndarray]:
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=1, radius=1.0)
    return np.asarray(s.vertices, dtype=np.float64), np.asarray(s.faces, dtype=np.int64)


# --------------------------------------------------------------------------------------
# the view


class SceneView:
    """A meshcat scene of obstacles, robots, C-obstacles, supersets and paths.

    Parameters
    ----------
    live : bool, default False
        False: record into an offline window (no server, no port); use :meth:`save` or
        :meth:`static_html`. True: start meshcat's zmq/web server (ports 6000/7000 or the next
        free ones); its URL is logged and available as :attr:`url`; call :meth:`close` (or use
        the view as a context manager) to stop it.
    grid : bool, default True
        Show a floor grid: :meth:`frame` replaces meshcat's fixed 20-unit grid by light-grey
        lines (``GRID_COLOR``, spacing 1, 2 or 5 times a power of ten) just under the scene.
    axes : bool, default True
        Show meshcat's axes (red x, green y, blue z; 0.5 long) at the data origin.

    Notes
    -----
    Drawing a name again replaces that drawing (the framing box keeps the old extent too).

    Examples
    --------
    >>> import numpy as np, trimesh
    >>> from cspace.viz import SceneView
    >>> box = trimesh.creation.box((1.0, 1.0, 1.0))
    >>> view = SceneView()
    >>> view.add_obstacle("box", box.vertices, box.faces)
    >>> view.add_path("p", [[1.0, -1.0, 0.0], [1.0, 1.0, 0.0]])
    >>> html = view.static_html()      # self-contained, opens offline
    >>> "obstacles/box" in view.paths()
    True
    """

    def __init__(self, *, live: bool = False, grid: bool = True, axes: bool = True):
        with warnings.catch_warnings():  # meshcat 0.3.2 imports zmq.eventloop.ioloop
            warnings.filterwarnings("ignore", category=DeprecationWarning, module=r"meshcat\.")
            import meshcat  # lazy: only drawing needs it

        self.live = bool(live)
        if self.live:
            self.vis = meshcat.Visualizer()  # spawns `python -m meshcat.servers.zmqserver`
            log.info("meshcat server at %s (zmq %s)", self.vis.url(), self.vis.window.zmq_url)
        else:
            self.vis = meshcat.Visualizer(window=_OfflineWindow())
        self._lo = np.full(3, np.inf)
        self._hi = np.full(3, -np.inf)
        self._paths: list[str] = []
        self._robots: dict[str, np.ndarray] = {}  # name -> robot vertices (own frame)
        self._fit_points: list[np.ndarray] = []
        self._framed = False
        self._grid = bool(grid)
        self._axes = bool(axes)
        white = [c / 255 for c in BACKGROUND_COLOR]
        self.vis["/Background"].set_property("top_color", white)
        self.vis["/Background"].set_property("bottom_color", white)
        if not self._grid:
            self.vis["/Grid"].set_property("visible", False)
        if not self._axes:
            self.vis["/Axes"].set_property("visible", False)

    # ---- bookkeeping ------------------------------------------------------------

    @property
    def url(self) -> str | None:
        """The web URL of the live server, or None for an offline view."""
        return self.vis.url() if self.live else None

    def paths(self) -> list[str]:
        """The scene-tree paths drawn so far, relative to ``/meshcat`` (e.g. ``obstacles/box``)."""
        return list(self._paths)

    @property
    def bounds(self) -> np.ndarray | None:
        """(2, 3) float64 bounding box of everything drawn (robots over their paths), or None."""
        if not np.isfinite(self._lo).all():
            return None
        return np.stack([self._lo, self._hi])

    def _grow(self, points: np.ndarray) -> None:
        self._lo = np.minimum(self._lo, points.min(axis=0))
        self._hi = np.maximum(self._hi, points.max(axis=0))
        # Keep (a bounded sample of) the points for the camera fit in frame().
        step = max(1, len(points) // 20000)
        self._fit_points.append(np.asarray(points[::step], dtype=np.float64))

    def _scale(self) -> float:
        """A length for default sizes: the bounding-box diagonal (1 if nothing is drawn)."""
        b = self.bounds
        d = 0.0 if b is None else float(np.linalg.norm(b[1] - b[0]))
        return d if d > 0 else 1.0

    def _mesh_node(self, path: str, vertices, faces, rgb, *, opacity=1.0, side=_DOUBLE_SIDE,
                   edges=False, **material) -> None:
        import meshcat.geometry as g

        v, f = _flat(vertices, faces)
        mat = g.MeshLambertMaterial(color=_hex(rgb), opacity=opacity, side=side, **material)
        self.vis[path].set_object(g.TriangularMeshGeometry(v, f), mat)
        self._record(path)
        if edges:
            seg = _crease_edges(vertices, faces)
            if len(seg):
                self._segments(path + "/edges", seg.reshape(-1, 3), _hex(rgb, EDGE_SHADE))

    def _segments(self, path: str, pairs: np.ndarray, color: int) -> None:
        import meshcat.geometry as g

        pts = np.ascontiguousarray(pairs.T, dtype=np.float32)  # meshcat wants 3 x N positions
        line = g.LineSegments(g.PointsGeometry(pts), g.LineBasicMaterial(color=color))
        self.vis[path].set_object(line)
        self._record(path)

    def _record(self, path: str) -> None:
        if path not in self._paths:
            self._paths.append(path)

    # ---- drawing ----------------------------------------------------------------

    def add_obstacle(self, name: str, vertices, faces=None, *, edges: bool = True) -> None:
        """Draw an obstacle, opaque grey-blue (``OBSTACLE_COLOR``), at ``/obstacles/<name>``.

        Parameters
        ----------
        name : str
            Node name (no ``/``).
        vertices : (n, 3) float64, or an object with ``.vertices`` and ``.faces``
            World coordinates.
        faces : (m, 3) int64, optional
            Triangles; omit when ``vertices`` is a mesh object.
        edges : bool, default True
            Also draw the facet outlines (edges between non-coplanar triangles).

        Raises
        ------
        ValueError
            (``InvalidMeshError``, ``EmptyMeshError``, ``NonFiniteError``) on bad arrays.
        """
        v, f = _mesh(vertices, faces, "obstacle")
        self._mesh_node(f"obstacles/{_name(name)}", v, f, OBSTACLE_COLOR, edges=edges)
        self._grow(v)

    def add_robot(self, name: str, vertices, faces=None, translation=(0.0, 0.0, 0.0), *,
                  reference=(0.0, 0.0, 0.0), rotation=None) -> None:
        """Draw a robot, opaque orange (``ROBOT_COLOR``), at ``/robot/<name>``.

        The node's transform places the robot: its reference point goes to ``translation``.
        :meth:`animate_robot` moves it along a path.

        Parameters
        ----------
        name : str
            Node name (no ``/``).
        vertices : (n, 3) float64, or an object with ``.vertices`` and ``.faces``
            The robot in its own frame.
        faces : (m, 3) int64, optional
            Triangles; omit when ``vertices`` is a mesh object.
        translation : (3,) float64, default (0, 0, 0)
            Where the reference point is placed (a configuration, in C-space coordinates).
        reference : (3,) float64, default (0, 0, 0)
            The reference point in the robot's own frame: the same ``c`` as in
            ``robot.reflected(c)`` for the C-obstacle.
        rotation : (3, 3) float64, optional
            The robot turned about its reference point (a pose's rotation); default none.
        """
        v, f = _mesh(vertices, faces, "robot")
        t = _vector(translation, "translation")
        v = v - _vector(reference, "reference")
        path = f"robot/{_name(name)}"
        self._mesh_node(path, v, f, ROBOT_COLOR)
        R = np.eye(3) if rotation is None else _rotation(rotation)
        self.vis[path].set_transform(_pose_matrix(t, R))
        self._robots[name] = v
        self._grow(v @ R.T + t)

    def add_cobstacle(self, name: str, vertices, faces=None, opacity: float = 0.35, *,
                      edges: bool = True) -> None:
        """Draw a C-obstacle, translucent crimson (``COBSTACLE_COLOR``), at ``/cobstacles/<name>``.

        Only the front faces are drawn (faces counter-clockwise from outside, as cspace gives
        them), so the translucent surface does not double up.

        Parameters
        ----------
        name : str
            Node name (no ``/``).
        vertices : (n, 3) float64, or an object with ``.vertices`` and ``.faces``
            E.g. ``MinkowskiSum.vertices``.
        faces : (m, 3) int64, optional
            E.g. ``MinkowskiSum.faces``; omit when ``vertices`` is a mesh object.
        opacity : float, default 0.35
            In (0, 1].
        edges : bool, default True
            Also draw the facet outlines (polygon facets, not their triangulation).
        """
        v, f = _mesh(vertices, faces, "C-obstacle")
        self._mesh_node(
            f"cobstacles/{_name(name)}", v, f, COBSTACLE_COLOR,
            opacity=_opacity(opacity), side=_FRONT_SIDE, edges=edges, depthWrite=False,
        )
        self._grow(v)

    def add_cells(self, name: str, vertices, faces=None, opacity: float = 0.25) -> None:
        """Draw cells of a decision (:meth:`cspace.planning.decide.Decision.to_trimesh`: the
        region the robot is confined to, or the wall that proves it), translucent teal
        (``CELLS_COLOR``), at ``/cells/<name>``."""
        v, f = _mesh(vertices, faces, "cells")
        self._mesh_node(f"cells/{_name(name)}", v, f, CELLS_COLOR, opacity=_opacity(opacity),
                        side=_FRONT_SIDE, edges=False, depthWrite=False)
        self._grow(v)

    def add_superset(self, name: str, vertices, faces=None, kinds=None, *,
                     opacity: float = 1.0) -> None:
        """Draw a Minkowski-sum superset with its facets coloured by kind.

        One node per kind, ``/superset/<name>/translated``, ``.../corner`` and ``.../edge``
        (``SUPERSET_COLORS``: blue, green, yellow), so each kind can be toggled on its own.
        Both sides are drawn: triangles of negative multiplicity face inwards.

        Parameters
        ----------
        name : str
            Node name (no ``/``).
        vertices : (n, 3) float64, or a ``cspace.minkowski.superset.Superset``
            Vertices; a Superset supplies vertices, faces and kinds itself.
        faces : (m, 3) int64, optional
            Triangles, e.g. ``Superset.triangles()[0]``.
        kinds : (m,) int or str, optional
            Per triangle, an index into ``KINDS`` or a kind name, e.g.
            ``S.kind[S.triangles()[1]]``.
        opacity : float, default 1.0
        """
        is_superset = hasattr(vertices, "triangles") and hasattr(vertices, "kind")
        if faces is None and kinds is None and is_superset:
            tri, facet, _ = vertices.triangles()
            vertices, faces, kinds = vertices.vertices, tri, np.asarray(vertices.kind)[facet]
        if faces is None or kinds is None:
            raise InvalidMeshError("superset: pass vertices, faces and kinds, or one Superset")
        v = _points(vertices, "superset vertices", min_rows=3)
        f = _faces(faces, len(v), "superset faces")
        k = np.asarray(kinds)
        if k.shape != (len(f),):
            raise InvalidMeshError(
                f"superset kinds must be ({len(f)},), one per face, got shape {k.shape}"
            )
        if k.dtype.kind in "US":
            bad = ~np.isin(k, KINDS)
            if bad.any():
                raise InvalidArgumentError(f"superset kinds must be in {KINDS}, got {k[bad][0]!r}")
            idx = np.array([KINDS.index(s) for s in k.tolist()], dtype=np.int64)
        elif k.dtype.kind in "iu":
            if len(k) and (k.min() < 0 or k.max() >= len(KINDS)):
                raise InvalidArgumentError(
                    f"superset kinds must be indices in [0, {len(KINDS) - 1}], "
                    f"got {k.min()}..{k.max()}"
                )
            idx = k.astype(np.int64)
        else:
            raise InvalidMeshError(
                f"superset kinds must be integers or kind names, got dtype {k.dtype}"
            )
        op = _opacity(opacity)
        base = f"superset/{_name(name)}"
        for i, kind in enumerate(KINDS):
            sel = f[idx == i]
            if len(sel):
                self._mesh_node(f"{base}/{kind}", v, sel, SUPERSET_COLORS[kind], opacity=op)
        self._grow(v)

    def add_path(self, name: str, points, *, radius: float | None = None) -> None:
        """Draw a path of the reference point: a dark-green polyline and waypoint spheres.

        Parameters
        ----------
        name : str
            Node name (no ``/``); drawn at ``/path/<name>/line`` and ``/path/<name>/waypoints``.
        points : (k, 3) float64
            Waypoints, k >= 1 (a polyline needs k >= 2).
        radius : float, optional
            Waypoint sphere radius; default 0.8% of the scene's bounding-box diagonal
            (path included).
        """
        p = _points(points, "path points", min_rows=1)
        base = f"path/{_name(name)}"
        self._grow(p)
        if radius is None:
            radius = 0.008 * self._scale()
        elif not (np.isfinite(radius) and radius > 0):
            raise InvalidArgumentError(f"radius must be positive and finite, got {radius}")
        if len(p) >= 2:
            self._segments(f"{base}/line", np.repeat(p, 2, axis=0)[1:-1], _hex(PATH_COLOR))
        sv, sf = _icosphere()
        v = (sv[None, :, :] * radius + p[:, None, :]).reshape(-1, 3)
        f = (sf[None, :, :] + len(sv) * np.arange(len(p))[:, None, None]).reshape(-1, 3)
        self._mesh_node(f"{base}/waypoints", v, f, PATH_COLOR)

    def animate_robot(self, name: str, path, *, fps: int = 30, seconds_per_segment: float = 1.0,
                      play: bool = True, repetitions: int = 1, rotations=None) -> None:
        """Move robot ``name`` (from :meth:`add_robot`) along ``path`` with a meshcat Animation.

        Keyframes sit at the waypoints; three.js interpolates linearly between them, so each
        segment takes ``seconds_per_segment`` at constant speed. The viewer's "Animations" panel
        plays, pauses and scrubs it. A view holds one animation (meshcat's limit): a second
        call replaces the first.

        Parameters
        ----------
        name : str
            A robot already added.
        path : (k, 3) float64
            Positions of the reference point, k >= 2.
        fps : int, default 30
        seconds_per_segment : float, default 1.0
        play : bool, default True
            Start playing when the page opens.
        repetitions : int, default 1
            Times to play (the robot stays at the last waypoint afterwards).
        rotations : (k, 3, 3) float64, optional
            The robot's rotation about its reference point at each waypoint (a path that turns
            the robot); the viewer turns it on the shortest arc between keyframes, as the
            motion between poses does. Default: no turning.
        """
        from meshcat.animation import Animation

        if name not in self._robots:
            raise InvalidArgumentError(
                f"no robot named {name!r}; add it with add_robot first "
                f"(have {sorted(self._robots)})"
            )
        p = _points(path, "animation path", min_rows=2)
        if not (isinstance(fps, int | np.integer) and fps > 0):
            raise InvalidArgumentError(f"fps must be a positive integer, got {fps!r}")
        if not (np.isfinite(seconds_per_segment) and seconds_per_segment > 0):
            raise InvalidArgumentError(
                f"seconds_per_segment must be positive and finite, got {seconds_per_segment}"
            )
        Rs = (np.broadcast_to(np.eye(3), (len(p), 3, 3)) if rotations is None
              else np.stack([_rotation(R) for R in np.asarray(rotations, dtype=np.float64)]))
        if len(Rs) != len(p):
            raise InvalidArgumentError(f"{len(Rs)} rotations for {len(p)} waypoints")
        anim = Animation(default_framerate=int(fps))
        node = f"robot/{name}"
        for i, (q, R) in enumerate(zip(p, Rs)):
            with anim.at_frame(self.vis, i * seconds_per_segment * fps) as frame:
                frame[node].set_transform(_pose_matrix(q, R))
        self.vis.set_animation(anim, play=bool(play), repetitions=int(repetitions))
        robot = self._robots[name]
        self._grow((np.einsum("kij,nj->kni", Rs, robot) + p[:, None, :]).reshape(-1, 3))

    # ---- camera and output ------------------------------------------------------

    def frame(self, *, direction=(1.0, -1.5, 1.2), margin: float = 1.08,
              aspect: float = 4 / 3) -> None:
        """Frame everything drawn so far: centre it and place the camera to see all of it.

        The bounding box's centre becomes the orbit centre (see the module Notes: the
        ``/meshcat`` root is shifted by ``−centre``), and the camera backs off along
        ``direction`` until every drawn point (vertices, waypoints, the robot at each
        waypoint) projects inside the view with ``margin`` to spare, for a window of the given
        ``aspect``. The view's vertical field of view is 45°. Called by :meth:`static_html` if
        never called.

        Parameters
        ----------
        direction : (3,) float64, default (1, -1.5, 1.2)
            From the centre towards the camera, world frame (z up); must not be vertical.
        margin : float, default 1.08
            Extra room (1 = the outermost points touch the window's edges).
        aspect : float, default 4/3
            Window width over height assumed for the fit (a wider window only adds room).
        """
        import meshcat.transformations as tf

        d = _vector(direction, "direction")
        if not np.any(d[:2]):  # the look-at frame is undefined only for an exactly vertical view
            raise InvalidArgumentError(f"direction must be non-zero and not vertical, got {d}")
        for value, what in ((margin, "margin"), (aspect, "aspect")):
            if not (np.isfinite(value) and value > 0):
                raise InvalidArgumentError(f"{what} must be positive and finite, got {value}")
        b = self.bounds
        if b is None:
            b = np.array([[-0.5, -0.5, 0.0], [0.5, 0.5, 0.0]])
        centre = (b[0] + b[1]) / 2
        half = np.maximum((b[1] - b[0]) / 2, 1e-6 * max(float(np.abs(b).max()), 1.0))
        r = float(np.linalg.norm(half))
        # Camera basis: looking along -d, z up.
        back = d / np.linalg.norm(d)
        right = np.cross(-back, [0.0, 0.0, 1.0])
        right /= np.linalg.norm(right)
        up = np.cross(right, -back)
        if self._fit_points:
            cloud = np.concatenate(self._fit_points)
        else:
            signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
            cloud = centre + signs * half
        tan_v = math.tan(math.radians(_CAMERA_FOV) / 2) / margin

        def distance(c):
            pts = cloud - c
            vertical = np.abs(pts @ up) / tan_v
            horizontal = np.abs(pts @ right) / (aspect * tan_v)
            need = pts @ back + np.maximum(vertical, horizontal)
            return max(float(need.max()), 1.5 * r), pts

        # Re-centre a few times so the drawing's projection, not its box, is centred on screen.
        for _ in range(4):
            dist, pts = distance(centre)
            depth = np.maximum(dist - pts @ back, 1e-12 * r)
            u, v = (pts @ right) / depth, (pts @ up) / depth
            centre = centre + dist / 2 * ((u.max() + u.min()) * right + (v.max() + v.min()) * up)
        dist, _ = distance(centre)
        eye = back * dist
        # The camera sits in /Cameras/default/rotated, a Y-up frame: world (x, y, z) -> (x, z, -y).
        cam = self.vis["/Cameras/default/rotated/<object>"]
        cam.set_property("position", [float(eye[0]), float(eye[2]), float(-eye[1])])
        cam.set_property("fov", _CAMERA_FOV)
        cam.set_property("near", dist * 1e-3)
        cam.set_property("far", (dist + r) * 20.0)
        self.vis.set_transform(tf.translation_matrix(-centre))  # the /meshcat root
        # Grid: our own floor just under the scene (meshcat's 20-unit GridHelper does not scale
        # with the scene, and a scale in the /Grid transform renders wrongly in 0.3.2).
        if self._grid:
            self._floor(centre, half, b[0, 2] - centre[2] - 0.01 * r)
        # Axes: marking the data origin (which moved to -centre).
        self.vis["/Axes"].set_transform(tf.translation_matrix(-centre))
        self._framed = True

    def _floor(self, centre: np.ndarray, half: np.ndarray, z: float) -> None:
        """Replace meshcat's grid with light-grey lines at height z, cells a 1-2-5 step near r/5."""
        import meshcat.geometry as g

        r = float(np.linalg.norm(half))
        raw = r / 5.0
        step = 10.0 ** math.floor(math.log10(raw))
        step *= min((1.0, 2.0, 5.0, 10.0), key=lambda m: abs(math.log(m * step / raw)))
        extent = max(float(half[0]), float(half[1])) + 2.0 * r
        # Lines at multiples of step in data coordinates (x = X - centre), over [-extent, extent].
        xs, ys = (
            np.arange(math.ceil((c - extent) / step), math.floor((c + extent) / step) + 1)
            * step - c
            for c in (float(centre[0]), float(centre[1]))
        )
        lo_x, hi_x, lo_y, hi_y = xs[0], xs[-1], ys[0], ys[-1]
        seg = [[[x, lo_y, z], [x, hi_y, z]] for x in xs]
        seg += [[[lo_x, y, z], [hi_x, y, z]] for y in ys]
        pts = np.ascontiguousarray(np.asarray(seg, dtype=np.float32).reshape(-1, 3).T)
        lines = g.LineSegments(g.PointsGeometry(pts), g.LineBasicMaterial(color=_hex(GRID_COLOR)))
        self.vis["/Grid"].set_object(lines)

    def static_html(self) -> str:
        """The scene as one self-contained HTML page (viewer inlined, no network needed)."""
        if not self._framed:
            self.frame()
        return self.vis.static_html()

    def save(self, path) -> Path:
        """Write :meth:`static_html` to ``path`` (parent folders are created); returns the path."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(self.static_html(), encoding="utf-8")
        return path

    def close(self) -> None:
        """Stop the live server, if any (meshcat 0.3.2's own ``Visualizer.close`` is broken)."""
        proc = getattr(self.vis.window, "server_proc", None) if self.live else None
        if proc is not None and proc.poll() is None:
            proc.kill()
            proc.wait()

    def __enter__(self) -> "SceneView":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        mode = f"live at {self.url}" if self.live else "offline"
        return f"<SceneView {mode}: {len(self._paths)} nodes>"
