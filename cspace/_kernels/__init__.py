"""Compiled exact kernels (Cython, built at install time), one module per Python module it
accelerates: :mod:`cspace._kernels.arrangement` serves :mod:`cspace.arrangement` (candidate
pairs, exact triangle-pair intersections and their endpoints), :mod:`cspace._kernels.meshquery`
:mod:`cspace.meshquery`, :mod:`cspace._kernels.planar` :mod:`cspace.planar` and
:mod:`cspace._kernels.trim` :mod:`cspace.trim`.

Each kernel has its pure-Python reference beside the code that calls it (same name, in the
accelerated module); ``tests/test_kernels.py`` and ``tests/test_kernels_intersections.py``
check that both give identical outputs. The extensions are compiled with
``-ffp-contract=off``: no fused multiply-add, so every float operation rounds exactly as the
reference's, and the filters' error bounds hold.
"""

import importlib
from types import ModuleType


def load(name: str) -> ModuleType:
    """The compiled kernel ``cspace._kernels.<name>``, or an :class:`ImportError` saying how
    to build it (an install that skipped the build step)."""
    try:
        return importlib.import_module(f"{__name__}.{name}")
    except ImportError as exc:  # pragma: no cover - an install without its build step
        raise ImportError(
            f"cspace's compiled kernels ({__name__}.{name}) are missing: install cspace with "
            "pip (`pip install -e .` in a checkout), which builds them with the system C "
            f"compiler ({exc})"
        ) from exc
