"""What watches a run without changing it: kept frames (with thinning), checkpoints, progress and
the steady-state test of dynamic relaxation (Section 4.2).  The integrator calls each only on the
steps where it is due (an integer or clock comparison per step: interfaces.Observer's ``due``).
What each gets: the frame store and the readings of the state (interfaces.FrameStore,
interfaces.RunReadings); a checkpoint the whole state, which it saves."""

from __future__ import annotations

import math
import time

from ...interfaces import FrameStore, RunReadings
from . import checkpoint
from .kernels import dot
from .state import State


# ----------------------------------------------------------------------------- frames
def keep_frame(st: FrameStore, t: float, D, k: int, shape, max_frames: int) -> None:
    """Append the frame (t, D) with its interval index k (-1: not an interval frame); past
    ``max_frames`` interval frames, keep the even-indexed ones and double the interval."""
    st.frame_t.append(float(t))
    st.frame_U.append(D.reshape(shape).copy())
    st.frame_k.append(int(k))
    if sum(1 for kk in st.frame_k if kk >= 0) > max_frames:
        keep = [i for i, kk in enumerate(st.frame_k) if kk < 0 or kk % 2 == 0]
        st.frame_t = [st.frame_t[i] for i in keep]
        st.frame_U = [st.frame_U[i] for i in keep]
        st.frame_k = [kk if kk < 0 else kk // 2 for kk in (st.frame_k[i] for i in keep)]
        st.frame_dt *= 2.0


def next_frame_time(st: FrameStore) -> float:
    """Simulated time [s] of the next interval frame (inf without interval frames)."""
    if st.frame_dt <= 0.0:
        return math.inf
    last = next((k for k in reversed(st.frame_k) if k >= 0), 0)
    return (last + 1) * st.frame_dt


# ----------------------------------------------------------------------------- checkpoints
class Checkpointer:
    """Writes the state every ``every`` steps, or (every None) every ``wall`` seconds of wall time,
    looked at every 100 steps (a checkpoint holds the kept frames: tens of MB on a big mesh).  A
    checkpoint that cannot be written (full disk, a folder gone) does not stop the run: the failure
    goes into ``warnings`` (the run's list) once per reason, naming the path, and the next one is
    tried when due."""

    def __init__(self, path, every, wall, extra=None, warnings=None):
        self.path, self.every, self.wall = path, every, wall
        self.extra = extra  # callable -> dict of extra arrays (an adaptive driver's state)
        self.t_last = time.perf_counter()
        self.warnings = warnings if warnings is not None else []
        self.failures = 0

    def due(self, step: int) -> bool:
        if not self.path:
            return False
        if self.every:
            return step % self.every == 0
        return step % 100 == 0 and time.perf_counter() - self.t_last >= self.wall

    def write(self, st: State) -> None:
        if not self.path:
            return
        try:
            checkpoint.save(self.path, st, self.extra() if self.extra else None)
        except OSError as e:
            self.failures += 1
            reason = getattr(e, "reason", None) or e.strerror or str(e)
            text = f"checkpoint {self.path} not written at step {st.step}: {reason}; the run goes on"
            if not any(
                w.startswith(f"checkpoint {self.path} not written") and w.endswith(f": {reason}; the run goes on")
                for w in self.warnings
            ):
                self.warnings.append(text)
        self.t_last = time.perf_counter()


# ----------------------------------------------------------------------------- progress
class Progress:
    """Calls ``callback(fraction, text)`` every ``every`` steps and at least every ``period`` seconds.
    The fraction never decreases; for a relaxation it is the larger of t/t_max and the log-progress of
    the residual and of E_kin/W_ext towards their tolerances (the smaller of the two, capped 0.99)."""

    def __init__(self, callback, every: int, s, period: float = 0.5):
        self.cb, self.every, self.period, self.s = callback, every, period, s
        self.t_last = time.perf_counter()
        self.frac = 0.0

    def due(self, step: int) -> bool:
        return step % self.every == 0 or time.perf_counter() - self.t_last >= self.period

    @staticmethod
    def _log_progress(x: float, tol: float) -> float:
        if not x > 0 or not math.isfinite(x):
            return 0.0 if not x == 0 else 0.99
        return min(0.99, max(0.0, math.log(max(x, tol)) / math.log(tol)))

    def fraction(self, st: RunReadings, step: int, end_step: int) -> float:
        f = step / max(end_step, 1)
        if self.s.relax:
            f = max(
                f,
                min(
                    self._log_progress(st.last_rel_res, self.s.tol_residual),
                    self._log_progress(st.last_rel_ke, self.s.tol_kinetic),
                ),
            )
        self.frac = max(self.frac, min(f, 1.0))
        return self.frac

    def report(self, st: RunReadings, step: int, end_step: int, t: float) -> None:
        frac = self.fraction(st, step, end_step)
        text = f"step {step}, t = {t:.4g} s, E_kin = {st.last_ekin:.3g}"
        if self.s.relax:
            text += f", residual {st.last_rel_res:.2e}"
        self.t_last = time.perf_counter()
        self.cb(frac, text)


# ----------------------------------------------------------------------------- steady state
def steady(st, s, P, vMv, E_floor) -> float | None:
    """E_kin / max(W_ext, E_strain, floor) at a check step when both it and the last residual are
    below their tolerances (steady), else None; the ratio is kept in ``st.last_rel_ke``."""
    Wext_c = st.w_ext_closed + dot(P, st.D - st.D0)
    Ek_c = 0.5 * vMv
    rel_ke = Ek_c / max(abs(Wext_c), abs(st.last.get("Es", 0.0)), E_floor)
    st.last_rel_ke = rel_ke
    if rel_ke < s.tol_kinetic and st.last_rel_res < s.tol_residual:
        st.last_ekin = Ek_c
        return rel_ke
    return None
