"""The output folder of one run: one live run per folder, never two runs' files mixed, never a
half-finished run that looks finished, and a kill at any moment leaves the old complete run or the
new complete run.

Life of a run's folder (:class:`RunFolder`):

1. :meth:`~RunFolder.check` -- before any work: the path must be a folder (or not exist yet), no live
   run may own it (its ``RUNNING`` marker locked, below: InputError naming the folder and the pid,
   ``--force`` or not), and every file in it must be one this package writes (an earlier run's
   outputs, listed in its ``summary.json`` "files" or by their known names, and the temporaries a
   run killed mid-write leaves of them or of this run's checkpoint).  Anything else is refused,
   naming the files, unless ``force`` (CLI ``--force``): then foreign files are kept and reported.
2. :meth:`~RunFolder.open` -- the folder is created, the ``RUNNING`` marker written with the run's
   id and pid and locked (``fcntl.flock``, held until the run ends: the kernel releases it when the
   process dies, kill -9 included, so a marker left by a dead run does not block the next), and the
   staging folder ``.<name>.new-<id>`` made beside the folder.  The earlier run's files are all
   still there, consistent with its summary.
3. the run's files are written into the staging folder, each stamped with the run id
   (solidshell.io); :meth:`~RunFolder.clear_stale` only lists the earlier run's files they replace.
4. :meth:`~RunFolder.finish` writes ``summary.json`` there, links what stays (a checkpoint, files
   kept with ``--force``) into it and swaps it with the folder in one step (``renameat2`` with
   ``RENAME_EXCHANGE``; where the system has none, two renames a moment apart), then deletes the
   old contents.  A folder that is a symbolic link, or that holds folders kept with ``--force``, is
   written in place instead (below).

:meth:`~RunFolder.abandon` undoes 2 when a run stops before it has complete results (bad input
found by a solver, Ctrl-C with no state, a failed results write): the staging folder and the
marker go, and the folder too if this run created it and it is empty.  A run killed before the swap
leaves the old run as it was (plus a stale marker and staging folder, which the next run clears).
Any OSError while preparing or writing becomes :class:`~solidshell.errors.IOFailure` naming the
path (CLI exit status 3).  A folder written in place (its parent cannot take the staging folder, or
see 4) is written as before the swap existed: the earlier run's files removed, its summary first,
once the solver has returned.
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
      (?:mesh|result)\.(?:xdmf|vtu) | deformed\.vtu | series\.(?:xdmf|pvd) | series_\d{5}\.vtu | summary\.json
    | RUNNING | projected_boundary\.csv | (?:top|iso|side|side_yz)\.png | (?:iso|top)_t\d+(?:\.\d+)?\.png
    | \.(?:mesh|result|deformed|series|series_\d{5}|summary|projected_boundary|top|iso|side|side_yz
         |(?:iso|top)_t\d+(?:\.\d+)?)
      \.[A-Za-z0-9_]+\.(?:xdmf|vtu|pvd|json|csv|png)
)$""",
    re.X,
)


def _io(exc: OSError, path) -> IOFailure:
    return IOFailure.from_oserror(exc, path)


def _staging_names(name: str) -> re.Pattern:
    """Sibling folders a run of folder ``name`` makes (and a killed one leaves): .<name>.new-<id>
    (the new run's files) and .<name>.old-<id> (the old ones, between the swap and their removal)."""
    return re.compile(rf"^\.{re.escape(name)}\.(?:new|old)-[0-9a-f]{{12}}$")


class RunFolder:
    """One run's output folder (see the module docstring).

    path    : the folder
    run_id  : the run's id (uuid4 hex)
    force   : go ahead when the folder holds files this package did not write (kept)
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
        self.stage = self.path  # where the files go: the staging folder once open() made it
        self._lock: int | None = None  # the marker's file descriptor, holding its lock

    @property
    def staged(self) -> bool:
        return self.stage != self.path

    # ------------------------------------------------------------------ 1. before any work
    def check(self) -> None:
        """Refuse a path that is not a folder, one a live run owns, or a folder with files we did
        not write (InputError)."""
        p = self.path
        if p.exists() and not p.is_dir():
            raise InputError(f"output path {p} exists and is not a directory")
        if not p.exists():
            self._recover()
        if not p.is_dir():
            return
        self._refuse_if_owned()
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

    def _recover(self) -> None:
        """A run killed between the two renames of a swap without RENAME_EXCHANGE leaves no folder,
        its complete new run in .<name>.new-<id> (summary.json written last): put that in place."""
        pat = _staging_names(self.path.name)
        try:
            done = [
                self.path.parent / n
                for n in os.listdir(self.path.parent)
                if pat.match(n) and ".new-" in n and (self.path.parent / n / "summary.json").is_file()
            ]
        except OSError:
            return
        if len(done) == 1:
            with contextlib.suppress(OSError):
                done[0].rename(self.path)

    def _refuse_if_owned(self) -> None:
        """InputError when a live run holds the folder's marker locked (or, where locks are not
        supported, when the marker's pid is a live process of this machine)."""
        m = self.path / MARKER
        try:
            fd = os.open(m, os.O_RDONLY)
        except OSError:
            return  # no marker (or unreadable: open() will say)
        try:
            owner = _owner(fd)
        finally:
            os.close(fd)
        if owner is not None:
            raise InputError(_busy(self.path, owner))

    def _old_summary(self) -> dict:
        f = self.path / "summary.json"
        try:
            d = json.loads(f.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return {}
        return d if isinstance(d, dict) else {}

    # ------------------------------------------------------------------ 2. the run starts
    def open(self) -> None:
        """Create the folder, write and lock the RUNNING marker (InputError if a live run got there
        first, IOFailure if writing fails) and make the staging folder beside it."""
        if not self.path.is_dir():
            try:
                self.path.mkdir(parents=True)
                self.created = True
            except FileExistsError:
                pass
            except OSError as e:
                raise _io(e, self.path) from None
        m = self.path / MARKER
        try:
            fd = os.open(m, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as e:
            raise _io(e, m) from None
        try:
            if not _lock(fd):
                owner = _owner(fd)
                if owner is not None or not _lock(fd):  # (a run that ended in between: once more)
                    raise InputError(_busy(self.path, owner or {}))
            # written in place, not by an atomic rename: the lock is on this inode
            info = {
                "run_id": self.run_id,
                "pid": os.getpid(),
                "started": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            }
            os.ftruncate(fd, 0)
            os.pwrite(fd, (json.dumps(info) + "\n").encode(), 0)
        except InputError:
            os.close(fd)
            raise
        except OSError as e:
            os.close(fd)
            raise _io(e, m) from None
        self._lock = fd
        self._clear_leftovers()
        if self.path.is_symlink() or any((self.path / n).is_dir() for n in self.foreign):
            # a linked folder (the exchange would replace the link), or folders kept with --force
            # (they would have to move through the staging folder): written in place
            return
        stage = self.path.parent / f".{self.path.name}.new-{self.run_id[:12]}"
        try:
            stage.mkdir()
            self.stage = stage
        except OSError:
            self.stage = self.path  # a parent we cannot write to: in place (module docstring)

    def _clear_leftovers(self) -> None:
        """Staging folders of this folder's earlier runs that were killed (we hold the lock: no live
        run of this folder is using one)."""
        pat = _staging_names(self.path.name)
        with contextlib.suppress(OSError):
            for n in os.listdir(self.path.parent):
                if pat.match(n):
                    _rmtree(self.path.parent / n)

    def abandon(self) -> None:
        """The run ends with nothing (complete) to write: remove the staging folder and the marker
        (and the folder if we made it and it is empty).  Never raises: it runs while another error
        is on its way out."""
        if self.staged:
            _rmtree(self.stage)
            self.stage = self.path
        with contextlib.suppress(OSError):
            (self.path / MARKER).unlink()
        self._release()
        if self.created:
            with contextlib.suppress(OSError):
                self.path.rmdir()

    def _release(self) -> None:
        if self._lock is not None:
            with contextlib.suppress(OSError):
                os.close(self._lock)
            self._lock = None

    # ------------------------------------------------------------------ 3. what the new run replaces
    def clear_stale(self) -> list[str]:
        """The earlier run's files this run replaces, its summary.json first.  Staged, they go at
        the swap (finish); in place, they are removed now (IOFailure naming the file)."""
        order = sorted(set(self.stale) - {MARKER}, key=lambda n: n != "summary.json")
        if not self.staged:
            for n in order:
                _unlink(self.path / n)
        return order

    # ------------------------------------------------------------------ 4. write, swap
    def write(self, name: str, writer, *args, **kw) -> Path:
        """``writer(stage / name, *args, **kw)`` with OSError turned into IOFailure naming the file
        the run is writing (its place in the folder, not the staging folder's)."""
        p = self.stage / name
        try:
            return Path(writer(p, *args, **kw))
        except OSError as e:
            if isinstance(e, IOFailure):
                raise
            raise IOFailure(self.path / name, e.strerror or str(e) or type(e).__name__) from None

    def write_json(self, name: str, data) -> Path:
        return self.write(name, sio.write_json, data)

    def finish(self, summary: dict) -> Path:
        """Write summary.json (last) and put the new run in place of the old one: the swap when
        staged, else the marker's removal."""
        self.write_json("summary.json", summary)
        if self.staged:
            self._swap()
        else:
            _unlink(self.path / MARKER)
        self._release()
        return self.path / "summary.json"

    def _swap(self) -> None:
        """What stays (a checkpoint, kept foreign files) linked into the staging folder, then the
        staging folder and the folder exchanged in one rename, and the old contents removed."""
        stage, path = self.stage, self.path
        gone = set(self.stale) | {MARKER}
        try:
            names = os.listdir(path)
        except OSError as e:
            raise _io(e, path) from None
        for n in names:
            src, dst = path / n, stage / n
            if n in gone or os.path.lexists(dst):
                continue  # the old run's, the marker, or a name the new run wrote itself
            try:
                _link_or_copy(src, dst)  # (no folders here: open() writes in place then)
            except OSError as e:
                raise _io(e, src) from None
        old = path.parent / f".{path.name}.old-{self.run_id[:12]}"
        try:
            if _exchange(stage, path):
                stage.rename(old)
            else:  # no atomic exchange here: two renames, a moment apart
                path.rename(old)
                stage.rename(path)
        except OSError as e:
            raise _io(e, path) from None
        self.stage = path
        _rmtree(old)


def check_checkpoint(path, out_dir=None) -> None:
    """Before the run: a checkpoint path must name a file the run can write (InputError, one line):
    not a folder, not one of the run's own outputs in its folder, and the nearest existing folder on
    its way writable (tried with a temporary file, removed at once; the run creates the folders
    below it).  A periodic checkpoint that fails later only warns (observers.Checkpointer)."""
    p = Path(path)
    if p.is_dir():
        raise InputError(f"checkpoint path {p} is a directory; give a file name, e.g. {p / 'state.npz'}")
    if out_dir is not None and _OURS.match(p.name):
        with contextlib.suppress(OSError):
            if p.parent.resolve() == Path(out_dir).resolve():
                raise InputError(f"checkpoint {p} is a file the run itself writes; choose another name")
    a = p.parent
    while not a.exists() and a != a.parent:
        a = a.parent
    if not a.is_dir():
        raise InputError(f"checkpoint path {p} cannot be created: {a} is not a directory")
    import tempfile

    try:
        fd, probe = tempfile.mkstemp(prefix=".solidshell-probe-", dir=a)
        os.close(fd)
        os.unlink(probe)
    except OSError as e:
        raise InputError(f"checkpoint path {p} cannot be written: {a}: {e.strerror or e}") from None


def _owner(fd: int) -> dict | None:
    """The marker's run when a live process holds it, else None.  With file locks: whether the lock
    is held; where the file system has none, whether the pid it names is alive here."""
    try:
        import fcntl

        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        fcntl.flock(fd, fcntl.LOCK_UN)
        return None
    except BlockingIOError:
        alive = True
    except (ImportError, OSError):
        alive = None  # no locks here: the pid decides
    try:
        info = json.loads(os.pread(fd, 4096, 0).decode("utf-8", "replace") or "{}")
    except (OSError, ValueError):
        info = {}
    info = info if isinstance(info, dict) else {}
    if alive is None:
        pid = info.get("pid")
        alive = isinstance(pid, int) and pid != os.getpid() and _pid_alive(pid)
    return info if alive else None


def _lock(fd: int) -> bool:
    """Take the marker's exclusive lock: True when taken (or when the file system has no locks),
    False when another process holds it."""
    try:
        import fcntl

        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        return True
    except BlockingIOError:
        return False
    except (ImportError, OSError):
        return True  # no locks here: _owner's pid test is the guard


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    except OSError:
        return False
    return True


def _busy(path: Path, owner: dict) -> str:
    pid = owner.get("pid", "?")
    since = f", started {owner['started']}" if owner.get("started") else ""
    return (
        f"output folder {path} is in use by a running solidshell run (pid {pid}{since}); "
        f"wait for it to end or choose another --out"
    )


def _exchange(a: Path, b: Path) -> bool:
    """Swap two paths in one step (Linux renameat2 RENAME_EXCHANGE); False where the system or file
    system has no such call (the caller renames twice)."""
    import ctypes
    import errno

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        fn = libc.renameat2
    except (OSError, AttributeError):
        return False
    fn.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    at_fdcwd, rename_exchange = -100, 2
    if fn(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):
        return False
    raise OSError(err, os.strerror(err), str(b))


def _link_or_copy(src: Path, dst: Path) -> None:
    """A hard link of a kept file into the staging folder (no copy of a large checkpoint), a copy
    where the file system has no links."""
    try:
        os.link(src, dst, follow_symlinks=False)
    except OSError:
        import shutil

        shutil.copy2(src, dst, follow_symlinks=False)


def _rmtree(p: Path) -> None:
    import shutil

    shutil.rmtree(p, ignore_errors=True)


def _unlink(p: Path) -> None:
    """Remove a file of the run folder if it is there (IOFailure naming it if that fails)."""
    try:
        p.unlink()
    except FileNotFoundError:
        pass
    except OSError as e:
        raise _io(e, p) from None
