"""``solidshell bench``: work-precision studies (error against wall time) and kernel throughput.

Each study (``studies.py``) runs a list of configurations of one problem -- mesh densities,
quadrilaterals against triangles, the static solvers, explicit relaxation with director-only or
uniform mass scaling, uniform against adaptive meshes -- and measures every run's wall time and
its error against a reference:

* ``strip``: the wool strip's tip deflection against the heavy elastica (reference/);
* ``pedestal``: square-pedestal's drape coefficient and projected boundary against the finest
  static run of the study (a self-convergence reference: said so in the output);
* ``sphere``: the cloth on the sphere's drape coefficient against the study's finest run;
* ``throughput``: element force evaluations and explicit element-steps per second.

Output per study (``workprec.py``): ``<study>.json`` (every run, the machine and its load),
``<study>.md`` (the table and the cheapest configuration within 1 % of the reference) and
``<study>.png`` (error against wall time, log-log).  Wall times are of one shared machine:
compare ratios inside one run (docs/benchmarks.md).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .studies import STUDIES

__all__ = ["STUDIES"]


def __getattr__(name):
    # on first use: the CLI's parser imports solidshell.bench.cli, and ``solidshell run`` starts its
    # pictures' process before NumPy (which the studies import) is loaded
    if name == "STUDIES":
        from .studies import STUDIES

        return STUDIES
    raise AttributeError(f"module 'solidshell.bench' has no attribute {name!r}")
