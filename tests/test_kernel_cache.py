"""A kernel rounds the same whether numba compiled it in this process or loaded it from its on-disk cache
(issue 34, "the test suite is deterministic").

Numba compiles a jitted callee (core._element_tangent, ...) into a library of its own and again,
re-optimised, inside each caller's library; the process that compiles the caller runs the callee's own
library, a process that loads the caller from the cache runs the copy inside it.  With fast-math flags
that let LLVM change a result (reassoc, contract, arcp) the copies rounded differently: a freshly
compiled core.force_tangent and the cached one differed by one ulp in 6 of 13824 entries of the
quads-ans-quasi tangents, and tests/test_half_tangent.py's bit-equality of the whole and the half
tangents failed whenever one of the two had been cached by an earlier process (a first run of the
suite, after a subprocess test had cached one of them).  core.py's kernels therefore carry no such
flag (core._FM_EXACT)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from numba.core.registry import CPUDispatcher

from solidshell.elements import core

VALUE_CHANGING = {"reassoc", "contract", "arcp", "afn", "fast"}

PROBE = """
import hashlib, sys
import numpy as np
sys.path.insert(0, sys.argv[1])
from test_half_tangent import warped_quads
from solidshell.elements import core
from solidshell.material import Fabric
from solidshell.model import Model

mesh = warped_quads()
m = Model(mesh, Fabric.wool(warp_angle=20.0), membrane="ans", thickness_strain="quasi")
U = 0.05 * np.random.default_rng(6).standard_normal((mesh.n_nodes, 6))
xo, xn, Uc = m._current(U)
b = m.blocks[0]
M, nd = len(b.conn), 6 * b.nn
f, w, K = np.empty((M, b.nn, 6)), np.empty(M), np.empty((M, nd, nd))
core.force_tangent(*b.args(xo, xn, Uc, m.quasi, m.mu), b.gp_membrane, f, w, K, 1, True)
loaded = sum(core.force_tangent.stats.cache_hits.values())
print(loaded, hashlib.sha256(K.tobytes() + f.tobytes() + w.tobytes()).hexdigest())
"""


def test_core_kernels_carry_no_fast_math_flag_that_changes_a_result():
    kernels = {name: d for name, d in vars(core).items() if isinstance(d, CPUDispatcher)}
    assert {"force_tangent", "energy_force", "_element_tangent", "_element_force"} <= set(kernels)
    for name, d in kernels.items():
        flags = set(d.targetoptions.get("fastmath") or ())
        assert not flags & VALUE_CHANGING, f"core.{name}: fastmath {sorted(flags)}"


@pytest.mark.slow
def test_cached_tangent_kernel_gives_the_bits_of_the_freshly_compiled_one(tmp_path):
    """Two interpreters on one empty numba cache: the first compiles core.force_tangent (half
    tangents, assumed membrane, Eq. 24) and caches it, the second loads it; the element tangents,
    forces and energies must be the same bits (one ulp in 6 entries before core._FM_EXACT)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"), NUMBA_NUM_THREADS="1")
    tests_dir = os.path.dirname(os.path.abspath(__file__))
    runs = []
    for _ in range(2):
        p = subprocess.run(
            [sys.executable, "-c", PROBE, tests_dir], env=env, capture_output=True, text=True, timeout=600
        )
        assert p.returncode == 0, p.stderr[-2000:]
        loaded, digest = p.stdout.split()[-2:]
        runs.append((int(loaded), digest))
    (loaded0, fresh), (loaded1, cached) = runs
    assert (loaded0, loaded1) == (0, 1), "the first run must compile, the second load from the cache"
    assert cached == fresh
