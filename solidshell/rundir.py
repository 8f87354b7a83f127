"""The output folder of one run: never two runs' files mixed, never a half-finished run that looks
finished.

Life of a run's folder (:class:`RunFolder`):

1. :meth:`~RunFolder.check` -- before any work: the path must be a folder (or not exist yet), and
   every file in it must be one this package writes (an earlier run's outputs, listed in its
   ``summary.json`` "files" or by their known names, and the temporaries a run killed mid-write
   leaves of them or of this run's checkpoint).  Anything else is refused, naming the files,
   unless ``force`` (CLI ``--force``): then foreign files are left untouched and reported.
2. :meth:`~RunFolder.open` -- the folder is created and a ``RUNNING`` marker holding the new run's id
   is written.  The earlier run's files are still all there, consistent with its summary.
3. :meth:`~RunFolder.clear_stale` -- once the solver has returned: the old ``summary.json`` is
   removed first, then the old run's other files.  A run killed from here on leaves no summary.
4. the run's files are written, each stamped with the run id (solidshell.io);
   :meth:`~RunFolder.finish` writes ``summary.json`` last and removes ``RUNNING``.

:meth:`~RunFolder.abandon` undoes 2 when a run stops before it has a state to write (bad input
found by a solver, Ctrl-C with no state): the marker goes, and the folder too if this run created
it and it is empty.  Any OSError while preparing or writing becomes
:class:`~solidshell.errors.IOFailure` naming the path (CLI exit status 3).
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import time
from pathlib import Path

from . import io as sio
from .errors import InputError, IOFailure

MARKER = "RUNNING"

# Names this package writes into a run folder (solidshell.runner) and the temporaries of its atomic
# writes (".<stem>.<random><suffix>", solidshell.io.atomic_path).
_OURS = re.compile(
    r"""^(?:
      (?:mesh|result)\.(?:xdmf|vtu) | deformed\.vtu | series\.xdmf | summary\.json | RUNNING
    | projected_boundary\.csv | (?:top|iso|side|side_yz)\.png | iso_t\d+(?:\.\d+)?\.png
    | \.(?:mesh|result|deformed|series|summary|projected_boundary|top|iso|side|side_yz|iso_t\d+(?:\.\d+)?)
      \.[A-Za-z0-9_]+\.(?:xdmf|vtu|json|csv|png)
)$""",
    re.X,
)


def _io(exc: OSError, path) -> IOFailure:
    return IOFailure.from_oserror(exc, path)


class RunFolder:
    """One run's output folder (see the module docstring).

    path    : the folder
    run_id  : the run's id (uuid4 hex)
    force   : go ahead when the folder holds files this package did not write (left untouched)
    keep    : file paths of this run that may sit in the folder but are not outputs to replace
              (a checkpoint, a restart file)
    """

    def __init__(self, path, run_id: str, force: bool = False, keep=()):
        self.path = Path(path)
        self.run_id = run_id
        self.force = bool(force)
        self.keep = set()
        for k in keep:
            if k:
                with contextlib.suppress(OSError):
                    if Path(k).resolve().parent == self.path.resolve():
                        self.keep.add(Path(k).name)
        self.created = False
        self.stale: list[str] = []
        self.foreign: list[str] = []

    # ------------------------------------------------------------------ 1. before any work
    def check(self) -> None:
        """Refuse a path that is not a folder, or a folder with files we did not write."""
        p = self.path
        if p.exists() and not p.is_dir():
            raise InputError(f"output path {p} exists and is not a directory")
        if not p.is_dir():
            return
        old = self._old_summary()
        listed = {n for n in old.get("files", []) if isinstance(n, str) and "/" not in n and n not in (".", "..")}
        ck = old.get("checkpoint")
        kept = set(self.keep) | ({Path(ck).name} if isinstance(ck, str) else set())
        try:
            names = sorted(os.listdir(p))
        except OSError as e:
            raise _io(e, p) from None
        for n in names:
            if n in kept:
                continue
            ours = n in listed or _OURS.match(n) or any(sio.is_temporary_of(n, k) for k in kept)
            if ours and (p / n).is_file():
                self.stale.append(n)
            else:
                self.foreign.append(n)
        if self.foreign and not self.force:
            shown = ", ".join(self.foreign[:5]) + (
                f" and {len(self.foreign) - 5} more" if len(self.foreign) > 5 else ""
            )
            raise InputError(
                f"output folder {p} holds files solidshell did not write ({shown}); "
                f"choose another --out, or --force (force=True) to write beside them"
            )

    def _old_summary(self) -> dict:
        f = self.path / "summary.json"
        try:
            d = json.loads(f.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return {}
        return d if isinstance(d, dict) else {}

    # ------------------------------------------------------------------ 2. the run starts
    def open(self) -> None:
        """Create the folder and write the RUNNING marker (IOFailure if either fails)."""
        if not self.path.is_dir():
            try:
                self.path.mkdir(parents=True)
                self.created = True
            except FileExistsError:
                pass
            except OSError as e:
                raise _io(e, self.path) from None
        self.write_json(
            MARKER,
            {"run_id": self.run_id, "pid": os.getpid(), "started": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())},
        )

    def abandon(self) -> None:
        """The run ends with nothing to write: remove the marker (and the folder if we made it and
        it is empty).  Never raises: it runs while another error is on its way out."""
        with contextlib.suppress(OSError):
            (self.path / MARKER).unlink()
        if self.created:
            with contextlib.suppress(OSError):
                self.path.rmdir()

    # ------------------------------------------------------------------ 3. replace the old run
    def clear_stale(self) -> list[str]:
        """Remove the earlier run's files, its summary.json first (IOFailure naming the file)."""
        order = sorted(set(self.stale) - {MARKER}, key=lambda n: n != "summary.json")
        for n in order:
            _unlink(self.path / n)
        return order

    # ------------------------------------------------------------------ 4. write
    def write(self, name: str, writer, *args, **kw) -> Path:
        """``writer(self.path / name, *args, **kw)`` with OSError turned into IOFailure."""
        p = self.path / name
        try:
            return Path(writer(p, *args, **kw))
        except OSError as e:
            if isinstance(e, IOFailure):
                raise
            raise _io(e, p) from None

    def write_json(self, name: str, data) -> Path:
        return self.write(name, sio.write_json, data)

    def finish(self, summary: dict) -> Path:
        """Write summary.json (last) and remove the RUNNING marker."""
        p = self.write_json("summary.json", summary)
        _unlink(self.path / MARKER)
        return p


def _unlink(p: Path) -> None:
    """Remove a file of the run folder if it is there (IOFailure naming it if that fails)."""
    try:
        p.unlink()
    except FileNotFoundError:
        pass
    except OSError as e:
        raise _io(e, p) from None
