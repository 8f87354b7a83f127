"""Size guard: the element count and memory of a run, estimated before anything is allocated.

A mesh density such as ``1000000x1000000x4`` is a valid string, and gmsh would start allocating
gigabytes before failing; :func:`check` refuses it at once with the estimate, from the density
alone (:func:`elements_of_density`), against the memory the machine has available now
(:func:`available_memory`).  ``allow_large=True`` (CLI ``--allow-large``) overrides it.

Memory per element (quads; a triangle costs less), measured as the rise in peak resident memory
of ``run_scene("square-pedestal", mesh=...)`` between meshes (on the 2-core development machine):

- meshing (gmsh) : 100x33x4 -> 200x66x4 (13200 -> 52800 elements): 1.0 KiB per element;
- explicit/relax : 48x16x4 -> 96x32x4 (3072 -> 12288): 2.6 KiB per element for the loop, plus
  kept frames: up to ``max_frames`` = 100 frames of 6 doubles per node = 4.7 KiB per node;
- static         : 48x16x4 -> 96x32x4: 51 KiB per element (the sparse tangent and its Cholesky
  factor; nested-dissection fill-in grows like N log N, so larger meshes cost more per element).

The constants below round these up (writing VTU/XDMF/PNG costs a few KiB per element more) and
a fixed 256 MiB covers the interpreter, numpy/scipy/numba and matplotlib (measured 210-230 MiB
on the smallest mesh).  They are estimates to stop absurd runs, not a promise that a run fits.
"""

from __future__ import annotations

import math
import os
import re

from .errors import InputError

KIB = 1024
MIB = 1024 * KIB

BASE_BYTES = 256 * MIB
"""Interpreter, numpy/scipy/numba/matplotlib and compiled kernels, independent of the mesh."""

BYTES_PER_ELEMENT = {
    "none": 4 * KIB,  # meshing 1 KiB + mesh files and pictures
    "explicit": 12 * KIB,  # loop 2.6 KiB + frames up to 4.7 KiB per node + files
    "relax": 12 * KIB,
    "static": 64 * KIB,  # tangent + factor, measured 51 KiB at 1.2e4 elements
}


def elements_of_density(density: str) -> int:
    """Number of elements a recipe density gives: the product of its counts for every built-in
    recipe (strip / square N x M, disc R x C, square_on_square A x B x 4 = 4AB quads; see
    solidshell.meshing).  Exact integer arithmetic, so a huge density does not overflow."""
    return math.prod(int(p) for p in re.split(r"\s*[xX×]\s*", str(density).strip()))


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation now: ``MemAvailable`` of /proc/meminfo (Linux:
    free memory plus reclaimable caches), else free physical pages from ``os.sysconf``; None when
    neither is known (then only the element count is reported)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * KIB
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def estimate_bytes(n_elements: int, kind: str) -> int:
    """Estimated peak memory [bytes] of a run of ``kind`` (static | explicit | relax | none)."""
    return BASE_BYTES + int(n_elements) * BYTES_PER_ELEMENT.get(kind, BYTES_PER_ELEMENT["static"])


def _human(n: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(n) < 1024 or unit == "PiB":
            return f"{n:.3g} {unit}" if unit != "B" else f"{int(n)} B"
        n /= 1024
    return f"{n:.3g} PiB"  # pragma: no cover


def check(n_elements: int, kind: str, what: str, allow_large: bool = False, available: int | None = None) -> int:
    """Refuse (InputError, one line) a run whose estimated memory exceeds the available memory.

    ``what`` names the mesh in the message (e.g. "--mesh 1000000x1000000x4"); ``available``
    defaults to :func:`available_memory`.  Returns the estimate in bytes."""
    need = estimate_bytes(n_elements, kind)
    if allow_large:
        return need
    have = available_memory() if available is None else int(available)
    if have is not None and need > have:
        raise InputError(
            f"{what}: {n_elements:.4g} elements need about {_human(need)} for a "
            f"{kind if kind != 'none' else 'mesh-only'} run, more than the "
            f"{_human(have)} available; use a coarser mesh, or --allow-large "
            f"(run_scene(..., allow_large=True)) to try anyway"
        )
    return need
