"""The energy balance of an explicit run (sampled every ``sample_every`` steps).

E_kin = 1/2 v_n.M.v_n with the central velocity v_n = (D_n+1 - D_n-1)/(2 dt); E_strain = model
energy at D_n; W_ext = P.(D_n - D_0) (dead loads, exact); E_damp = trapezoidal sum over steps of
alpha v_m.M.v_m dt; E_contact = penalty energy at D_n; W_f = friction work (central rule); J = the
Eq. (24) jumps of the quasi thickness strain (booked where a corner's branch flag switched, see
docs/explicit.md).  The balance error of a sample is

    |C + (E_kin - E_kin,0) + (E_strain - E_strain,0 - J) - W_ext + E_damp + (E_c - E_c,0) - W_f| / scale,

scale = max(|W_ext|, max E_kin, initial energy, |dE_strain|, floor).  A run is a sequence of ledger
*segments* (one per mesh): the references (subscript 0, and D_0 of W_ext) belong to the current
segment; C (``closed_change``) is the energy change E_end - E_0 of the closed segments and W_ext
includes their work, so the balance reads the whole run across a mesh change, whose own energy change
(E_after - E_before, with the loads' potential -P.D) is booked apart as ``remesh_energy_jump``.
"""

from __future__ import annotations

import numpy as np

from .kernels import dot


def energy_floor(P, Mf, free_idx, X0, omega_el) -> float:
    """Floor of the energy scale: the work of the loads over 1e-9 of the mesh size (so that the first
    samples, all energies ~0 and the imbalance at round-off, do not read as a 100 % error), and, with
    no load at all, the energy of a 1e-9 L vibration at omega_max (far above round-off)."""
    N = X0.shape[0]
    L_char = float(np.ptp(X0, axis=0).max()) if N > 1 else 1.0
    return max(
        1e-9 * float(np.abs(P).sum()) * L_char,
        0.5 * float(Mf[free_idx].sum()) * (1e-9 * L_char * omega_el) ** 2,
        1e-300,
    )


def book_jumps(st, Es, qf) -> None:
    """Eq. (24) is discontinuous where a corner's n_p.d_p crosses -mu: the stored thickness energy
    jumps with no work done.  Over a sample interval in which a branch flag changed, the jump is the
    change of the strain energy minus the work of the internal forces (trapezoidal rule, accumulated
    every step); it is booked (counted, reported) and kept out of the balance.  Intervals without a
    switch are smooth and checked as usual."""
    nsw = int(np.count_nonzero(qf != st.qflags))
    if nsw:
        st.q_jump += (Es - st.es_prev) - (st.w_int - st.w_int_prev)
        st.q_samples += 1
        st.q_corners += nsw
        st.qflags = qf
    st.es_prev, st.w_int_prev = Es, st.w_int


def external_work(st, P, D) -> float:
    """W_ext of the whole run: closed segments' plus P.(D - D_0) of the current one."""
    return st.w_ext_closed + dot(P, D - st.D0)


def balance_error(st, Ek, Es, Wext, Edamp, Ecn, Efric, E_floor) -> float:
    """The relative balance error of one sample (see the module docstring); updates the maximum."""
    bal = st.closed_change + (Ek - st.Ek0) + (Es - st.Es0 - st.q_jump) - Wext + Edamp + (Ecn - st.Ec0) + Efric
    scale = max(abs(Wext), st.ekin_max, st.E_init, abs(Es - st.Es0), E_floor)
    err = abs(bal) / scale
    st.balance_err = max(st.balance_err, err)
    return err


def close_segment(st) -> None:
    """Fold the current segment (its energy change close_E - E_0 and the run's external work close_W,
    read at the end of the last advance) into the carried totals."""
    st.closed_change += st.close_E - (st.Ek0 + st.Es0 + st.Ec0)
    st.w_ext_closed = st.close_W


def open_segment(st, Ek0, Es0, Ec0, D0, PD) -> None:
    """Start a segment at the current state: references at it, and the change of the mechanical
    energy E_kin + E_strain + E_contact - P.D since the last reading (close_E and close_PD, the same
    state on the previous mesh) booked as a remesh jump.  The loads' potential -P.D is in it because
    a remesh moves nodes (a settled new node sags under its load) and lumps the loads anew; the
    run's W_ext does not see either (it sums P.dD within segments)."""
    E_after = Ek0 + Es0 + Ec0
    st.remesh_energy_jump += (E_after - st.close_E) - (PD - st.close_PD)
    st.Ek0, st.Es0, st.Ec0, st.D0 = Ek0, Es0, Ec0, D0.copy()
    st.segments += 1
