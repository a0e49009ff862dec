"""A process's memory handed back to the system once a step has freed it.

A process's peak memory is what its allocators hold, not what it uses: memory freed by
one step stays with the allocator that gave it (Arrow's pool, the C library's heap)
until it is reused, so a later step that allocates through another one adds to it. A
step that reads and writes many rows (a landing of the map, a package's check) hands
back what it freed before the next one begins: :func:`return_free_memory`.
"""

from __future__ import annotations

import sys


def return_free_memory(*, collect: bool = True) -> None:
    """Hand the memory freed so far back to the system: Python's garbage (``collect``;
    a full collection, which costs time in a process holding many objects), Arrow's pool
    when Arrow is loaded and, where the C library has it (glibc), the heap's free pages."""
    import ctypes
    import gc

    if collect:
        gc.collect()
    arrow = sys.modules.get("pyarrow")
    if arrow is not None:
        arrow.default_memory_pool().release_unused()
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):  # not glibc: the pages stay until reused
        pass
