#!/usr/bin/env python3
"""The free block of one nscd step, solved by solvers outside confpack.

Reads a folder written by `confpack-bench --micro --micro-pile PACKING --micro-dump DIR` (the
contact problem of a pile's step and MPRGP's solution; bench/microbench.hpp gives its columns) and
measures what docs/performance.md, "The preconditioner and the creep's solve", reports of it:

  - the problem: w = A r + q >= 0, r >= 0, r.w = 0, with A = G M^-1 G^T the Delassus operator and
    q = G v_free + c; how well the dumped solution satisfies it;
  - the free block A_FF (the rows with r > 0), its conditioning (Jacobi-scaled: the lowest
    eigenvalues and the largest);
  - conjugate gradients on A_FF r_F = -q_F to a relative residual of 1e-10: plain, Jacobi and
    symmetric Gauss-Seidel (two sweeps, what MPRGP's "sgs" applies), and the exact solve; then
    with symmetric Gauss-Seidel and the k softest modes against it deflated (solved exactly);
  - with petsc4py: the same in PETSc, timed, with symmetric SOR, incomplete Cholesky (0 to 2
    levels of fill) and smoothed aggregation over the contacts (GAMG on A_FF); then body-space
    algebraic multigrid (PETSc's GAMG, and hypre's BoomerAMG where PETSc has it) as the
    preconditioner of K_F = eps M + G_F^T G_F, whose inverse gives the regularised
    block's, (A_FF + eps I)^-1 = (I - G_F K_F^-1 G_F^T) / eps (Woodbury), GAMG with and without the
    grains' rigid-body motions (translations and rotations about the aggregates, from the centres)
    as its near-null space: CG iterations on K_F y = G_F^T (-q_F);
  - the whole problem (every row, its bounds) by truncated nonsmooth Newton multigrid (Graeser and
    Kornhuber): a symmetric projected Gauss-Seidel sweep, then a linear correction on the free rows
    (none, exact, or one V-cycle of GAMG or BoomerAMG), line-searched along its projection onto the
    bounds or along itself up to the first bound, whichever lowers the energy more; iterations to
    MPRGP's residual of 1e-10 (its projected gradient in Jacobi-scaled impulses, relative to the
    scaled q).

Usage: python3 bench/free_block.py DIR [--eps 1e-3] [--no-petsc] [--deflate K ...] [--tnnmg-iterations N]
(python3-numpy, python3-scipy; python3-petsc4py for PETSc's solvers).
"""
import argparse
import csv
import glob
import json
import os
import sys
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

TOL = 1e-10  # the solver's default tolerance (nscd_settings.hpp)


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], np.array(rows[1:], dtype=float)


def load(folder):
    with open(os.path.join(folder, "block.json")) as f:
        block = json.load(f)
    _, rows = read_csv(os.path.join(folder, "rows.csv"))
    _, bodies = read_csv(os.path.join(folder, "bodies.csv"))
    return block, rows, bodies


def operators(rows, bodies):
    """G (rows x dofs; the last body, the walls, left out: it does not move), M, M^-1, v_free, c, r
    and the bodies' centres. Three dofs a body where no row has a lever arm across its normal (spheres:
    |l x n| ~ 1e-16, no normal impulse turns a grain), six otherwise."""
    n = bodies.shape[0] - 1
    a = rows[:, 0].astype(int)
    b = rows[:, 1].astype(int)
    nrm, axn, bxn = rows[:, 2:5], rows[:, 5:8], rows[:, 8:11]
    c, r = rows[:, 11], rows[:, 12]
    dofs = 3 if max(abs(axn).max(), abs(bxn).max()) < 1e-12 else 6
    i, j, v = [], [], []
    # u_n = n.(v_b - v_a) + (l_b x n).w_b - (l_a x n).w_a
    for body, sign, arm in ((b, 1.0, bxn), (a, -1.0, axn)):
        moving = np.flatnonzero(body != n)
        for d in range(3):
            i.append(moving)
            j.append(dofs * body[moving] + d)
            v.append(sign * nrm[moving, d])
            if dofs == 6:
                i.append(moving)
                j.append(dofs * body[moving] + 3 + d)
                v.append(sign * arm[moving, d])
    G = sp.csr_matrix((np.concatenate(v), (np.concatenate(i), np.concatenate(j))), shape=(rows.shape[0], dofs * n))
    inverse, mass = [], []
    for body in range(n):
        linear = sp.identity(3) * bodies[body, 0]
        angular = bodies[body, 1:10].reshape(3, 3)
        inverse.append(linear if dofs == 3 else sp.block_diag([linear, angular]))
        mass.append(linear / bodies[body, 0] ** 2 if dofs == 3 else sp.block_diag([linear / bodies[body, 0] ** 2,
                                                                                   np.linalg.inv(angular)]))
    Minv = sp.block_diag(inverse, format="csr")
    M = sp.block_diag(mass, format="csr")
    vfree = (bodies[:n, 10:13] if dofs == 3 else bodies[:n, 10:16]).reshape(-1)
    return G, M, Minv, vfree, c, r, bodies[:n, 16:19], dofs


def pcg_iterations(A, rhs, M=None):
    """CG iterations to ||A x - rhs|| <= 1e-10 ||rhs|| from x = 0 (scipy's cg, counted)."""
    count = [0]

    def tick(_):
        count[0] += 1

    x, info = spla.cg(A, rhs, tol=TOL, atol=0.0, maxiter=20000, M=M, callback=tick)
    return count[0], x, info


def sgs_operator(A):
    """Symmetric Gauss-Seidel of A as a preconditioner: z = (D + U)^-1 D (D + L)^-1 r."""
    D = sp.diags(A.diagonal())
    lower = sp.tril(A, format="csr")
    upper = sp.triu(A, format="csr")

    def apply(res):
        y = spla.spsolve_triangular(lower, res, lower=True)
        return spla.spsolve_triangular(upper, D @ y, lower=False)

    return spla.LinearOperator(A.shape, matvec=apply)


def deflated_iterations(A, rhs, precond, modes):
    """Deflated CG (Frank and Vuik): the coarse space of `modes` solved exactly, CG with
    `precond` on P A x = P b, P = I - A Z (Z^T A Z)^-1 Z^T; iterations to TOL."""
    Z = modes
    AZ = A @ Z
    E = Z.T @ AZ

    def project(v):
        return v - AZ @ np.linalg.solve(E, Z.T @ v)

    PA = spla.LinearOperator(A.shape, matvec=lambda v: project(A @ v))
    its, _, info = pcg_iterations(PA, project(rhs), precond)
    return its, info


def sgs_modes(A, count):
    """The `count` softest modes of A against symmetric Gauss-Seidel: A v = lambda M v with
    M = (D + L) D^-1 (D + U), the directions SGS-preconditioned CG is slowest on (dense: a few
    thousand rows)."""
    import scipy.linalg as la

    dense = A.toarray()
    lower = np.tril(dense)
    M = lower @ np.diag(1.0 / np.diag(dense)) @ lower.T
    return la.eigh(dense, M, subset_by_index=[0, count - 1])[1]


def petsc_contact_space(A_FF, rhs):
    """CG iterations and wall time (one thread) on A_FF r_F = rhs with PETSc's one-level
    preconditioners, symmetric SOR (what MPRGP's "sgs" applies) and incomplete Cholesky with 0, 1
    and 2 levels of fill, and with smoothed aggregation over the contacts (GAMG)."""
    out = {}
    for name, pc_type, levels in (("symmetric SOR", "sor", None), ("ICC(0)", "icc", 0), ("ICC(1)", "icc", 1),
                                  ("ICC(2)", "icc", 2), ("GAMG (smoothed aggregation over the contacts)", "gamg", None)):
        mat, ksp = petsc_solver(A_FF.tocsr(), "cg", pc_type)
        if levels is not None:
            ksp.getPC().setFactorLevels(levels)
        out[name] = timed_solve(ksp, mat, rhs)
    return out


def petsc_solver(A, ksp_type, pc_type):
    """PETSc's matrix of the CSR matrix A and a solver of `ksp_type` on it, preconditioned by `pc_type`
    ("hypre": BoomerAMG)."""
    from petsc4py import PETSc  # optional: imported only here

    A.sort_indices()
    mat = PETSc.Mat().createAIJ(size=A.shape, csr=(A.indptr, A.indices, A.data))
    ksp = PETSc.KSP().create()
    ksp.setOperators(mat)
    ksp.setType(ksp_type)
    pc = ksp.getPC()
    pc.setType(pc_type)
    if pc_type == "hypre":
        pc.setHYPREType("boomeramg")
    return mat, ksp


def timed_solve(ksp, mat, rhs):
    """Solves to TOL from zero: "iterations, wall time (setup)"."""
    ksp.setTolerances(rtol=TOL, atol=0.0, max_it=20000)
    x, b = mat.createVecs()
    b.setArray(rhs)
    start = time.perf_counter()
    ksp.setUp()
    setup = time.perf_counter() - start
    ksp.solve(b, x)
    total = time.perf_counter() - start
    its = ksp.getIterationNumber()
    converged = "" if ksp.getConvergedReason() > 0 else " (not converged)"
    return f"{its} iterations{converged}, {1e3 * total:.0f} ms ({1e3 * setup:.0f} ms setup)"


def petsc_multigrids(G_F, M, rhs, eps, centres, dofs):
    """CG iterations and wall time (one thread) on K_F y = rhs, preconditioned by PETSc's symmetric
    SOR (the one-level reference in the same library) or one V-cycle of each multigrid."""
    from petsc4py import PETSc  # optional: imported only here

    K = (eps * M + G_F.T @ G_F).tocsr()
    out = {}
    for name, pc_type, rigid in (("symmetric SOR (one-level)", "sor", False), ("GAMG", "gamg", False),
                                 ("GAMG, rigid-body near-null space", "gamg", True), ("BoomerAMG", "hypre", False)):
        if rigid and dofs != 3:
            out[name] = "only for bodies that do not turn"
            continue
        try:
            mat, ksp = petsc_solver(K, "cg", pc_type)
        except PETSc.Error:  # a PETSc built without hypre
            out[name] = "not in this PETSc"
            continue
        # Read by the preconditioner when it is set up (timed_solve), not before.
        mat.setBlockSize(dofs)
        if rigid:
            coords = PETSc.Vec().createWithArray(np.ascontiguousarray(centres.reshape(-1)))
            coords.setBlockSize(3)
            mat.setNearNullSpace(PETSc.NullSpace().createRigidBody(coords))
        out[name] = timed_solve(ksp, mat, rhs)
    return out


def projected_gauss_seidel(A, y, b, order):
    """One projected Gauss-Seidel sweep in `order` on min y.A y / 2 + b.y, y >= 0, A of unit diagonal
    (a loop over rows: no library sweeps with bounds)."""
    ptr, idx, val = A.indptr, A.indices, A.data
    for i in order:
        g = b[i] + val[ptr[i]:ptr[i + 1]] @ y[idx[ptr[i]:ptr[i + 1]]]
        y[i] = max(0.0, y[i] - g)


def projected_residual(A, y, b):
    """MPRGP's residual: the projected gradient's norm relative to b's, and the gradient."""
    g = A @ y + b
    return np.linalg.norm(np.where(y > 0.0, g, np.minimum(g, 0.0))) / np.linalg.norm(b), g


def tnnmg(A, b, correction, max_iterations):
    """Truncated nonsmooth Newton multigrid from y = 0: per iteration one symmetric projected
    Gauss-Seidel sweep, the linear correction of the free rows (y > 0) by `correction(A_FF, -g_F)`,
    then an exact line search along its projection onto y >= 0 or along itself up to the first
    bound, whichever lowers the energy more.
    Returns the iterations to TOL (or max_iterations), the distinct free sets, the correction's
    wall time and the last residual."""
    n = A.shape[0]
    y = np.zeros(n)
    forward, backward = np.arange(n), np.arange(n)[::-1]
    sets, seconds, last, residual = 0, 0.0, None, 1.0
    for k in range(1, max_iterations + 1):
        projected_gauss_seidel(A, y, b, forward)
        projected_gauss_seidel(A, y, b, backward)
        residual, g = projected_residual(A, y, b)
        if residual < TOL:
            return k, sets, seconds, residual
        free = np.flatnonzero(y > 0.0)
        if last is None or not np.array_equal(free, last):
            sets, last = sets + 1, free
        d = np.zeros(n)
        start = time.perf_counter()
        if free.size:
            d[free] = correction(A[free][:, free].tocsr(), -g[free])
        seconds += time.perf_counter() - start
        # The correction projected onto y >= 0 (Graeser and Kornhuber), or as it is up to the first
        # bound it meets: a singular free block (pinacoids) gives corrections along its null space
        # that projection bends into stiff directions. The step that lowers the energy more is taken.
        best, gain = None, 0.0
        for step in (np.maximum(y + d, 0.0) - y, d):
            curvature = step @ (A @ step)
            falling = step < 0.0
            reach = np.min(-y[falling] / step[falling]) if falling.any() else np.inf
            alpha = min(-(g @ step) / curvature if curvature > 0.0 else np.inf, reach)
            if not np.isfinite(alpha) or alpha <= 0.0:
                continue
            lowered = -alpha * (g @ step) - 0.5 * alpha * alpha * curvature
            if lowered > gain:
                best, gain = alpha * step, lowered
        if best is not None:
            y = np.maximum(y + best, 0.0)  # the bound met, exactly
        residual, _ = projected_residual(A, y, b)
        if residual < TOL:
            return k, sets, seconds, residual
    return max_iterations, sets, seconds, residual


def exact_correction(A_FF, rhs):
    """(A_FF + 1e-8 I)^-1 rhs by a sparse LU: A_FF's diagonal is 1, so this is A_FF's own solve where
    it is regular. Where it is singular (points of one face contact) the shift gives a solve whose
    part along the null space is large, and which the step up to the first bound cuts (tnnmg)."""
    return spla.splu((A_FF + 1e-8 * sp.identity(A_FF.shape[0])).tocsc()).solve(rhs)


def petsc_vcycle(pc_type):
    """One V-cycle of PETSc's GAMG ("gamg") or hypre's BoomerAMG ("hypre") on A_FF, set up anew."""

    def apply(A_FF, rhs):
        mat, ksp = petsc_solver(A_FF, "preonly", pc_type)
        x, b = mat.createVecs()
        b.setArray(rhs)
        ksp.solve(b, x)
        return x.getArray().copy()

    return apply


def tnnmg_section(A, q, max_iterations, with_petsc):
    """TNNMG on the whole step's problem, Jacobi-scaled as MPRGP solves it, with each correction."""
    s = 1.0 / np.sqrt(A.diagonal())
    A_s = (sp.diags(s) @ A @ sp.diags(s)).tocsr()
    corrections = [("none (projected Gauss-Seidel alone)", lambda A_FF, rhs: np.zeros(rhs.size)),
                   ("exact (a sparse LU of A_FF + 1e-8 I)", exact_correction)]
    if with_petsc:
        corrections += [("one V-cycle of GAMG", petsc_vcycle("gamg")),
                        ("one V-cycle of BoomerAMG", petsc_vcycle("hypre"))]
    for name, correction in corrections:
        its, sets, seconds, residual = tnnmg(A_s, s * q, correction, max_iterations)
        state = "" if residual < TOL else f" (not converged: residual {residual:.1e})"
        print(f"TNNMG, correction {name}: {its} iterations{state}, {sets} free sets, "
              f"{seconds:.1f} s in the corrections", flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dir")
    ap.add_argument("--eps", type=float, default=1e-3, help="the regularisation of K_F (default 1e-3)")
    ap.add_argument("--no-petsc", action="store_true", help="leave out PETSc's solvers")
    ap.add_argument("--deflate", type=int, nargs="*", default=[10, 50, 100, 200],
                    help="numbers of softest modes to deflate (default 10 50 100 200; none: leave out)")
    ap.add_argument("--tnnmg-iterations", type=int, default=1000,
                    help="cap of the TNNMG runs (default 1000; 0: leave them out)")
    args = ap.parse_args()
    try:
        block, rows, bodies = load(args.dir)
    except (OSError, ValueError, KeyError) as e:
        sys.exit(f"free_block.py: {args.dir}: not a block folder ({e})")

    G, M, Minv, vfree, c, r, centres, dofs = operators(rows, bodies)
    A = (G @ Minv @ G.T).tocsr()
    q = G @ vfree + c
    w = A @ r + q
    scale = max(np.linalg.norm(q), 1e-300)
    print(f"block: {A.shape[0]} rows, {bodies.shape[0] - 1} bodies, dt {block['dt']}; "
          f"MPRGP {block['mprgp_iterations']} iterations, residual {block['mprgp_residual']:.2e}")
    print(f"solution: min r {r.min():.2e}, min w {w.min():.2e} (relative {w.min() / scale:.2e}), "
          f"|r.w| {abs(r @ w) / (np.linalg.norm(r) * scale):.2e} relative")

    free = np.flatnonzero(r > 1e-12 * r.max())
    A_FF = A[free][:, free].tocsc()
    rhs = -q[free]
    print(f"free block: {free.size} rows of {A.shape[0]}")

    d = A_FF.diagonal()
    S = sp.diags(1.0 / np.sqrt(d))
    B = (S @ A_FF @ S).tocsc()
    high = spla.eigsh(B, k=1, which="LA", return_eigenvectors=False)[0]
    low = np.sort(spla.eigsh(B, k=5, sigma=0.0, which="LM", return_eigenvectors=False))
    print(f"Jacobi-scaled A_FF: lowest eigenvalues {', '.join(f'{x:.2e}' for x in low)}; largest {high:.2f}; "
          f"condition {high / low[0] if low[0] > 0 else float('inf'):.2e}")

    # A face contact's points share its normal: with pinacoids the free block is singular (the split
    # of a face's load between its points is undetermined), and CG on it has no answer to converge
    # to at 1e-10. Only the regularised body-space problem is solved then.
    singular = low[0] < 1e-12 * high
    if singular:
        print("the free block is singular (points of one face contact share its normal): the solves on A_FF are "
              "left out, K_F's are not")
    else:
        exact = spla.spsolve(A_FF, rhs)
        print(f"exact solve: differs from MPRGP's impulses by {np.linalg.norm(exact - r[free]) / np.linalg.norm(r):.2e} "
              f"(relative)")
        A_FF = A_FF.tocsr()
        for name, precond in (("plain", None), ("Jacobi", sp.diags(1.0 / d)),
                              ("symmetric Gauss-Seidel", sgs_operator(A_FF))):
            its, _, info = pcg_iterations(A_FF, rhs, precond)
            print(f"CG, {name}: {its} iterations{'' if info == 0 else ' (not converged)'}")

        sgs = sgs_operator(A_FF)
        modes = sgs_modes(A_FF, max(args.deflate)) if args.deflate else None
        if modes is not None:
            # How many rows a mode moves: the participation ratio (sum v^2)^2 / (n sum v^4).
            shares = [np.sum(v**2) ** 2 / (v.size * np.sum(v**4)) for v in modes[:, :10].T]
            print(f"the 10 softest modes against SGS each spread over {100 * min(shares):.0f} to "
                  f"{100 * max(shares):.0f} % of the rows (participation ratio)")
        for k in args.deflate:
            its, info = deflated_iterations(A_FF, rhs, sgs, modes[:, :k])
            print(f"CG, symmetric Gauss-Seidel, the {k} softest modes deflated: {its} iterations"
                  f"{'' if info == 0 else ' (not converged)'}")

    petsc = not args.no_petsc and petsc_available()
    if petsc:
        if not singular:
            for name, result in petsc_contact_space(A_FF, rhs).items():
                print(f"CG on A_FF, PETSc, {name}: {result}")
        G_F = G[free]
        for name, result in petsc_multigrids(G_F, M, G_F.T @ rhs, args.eps, centres, dofs).items():
            print(f"CG on K_F (eps {args.eps:g}, {G_F.shape[1]} unknowns), {name}: {result}")
    if args.tnnmg_iterations > 0:
        tnnmg_section(A, q, args.tnnmg_iterations, petsc)


def petsc_available():
    """Whether petsc4py imports, said when not."""
    # Debian's python3-petsc4py finds its module through /usr/lib/petsc, a link that only PETSc's
    # development package sets up; without it, look in the real-scalar build's folder.
    sys.path += glob.glob("/usr/lib/petscdir/petsc*/*-real/lib/python3/dist-packages")
    try:
        import petsc4py  # noqa: F401
    except ImportError:
        print("petsc4py not installed: PETSc's solvers are left out (apt-get install python3-petsc4py)")
        return False
    return True


if __name__ == "__main__":
    main()
