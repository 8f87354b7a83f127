"""The sweep's results table: a Parquet dataset, one part file per finished run.

``OUT/ledger/<key>.parquet`` holds one row, written by the client (never by a worker) as soon as the
run's result arrives, through a temporary file and an atomic rename: a client killed at any moment
leaves whole part files only (a stray ``.<key>.tmp`` is ignored and overwritten later).  The part's
name is the run's key, so a run can be recorded once and only once; a resumed sweep skips the keys
present.  ``pyarrow.parquet.read_table("OUT/ledger")`` (or :meth:`Ledger.read`) reads the table.

Every part of one sweep has the same schema (:func:`schema`): the fixed columns below plus one typed
column per varied scene key (its dotted name).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from ..errors import InputError, IOFailure

__all__ = ["Ledger", "schema", "FIXED_COLUMNS", "PROFILE_POINTS"]

PROFILE_POINTS = 360
"""Angles of the stored radius profile r(theta) (1 deg): the state classification compares runs
on it.  1 deg resolves a 12-fold pattern (30 deg period) with 30 points per fold."""


def _pa():
    import pyarrow as pa

    return pa


def FIXED_COLUMNS():
    """(name, pyarrow type, meaning) of every column a sweep row always has."""
    pa = _pa()
    return [
        ("key", pa.string(), "the run's key (hash of scene, mesh, solver, settings)"),
        ("index", pa.int64(), "the run's position in the sweep's expansion"),
        ("case", pa.int64(), "its [[case]] number (0 without cases)"),
        ("sweep", pa.string(), "the sweep's name"),
        ("scene", pa.string(), "scene name"),
        ("mesh", pa.string(), "mesh density"),
        ("solver", pa.string(), "static | explicit | relax"),
        ("inputs", pa.string(), "JSON of the run's mesh, solver and --set keys"),
        ("status", pa.string(), "done (a result) | error (refused or failed: see error)"),
        ("error", pa.string(), "one line, when status is error"),
        ("converged", pa.bool_(), "the solver's converged flag"),
        ("solver_status", pa.string(), "the solver's info['status'] word"),
        ("stable", pa.bool_(), "static: positive-definite tangent; relax: steady state reached"),
        ("min_tangent_eigenvalue", pa.float64(), "static: smallest free-dof tangent eigenvalue [gf/cm]"),
        ("residual", pa.float64(), "final relative residual |P - F|/|P| (free dofs)"),
        ("drape_coefficient", pa.float64(), "DC = (A_proj - A_ped)/(A_sheet - A_ped)"),
        ("fold_count", pa.int64(), "folds of the projected boundary (solidshell.analysis)"),
        ("fold_angles_deg", pa.list_(pa.float64()), "polar angles of the fold crests [deg]"),
        ("mean_radius", pa.float64(), "mean radius of the projected boundary [cm]"),
        ("interpenetrated_nodes", pa.int64(), "nodes whose director turned through the sheet (n_p . d_p < 0, §4.3)"),
        ("radius_profile", pa.list_(pa.float32()), f"r(theta) [cm] at {PROFILE_POINTS} angles, 1 deg apart"),
        ("fingerprint", pa.string(), "folds, canonical fold angles (5 deg) under the symmetry group, DC"),
        ("symmetry", pa.string(), "the symmetry group the fingerprint is taken under"),
        ("nodes", pa.int64(), "mesh nodes"),
        ("elements", pa.int64(), "mesh elements"),
        ("wall_time_s", pa.float64(), "the run's wall time on its worker [s]"),
        ("cpu_time_s", pa.float64(), "CPU time of the worker process during the run (all threads) [s]"),
        ("run_dir", pa.string(), "the run's folder (summary.json, result.vtu, top.png)"),
        ("worker", pa.string(), "address of the worker that ran it"),
        ("finished_at", pa.string(), "UTC time the result was recorded (ISO 8601)"),
    ]


def _axis_type(values):
    pa = _pa()
    vals = [v for v in values if v is not None]
    if vals and all(isinstance(v, bool) for v in vals):
        return pa.bool_()
    if vals and all(isinstance(v, int) and not isinstance(v, bool) for v in vals):
        return pa.int64()
    if vals and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in vals):
        return pa.float64()
    return pa.string()


def schema(spec):
    """The Parquet schema of a sweep's rows: fixed columns, then one per varied scene key."""
    pa = _pa()
    fields = [pa.field(n, t) for n, t, _ in FIXED_COLUMNS()]
    names = {f.name for f in fields}
    for k in spec.axes:
        if k in names:
            continue
        t = _axis_type([r.overrides.get(k) for r in spec.runs])
        fields.append(pa.field(k, t))
    return pa.schema(fields)


def axis_value(v, typ):
    """A setting's value as its column stores it (arrays and mixed types as JSON text)."""
    pa = _pa()
    if v is None:
        return None
    if typ == pa.string() and not isinstance(v, str):
        return json.dumps(v)
    if typ == pa.float64():
        return float(v)
    return v


class Ledger:
    """The ledger folder of a sweep's output folder ``out`` (see the module docstring)."""

    def __init__(self, out, spec):
        self.out = Path(out)
        self.dir = self.out / "ledger"
        self.spec = spec
        self.schema = schema(spec)

    def check(self) -> None:
        """Refuse an output folder that holds another sweep's ledger (InputError naming both)."""
        meta = self.out / "sweep.json"
        if meta.is_file():
            try:
                other = json.loads(meta.read_text()).get("name")
            except (OSError, ValueError):
                other = None
            if other != self.spec.name:
                raise InputError(
                    f"{self.out} holds the ledger of sweep {other!r}, not {self.spec.name!r}; choose another --out"
                )
        elif self.out.exists() and not self.out.is_dir():
            raise InputError(f"output path {self.out} exists and is not a directory")

    def open(self) -> None:
        """Create the folders and write sweep.json (the sweep's name, source and run count)."""
        try:
            self.dir.mkdir(parents=True, exist_ok=True)
            meta = {
                "name": self.spec.name,
                "source": self.spec.source,
                "scene": self.spec.scene,
                "runs": self.spec.n_runs,
                "axes": list(self.spec.axes),
            }
            tmp = self.out / ".sweep.json.tmp"
            tmp.write_text(json.dumps(meta, indent=1))
            os.replace(tmp, self.out / "sweep.json")
        except OSError as e:
            raise IOFailure.from_oserror(e, self.out) from None

    def done_keys(self) -> set:
        """Keys of the runs already recorded."""
        if not self.dir.is_dir():
            return set()
        return {p.stem for p in self.dir.glob("*.parquet")}

    def errors(self) -> list:
        """(key, one-line reason) of the recorded runs without a result (status other than "done"),
        in key order; only the key, status and error columns are read."""
        import pyarrow.parquet as pq

        if not self.dir.is_dir():
            return []
        out = []
        for p in sorted(self.dir.glob("*.parquet")):
            t = pq.read_table(p, columns=[c for c in ("key", "status", "error") if c in pq.read_schema(p).names])
            for r in t.to_pylist():
                if r.get("status") != "done":
                    out.append((r.get("key", p.stem), r.get("error") or f"status {r.get('status')!r}"))
        return out

    def append(self, row: dict) -> bool:
        """Record one run's row; False (nothing written) when its key is already recorded."""
        import pyarrow.parquet as pq

        pa = _pa()
        key = row["key"]
        final = self.dir / f"{key}.parquet"
        if final.exists():
            return False
        full = {}
        for f in self.schema:
            v = row.get(f.name)
            full[f.name] = axis_value(v, f.type) if f.name in self.spec.axes else v
        table = pa.Table.from_pylist([full], schema=self.schema)
        tmp = self.dir / f".{key}.tmp"
        try:
            pq.write_table(table, tmp)
            os.replace(tmp, final)
        except OSError as e:
            raise IOFailure.from_oserror(e, final) from None
        return True

    def read(self):
        """All recorded rows as one pyarrow Table (ordered by run index); an empty table if none."""
        import pyarrow.parquet as pq

        pa = _pa()
        parts = sorted(self.dir.glob("*.parquet")) if self.dir.is_dir() else []
        if not parts:
            return self.schema.empty_table()
        return pa.concat_tables([self._part(pq.read_table(p)) for p in parts]).sort_by("index")

    def _part(self, t):
        """A part in this ledger's schema (a column an older part lacks is read as nulls)."""
        pa = _pa()
        cols = [
            t.column(f.name).cast(f.type) if f.name in t.column_names else pa.nulls(t.num_rows, f.type)
            for f in self.schema
        ]
        return pa.Table.from_arrays(cols, schema=self.schema)
