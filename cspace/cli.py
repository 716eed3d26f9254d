"""The ``cspace`` command line; each subcommand mirrors a Python function.

- ``cspace convex-sum A B`` — :func:`cspace.convex_minkowski_sum` of two convex shapes
  (mesh files, hulled), optionally as a C-obstacle ``A ⊕ (−(B − c))`` with ``--reflect-b``.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence


def _convex_sum(args: argparse.Namespace) -> int:
    # Heavy imports here so that `cspace --help` stays fast.
    import numpy as np
    import trimesh

    from .convex import FACET_KINDS, ConvexPolytope, convex_minkowski_sum
    from .exact import Grid

    def load_points(path: str) -> np.ndarray:
        mesh = trimesh.load(path, force="mesh", process=False)
        return np.asarray(mesh.vertices, dtype=np.float64)

    a, b = load_points(args.a), load_points(args.b)
    grid = Grid.for_points(a, b, bits=args.grid_bits)
    A = ConvexPolytope.from_points(a, grid=grid, name=args.a)
    B = ConvexPolytope.from_points(b, grid=grid, name=args.b)
    if args.reflect_b is not None:
        B = B.reflected(args.reflect_b)
    t = time.perf_counter()
    S = convex_minkowski_sum(A, B)
    dt = time.perf_counter() - t
    kinds = ", ".join(f"{int((S.kind == k).sum())} {name}" for k, name in enumerate(FACET_KINDS))
    print(f"A: {A.n_facets} facets, {len(A.ints)} vertices ({args.a})")
    print(f"B: {B.n_facets} facets, {len(B.ints)} vertices ({args.b}){' reflected' if args.reflect_b is not None else ''}")
    print(f"A ⊕ B: {S.polytope.n_facets} facets ({kinds}), {len(S.vertices)} vertices, volume {S.volume:.9g}")
    print(f"grid step {grid.step:.3g}; snapping moved each input point by at most {S.error_bound:.3g}")
    print(f"time {dt * 1e3:.2f} ms")
    if args.output:
        S.polytope.to_trimesh().export(args.output)
        print(f"wrote {args.output}")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``cspace`` command line; returns the exit status."""
    parser = argparse.ArgumentParser(prog="cspace", description="Exact translational C-space obstacles.")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("convex-sum", help="exact Minkowski sum of two convex shapes (CVMS)")
    p.add_argument("a", help="mesh file of A (its convex hull is used)")
    p.add_argument("b", help="mesh file of B (its convex hull is used)")
    p.add_argument("-o", "--output", help="write the sum as a mesh file (any format trimesh exports)")
    p.add_argument(
        "--reflect-b", nargs=3, type=float, metavar=("X", "Y", "Z"),
        help="use -(B - c) for this reference point c: the C-obstacle of robot B around obstacle A",
    )
    p.add_argument("--grid-bits", type=int, default=26, help="snapped coordinates satisfy |k| <= 2**bits")
    p.set_defaults(func=_convex_sum)
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except (ValueError, FileNotFoundError) as e:
        print(f"cspace: error: {e}", file=sys.stderr)
        return 2
