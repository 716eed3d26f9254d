"""How much memory a build may take: the budget, and sizes written as people write them.

A build that would not fit stops before it allocates, with a
:class:`~cspace.errors.MemoryBudgetError` that says how much it needed; it is never killed by
the kernel. The budget is, in this order:

1. the ``memory`` argument (bytes, or a size string such as ``"6G"``; ``--memory`` on the
   command line);
2. ``$CSPACE_MEMORY`` (same forms);
3. half of the memory available to this process when the budget is read: ``MemAvailable`` of
   ``/proc/meminfo``, capped by the cgroup's ``memory.max`` less what the cgroup already uses
   (containers), else half of the physical memory (``os.sysconf``).

Half leaves room for what the estimates do not see (Python objects, the caller's own data);
the estimates themselves are upper bounds measured on the constructions they cover
(:data:`cspace.cobstacle.pairs.PAIR_BYTES`).
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from .errors import InvalidArgumentError, MemoryBudgetError

__all__ = ["memory_budget", "budget_and_source", "parse_size", "format_size", "available_memory",
           "resident_memory", "MemoryGuard"]

_UNITS = {"": 1, "B": 1, "K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}
_SIZE = re.compile(r"^\s*([0-9]*\.?[0-9]+)\s*([KMGT]?)(I?B)?\s*$", re.IGNORECASE)
DEFAULT_FRACTION = 0.5


def parse_size(value, name: str = "memory") -> int:
    """Bytes from an int or a string such as ``"512M"``, ``"6G"``, ``"1.5GiB"``, ``"2e9"``
    (binary units: K = 1024). Raises :class:`InvalidArgumentError` naming ``name``."""
    if isinstance(value, bool):
        raise InvalidArgumentError(f"{name} must be a size in bytes (such as 6G), got {value!r}")
    if isinstance(value, (int, float)):
        out = float(value)
    else:
        text = str(value)
        m = _SIZE.match(text)
        try:
            out = float(m.group(1)) * _UNITS[m.group(2).upper()] if m else float(text)
        except ValueError:
            raise InvalidArgumentError(
                f"{name} must be a size such as 512M, 6G or a number of bytes, got {value!r}"
            ) from None
    if not out > 0 or out == float("inf"):
        raise InvalidArgumentError(f"{name} must be a positive size, got {value!r}")
    return int(out)


def format_size(n: float) -> str:
    """``n`` bytes for people: ``'3.2 GB'`` (decimal units, one decimal)."""
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.1f} {unit}"
    return f"{int(n)} B"


def _read_int(path: Path) -> int | None:
    try:
        text = path.read_text().strip()
    except OSError:
        return None
    return int(text) if text.isdigit() else None


def available_memory() -> int:
    """Bytes this process can still take: the kernel's ``MemAvailable``, capped by the
    cgroup's limit (v2 ``memory.max`` less ``memory.current``; v1 alike); the physical
    memory where ``/proc`` is not there."""
    available = None
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                available = int(line.split()[1]) * 1024
                break
    except (OSError, ValueError, IndexError):
        pass
    if available is None:
        try:
            available = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        except (ValueError, OSError, AttributeError):  # pragma: no cover - exotic platforms
            available = 4 * 2**30
    for limit, used in ((Path("/sys/fs/cgroup/memory.max"), Path("/sys/fs/cgroup/memory.current")),
                        (Path("/sys/fs/cgroup/memory/memory.limit_in_bytes"),
                         Path("/sys/fs/cgroup/memory/memory.usage_in_bytes"))):
        cap = _read_int(limit)  # "max" (no limit) reads as None
        if cap is not None and cap < 2**60:
            available = min(available, max(0, cap - (_read_int(used) or 0)))
    return int(available)


def memory_budget(memory=None) -> int:
    """The bytes a build may take (see the module): ``memory``, else ``$CSPACE_MEMORY``, else
    half of :func:`available_memory`."""
    return budget_and_source(memory)[0]


def budget_and_source(memory=None) -> tuple[int, str]:
    """:func:`memory_budget` and where it came from, for messages (``'memory='``,
    ``'$CSPACE_MEMORY'``, ``'half of the 23.1 GB available'``)."""
    if memory is not None:
        return parse_size(memory), "memory= / --memory"
    env = os.environ.get("CSPACE_MEMORY", "").strip()
    if env:
        return parse_size(env, "$CSPACE_MEMORY"), "$CSPACE_MEMORY"
    available = available_memory()
    return int(DEFAULT_FRACTION * available), f"half of the {format_size(available)} available"


def resident_memory() -> int | None:
    """Bytes of this process resident in memory now (``/proc/self/statm``); None where that
    is not known (then nothing is watched)."""
    try:
        pages = int(Path("/proc/self/statm").read_text().split()[1])
    except (OSError, ValueError, IndexError):
        return None
    return pages * os.sysconf("SC_PAGE_SIZE")


class MemoryGuard:
    """Watches a build whose memory cannot be told before it runs (an exact sum's
    arrangements grow with how its superset folds: 1.2 GB for a block of 840 triangles ⊕ a
    320-facet sphere) and stops it with a :class:`~cspace.errors.MemoryBudgetError` once its
    resident memory has grown past the budget (:func:`budget_and_source`), before the
    kernel kills the process. ``check`` reads ``/proc/self/statm`` (some microseconds):
    callers check between stages and every few dozen units of work. A forked worker
    inherits the guard and its starting point, so it counts what its parent had grown by
    too: the processes' total, roughly."""

    def __init__(self, what: str, memory=None):
        self.what = what
        self.budget, self.source = budget_and_source(memory)
        self.start = resident_memory()

    def check(self, stage: str, detail: str = "") -> None:
        """Raise :class:`MemoryBudgetError` when this process has grown by more than the
        budget since the guard was made (``stage`` and ``detail`` go into the message)."""
        if self.start is None:
            return
        now = resident_memory()
        if now is None or now - self.start <= self.budget:
            return
        grown = now - self.start
        raise MemoryBudgetError(
            f"{self.what}: grew by {format_size(grown)} by its {stage} stage{detail}, over the "
            f"memory budget of {format_size(self.budget)} ({self.source}); stopped before the "
            "system could kill it, nothing is kept. Use a robot with fewer facets or its convex "
            "hull (robot_hull=True, --robot-hull: conservative), or a larger budget (memory=, "
            "--memory, $CSPACE_MEMORY)", needed=grown, budget=self.budget)
