"""The public API is small, pinned, and documented."""

from __future__ import annotations

import inspect

import cspace

PUBLIC = {
    "__version__", "Grid", "ClosedMesh", "as_mesh", "ConvexPolytope", "MinkowskiSum",
    "FACET_KINDS", "convex_minkowski_sum", "Superset", "SUPERSET_KINDS", "minkowski_superset",
    "minkowski_sum", "SumPolyhedron", "model_scene", "SceneModel",
    "Body", "Scene", "load_scene", "save_scene", "SceneError", "CSpaceObstacle", "CSpace", "CspaceError", "InvalidMeshError", "EmptyMeshError",
    "NonFiniteError", "OpenMeshError", "NonManifoldError", "DegenerateError",
    "DuplicateFaceError", "NotConvexError", "GridRangeError", "ExactnessError", "BuildError",
    "OutputError", "MeshFileError", "MeshFileNotFoundError", "OperandTypeError",
    "InvalidQueryError", "InvalidArgumentError", "ArgumentTypeError", "SelfIntersectionError",
    "MissingDependencyError", "MemoryBudgetError", "UnsupportedError",
}


def test_all_is_pinned():
    assert set(cspace.__all__) == PUBLIC
    for name in cspace.__all__:
        assert hasattr(cspace, name), name


def test_public_callables_are_documented():
    for name in cspace.__all__:
        obj = getattr(cspace, name)
        if inspect.isclass(obj) or inspect.isfunction(obj):
            assert inspect.getdoc(obj), f"{name} has no docstring"
    for fn in (cspace.convex_minkowski_sum, cspace.ConvexPolytope.from_points, cspace.Grid.snap,
               cspace.minkowski_superset, cspace.minkowski_sum):
        doc = inspect.getdoc(fn)
        assert "Parameters" in doc and "Returns" in doc, fn.__qualname__


def test_errors_subclass_the_builtin_they_stand_for():
    for name in ("InvalidMeshError", "EmptyMeshError", "NonFiniteError", "OpenMeshError",
                 "NonManifoldError", "DegenerateError", "DuplicateFaceError", "NotConvexError",
                 "GridRangeError", "SceneError"):
        err = getattr(cspace, name)
        assert issubclass(err, cspace.CspaceError) and issubclass(err, ValueError), name


def test_reprs_fit_on_a_few_lines():
    """What a user prints in a session (a scene, its model and bodies, the C-space, a sum, a
    hull) says what it is in a few short lines, never the arrays it holds."""
    import numpy as np
    import trimesh

    box = trimesh.creation.box((1.0, 1.0, 1.0))
    scene = cspace.Scene.from_meshes(trimesh.creation.box((0.1, 0.1, 0.1)), [box],
                                     start=(-1.0, -1.0, -1.0), goal=(1.0, 1.0, 1.0))
    model = cspace.model_scene(scene)
    hull = cspace.ConvexPolytope.from_points(np.asarray(box.vertices))
    total = cspace.minkowski_sum((box.vertices, box.faces), 0.1 * box.vertices)
    for obj in (scene, model, *model.bodies, model.cspace(), hull, total):
        text = repr(obj)
        assert text.count("\n") <= 3 and len(text) <= 400, text[:200]
        assert "array(" not in text, text[:200]
