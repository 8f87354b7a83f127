"""Ensembles of drape runs on ``dask.distributed``: multi-stability maps and parameter sweeps.

    solidshell sweep SWEEP.toml [--scheduler tcp://HOST:PORT] [--workers N] [--out DIR]

Modules, one job each:

* ``spec``    the sweep file: scene, fixed keys, cases, grid / zip / random sample -> runs (checked)
* ``task``    one run on a worker: run_scene -> a ledger row
* ``ledger``  the Parquet results table, one part per run: resume, never a run twice
* ``engine``  the Dask client: LocalCluster or a scheduler address, retries, progress
* ``states``  runs grouped into distinct equilibria (fold count, symmetry group, DC, boundary)
* ``plots``   the state gallery, fold-count frequencies, response curves
* ``report``  the summary written after a sweep (states.csv, report.md, the figure)
* ``studies/`` the packaged sweep files (``solidshell sweep --list``)

dask[distributed] and pyarrow are optional (``pip install 'solidshell[sweep]'``): only ``engine``
and ``ledger`` import them, when a sweep runs.
"""

from .spec import SweepSpec, load_spec, studies

__all__ = ["SweepSpec", "load_spec", "studies"]
