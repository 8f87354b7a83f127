"""The info dict of an explicit run (summary.json's solver keys: public, never rename one)."""

from __future__ import annotations

import time

import numpy as np

from ..timestep import critical_time_step


def info(integ, ok: bool) -> dict:
    """summary.json's solver keys (public: never rename one)."""
    st, lim, last = integ.state, integ.lim, integ.state.last
    info = {
        "steps": int(st.step),
        "dt": float(st.dt),
        "dt_initial": float(st.dt_initial),
        "critical_time_step": float(lim.dt_crit),
        "critical_time_step_min": float(st.dtc_min),
        "time_step_rechecks": int(st.rechecks),
        "time_step_reductions": int(st.reductions),
        "critical_time_step_sheet": float(critical_time_step(lim.omega_el, integ.alpha)),
        "critical_step_method": lim.method,
        "omega_max": float(lim.omega),
        "time_step_estimate_s": float(lim.seconds),
        "time_step_force_evals": int(lim.n_evals),
        "safety": float(integ.s.safety),
        "t_final": float(integ.time_of(st.step)),
        "alpha": float(integ.alpha),
        "damping": integ.damping,
        "mass_scaling": float(integ.s.mass_scaling),
        "mass_scaling_mode": integ.s.mass_scaling_mode,
        "energy_balance_error": float(st.balance_err),
        "max_interpenetrated_nodes": int(st.max_interp),
        "wall_time_s": float(time.perf_counter() - integ.wall0),
        "element_steps_per_second": (
            float(integ.n_elem * integ.steps_done / integ.t_loop) if integ.t_loop > 0 and integ.steps_done else 0.0
        ),
        "converged": bool(ok),
        "steady_state_reached": integ.status == "steady",
        "final_kinetic_energy": float(st.last_ekin),
        "final_relative_residual": float(st.last_rel_res),
        "kinetic_energy": float(last.get("Ek", 0.0)),
        "strain_energy": float(last.get("Es", 0.0)),
        "external_work": float(last.get("Wext", 0.0)),
        "damping_dissipation": float(last.get("Edamp", 0.0)),
        "contact_energy": float(last.get("Ec", 0.0)),
        "contact_work": float(st.contact_work),
        "max_contact_nodes": int(st.max_contact),
        "max_contact_penetration": float(st.max_pen),  # deepest, over every step (p = |f|/k)
        "kinetic_resets": int(st.resets),
        "max_interpenetration_time": float(st.t_max_interp),
        "interpenetrated_nodes_last_sample": int(last.get("interp", 0)),
        "status": integ.status,
    }
    if integ.n_fric:
        info.update(
            {
                "friction": [float(m) for m in integ.fric_of],
                "friction_stiffness_ratio": float(integ.s.friction_stiffness),
                "friction_work": float(-st.fric_work),  # energy taken out by friction
                "friction_stick_energy": float(last.get("Et", 0.0)),  # of it, still in the stick springs
                "friction_dissipation": float(-st.fric_work - last.get("Et", 0.0)),
                "max_slipping_nodes": int(st.max_slip),
            }
        )
    if integ.self_contact:
        sc = integ.forces.selfc
        info.update(
            {
                "self_contact": "penalty",  # contact_self_penalty.py
                "self_contact_max_pairs": int(st.max_self),  # most vertex-triangle pairs in contact at a sample
                "self_contact_searches": int(sc.searches),  # candidate searches since the last step estimate
                # the closest two layers came in those passes [length] (None: never within h)
                "self_contact_min_distance": float(sc.min_gap) if np.isfinite(sc.min_gap) else None,
            }
        )
    if integ.quasi:
        info.update(
            {
                "thickness_strain_energy_jump": float(st.q_jump),
                "thickness_strain_switch_samples": int(st.q_samples),
                "thickness_strain_corner_switches": int(st.q_corners),
            }
        )
    if integ.relax and integ.bodies and integ.forces.augmentable:
        info.update(
            {
                "contact_augment_updates": int(st.augment_updates),  # contact_augment.py
                "contact_augment_energy_jump": float(st.augment_jump),
                # the deepest raw penetration of a node or face point at the last steady state (-1: none reached)
                "contact_augment_depth": float(st.augment_depth),
            }
        )
    if st.segments:
        info.update({"ledger_segments": int(st.segments) + 1, "remesh_energy_jump": float(st.remesh_energy_jump)})
    info.update(integ.info_dt)
    if integ.restarted_from is not None:
        info["restarted_from_step"] = int(integ.restarted_from)
    if integ.warnings:
        info["warnings"] = list(integ.warnings)
    return info
