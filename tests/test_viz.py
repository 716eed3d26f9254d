"""cspace.viz: scene tree, offline HTML, input checks, and real headless-Chromium renders.

The render tests draw scenes with SceneView, save the offline HTML, screenshot it with the
real Chromium (no mocks) and look for each drawing's colour in the pixels, by hue: lighting
scales brightness but keeps hue, and the translucent C-obstacle keeps its hue over white.
An empty scene rendered the same way is the negative control: it must show none of them.
Both use ``axes=False``: meshcat's axes are red/green/blue lines whose hues overlap ours.
"""

from __future__ import annotations

import base64
import dataclasses
import importlib.util
import colorsys
import os
import re
import shutil
import subprocess
import time
from concurrent.futures import ThreadPoolExecutor

from pathlib import Path

import numpy as np
import pytest
import trimesh
import umsgpack

import cspace
from cspace import viz
from cspace.viz import scene_view
from cspace.minkowski.superset import SUPERSET_KINDS, minkowski_superset

SIZE = (1024, 768)
# The example's own scene (examples/view_convex.py): the test draws exactly what users see.
_spec = importlib.util.spec_from_file_location(
    "view_convex", Path(__file__).resolve().parents[1] / "examples" / "view_convex.py")
_example = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_example)
REFERENCE, PATH, outside_convex = _example.REFERENCE, _example.PATH, _example.outside_convex


# --------------------------------------------------------------------------------------
# scenes


def demo_parts():
    """Rotated box O, ellipsoid-like robot R, CO = O ⊕ (−(R − c)) (the example's scene)."""
    return _example.demo_scene()[:3]


def demo_view() -> viz.SceneView:
    O, R, CO = demo_parts()
    dense = np.vstack([np.linspace(PATH[i], PATH[i + 1], 100) for i in range(len(PATH) - 1)])
    assert outside_convex(CO.vertices, CO.faces, dense).all(), "test path must stay outside CO"
    view = viz.SceneView(axes=False)
    view.add_obstacle("box", O.vertices, O.faces)
    view.add_cobstacle("box", CO.vertices, CO.faces)
    view.add_path("free", PATH)
    view.add_robot("robot", R.vertices, R.faces, PATH[0], reference=REFERENCE)
    view.animate_robot("robot", PATH, play=False)  # robot stays at PATH[0]: deterministic pixels
    view.frame()
    return view


def superset():
    torus = trimesh.creation.torus(
        major_radius=1.0, minor_radius=0.35, major_sections=8, minor_sections=6
    )
    box = trimesh.creation.box((0.5, 0.4, 0.3)).vertices
    return minkowski_superset(torus, box)


def superset_view() -> viz.SceneView:
    S = superset()
    faces, facet, _ = S.triangles()
    view = viz.SceneView(axes=False)
    view.add_superset("torus_box", S.vertices, faces, S.kind[facet])
    view.frame()
    return view


SCENES = Path(__file__).resolve().parents[1] / "scenes"


def shipped_scene_view() -> viz.SceneView:
    """The shipped window scene with its exact C-obstacles and a path through the window."""
    from cspace.scene.files import load_scene

    scene = load_scene(SCENES / "window.toml")
    path = np.array([scene.start, (-0.8, 0.0, 1.5), (0.8, 0.0, 1.5), scene.goal])
    view = viz.SceneView(axes=False)
    report = viz.draw_scene(view, scene, path=path, animate=False)
    assert all(v.startswith("C-obstacle") for v in report.values()), report
    return view


def scene_commands(html: str) -> list[dict]:
    """The meshcat commands embedded in a static HTML page, decoded."""
    blobs = re.findall(r'fetch\("data:application/octet-binary;base64,([A-Za-z0-9+/=]+)"\)', html)
    return [umsgpack.unpackb(base64.b64decode(b)) for b in blobs]


# --------------------------------------------------------------------------------------
# the browser


@pytest.fixture(scope="session")
def chromium() -> str:
    """Path of a Chromium executable; installs Debian's package if absent and root; else skips."""
    found = viz.find_chromium()
    if found:
        return found
    where = os.environ.get("CSPACE_CHROMIUM")
    missing = f"CSPACE_CHROMIUM={where} is not an executable" if where else "not on PATH"
    if not (hasattr(os, "geteuid") and os.geteuid() == 0 and shutil.which("apt-get")):
        pytest.skip(f"Chromium could not be installed: {missing}, and not root with apt-get")
    reason = f"apt-get install -y chromium succeeded but Chromium is still {missing}"
    deadline = time.monotonic() + 300
    env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
    try:
        for cmd in (["apt-get", "update"], ["apt-get", "install", "-y", "chromium"]):
            done = subprocess.run(cmd, env=env, capture_output=True, text=True,
                                  timeout=max(1.0, deadline - time.monotonic()))
            if done.returncode != 0:
                tail = " | ".join(done.stderr.strip().splitlines()[-3:])
                reason = f"`{' '.join(cmd)}` exited {done.returncode}: {tail}"
                break
    except subprocess.TimeoutExpired as e:
        reason = f"`{' '.join(e.cmd)}` did not finish within the 300 s budget"
    found = viz.find_chromium()
    if found:
        return found
    pytest.skip(f"Chromium could not be installed: {reason}")


def render(view: viz.SceneView, tmp_path, name: str) -> np.ndarray:
    """Save the view's HTML, screenshot it with headless Chromium: (H, W, 3) uint8."""
    from PIL import Image  # a dependency of meshcat

    html = view.save(tmp_path / f"{name}.html")
    png = viz.screenshot(html, tmp_path / f"{name}.png", size=SIZE, timeout=30, retries=2)
    with Image.open(png) as im:
        return np.asarray(im.convert("RGB"), dtype=np.uint8)


@pytest.fixture(scope="module")
def shots(chromium, tmp_path_factory) -> dict[str, np.ndarray]:
    """The demo scene, the superset scene and the empty control, rendered once (in parallel)."""
    tmp = tmp_path_factory.mktemp("viz_shots")
    views = {"demo": demo_view(), "superset": superset_view(), "scene": shipped_scene_view(),
             "empty": viz.SceneView(axes=False)}
    with ThreadPoolExecutor(max_workers=len(views)) as pool:
        futures = {k: pool.submit(render, v, tmp, k) for k, v in views.items()}
        return {k: f.result() for k, f in futures.items()}


def hue_of(rgb) -> float:
    return 360.0 * colorsys.rgb_to_hsv(*(c / 255 for c in rgb))[0]


def hue_mask(img: np.ndarray, lo: float, hi: float, *, min_sat=0.15, min_val=0.1) -> np.ndarray:
    """Pixels with hue in [lo, hi) degrees (wrapping past 360), with enough saturation and value."""
    x = img.astype(np.float64) / 255.0
    mx, mn = x.max(axis=2), x.min(axis=2)
    chroma = mx - mn
    sat = np.divide(chroma, mx, out=np.zeros_like(mx), where=mx > 0)
    r, g, b = x[..., 0], x[..., 1], x[..., 2]
    c = np.where(chroma > 0, chroma, 1.0)
    h = 60.0 * np.where(
        mx == r, ((g - b) / c) % 6.0, np.where(mx == g, (b - r) / c + 2.0, (r - g) / c + 4.0)
    )
    lo, hi = lo % 360.0, hi % 360.0
    in_hue = (h >= lo) & (h < hi) if lo < hi else (h >= lo) | (h < hi)
    return in_hue & (sat >= min_sat) & (mx >= min_val) & (chroma > 0)


def near(rgb, tol: float = 12.0) -> tuple[float, float]:
    h = hue_of(rgb)
    return h - tol, h + tol


N = 300  # pixels a drawing must cover (of 1024 x 768); the control must have none

CO_HUE = near(scene_view.COBSTACLE_COLOR, 15.0)
# The obstacle lies inside its C-obstacle, so it is only ever seen through it: grey-blue under
# translucent crimson mixes to a violet between the two hues (215 deg and 339 deg).
THROUGH_HUE = (hue_of(scene_view.OBSTACLE_COLOR) + 12.0, hue_of(scene_view.COBSTACLE_COLOR) - 15.0)
DEMO_COLOURS = {
    "C-obstacle (crimson, over white)": CO_HUE,
    "obstacle (seen through the C-obstacle)": THROUGH_HUE,
    "path (dark green)": near(scene_view.PATH_COLOR),
    "robot (orange)": near(scene_view.ROBOT_COLOR),
}
SUPERSET_COLOURS = {kind: near(scene_view.SUPERSET_COLORS[kind]) for kind in SUPERSET_KINDS}


# --------------------------------------------------------------------------------------
# rendered with a real browser


def test_hue_windows_are_disjoint():
    windows = sorted(DEMO_COLOURS.values())
    assert all(a[1] <= b[0] for a, b in zip(windows, windows[1:])), windows
    windows = sorted(SUPERSET_COLOURS.values())
    assert all(a[1] <= b[0] for a, b in zip(windows, windows[1:])), windows


def test_screenshot_has_the_window_size(shots):
    for name, img in shots.items():
        assert img.shape == (SIZE[1], SIZE[0], 3), name


def test_demo_scene_shows_obstacle_cobstacle_path_and_robot(shots):
    img, empty = shots["demo"], shots["empty"]
    for what, (lo, hi) in DEMO_COLOURS.items():
        seen = int(hue_mask(img, lo, hi).sum())
        assert seen >= N, f"{what}: {seen} pixels with hue in [{lo:.0f}, {hi:.0f}) deg, want >= {N}"
        assert int(hue_mask(empty, lo, hi).sum()) == 0, f"{what}: shows in the empty control"


def test_shipped_scene_shows_obstacles_cobstacles_path_and_robots(shots):
    img, empty = shots["scene"], shots["empty"]
    # The path runs through the window, mostly behind the translucent C-obstacles: only its
    # waypoints outside them show pure dark green, hence the lower bar for it.
    need = {**{k: N for k in DEMO_COLOURS}, "path (dark green)": 150}
    for what, (lo, hi) in DEMO_COLOURS.items():
        assert hue_mask(img, lo, hi).sum() >= need[what], what
        assert hue_mask(empty, lo, hi).sum() == 0, what


def test_cobstacle_is_translucent_over_white(shots):
    """Most C-obstacle pixels are light (blended with the white background), not the full colour."""
    img = shots["demo"]
    mask = hue_mask(img, *CO_HUE)
    light = mask & (img.min(axis=2) > 120)  # crimson at 0.35 over white: about (238, 175, 198)
    assert int(light.sum()) >= N


def test_superset_kinds_each_show_their_colour(shots):
    img, empty = shots["superset"], shots["empty"]
    for kind, (lo, hi) in SUPERSET_COLOURS.items():
        seen = int(hue_mask(img, lo, hi).sum())
        assert seen >= N, f"superset {kind}: {seen} pixels with hue in [{lo:.0f}, {hi:.0f}) deg"
        assert int(hue_mask(empty, lo, hi).sum()) == 0, f"{kind}: shows in the empty control"


def test_empty_control_is_white_with_a_grey_floor(shots):
    img = shots["empty"].astype(int)
    assert (img.max(axis=2) - img.min(axis=2) <= 8).mean() > 0.99  # no colour anywhere ...
    assert (img.min(axis=2) >= 250).mean() > 0.5  # ... mostly white background


# --------------------------------------------------------------------------------------
# no browser


def test_offline_view_starts_nothing():
    view = viz.SceneView()
    assert view.url is None
    assert not hasattr(view.vis.window, "server_proc")
    view.close()  # no-op


def test_tree_names_are_in_the_html():
    view = demo_view()
    S = superset()
    view.add_superset("s", S)  # a Superset object directly
    paths = {c["path"] for c in scene_commands(view.static_html())}
    for p in [
        "/meshcat/obstacles/box", "/meshcat/obstacles/box/edges", "/meshcat/robot/robot",
        "/meshcat/cobstacles/box", "/meshcat/cobstacles/box/edges",
        "/meshcat/path/free/line", "/meshcat/path/free/waypoints",
        "/meshcat/superset/s/translated", "/meshcat/superset/s/corner", "/meshcat/superset/s/edge",
        "/Background", "/Cameras/default/rotated/<object>", "/meshcat", "/Grid",
    ]:
        assert p in paths, p
    drawn = {p.removeprefix("/meshcat/") for p in paths if p.startswith("/meshcat/")}
    assert set(view.paths()) >= drawn


def test_superset_nodes_split_faces_by_kind():
    S = superset()
    faces, facet, _ = S.triangles()
    kinds = S.kind[facet]
    view = viz.SceneView()
    view.add_superset("s", S.vertices, faces, [SUPERSET_KINDS[k] for k in kinds])  # names work too
    cmds = scene_commands(view.static_html())
    objects = {c["path"]: c["object"] for c in cmds if c["type"] == "set_object"}
    for i, kind in enumerate(SUPERSET_KINDS):
        obj = objects[f"/meshcat/superset/s/{kind}"]
        (geometry,) = obj["geometries"]
        (material,) = obj["materials"]
        n_corners = len(np.frombuffer(geometry["data"]["index"]["array"].data, dtype=np.uint32))
        assert n_corners == 3 * int((kinds == i).sum())
        assert material["color"] == scene_view._hex(scene_view.SUPERSET_COLORS[kind])


def test_animation_keyframes_follow_the_path():
    view = demo_view()
    (anim,) = [c for c in scene_commands(view.static_html()) if c["type"] == "set_animation"]
    (clip,) = anim["animations"]
    assert clip["path"] == "/meshcat/robot/robot"
    (position,) = [t for t in clip["clip"]["tracks"] if t["name"] == ".position"]
    got = np.array([k["value"] for k in position["keys"]])
    np.testing.assert_allclose(got, PATH)
    times = np.array([k["time"] for k in position["keys"]]) / clip["clip"]["fps"]
    np.testing.assert_allclose(times, np.arange(len(PATH)) * 1.0)


def test_frame_puts_everything_in_view():
    """From the recorded camera and root shift, every drawn point is inside the view cone."""
    view = demo_view()
    cmds = scene_commands(view.static_html())
    cam = {c["property"]: c["value"] for c in cmds
           if c["type"] == "set_property" and c["path"] == "/Cameras/default/rotated/<object>"}
    (root,) = [c for c in cmds if c["type"] == "set_transform" and c["path"] == "/meshcat"]
    shift = np.array(root["matrix"]).reshape(4, 4).T[:3, 3]
    x, y, z = cam["position"]
    eye = np.array([x, -z, y])  # the Y-up camera frame back to world
    forward = -eye / np.linalg.norm(eye)  # meshcat looks at the world origin
    right = np.cross(forward, [0, 0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    pts = np.concatenate(view._fit_points) + shift - eye
    depth = pts @ forward
    assert (depth > 0).all()
    tan_v = np.tan(np.radians(cam["fov"]) / 2)
    assert (np.abs(pts @ up) / depth <= tan_v).all()
    assert (np.abs(pts @ right) / depth <= tan_v * SIZE[0] / SIZE[1]).all()
    # ... and the drawing is not tiny: it spans at least half the view's height.
    v = (pts @ up) / depth
    assert v.max() - v.min() >= tan_v


def test_save_writes_offline_html(tmp_path):
    path = demo_view().save(tmp_path / "sub" / "scene.html")
    assert path == tmp_path / "sub" / "scene.html" and path.is_file()
    html = path.read_text(encoding="utf-8")
    assert html.startswith("<!DOCTYPE html>") and "MeshCat.Viewer" in html
    assert not re.search(r"<(script|link|img|iframe)\b[^>]*\b(src|href)\s*=", html, re.I)
    urls = set(re.findall(r"https?://[^\s\"'<>)]+", html))
    assert urls <= {"http://www.w3.org/1999/xhtml"}, urls  # an XML namespace, never fetched


def test_static_html_frames_automatically():
    view = viz.SceneView()
    box = trimesh.creation.box((1.0, 2.0, 3.0))
    view.add_obstacle("b", box)  # a mesh object alone works too
    paths = {c["path"] for c in scene_commands(view.static_html())}
    assert "/Cameras/default/rotated/<object>" in paths and "/meshcat" in paths
    np.testing.assert_allclose(view.bounds, [[-0.5, -1.0, -1.5], [0.5, 1.0, 1.5]])


def test_live_view_starts_and_stops_a_server():
    view = viz.SceneView(live=True)
    try:
        assert view.url.startswith("http://")
        proc = view.vis.window.server_proc
        box = trimesh.creation.box((1.0, 1.0, 1.0))
        view.add_obstacle("box", box.vertices, box.faces)
        assert "MeshCat.Viewer" in view.static_html()
    finally:
        view.close()
    assert proc.poll() is not None


def test_screenshot_without_chromium_raises(tmp_path, monkeypatch):
    html = viz.SceneView().save(tmp_path / "a.html")
    monkeypatch.setenv("CSPACE_CHROMIUM", str(tmp_path / "no-such-chromium"))
    with pytest.raises(RuntimeError, match="Chromium not found"):
        viz.screenshot(html, tmp_path / "a.png")


BOX = trimesh.creation.box((1.0, 1.0, 1.0))
V, F = np.asarray(BOX.vertices), np.asarray(BOX.faces)
ROW3 = np.arange(len(V))[:, None] == 3


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda v: v.add_obstacle("o", V[:, :2], F), r"\(n, 3\)"),
        (lambda v: v.add_obstacle("o", np.where(ROW3, np.nan, V), F), "non-finite.*row 3"),
        (lambda v: v.add_obstacle("o", V, F + 1), r"indices must lie in \[0, 7\]"),
        (lambda v: v.add_obstacle("o", V, F + 0.5), "integer vertex indices"),
        (lambda v: v.add_obstacle("o", V, np.zeros((0, 3), int)), "no triangles"),
        (lambda v: v.add_obstacle("o", V), "pass vertices and faces"),
        (lambda v: v.add_obstacle("a/b", V, F), "without '/'"),
        (lambda v: v.add_obstacle("", V, F), "non-empty"),
        (lambda v: v.add_cobstacle("c", V, F, opacity=0.0), r"opacity must be in \(0, 1\]"),
        (lambda v: v.add_robot("r", V, F, translation=(0, 0)), r"translation must be a \(3,\)"),
        (lambda v: v.add_robot("r", V, F, translation=(0, np.inf, 0)), "must be finite"),
        (lambda v: v.add_superset("s", V, F, np.zeros(len(F) - 1, int)), "one per face"),
        (lambda v: v.add_superset("s", V, F, np.full(len(F), 3)), r"indices in \[0, 2\]"),
        (lambda v: v.add_superset("s", V, F, ["vertex"] * len(F)), "kinds must be in"),
        (lambda v: v.add_superset("s", V, F), "or one Superset"),
        (lambda v: v.add_path("p", np.zeros((3, 2))), r"\(n, 3\)"),
        (lambda v: v.add_path("p", np.zeros((0, 3))), "at least 1 row"),
        (lambda v: v.add_path("p", np.zeros((2, 3)), radius=-1.0), "radius must be positive"),
        (lambda v: v.animate_robot("ghost", np.zeros((2, 3))), "no robot named 'ghost'"),
        (lambda v: (v.add_robot("r", V, F), v.animate_robot("r", np.zeros((1, 3)))), "at least 2"),
        (lambda v: (v.add_robot("r", V, F), v.animate_robot("r", np.zeros((2, 3)), fps=0)), "fps"),
        (lambda v: v.frame(direction=(0, 0, 1)), "not vertical"),
        (lambda v: v.frame(margin=0), "margin must be positive"),
    ],
)
def test_bad_input_raises_value_error(call, message):
    with pytest.raises(ValueError, match=message):
        call(viz.SceneView())


def test_colours_are_documented_in_the_module_docstring():
    doc = scene_view.__doc__
    for rgb in [scene_view.OBSTACLE_COLOR, scene_view.ROBOT_COLOR, scene_view.COBSTACLE_COLOR, scene_view.PATH_COLOR,
                *scene_view.SUPERSET_COLORS.values()]:
        assert str(tuple(rgb)) in doc and f"#{scene_view._hex(rgb):06x}" in doc, rgb
    assert scene_view.KINDS == SUPERSET_KINDS == cspace.FACET_KINDS


def test_an_exact_proof_is_drawn_as_its_separating_surface():
    """With the exact free space's proof, draw_scene draws the closed surface around the
    start's component (its triangles, in the cells colour) and no cells."""
    from cspace.planning.decide import decide
    from cspace.scene.files import load_scene
    from cspace.scene.model import model_scene

    scene = load_scene(SCENES / "cage.toml")
    d = decide(model_scene(scene).cspace(), scene.start, scene.goal, bounds=scene.bounds)
    assert d.answer == "no path" and d.separation is not None
    view = viz.SceneView(axes=False)
    viz.draw_scene(view, scene, decision=d, animate=False)
    objects = {c["path"]: c["object"] for c in scene_commands(view.static_html())
               if c["type"] == "set_object"}
    assert "/meshcat/cells/confined" not in objects and "/meshcat/cells/wall" not in objects
    (geometry,) = objects["/meshcat/cells/separator"]["geometries"]
    index = np.frombuffer(geometry["data"]["index"]["array"].data, dtype=np.uint32)
    assert len(index) == 3 * len(d.separation.faces) > 0


def test_a_proof_that_no_path_exists_is_drawn_as_its_cells():
    """draw_scene(decision=...) draws the cells the robot is confined to and the wall around
    them, in the cells colour, one box (12 triangles) per cell."""
    from cspace.planning.decide import decide
    from cspace.scene.files import load_scene
    from cspace.scene.model import model_scene

    scene = load_scene(SCENES / "cage.toml")
    d = decide(model_scene(scene).cspace(), scene.start, scene.goal, bounds=scene.bounds,
               exact=False)  # the cells' proof (the exact one: the test below)
    assert d.answer == "no path"
    view = viz.SceneView(axes=False)
    report = viz.draw_scene(view, scene, decision=d, animate=False)
    assert report["decision"].startswith("no path")
    objects = {c["path"]: c["object"] for c in scene_commands(view.static_html())
               if c["type"] == "set_object"}
    for name, cells in (("confined", d.start_component), ("wall", d.wall)):
        obj = objects[f"/meshcat/cells/{name}"]
        (geometry,) = obj["geometries"]
        (material,) = obj["materials"]
        index = np.frombuffer(geometry["data"]["index"]["array"].data, dtype=np.uint32)
        assert len(index) == 3 * 12 * int(cells.sum()) > 0
        assert material["color"] == scene_view._hex(scene_view.CELLS_COLOR)


def test_a_turning_path_animates_the_robot_turning():
    """Keyframes carry each waypoint's rotation (meshcat's quaternion track, x y z w), and the
    robot at the goal is drawn at the goal's orientation."""
    from scipy.spatial.transform import Rotation

    scene = cspace.load_scene(Path(__file__).resolve().parents[1] / "scenes" / "piano.toml")
    G = Rotation.from_euler("z", 90, degrees=True).as_matrix()
    scene = dataclasses.replace(scene, goal_rotation=G)
    path = np.array([scene.start, [0.0, 0.0, 0.5], scene.goal])
    rots = Rotation.from_euler("z", [[0], [45], [90]], degrees=True)
    view = viz.SceneView()
    viz.draw_scene(view, scene, path=path, rotations=rots.as_matrix(), cobstacles=False)
    cmds = scene_commands(view.static_html())
    (anim,) = [c for c in cmds if c["type"] == "set_animation"]
    (clip,) = anim["animations"]
    (quat,) = [t for t in clip["clip"]["tracks"] if t["name"] == ".quaternion"]
    got = np.array([k["value"] for k in quat["keys"]])
    np.testing.assert_allclose(np.abs(got @ rots.as_quat().T).diagonal(), 1.0, atol=1e-9)
    (goal,) = [c for c in cmds if c["type"] == "set_transform" and c["path"] == "/meshcat/robot/goal"]
    M = np.array(goal["matrix"]).reshape(4, 4).T
    np.testing.assert_allclose(M[:3, :3], G, atol=1e-12)
    np.testing.assert_allclose(M[:3, 3], scene.goal)
