"""Build of cspace's compiled kernels (Cython, at install time; metadata in pyproject.toml).

Every extension is compiled without fused multiply-add (``-ffp-contract=off``; MSVC does not
contract by default): each float operation then rounds exactly as in the pure-Python
reference, which the float filters' error bounds assume.
"""

import sys

from Cython.Build import cythonize
from setuptools import Extension, setup

FLAGS = [] if sys.platform == "win32" else ["-O2", "-ffp-contract=off"]

KERNELS = ["meshquery"]  # cspace/_kernels/<name>.pyx accelerates cspace/<name>.py

setup(
    ext_modules=cythonize(
        [Extension(f"cspace._kernels.{k}", [f"cspace/_kernels/{k}.pyx"],
                   extra_compile_args=FLAGS) for k in KERNELS],
        language_level=3,
    ),
)
