"""Checkpoints of the integrator state: one atomic ``.npz`` file, and the run's fingerprint.

``save(path, state, extra)`` writes every :data:`state.FIELDS` entry, the kept frames, the state's
``fingerprint`` (per-item digests of everything that shapes the run, :func:`fingerprint`) and any
``extra`` arrays (e.g. an adaptive driver's mesh state) to a temporary file, fsyncs it and renames it
over ``path``: a reader sees the old or the new checkpoint, never half of one; a failure is an
IOFailure naming ``path``.  ``load(path)``
returns ``(state, extra)`` or raises one InputError line (missing, truncated, foreign, old version).
"""

from __future__ import annotations

import dataclasses
import hashlib
import zipfile

import numpy as np

from ...errors import InputError, IOFailure
from ...interfaces import QuasiStrainModel, SolverProblem
from ...io import atomic_path
from ...model import Model
from .state import FIELDS, State

VERSION = 3
_EXTRA = "extra_"
_FP = "fp_"


def save(path, state: State, extra: dict | None = None) -> None:
    """Write ``state`` (and ``extra``: name -> array) to ``path`` atomically."""
    arrays = {k: np.asarray(getattr(state, k)) for k in FIELDS}
    arrays["frame_t"] = np.asarray(state.frame_t, dtype=float)
    arrays["frame_k"] = np.asarray(state.frame_k, dtype=np.int64)
    for i, u in enumerate(state.frame_U):  # one array each: frames of a remeshed run differ in size
        arrays[f"frame_U{i}"] = np.asarray(u)
    for k, v in state.fingerprint.items():
        arrays[_FP + k] = np.asarray(v)
    for k, v in (extra or {}).items():
        arrays[_EXTRA + k] = np.asarray(v)
    arrays["version"] = np.asarray(VERSION)
    try:
        with atomic_path(path) as tmp:  # a run killed mid-write leaves a temporary the run
            with open(tmp, "wb") as fh:  # folder knows as this file's (rundir), not a stray file
                np.savez(fh, **arrays)
    except OSError as e:  # named by the checkpoint's path, not the temporary's
        raise IOFailure(path, e.strerror or str(e) or type(e).__name__) from None


def load(path) -> tuple[State, dict]:
    """(state, extra) read from ``path``; InputError naming the file and the reason if unreadable."""
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}  # reads every member now: a truncated file fails here
    except FileNotFoundError:
        raise InputError(f"restart file {path} does not exist") from None
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile) as exc:
        raise InputError(
            f"cannot read restart file {path}: truncated or not a checkpoint ({type(exc).__name__})"
        ) from None
    version = int(data["version"]) if "version" in data else None
    if version != VERSION:
        raise InputError(f"restart file {path} has checkpoint version {version}, this solver writes {VERSION}")
    missing = [k for k in FIELDS if k not in data]
    if missing:
        raise InputError(f"restart file {path} is not a complete checkpoint: it lacks {', '.join(missing)}")
    n_frames = len(data.get("frame_t", ()))
    kw = {k: data[k] for k in FIELDS}
    kw["frame_t"] = list(data["frame_t"])
    kw["frame_k"] = list(data["frame_k"])
    kw["frame_U"] = [data[f"frame_U{i}"] for i in range(n_frames)]
    st = State(**kw).typed()
    st.fingerprint = {k[len(_FP) :]: str(v) for k, v in data.items() if k.startswith(_FP)}
    extra = {k[len(_EXTRA) :]: v for k, v in data.items() if k.startswith(_EXTRA)}
    return st, extra


# ----------------------------------------------------------------------------- fingerprint
def _feed(h, obj, depth=0) -> None:
    """Feed a canonical byte form of ``obj`` (arrays, numbers, strings, containers, dataclasses and
    plain objects' public attributes) into the hash ``h``."""
    if depth > 6:
        h.update(b"<deep>")
    elif isinstance(obj, np.ndarray) or isinstance(obj, np.generic):
        a = np.ascontiguousarray(obj)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes() if a.dtype != object else repr(a.tolist()).encode())
    elif obj is None or isinstance(obj, (bool, int, float, str, bytes)):
        h.update(repr(obj).encode())
    elif isinstance(obj, dict):
        for k in sorted(obj, key=str):
            h.update(str(k).encode())
            _feed(h, obj[k], depth + 1)
    elif isinstance(obj, (list, tuple)):
        h.update(f"[{len(obj)}".encode())
        for v in obj:
            _feed(h, v, depth + 1)
    elif dataclasses.is_dataclass(obj):
        h.update(type(obj).__name__.encode())
        _feed(h, {f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)}, depth + 1)
    elif hasattr(obj, "__dict__"):
        h.update(type(obj).__name__.encode())
        _feed(h, {k: v for k, v in vars(obj).items() if not k.startswith("_") and not callable(v)}, depth + 1)
    else:
        h.update(repr(obj).encode())


def digest(obj) -> str:
    h = hashlib.blake2b(digest_size=16)
    _feed(h, obj)
    return h.hexdigest()


def fingerprint(problem: SolverProblem, settings: dict, mass: np.ndarray) -> dict[str, str]:
    """Per-item digests of everything that shapes a run: mesh nodes and elements, material/section,
    the (scaled) masses, loads, supports, prescribed values, contact bodies, and each solver setting
    (``settings``: the ones that shape the run)."""
    model = problem.model
    if isinstance(model, Model):
        mesh, membrane = model.mesh, model.membrane
        if isinstance(membrane, tuple):
            # one value per quad (an adaptive mesh's coarse "ans" and finest "full"): one array, not a
            # tuple fed item by item (1600 hash updates, 2 % of each remesh on square-pedestal)
            membrane = np.asarray(membrane, dtype=str)
        nodes, elements = mesh.nodes, [mesh.quads, mesh.tris, mesh.directors]
        section = [model.material, model.quasi, model.mu, membrane]
    else:  # a model of its own (interfaces.ExplicitModel): its class, and Eq. (24)'s flags if it has them
        q = isinstance(model, QuasiStrainModel)
        nodes, elements = model.n_nodes, [None, None, None]
        section = [type(model).__name__, model.quasi if q else None, model.mu if q else None, None]
    items = {
        "mesh nodes": nodes,
        "mesh elements": elements,
        "material": section,
        "masses": mass,
        "loads": problem.loads,
        "supports": problem.fixed,
        "prescribed displacements": problem.prescribed,
        "contact bodies": [type(b).__name__ for b in problem.contact or []] + list(problem.contact or []),
        "friction coefficients": [float(b.friction) for b in problem.contact or []],
    }
    fp = {k: digest(v) for k, v in items.items()}
    fp.update({f"setting {k}": digest(v) for k, v in settings.items()})
    return fp


def check_fingerprint(saved: dict, now: dict, path) -> None:
    """InputError naming every item whose digest differs between a checkpoint and this run."""
    diff = [k for k in sorted(set(saved) | set(now)) if saved.get(k) != now.get(k)]
    if diff:
        raise InputError(
            f"restart file {path} does not match this run: {', '.join(diff)} differ(s) "
            f"(a checkpoint only continues the run that wrote it)"
        )
