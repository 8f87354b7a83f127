"""The integrator state: everything that changes during a run, saved in checkpoints.

Positions are the dof vectors of Eq. (1) flattened to (6N,): ``D`` = D_n and ``D_prev`` = D_n-1 of
the central-difference scheme, Eq. (23).  Times in seconds, energies in the model's units.
"""

from __future__ import annotations

import copy
import math

import numpy as np

# name -> kind: "i" integer, "f" float, "a" array, "s" string
FIELDS = {
    # position and time: D_n, D_n-1, the step n and the step dt, t = t_base + (n - n_base) dt
    "D": "a",
    "D_prev": "a",
    "step": "i",
    "dt": "f",
    "n_base": "i",
    "t_base": "f",
    # step control: the estimate the run started from, re-checks, reductions, the smallest dt_crit
    # of the current mesh (start or remesh estimate and re-checks since)
    "omega_el": "f",
    "method": "s",
    "dt_initial": "f",
    "mode": "a",
    "rechecks": "i",
    "reductions": "i",
    "dtc_min": "f",
    # energy ledger: the current segment's references, totals carried across segments
    "D0": "a",
    "Ek0": "f",
    "Es0": "f",
    "Ec0": "f",
    "E_init": "f",
    "closed_change": "f",
    "w_ext_closed": "f",
    "remesh_energy_jump": "f",
    "segments": "i",
    "close_E": "f",
    "close_W": "f",
    "close_PD": "f",
    "damp_sum": "f",
    "ekin_max": "f",
    "balance_err": "f",
    "contact_work": "f",
    # Eq. (24) jumps (zero / empty unless thickness_strain = "quasi")
    "w_int": "f",
    "w_int_prev": "f",
    "es_prev": "f",
    "qflags": "a",
    "q_jump": "f",
    "q_samples": "i",
    "q_corners": "i",
    "q_F": "a",
    "q_D": "a",
    # Coulomb friction anchors (n_fric, N, 3) and work (empty / zero without a frictional body)
    "anchors": "a",
    "fric_work": "f",
    "max_slip": "i",
    # augmented-Lagrangian contact (contact_augment.py): the shifts lambda / k of the nodes
    # (n_bodies, N) and face points (n_bodies, P), (0, 0) before the first update; updates made and
    # the energy their changes of the contact potential booked apart; the deepest raw penetration
    # [length] at the last steady state, the shallowest one so far and the updates since it
    "shift_n": "a",
    "shift_q": "a",
    "shift_r": "a",  # the rim points' shifts (R,) (contact_rims.update), (0,) before the first update
    "augment_updates": "i",
    "augment_jump": "f",
    "augment_depth": "f",
    "augment_best": "f",
    "augment_stalls": "i",
    # watched maxima and the latest readings
    "max_interp": "i",
    "t_max_interp": "f",
    "max_contact": "i",
    "max_pen": "f",
    "max_self": "i",  # most self-contact pairs in contact at a sample
    "ek_prev_half": "f",
    "resets": "i",
    "last_ekin": "f",
    "last_rel_res": "f",
    # dampers (damping/): FIRE's mixing a and steps since its last freeze; the viscous alpha [1/s] now
    "fire_a": "f",
    "fire_n": "i",
    "damper_alpha": "f",
    # interval frames: the interval [s] (doubled at each thinning)
    "frame_dt": "f",
}
FRAMES = ("frame_t", "frame_U", "frame_k")  # lists: time [s], (N,6) U, interval index (-1: other)
TRANSIENT = ("good_D", "good_t", "last", "last_rel_ke")  # not checkpointed (as before the split)
# ``fingerprint`` (name -> digest) is saved as items of its own (checkpoint.save)


class State:
    """All of :data:`FIELDS`, the frame lists and the transient readings as attributes."""

    def __init__(self, **kw):
        self.frame_t, self.frame_U, self.frame_k = [], [], []
        self.good_D, self.good_t, self.last, self.last_rel_ke = None, 0.0, {}, math.inf
        self.fingerprint = {}  # per-item digests of what shaped the run (checkpoint.fingerprint)
        self.__dict__.update(kw)
        missing = [k for k in FIELDS if k not in self.__dict__]
        if missing:
            raise ValueError(f"state lacks {', '.join(missing)}")

    @property
    def n_nodes(self) -> int:
        return self.D.size // 6

    @property
    def t(self) -> float:
        """Simulated time [s] of D_n."""
        return self.t_base + (self.step - self.n_base) * self.dt

    def copy(self) -> State:
        return copy.deepcopy(self)

    def typed(self) -> State:
        """Scalars as Python int / float / str and arrays as owned copies (after a load)."""
        conv = {"i": int, "f": float, "s": str, "a": np.array}
        for k, kind in FIELDS.items():
            setattr(self, k, conv[kind](getattr(self, k)))
        self.frame_t = [float(t) for t in self.frame_t]
        self.frame_k = [int(k) for k in self.frame_k]
        self.frame_U = [np.array(u) for u in self.frame_U]
        return self
