"""Build of cspace's compiled kernels (Cython, at install time; metadata in pyproject.toml).

Every extension is compiled without fused multiply-add (``-ffp-contract=off``; MSVC does not
contract by default): each float operation then rounds exactly as in the pure-Python
reference, which the float filters' error bounds assume.
"""

import os
import sys

from Cython.Build import cythonize
from setuptools import Extension, setup

# Built on the machine that runs it (pip install from source): its own instruction set, as
# numba did (the BVH distances are 15% slower on generic x86-64). Wheels set
# CSPACE_PORTABLE_BUILD=1 (pyproject's cibuildwheel section) for the generic one.
PORTABLE = os.environ.get("CSPACE_PORTABLE_BUILD") == "1"
if sys.platform == "win32":
    FLAGS = []
else:
    FLAGS = ["-O3", "-ffp-contract=off"] + ([] if PORTABLE else ["-march=native"])

KERNELS = ["arrangement", "boxtree", "clearance", "convex", "graph", "meshquery", "pairquery", "planar", "trim"]  # cspace/geometry/_kernels/<name>.pyx (see its __init__)

setup(
    ext_modules=cythonize(
        [Extension(f"cspace.geometry._kernels.{k}", [f"cspace/geometry/_kernels/{k}.pyx"],
                   extra_compile_args=FLAGS) for k in KERNELS],
        language_level=3,
    ),
)
