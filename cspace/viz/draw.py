"""Drawing a whole scene in a :class:`~cspace.viz.scene_view.SceneView`: :func:`draw_scene`
(obstacles, C-obstacles as the scene model builds them, the robot at start and goal, a path,
a decision's cells)."""

from __future__ import annotations

import numpy as np

from .scene_view import SceneView

__all__ = ["draw_scene"]


def draw_scene(view: SceneView, scene, *, path=None, cobstacles: bool = True,
               superset: bool = False, animate: bool = True, cache=None,
               decision=None, free_space=None, rotations=None, progress=None,
               memory=None) -> dict[str, str]:
    """Draw a :class:`cspace.scene.scene.Scene`: obstacles, the robot at start and goal, C-obstacles, a path.

    The scene is modelled and built as :func:`cspace.scene.model.model_scene` does (exact robot
    parts; every body's C-obstacles, whatever the construction: CVMS, NCC-CVMS, pieces).
    ``superset=True`` draws the untrimmed superset of a body whose build failed.

    Parameters
    ----------
    view : SceneView
    scene : Scene
    path : (k, 3) float64, optional
        Reference-point positions of a path; drawn as a polyline, and the robot is animated
        along it when ``animate``.
    rotations : (k, 3, 3) float64, optional
        With ``path``: the robot's rotation at each waypoint, relative to the scene's start
        orientation (a path that turns the robot: the animation turns it too). The robot at
        the goal is drawn at the goal's orientation either way.
    cobstacles, superset : bool
        Whether to draw the C-obstacles / the superset of a body whose build failed.
    cache : COCache, path, True, or None
        The disk cache the C-obstacles are built through (:func:`cspace.scene.model.model_scene`).
    progress : callable, optional
        ``progress(fraction, stage)`` during the build (as ``model_scene``'s).
    memory : int or str, optional
        The build's memory budget (as ``model_scene``'s).
    decision : Decision, optional
        A :func:`cspace.planning.decide.decide` answer: with ``'no path'``, the closed
        surface around the start's component when the exact free space proved it
        (``/cells/separator``); else the cells the robot is confined to
        (``/cells/confined``) and the wall of cells inside the C-obstacles around them
        (``/cells/wall``).
    free_space : FreeSpace, optional
        A :func:`cspace.planning.free_space.free_space`: the boundary of each of its
        components (``/cells/free 0``, ...; the first bounded by the bounds' box too).

    Returns
    -------
    report : dict[str, str]
        For each obstacle body, what was drawn for it.
    """
    import warnings

    from ..errors import InvalidMeshError
    from ..scene.model import model_scene
    from ..minkowski.superset import minkowski_superset

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the scene already warned when it was loaded
        m = model_scene(scene, cache=cache, progress=progress, memory=memory)
    report: dict[str, str] = {}
    for body in m.bodies:
        view.add_obstacle(body.name, body.vertices, body.faces)
        report[body.name] = "obstacle"
        cos = body.cos
        if cos and cobstacles:
            for k, co in enumerate(cos):
                view.add_cobstacle(body.name if len(cos) == 1 else f"{body.name} {k}",
                                   co.vertices, co.faces)
            how = ", ".join(sorted({p.construction for p in body.pairs}))
            report[body.name] = (f"C-obstacle ({how}, {sum(co.n_facets for co in cos)} facets"
                                 + (f" in {len(cos)} parts" if len(cos) > 1 else "") + ")")
        elif body.error and superset and m.robot is not None:
            try:
                S = minkowski_superset((body.vertices, body.faces),
                                       m.robot.reflected(scene.reference_point))
            except InvalidMeshError as e:
                report[body.name] = f"obstacle only: {e}"
                continue
            view.add_superset(body.name, S)
            report[body.name] = (f"superset ({S.n_facets} facets): its C-obstacle failed to "
                                 f"build: {body.error}")
        elif body.error:
            report[body.name] = f"obstacle only: its C-obstacle failed to build: {body.error}"
        elif not cos:
            report[body.name] = f"obstacle only ({body.kind}: {body.reason.split(': ', 1)[-1]})"
    if decision is not None and decision.answer == "no path" and decision.separation is not None:
        # the exact proof: the closed surface around the start's component
        view.add_cells("separator", decision.to_trimesh("start"), opacity=0.35)
    elif decision is not None and decision.answer == "no path":
        view.add_cells("confined", decision.to_trimesh("start"), opacity=0.2)
        view.add_cells("wall", decision.to_trimesh("blocked"), opacity=0.45)
        report["decision"] = f"no path: {decision.reason}"
    if free_space is not None:
        for k in range(free_space.n_components):
            view.add_cells(f"free {k}", free_space.component_mesh(k), opacity=0.2)
        report["free space"] = repr(free_space)
    view.add_robot("start", scene.robot.vertices, scene.robot.faces, scene.start,
                   reference=scene.reference_point)
    view.add_robot("goal", scene.robot.vertices, scene.robot.faces, scene.goal,
                   reference=scene.reference_point,
                   rotation=np.asarray(scene.goal_rotation) @ np.asarray(scene.start_rotation).T)
    if path is not None:
        # Waypoints a little larger than the default: a scene's path is its subject.
        view.add_path("path", path, radius=0.015 * float(np.ptp(scene.bounds, axis=0).max()))
        if animate:
            view.animate_robot("start", path, rotations=rotations)
    # Look across the start -> goal direction (from above) so a passage is seen edge-on.
    travel = np.asarray(scene.goal, float) - np.asarray(scene.start, float)
    side = np.cross(travel, [0.0, 0.0, 1.0])
    if np.linalg.norm(side) > 0:
        view.frame(direction=side / np.linalg.norm(side) + [0.0, 0.0, 0.6])
    return report
