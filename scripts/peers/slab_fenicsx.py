#!/usr/bin/python3
"""The seed's slab (seed 000 sec 4.2) solved with FEniCSx, for issue 22's
side-by-side benchmark (scripts/bench.sh): the same problem, mesh and
scheme as `scenarios/slab-1d.toml` in fdem.

Slab 1 m x 0.1 m x 0.1 m, k = 1 W/m/K, rho c = 100 J/m^3/K, T = 0 at
t = 0, T = 1 on x = 1, insulated elsewhere. Hexahedra of size h split in
6 Tet4 (dolfinx's box mesh), P1, lumped capacity (vertex quadrature, as
the scenario's `capacity = "lumped"`), backward Euler with dt, the step
matrix A = C/dt + K assembled once and the right-hand side C/dt T_old
plus the constant Dirichlet lifting by one matrix-vector product per
step: the cheapest per-step loop FEniCSx offers.

Prints one line per solver: the time loop's seconds per step (largest
over ranks), Krylov iterations per step, and the largest nodal error at
the end against the analytic series. With --fdem H5, also the largest
nodal error of fdem's temperatures in that output step file (its mesh
file next to it) against the same series, so both are compared at equal
error.

Run: mpirun -n P /usr/bin/python3 scripts/peers/slab_fenicsx.py --h 0.0125
"""

import argparse
import math
import time

import numpy as np
import ufl
from dolfinx import fem, mesh
from dolfinx.fem.petsc import assemble_matrix
from mpi4py import MPI
from petsc4py import PETSc

K, RHO_C, L = 1.0, 100.0, 1.0

SOLVERS = {
    "cg/jacobi": {"ksp_type": "cg", "pc_type": "jacobi"},
    "cg/gamg": {"ksp_type": "cg", "pc_type": "gamg"},
    "cg/hypre": {"ksp_type": "cg", "pc_type": "hypre"},
    "preonly/cholesky": {"ksp_type": "preonly", "pc_type": "cholesky"},
}


def analytic(x, t):
    """T(x, t) of the slab: insulated at x = 0, T = 1 at x = L, T0 = 0
    (separation of variables; 200 terms are far below the FE error)."""
    alpha = K / RHO_C
    s = np.zeros_like(x)
    for n in range(200):
        lam = (2 * n + 1) * math.pi / (2 * L)
        s += 4 * (-1) ** n / ((2 * n + 1) * math.pi) * np.cos(lam * x) * math.exp(-alpha * lam * lam * t)
    return 1.0 - s


def run(comm, h, dt, steps, name):
    n, m = int(round(L / h)), max(1, int(round(0.1 / h)))
    domain = mesh.create_box(
        comm, [np.array([0.0, 0.0, 0.0]), np.array([L, 0.1, 0.1])], [n, m, m], mesh.CellType.tetrahedron
    )
    V = fem.FunctionSpace(domain, ("Lagrange", 1))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    dx_lumped = ufl.dx(metadata={"quadrature_rule": "vertex", "quadrature_degree": 1})
    cap = (RHO_C / dt) * u * v * dx_lumped
    stiff = K * ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx
    dofs = fem.locate_dofs_geometrical(V, lambda x: np.isclose(x[0], L))
    bc = fem.dirichletbc(PETSc.ScalarType(1.0), dofs, V)
    A = assemble_matrix(fem.form(cap + stiff), bcs=[bc])
    A.assemble()
    A_full = assemble_matrix(fem.form(cap + stiff))
    A_full.assemble()
    C = assemble_matrix(fem.form(cap))
    C.assemble()
    T = fem.Function(V)
    T.x.array[:] = 0.0
    x = T.vector
    # Constant lifting: -A_full g on the free rows (g = 1 on x = L).
    g = x.duplicate()
    g.set(0.0)
    owned = V.dofmap.index_map.size_local
    bc_owned = dofs[dofs < owned]
    g.setValuesLocal(bc_owned.astype(np.int32), np.ones(len(bc_owned)))
    g.assemble()
    lift = x.duplicate()
    A_full.mult(g, lift)
    lift.scale(-1.0)
    b = x.duplicate()
    ksp = PETSc.KSP().create(comm)
    ksp.setOperators(A)
    opts = SOLVERS[name]
    ksp.setType(opts["ksp_type"])
    pc = ksp.getPC()
    pc.setType(opts["pc_type"])
    if opts["pc_type"] == "cholesky" and comm.size > 1:
        pc.setFactorSolverType("mumps")
    ksp.setTolerances(rtol=1e-10, atol=1e-50, max_it=10000)
    if opts["ksp_type"] != "preonly":
        ksp.setInitialGuessNonzero(True)
    ksp.setUp()
    its = 0
    comm.Barrier()
    t0 = time.perf_counter()
    for _ in range(steps):
        C.mult(x, b)
        b.axpy(1.0, lift)
        arr = b.getArray()
        arr[bc_owned] = 1.0
        ksp.solve(b, x)
        its += ksp.getIterationNumber()
    elapsed = comm.allreduce(time.perf_counter() - t0, op=MPI.MAX)
    xs = V.tabulate_dof_coordinates()[:owned, 0]
    err = np.max(np.abs(x.getArray()[:owned] - analytic(xs, steps * dt)), initial=0.0)
    err = comm.allreduce(err, op=MPI.MAX)
    cells = domain.topology.index_map(3).size_global
    return cells, V.dofmap.index_map.size_global, elapsed / steps, its / steps, err


def fdem_error(path, time_s):
    """Largest nodal error of fdem's temperatures in step file `path`."""
    import os

    import h5py

    steps_dir = os.path.dirname(path)
    series = steps_dir[: -len("_steps")] + ".h5"
    with h5py.File(series) as f:
        xs = f["mesh/coordinates"][:, 0]
    with h5py.File(path) as f:
        t = f["fields/node/temperature"][:]
    return float(np.max(np.abs(t - analytic(xs, time_s))))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--h", type=float, default=0.1)
    p.add_argument("--dt", type=float, default=5e-4)
    p.add_argument("--steps", type=int, default=2000)
    p.add_argument("--solvers", default=",".join(SOLVERS))
    p.add_argument("--fdem", help="fdem's output step file at the end time")
    a = p.parse_args()
    comm = MPI.COMM_WORLD
    for name in a.solvers.split(","):
        cells, ndofs, per, its, err = run(comm, a.h, a.dt, a.steps, name)
        if comm.rank == 0:
            print(
                f"fenicsx h={a.h} ranks={comm.size} tets={cells} nodes={ndofs} solver={name} "
                f"steps={a.steps} per_step_us={per * 1e6:.1f} its_per_step={its:.2f} max_error={err:.3e}",
                flush=True,
            )
    if a.fdem and comm.rank == 0:
        print(f"fdem h={a.h} max_error={fdem_error(a.fdem, a.steps * a.dt):.3e}", flush=True)


if __name__ == "__main__":
    main()
