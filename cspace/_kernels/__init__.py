"""Compiled exact kernels (Cython, built at install time), one module per Python module it
accelerates: :mod:`cspace._kernels.meshquery` serves :mod:`cspace.meshquery`.

Each kernel has its pure-Python reference beside the code that calls it (same name, in the
accelerated module); ``tests/test_kernels.py`` checks that both give identical outputs. The
extensions are compiled with ``-ffp-contract=off``: no fused multiply-add, so every float
operation rounds exactly as the reference's, and the filters' error bounds hold.
"""
