"""Deliberately broken builds for the mutation sweep (``benchmarks/bench_mutations.py``).

Each mutant is one small wrong change to the exact kernel, the C-obstacle queries or the scene
model, applied by monkeypatching at the start of a pytest session whose environment names it
(``CSPACE_MUTANT=<name>``; ``tests/conftest.py`` applies it). A test suite worth trusting
fails on each of them; the sweep records which tests kill which mutant, and which survive.

Only Python-level functions can be patched here: the compiled kernels are tested identical to
their references by their own tests, so a mutant of a reference is killed there.
"""

from __future__ import annotations

import numpy as np


def _flip_orient3d():
    from cspace.geometry import exact

    f = exact.orient3d
    exact.orient3d = lambda *a, **k: -f(*a, **k)


def _flip_plane_sign():
    from cspace.cobstacle import convex, pairs

    f = convex.exact_plane_sign
    convex.exact_plane_sign = pairs.exact_plane_sign = lambda *a, **k: -f(*a, **k)


def _drop_a_cobstacle():
    """The union of a scene's C-obstacles forgets its first member."""
    from cspace.cobstacle import union

    near = union._UnionOf._near

    def _near(self, lo, hi):
        for k, rows in near(self, lo, hi):
            if k != 0:
                yield k, rows

    union._UnionOf._near = _near


def _no_margin():
    """No outward rounding: the exact C-obstacles of the snapped input (two-sided errors)."""
    from cspace.scene import model

    f = model._margin
    model._margin = lambda scene, grid, conservative: f(scene, grid, conservative
                                                        ).without_growth()


def _shift_grid_origin():
    """Snapping off by one step in x for every point (the scene moves under the grid)."""
    from cspace.geometry.exact import Grid

    snap = Grid.snap

    def shifted(self, x):
        k = snap(self, x)
        k = np.array(k, copy=True)
        k[..., 0] += 1
        return k

    Grid.snap = shifted


def _no_containment():
    """No containment terms (a robot wholly inside a closed body, or holding a component)."""
    from cspace.scene import build

    build._containment_cos = lambda *a, **k: []


def _one_component():
    """Containment terms for the first connected component only."""
    from cspace.cobstacle import pairs
    from cspace.scene import build

    f = pairs.component_points
    build.component_points = pairs.component_points = lambda *a, **k: f(*a, **k)[:1]


def _closed_bodies_are_bare_surfaces():
    """A closed non-convex body modelled as a bare surface: its inside counts as free."""
    from cspace.scene import classify

    f = classify._closed_kind

    def kind(name, P, F, grid):
        k, why, operand = f(name, P, F, grid)
        return ("surface", why, None) if k == "solid" else (k, why, operand)

    classify._closed_kind = kind


def _hull_every_body():
    """Every closed body is taken for convex: its hull stands for it."""
    from cspace.mesh import convex
    from cspace.mesh.convex import ConvexPolytope

    def hulled(mesh, bend=None):
        return ConvexPolytope.from_ints(mesh.ints, grid=mesh.grid, name=mesh.name), "convex"

    convex.convex_within_bound = hulled
    from cspace.scene import classify

    classify.convex_within_bound = hulled


def _lose_thin_features():
    """What snapping takes (segments and points thinner than the step, a lost inside) is
    dropped, as before issue #51."""
    from cspace.scene import model

    model._snapped_body = lambda *a, **k: None
    model.snapping_losses = lambda n, welded, F: (np.zeros((0, 3), np.int64), None)


def _segment_filter_says_free():
    """The convex engine's segment filter calls every undecided motion free."""
    from cspace.cobstacle import convex

    f = convex.segment_filter

    def filt(v0, v1, e0, e1):
        free, sure, t, terr, enter = f(v0, v1, e0, e1)
        return free | ~sure, sure, t, terr, enter

    convex.segment_filter = filt


def _skip_every_flat_pair():
    """Every pair whose normals are parallel or zero is left out as flat (the reference rule
    before issue #51, which dropped a degenerate triangle's pieces)."""
    from cspace.cobstacle import pairs

    pairs._parallel = lambda ns, nt: ((ns == nt).all(axis=1) | ~ns.any(axis=1)
                                      | ~nt.any(axis=1))


def _robot_not_reflected():
    """C-obstacles built from ``c + R`` instead of ``c - R`` (the classic sign slip of
    ``O ⊕ (-R)``): reflecting twice."""
    from cspace.mesh.convex import ConvexPolytope

    f = ConvexPolytope.reflected
    ConvexPolytope.reflected = lambda self, c=(0.0, 0.0, 0.0): f(f(self, (0.0, 0.0, 0.0)), c)


def _no_self_intersections():
    """The exact self-intersection test finds nothing: a folded body is taken for a solid."""
    from cspace.mesh import self_intersection
    from cspace.minkowski import sum as sum_module

    none = lambda mesh: np.zeros((0, 2), dtype=np.int64)  # noqa: E731
    self_intersection.self_intersections = sum_module.self_intersections = none


def _mesh_exact_fallback_flipped():
    """The mesh C-obstacle's exact membership fallback answers the opposite."""
    from cspace.mesh.query import MeshCO

    f = MeshCO._contains_exact
    MeshCO._contains_exact = lambda self, q: not f(self, q)


def _enclosed_region_ignored():
    """A closed surface's enclosed region (a folded body, a lost inside) holds no robot."""
    from cspace.scene import build

    f = build._containment_cos

    def terms(body, part, *a, **k):
        saved, body._encloses = body._encloses, None
        try:
            return f(body, part, *a, **k)
        finally:
            body._encloses = saved

    build._containment_cos = terms


MUTANTS = {
    "orient3d flipped": ("kernel", _flip_orient3d),
    "exact plane sign flipped": ("kernel", _flip_plane_sign),
    "grid origin shifted a step": ("kernel", _shift_grid_origin),
    "a C-obstacle dropped from the union": ("queries", _drop_a_cobstacle),
    "segment filter says free": ("queries", _segment_filter_says_free),
    "flat-pair rule of old (degenerate pairs dropped)": ("queries", _skip_every_flat_pair),
    "robot not reflected": ("queries", _robot_not_reflected),
    "no outward rounding": ("scene model", _no_margin),
    "no containment terms": ("scene model", _no_containment),
    "containment for one component only": ("scene model", _one_component),
    "closed bodies as bare surfaces": ("scene model", _closed_bodies_are_bare_surfaces),
    "every body hulled": ("scene model", _hull_every_body),
    "thin features lost": ("scene model", _lose_thin_features),
    "no self-intersection found": ("kernel", _no_self_intersections),
    "mesh membership fallback flipped": ("queries", _mesh_exact_fallback_flipped),
    "enclosed region ignored": ("scene model", _enclosed_region_ignored),
}


def apply(name: str) -> None:
    """Apply the mutant ``name`` (a key of :data:`MUTANTS`) to this process."""
    MUTANTS[name][1]()
