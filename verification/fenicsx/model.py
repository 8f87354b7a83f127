"""Geometrically nonlinear Naghdi (Reissner-Mindlin) shell in UFL for DOLFINx 0.5.2.

Runs under the SYSTEM python3 (Debian ``python3-dolfinx``), never under the project venv: it imports
nothing from ``solidshell``.  It reads one job file (JSON, written by ``crosscheck.py`` from a
solidshell mesh and section) and writes one result file (JSON):

    python3 verification/fenicsx/model.py JOB.json RESULT.json
    mpirun -n 2 python3 verification/fenicsx/model.py JOB.json RESULT.json

Model (flat reference mid-surface in the x-y plane, which every solidshell drape mesh is)
---------------------------------------------------------------------------------------
Unknowns: the mid-surface displacement u (3 components) and a rotation vector theta = (tx, ty, 0)
in the reference plane; the director is the unit vector d = R(theta) e3 (Rodrigues):

    d = cos|theta| e3 + sinc|theta| (ty, -tx, 0),

singular only at |theta| = pi (director upside down), unlike the spherical-angle parametrisation of
the FEniCS-Shells demos, which is singular at 90 degrees -- exactly where a drape hangs.
With F = I_32 + grad u (3x2) the Naghdi strains are (total Lagrangian, reference frame):

    membrane  e = (F^T F - I) / 2          bending  k = sym(F^T grad d)        shear  g = F^T d

(the reference is flat and d0 = e3, so the reference curvature and shear vanish).  The strain energy
per reference area is the uncoupled quadratic form of the paper's Eq. (7), with the resultant
rigidities C_m, C_b, C_t of ``solidshell.material`` (Table 1 for the fabric) acting on the Voigt
components in the material frame (x = warp at angle alpha from global X, y = weft):

    psi = 1/2 em.C_m.em + 1/2 kb.C_b.kb + 1/2 gs.C_t.gs,  em = (e_ww, e_ff, 2 e_wf), kb alike,
    gs = (g.a, g.b),  a = (cos alpha, sin alpha), b = (-sin alpha, cos alpha).

The director is inextensible, so the thickness modulus E_z of the solid-shell has no counterpart.
Loads are dead: gravity -lambda * weight_per_area * e_z per reference area and an optional line
force per reference length on a named edge.

Discretisation: Q2 (9-node) Lagrange for u and theta on the quadrilaterals of the solidshell gmsh
mesh, locking removed by partial selective reduced integration (PSRI, Arnold & Brezzi 1993;
Hale et al. 2018): bending with the full 3x3 Gauss rule, membrane + shear split as
alpha_e * (3x3) + (1 - alpha_e) * (2x2) with alpha_e = min(1, t_eff^2 / h_e^2), t_eff^2 =
12 * tr(C_b) / tr(C_m) the thickness of the isotropic plate with the same bending-to-membrane ratio
(for an isotropic section exactly h^2) and h_e the cell diameter.

Solver: PETSc SNES (newtonls with a backtracking line search by default) on the load factor lambda
from 0 to 1; a step that does not converge is retried with half the increment, a step that
converges in few iterations lets the next grow by 1.5.  The linear solves are MUMPS LU.  At the end
the inertia of the tangent (MUMPS Cholesky, Dirichlet rows replaced by 1 on the diagonal) counts its
negative eigenvalues: 0 means a stable equilibrium.
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np


def _fail(msg: str, code: int = 2):
    print(f"fenicsx model: {msg}", file=sys.stderr)
    sys.exit(code)


try:
    import dolfinx
    import dolfinx.fem.petsc as fpetsc
    import ufl
    from dolfinx import fem
    from dolfinx import mesh as dmesh
    from mpi4py import MPI
    from petsc4py import PETSc
except ImportError as exc:  # the one-line message crosscheck.py also gives
    _fail(f"DOLFINx is not available under {sys.executable} ({exc.name} missing)", 3)


COMM = MPI.COMM_WORLD


# ----------------------------------------------------------------------------- mesh
def build_mesh(job):
    """DOLFINx quadrilateral mesh from the solidshell nodes/quads (read on rank 0, distributed)."""
    m = job["mesh"]
    if COMM.rank == 0:
        X = np.asarray(m["nodes"], dtype=np.float64)
        q = np.asarray(m.get("quads") or [], dtype=np.int64).reshape(-1, 4)
        if m.get("tris"):
            _fail("triangles in the mesh: this model takes quadrilateral meshes only")
        if np.ptp(X[:, 2]) > 1e-12 * max(1.0, np.ptp(X[:, :2])):
            _fail("the reference mid-surface must be flat (z = const): this model takes flat meshes only")
        # solidshell quads are counter-clockwise; DOLFINx numbers quadrilateral vertices as a tensor
        # product (0, 1, 3, 2 around the cell)
        cells = q[:, [0, 1, 3, 2]]
        x = X[:, :2].copy()
    else:
        cells = np.empty((0, 4), dtype=np.int64)
        x = np.empty((0, 2), dtype=np.float64)
    domain = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.quadrilateral, 1))
    return dmesh.create_mesh(COMM, cells, x, domain)


class NodeMap:
    """Maps between the input (solidshell) node numbering and a vector Q1 space on this rank."""

    def __init__(self, msh, n_nodes, dim):
        self.V1 = fem.VectorFunctionSpace(msh, ("Lagrange", 1), dim=dim)
        gdofs = msh.geometry.dofmap.array.reshape(-1)
        vdofs = self.V1.dofmap.list.array.reshape(-1)
        # geometry and V1 use the same Q1 element, so cell-local numbering coincides
        orig = np.asarray(msh.geometry.input_global_indices, dtype=np.int64)
        self.dof_of_local = np.full(len(msh.geometry.x), -1, dtype=np.int64)
        self.dof_of_local[gdofs] = vdofs
        self.orig = orig
        self.n_nodes = n_nodes
        self.dim = dim
        nown = self.V1.dofmap.index_map.size_local
        self.owned = self.dof_of_local < nown

    def gather(self, f1):
        """Nodal values of the Q1 function f1 on rank 0 as an (n_nodes, dim) array (None elsewhere)."""
        vals = f1.x.array.reshape(-1, self.dim)[self.dof_of_local]
        parts = COMM.gather((self.orig[self.owned], vals[self.owned]), root=0)
        if COMM.rank != 0:
            return None
        out = np.full((self.n_nodes, self.dim), np.nan)
        for idx, v in parts:
            out[idx] = v
        return out

    def scatter(self, values):
        """Q1 function with the nodal values (n_nodes, dim) given on every rank."""
        f1 = fem.Function(self.V1)
        arr = f1.x.array.reshape(-1, self.dim)
        arr[self.dof_of_local] = np.asarray(values)[self.orig]
        f1.x.scatter_forward()
        return f1


def _interp_points(V):
    ip = V.element.interpolation_points
    return ip() if callable(ip) else ip


# ----------------------------------------------------------------------------- kinematics
def director(theta):
    """d = R(theta) e3 for an in-plane rotation vector theta = (tx, ty); smooth at theta = 0."""
    r2 = ufl.dot(theta, theta)
    small = ufl.lt(r2, 1e-6)
    r = ufl.sqrt(r2)
    # both branches are evaluated in the generated code; the ternary picks the finite one
    sinc = ufl.conditional(small, 1.0 - r2 / 6.0 + r2 * r2 / 120.0, ufl.sin(r) / r)
    cosr = ufl.conditional(small, 1.0 - r2 / 2.0 + r2 * r2 / 24.0, ufl.cos(r))
    return ufl.as_vector([sinc * theta[1], -sinc * theta[0], cosr])


def rotation_vector_from_director(d):
    """Inverse of :func:`director` on nodal arrays (N,3): theta = (tx, ty)."""
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    r = np.arccos(np.clip(d[:, 2], -1.0, 1.0))
    s = np.where(r > 1e-12, r / np.maximum(np.sin(r), 1e-300), 1.0)
    return np.column_stack([-d[:, 1] * s, d[:, 0] * s])


def strains(u, theta):
    I32 = ufl.as_matrix([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]])
    F = I32 + ufl.grad(u)
    d = director(theta)
    e = 0.5 * (F.T * F - ufl.Identity(2))
    k = 0.5 * (F.T * ufl.grad(d) + ufl.grad(d).T * F)
    g = F.T * d
    return e, k, g, d


def voigt(t, a, b):
    """(t_aa, t_bb, 2 t_ab) of a symmetric 2x2 tensor in the material frame (a = warp, b = weft)."""
    return ufl.as_vector([ufl.dot(a, t * a), ufl.dot(b, t * b), 2.0 * ufl.dot(a, t * b)])


# ----------------------------------------------------------------------------- problem
class Shell:
    def __init__(self, job):
        self.job = job
        self.msh = build_mesh(job)
        msh = self.msh
        n_nodes = len(job["mesh"]["nodes"])
        deg = int(job.get("degree", 2))
        cell = msh.ufl_cell()
        Ue = ufl.VectorElement("Lagrange", cell, deg, dim=3)
        Te = ufl.VectorElement("Lagrange", cell, deg, dim=2)
        self.W = fem.FunctionSpace(msh, ufl.MixedElement([Ue, Te]))
        self.w = fem.Function(self.W)
        self.map3 = NodeMap(msh, n_nodes, 3)
        self.map2 = NodeMap(msh, n_nodes, 2)
        sec = job["section"]
        Cm = ufl.as_matrix(sec["C_m"])
        Cb = ufl.as_matrix(sec["C_b"])
        Ct = ufl.as_matrix(sec["C_t"])
        al = float(sec.get("warp_angle_rad", 0.0))
        a = ufl.as_vector([np.cos(al), np.sin(al)])
        b = ufl.as_vector([-np.sin(al), np.cos(al)])
        u, theta = ufl.split(self.w)
        e, k, g, d = strains(u, theta)
        self.d_expr = d
        em, kb = voigt(e, a, b), voigt(k, a, b)
        gs = ufl.as_vector([ufl.dot(g, a), ufl.dot(g, b)])
        psi_m = 0.5 * ufl.dot(em, Cm * em)
        psi_b = 0.5 * ufl.dot(kb, Cb * kb)
        psi_s = 0.5 * ufl.dot(gs, Ct * gs)
        qf, qr = int(job.get("quad_full", 2 * deg)), int(job.get("quad_reduced", 2 * deg - 2))
        dx_f = ufl.dx(metadata={"quadrature_degree": qf})
        dx_r = ufl.dx(metadata={"quadrature_degree": qr})
        t2 = 12.0 * np.trace(np.asarray(sec["C_b"])) / np.trace(np.asarray(sec["C_m"]))
        he = ufl.CellDiameter(msh)
        psri = bool(job.get("psri", True))
        alpha = ufl.min_value(1.0, t2 / he**2) if psri else 1.0
        self.lam = fem.Constant(msh, PETSc.ScalarType(0.0))
        Pi = psi_b * dx_f + alpha * (psi_m + psi_s) * dx_f
        if psri:
            Pi += (1.0 - alpha) * (psi_m + psi_s) * dx_r
        # proximal (implicit gradient-flow) term c/2 |w - w_p|^2: c = 0 is the plain energy; c > 0
        # shifts the tangent by c (positive definite for c large enough) and limits each step
        # -- see solve() for how c is driven to 0 so that the end state is an equilibrium of Pi
        self.w_p = fem.Function(self.W)
        self.cprox = fem.Constant(msh, PETSc.ScalarType(0.0))
        up, thp = ufl.split(self.w_p)
        ell2 = float(job.get("prox", {}).get("length", 1.0)) ** 2
        Pi += 0.5 * self.cprox * (ufl.dot(u - up, u - up) + ell2 * ufl.dot(theta - thp, theta - thp)) * dx_r
        if job.get("gravity", False):
            Pi += self.lam * float(sec["weight_per_area"]) * u[2] * dx_f
        self.facet_sets = {}
        ll = job.get("line_load")
        fdim = msh.topology.dim - 1
        msh.topology.create_connectivity(fdim, msh.topology.dim)
        if ll:
            facets = self.facets_of_set(ll["set"])
            tags = dmesh.meshtags(msh, fdim, facets, np.full(len(facets), 1, dtype=np.int32))
            ds = ufl.Measure("ds", domain=msh, subdomain_data=tags, metadata={"quadrature_degree": qf})
            q = ufl.as_vector([float(c) for c in ll["force_per_length"]])
            Pi -= self.lam * ufl.dot(q, u) * ds(1)
        self.Pi = Pi
        self.F = ufl.derivative(Pi, self.w, ufl.TestFunction(self.W))
        self.J = ufl.derivative(self.F, self.w, ufl.TrialFunction(self.W))
        clamp = self.facets_of_set(job["clamped"])
        dofs = fem.locate_dofs_topological(self.W, fdim, clamp)
        self.bcs = [fem.dirichletbc(fem.Function(self.W), dofs)]
        self.Fform, self.Jform = fem.form(self.F), fem.form(self.J)
        self.Piform = fem.form(Pi)
        self.n_dofs = self.W.dofmap.index_map.size_global * self.W.dofmap.index_map_bs
        self.alpha_range = None

    def facets_of_set(self, name):
        """Boundary facets whose vertices all belong to the named solidshell node set."""
        m = self.job["mesh"]
        X = np.asarray(m["nodes"], dtype=np.float64)[np.asarray(m["node_sets"][name], dtype=np.int64)][:, :2]
        scale = max(1.0, float(np.max(np.abs(np.asarray(m["nodes"])[:, :2]))))
        tol = 1e-8 * scale

        def marker(x):
            out = np.zeros(x.shape[1], dtype=bool)
            for i in range(0, x.shape[1], 2048):
                xi = x[:2, i : i + 2048].T
                dist = np.min(np.linalg.norm(xi[:, None, :] - X[None, :, :], axis=2), axis=1)
                out[i : i + 2048] = dist < tol
            return out

        fdim = self.msh.topology.dim - 1
        return dmesh.locate_entities_boundary(self.msh, fdim, marker)

    # -- state exchange
    def set_state(self, U, D):
        u1 = self.map3.scatter(U)
        t1 = self.map2.scatter(rotation_vector_from_director(np.asarray(D, dtype=np.float64)))
        Vu, mu = self.W.sub(0).collapse()
        Vt, mt = self.W.sub(1).collapse()
        fu, ft = fem.Function(Vu), fem.Function(Vt)
        fu.interpolate(u1)
        ft.interpolate(t1)
        self.w.x.array[mu] = fu.x.array
        self.w.x.array[mt] = ft.x.array
        self.w.x.scatter_forward()

    def nodal_state(self):
        u1 = fem.Function(self.map3.V1)
        u1.interpolate(self.w.sub(0).collapse())
        d1 = fem.Function(self.map3.V1)
        d1.interpolate(fem.Expression(self.d_expr, _interp_points(self.map3.V1)))
        return self.map3.gather(u1), self.map3.gather(d1)

    def energy(self):
        return COMM.allreduce(fem.assemble_scalar(self.Piform), op=MPI.SUM)


class SNESProblem:
    """Residual and tangent callbacks for PETSc SNES (Dirichlet rows by lifting, as in DOLFINx demos)."""

    def __init__(self, shell):
        self.s = shell

    def F(self, snes, x, b):
        s = self.s
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        x.copy(s.w.vector)
        s.w.vector.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        with b.localForm() as bl:
            bl.set(0.0)
        fpetsc.assemble_vector(b, s.Fform)
        fpetsc.apply_lifting(b, [s.Jform], bcs=[s.bcs], x0=[x], scale=-1.0)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        fpetsc.set_bc(b, s.bcs, x, -1.0)

    def J(self, snes, x, A, P):
        A.zeroEntries()
        fpetsc.assemble_matrix(A, self.s.Jform, bcs=self.s.bcs)
        A.assemble()


def make_snes(shell, opts):
    prob = SNESProblem(shell)
    b = fpetsc.create_vector(shell.Fform)
    A = fpetsc.create_matrix(shell.Jform)
    snes = PETSc.SNES().create(COMM)
    snes.setFunction(prob.F, b)
    snes.setJacobian(prob.J, A)
    snes.setOptionsPrefix("shell_")
    snes.setType(opts.get("type", "newtonls"))
    popts = PETSc.Options()
    # the first Newton correction from a flat sheet stretches the mid-surface and raises the residual
    # by orders of magnitude before Newton settles: no divergence test on the residual norm
    if not popts.hasName("shell_snes_divergence_tolerance"):
        popts["shell_snes_divergence_tolerance"] = -1.0
    if not popts.hasName("shell_snes_linesearch_type"):  # the environment may override
        popts["shell_snes_linesearch_type"] = opts.get("linesearch", "basic")
    # rtol on the residual of the load increment; stol stops a Newton that has reached round-off
    # (its correction below 1e-10 of the state), where the residual can no longer fall by rtol
    snes.setTolerances(
        rtol=opts.get("rtol", 1e-8),
        atol=opts.get("atol", 1e-14),
        stol=opts.get("stol", 1e-10),
        max_it=opts.get("max_it", 25),
    )
    ksp = snes.getKSP()
    ksp.setType("preonly")
    pc = ksp.getPC()
    pc.setType("lu")
    pc.setFactorSolverType("mumps")
    snes.setFromOptions()
    return snes, A


def inertia(shell, A):
    """(negative, zero, positive) eigenvalue counts of the tangent at the current state."""
    A.zeroEntries()
    fpetsc.assemble_matrix(A, shell.Jform, bcs=shell.bcs)
    A.assemble()
    A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    ksp = PETSc.KSP().create(COMM)
    ksp.setOperators(A)
    ksp.setType("preonly")
    pc = ksp.getPC()
    pc.setType("cholesky")
    pc.setFactorSolverType("mumps")
    opts = PETSc.Options()
    opts["mat_mumps_icntl_13"] = 1  # inertia over the whole matrix in parallel (MUMPS manual)
    opts["mat_mumps_icntl_24"] = 1  # null pivots detected rather than failing
    pc.setFromOptions()
    pc.setUp()
    neg, zero, pos = pc.getFactorMatrix().getInertia()
    del opts["mat_mumps_icntl_13"], opts["mat_mumps_icntl_24"]
    return int(neg), int(zero), int(pos)


def _say(msg):
    if COMM.rank == 0:
        print(f"fenicsx model: {msg}", flush=True)


def _loadavg():
    try:
        with open("/proc/loadavg") as fh:
            return float(fh.read().split()[0])
    except (OSError, ValueError, IndexError):
        return float("nan")


def solve(job):
    t_start = time.perf_counter()
    load_start = _loadavg()  # wall times mean little without the machine's load (shared cores)
    shell = Shell(job)
    t_setup = time.perf_counter() - t_start
    _say(f"{job.get('name', '?')}: {shell.n_dofs} dofs, forms compiled in {t_setup:.1f} s")
    st = job.get("steps", {})
    dlam = float(st.get("initial", 0.05))
    dmin, dmax = float(st.get("min", 1e-5)), float(st.get("max", 0.25))
    grow_below = int(st.get("grow_below", 6))
    snes, A = make_snes(shell, job.get("snes", {}))
    if job.get("initial_state"):
        shell.set_state(job["initial_state"]["U"], job["initial_state"]["director"])
        lam = float(job["initial_state"].get("lambda", 1.0))
        dlam = 1.0 - lam
    else:
        lam = 0.0
    x = shell.w.vector.copy()
    x_prev = x.copy()
    history, n_newton, n_lin, n_fail = [], 0, 0, 0
    status = "converged"
    # proximal continuation (job["prox"], used for the drapes): every step minimises
    # Pi_lambda(w) + c/2 |w - w_prev|^2; c falls by `relax` after each easy step and grows by 4 after a
    # failed one; once lambda = 1 and c < c_min * c0 a last step with c = 0 makes the end state an
    # equilibrium of Pi itself (so the inertia test below speaks about the model, not the shift).
    prox = job.get("prox")
    c0 = float(prox.get("c0", 1.0)) if prox else 0.0
    c_min = c0 * float(prox.get("c_min_ratio", 1e-6)) if prox else 0.0
    relax = float(prox.get("relax", 0.5)) if prox else 1.0
    max_steps = int(st.get("max_steps", 2000))
    c = c0
    t0 = time.perf_counter()
    done = False
    while not done:
        if len(history) + n_fail >= max_steps:
            status = f"stopped after {max_steps} steps at lambda={lam:.6g}, c={c:.3g}"
            break
        target = min(1.0, lam + dlam) if lam < 1.0 - 1e-14 else 1.0
        shell.lam.value = target
        shell.cprox.value = c
        x_prev.copy(shell.w_p.vector)
        shell.w_p.x.scatter_forward()
        x_prev.copy(x)  # PETSc: a.copy(b) writes a into b
        snes.solve(None, x)
        its = snes.getIterationNumber()
        n_newton += its
        n_lin += snes.getLinearSolveIterations()
        reason = snes.getConvergedReason()
        if reason > 0 and np.all(np.isfinite(x.array)):
            lam = target
            x.copy(x_prev)
            history.append(dict(lam=lam, c=c, iterations=its, reason=int(reason)))
            _say(f"lambda {lam:.4f} c {c:.3g}: {its} iterations")
            if lam >= 1.0 - 1e-14 and c == 0.0:
                done = True
            if its <= grow_below:
                dlam = min(dmax, 1.5 * dlam)
                c *= relax
            if prox and lam >= 1.0 - 1e-14 and c < c_min:
                c = 0.0
        else:
            _say(f"lambda {target:.4f} c {c:.3g}: not converged (reason {reason}, {its} iterations)")
            n_fail += 1
            x_prev.copy(x)
            if prox:
                c = 4.0 * c if c > 0.0 else 4.0 * c_min
            if lam < 1.0 - 1e-14:
                dlam *= 0.5
                if dlam < dmin:
                    status = f"step to lambda={target:.6g} failed (reason {reason}) below the minimum increment"
                    break
            elif not prox:
                # at the full load (a restart from a given state) only the proximal shift can shorten
                # the step: without it a retry would repeat the failure
                status = f"the solve at lambda=1 failed (reason {reason}) and there is no proximal shift to raise"
                break
            if prox and c > 1e6 * c0:
                status = f"step to lambda={target:.6g} failed (reason {reason}) with the proximal shift at its maximum"
                break
    wall = time.perf_counter() - t0
    x_prev.copy(shell.w.vector)
    shell.w.x.scatter_forward()
    converged = status == "converged"
    result = dict(
        converged=converged,
        status=status,
        load_factor=lam,
        steps=len(history),
        failed_steps=n_fail,
        newton_iterations=n_newton,
        linear_solves=n_lin,
        wall_time_s=wall,
        setup_time_s=t_setup,
        n_dofs=int(shell.n_dofs),
        n_cells=int(shell.msh.topology.index_map(2).size_global),
        ranks=COMM.size,
        history=history,
        energy=shell.energy(),
        load_average=[load_start, _loadavg()],
        dolfinx_version=dolfinx.__version__,
    )
    if job.get("stability", True):
        t1 = time.perf_counter()
        neg, zero, pos = inertia(shell, A)
        result.update(
            negative_eigenvalues=neg,
            zero_eigenvalues=zero,
            stable=(neg == 0 and zero == 0),
            stability_time_s=time.perf_counter() - t1,
        )
    U, D = shell.nodal_state()
    if COMM.rank == 0:
        result["U"] = U.tolist()
        result["director"] = D.tolist()
    return result


def main(argv):
    if len(argv) != 3:
        _fail("usage: model.py JOB.json RESULT.json")
    with open(argv[1]) as fh:
        job = json.load(fh)
    res = solve(job)
    if COMM.rank == 0:
        with open(argv[2], "w") as fh:
            json.dump(res, fh)
        print(
            f"fenicsx model: {job.get('name', '?')}: converged={res['converged']} steps={res['steps']} "
            f"newton={res['newton_iterations']} wall={res['wall_time_s']:.2f}s dofs={res['n_dofs']} "
            f"ranks={res['ranks']}" + (f" negative_eigs={res.get('negative_eigenvalues')}"),
            flush=True,
        )
    return 0 if res["converged"] else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
