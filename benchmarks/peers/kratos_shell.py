"""KratosMultiphysics worker: a clamped isotropic shell under its own weight, solved statically with
geometric nonlinearity (corotational shell, Newton-Raphson with uniform load stepping).

Runs in the Python that has KratosMultiphysics (``.venv-kratos``, see ``benchmarks/peers/README.md``);
it imports nothing from solidshell.  ``kratos_launch.run_kratos`` feeds it one JSON problem on stdin
and reads one JSON answer from stdout (Kratos' own banner goes to stderr):

problem: nodes (N,3) [cm], quads (E,4) 0-based, counter-clockwise seen from +z; clamped (node
indices, all 6 dofs fixed); section {E [gf/cm^2], nu, h [cm]}; weight [gf/cm^2] acting along -z;
element (a Kratos element name); steps (uniform load increments); tol (relative residual), abs_tol
(residual norm [gf]);
max_iter; linear_solver (a Kratos solver_type); matrix (return the last tangent, CSR); initial
(optional {displacement (N,3), rotation (N,3) rotation vectors}: the state Newton starts from);
line_search (Kratos' LineSearchStrategy instead of plain Newton-Raphson).

answer: displacement (N,3) and rotation (N,3), converged, per-step Newton iterations, the wall
times of set-up and solve [s], the Kratos version, and (if asked) the tangent of the last Newton
iteration in CSR arrays with the fixed dofs' rows and columns removed (for a stability check).

The weight enters as a body force: nodal VOLUME_ACCELERATION (0, 0, -lambda) with DENSITY =
weight / h, so that the element's mass per area (DENSITY * h) times the acceleration is the weight
per area; lambda runs 1/steps, 2/steps, ..., 1.
"""

from __future__ import annotations

import contextlib
import json
import os
import sys
import time


def solve(p: dict) -> dict:
    import KratosMultiphysics as KM
    import KratosMultiphysics.LinearSolversApplication  # noqa: F401  (registers sparse_lu)
    import KratosMultiphysics.StructuralMechanicsApplication as SMA
    from KratosMultiphysics import python_linear_solver_factory as lsf

    KM.Logger.GetDefaultOutput().SetSeverity(KM.Logger.Severity.INFO if p.get("echo") else KM.Logger.Severity.WARNING)
    t0 = time.perf_counter()
    model = KM.Model()
    mp = model.CreateModelPart("shell")
    mp.SetBufferSize(2)
    for v in (KM.DISPLACEMENT, KM.ROTATION, KM.REACTION, KM.REACTION_MOMENT, KM.VOLUME_ACCELERATION):
        mp.AddNodalSolutionStepVariable(v)
    prop = mp.GetProperties()[1]
    sec = p["section"]
    prop.SetValue(KM.YOUNG_MODULUS, float(sec["E"]))
    prop.SetValue(KM.POISSON_RATIO, float(sec["nu"]))
    prop.SetValue(KM.THICKNESS, float(sec["h"]))
    prop.SetValue(KM.DENSITY, float(p["weight"]) / float(sec["h"]))
    # Kratos 10.x maps ShellThickElementCorotational3D4N to its MITC4 element, which takes the
    # through-thickness-integrated Reissner-Mindlin law; the thin element integrates a plane-stress law.
    thick = "Thick" in p["element"] and hasattr(SMA, "ReissnerMindlinShellElasticConstitutiveLaw")
    prop.SetValue(
        KM.CONSTITUTIVE_LAW,
        SMA.ReissnerMindlinShellElasticConstitutiveLaw() if thick else SMA.LinearElasticPlaneStress2DLaw(),
    )
    for i, (x, y, z) in enumerate(p["nodes"]):
        mp.CreateNewNode(i + 1, float(x), float(y), float(z))
    vu = KM.VariableUtils()
    for d, r in (("DISPLACEMENT", "REACTION"), ("ROTATION", "REACTION_MOMENT")):
        for c in "XYZ":
            vu.AddDof(KM.KratosGlobals.GetVariable(f"{d}_{c}"), KM.KratosGlobals.GetVariable(f"{r}_{c}"), mp)
    for e, q in enumerate(p["quads"]):
        mp.CreateNewElement(p["element"], e + 1, [int(i) + 1 for i in q], prop)
    clamped = [int(i) + 1 for i in p["clamped"]]
    for i in clamped:
        node = mp.Nodes[i]
        for d in ("DISPLACEMENT", "ROTATION"):
            for c in "XYZ":
                node.Fix(KM.KratosGlobals.GetVariable(f"{d}_{c}"))

    echo = int(p.get("echo", 0))

    def newton(scheme, tol, abs_tol, max_iter):
        lin = lsf.ConstructSolver(KM.Parameters(json.dumps({"solver_type": p.get("linear_solver", "sparse_lu")})))
        crit = KM.ResidualCriteria(tol, abs_tol)
        crit.SetEchoLevel(echo)
        bs = KM.ResidualBasedBlockBuilderAndSolver(lin)
        if p.get("line_search"):
            # Kratos' Newton with a line search along each Newton direction (secant on the
            # directional residual, step in [min_alpha, max_alpha])
            st = KM.LineSearchStrategy(
                mp,
                scheme,
                crit,
                bs,
                KM.Parameters(
                    json.dumps(
                        {
                            "max_iteration": max_iter,
                            "compute_reactions": False,
                            "reform_dofs_at_each_step": False,
                            "move_mesh_flag": True,
                            "max_line_search_iterations": 10,
                            "first_alpha_value": float(p.get("ls_first", 0.5)),
                            "second_alpha_value": float(p.get("ls_second", 1.0)),
                            "min_alpha": 0.05,
                            "max_alpha": 1.0,
                            "line_search_tolerance": 0.5,
                        }
                    )
                ),
            )
        else:
            st = KM.ResidualBasedNewtonRaphsonStrategy(mp, scheme, crit, bs, max_iter, False, False, True)
        st.SetEchoLevel(echo)
        st.Initialize()
        st.Check()
        return st

    def gravity(lam):
        vu.SetVariable(KM.VOLUME_ACCELERATION, KM.Array3([0.0, 0.0, -lam]), mp.Nodes)

    if p.get("initial"):
        # Start Newton from a given state (displacements and rotation vectors), set before the
        # strategy initialises the elements: the corotational transformation reads the nodal
        # ROTATION into its nodal orientations when it is initialised, so the start is consistent.
        for node, u, r in zip(mp.Nodes, p["initial"]["displacement"], p["initial"]["rotation"]):
            for buf in (0, 1):
                node.SetSolutionStepValue(KM.DISPLACEMENT, buf, KM.Array3([float(v) for v in u]))
                node.SetSolutionStepValue(KM.ROTATION, buf, KM.Array3([float(v) for v in r]))
        vu.UpdateCurrentPosition(mp.Nodes)

    tol, abs_tol, max_iter = float(p.get("tol", 1e-9)), float(p.get("abs_tol", 1e-30)), int(p.get("max_iter", 30))
    strategy = newton(KM.ResidualBasedIncrementalUpdateStaticScheme(), tol, abs_tol, max_iter)
    t_setup = time.perf_counter() - t0
    iters, converged = [], True
    t1 = time.perf_counter()
    steps = int(p["steps"])
    for k in range(1, steps + 1):
        lam = k / steps
        mp.CloneTimeStep(lam)
        mp.ProcessInfo[KM.STEP] = k
        gravity(lam)
        strategy.Solve()
        iters.append(int(mp.ProcessInfo[KM.NL_ITERATION_NUMBER]))
        if not strategy.IsConverged():
            converged = False
            break
    t_solve = time.perf_counter() - t1

    disp = [list(n.GetSolutionStepValue(KM.DISPLACEMENT)) for n in mp.Nodes]
    rot = [list(n.GetSolutionStepValue(KM.ROTATION)) for n in mp.Nodes]
    out = {
        "displacement": disp,
        "rotation": rot,
        "converged": converged,
        "iterations": iters,
        "load_factor": len(iters) / steps if converged else (len(iters) - 1) / steps,
        "seeded": bool(p.get("initial")),
        "wall_setup_s": t_setup,
        "wall_solve_s": t_solve,
        "kratos_version": KM.KratosGlobals.Kernel.Version(),
        "element": p["element"],
    }
    if p.get("matrix"):
        A = strategy.GetSystemMatrix()
        # dof ids of the fixed dofs: the block builder keeps them in the system with a unit-like
        # diagonal; the caller drops them before the stability check.
        names = [f"{d}_{c}" for d in ("DISPLACEMENT", "ROTATION") for c in "XYZ"]
        fixed = sorted(
            node.GetDof(KM.KratosGlobals.GetVariable(v)).EquationId
            for node in mp.Nodes
            for v in names
            if node.IsFixed(KM.KratosGlobals.GetVariable(v))
        )
        out["matrix"] = {
            "indptr": list(A.index1_data()),
            "indices": list(A.index2_data()),
            "data": list(A.value_data()),
            "n": A.Size1(),
            "fixed": fixed,
        }
    return out


def main():
    p = json.load(sys.stdin)
    # Kratos' banner and logger write to the C-level stdout: point fd 1 at stderr for the solve and
    # keep the original stdout for the one JSON answer.
    answer = os.fdopen(os.dup(1), "w")
    os.dup2(2, 1)
    with contextlib.redirect_stdout(sys.stderr):
        out = solve(p)
    answer.write(json.dumps(out))
    answer.flush()


if __name__ == "__main__":
    main()
