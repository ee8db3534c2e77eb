"""The linear solver of Newton: a PETSc KSP under the options prefix ``comove_``.

Defaults: preonly + LU + MUMPS (a direct solve; the symbolic analysis is done at the first
factorisation and reused while the sparsity stays), MUMPS without its scaling (MUMPS_DEFAULTS), and
the tangent in the matrix type the solver takes (matrix_kind: PETSc's blocked BAIJ for an LU by MUMPS
or PETSc, AIJ otherwise). PETSc options under the prefix change them, from
the PETSC_OPTIONS environment variable or the command line (``-comove_pc_factor_mat_solver_type
petsc``, ``-comove_mat_mumps_icntl_7 5``, ``-comove_ksp_type gmres -comove_pc_type gamg``) or from
``NewtonSettings.petsc_options`` (keys without the prefix). The settings' options are put into
PETSc's global database only while this solver reads them (set-up and every solve: MUMPS and GAMG
read theirs at the factorisation, not at ``setFromOptions``) and removed afterwards, so two models
never share them. The iterative path (GMRES with algebraic multigrid, and the rigid motions of the
current configuration as the matrix's near-nullspace at every tangent) is krylov.py's.
"""
from __future__ import annotations

import re
from contextlib import contextmanager

from petsc4py import PETSc

from .. import compat
from ..checks import SolverOptionError, petsc_options_error
from ..mechanics.model import rigid_motions
from ..parallel import first_failure

PREFIX = "comove_"
DEFAULTS = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}
#: MUMPS's settings that differ from its own defaults, unless the settings' options or PETSc's
#: database (PETSC_OPTIONS) name them: no scaling (ICNTL(8) = 0). MUMPS's default (77) computes a
#: scaling of the rows and columns at every factorisation, 9 to 21 % of a factorisation of the
#: ring (1.4k to 45k dofs) and the plate (195k); every run of the stability map ends the same
#: without it (docs/performance.md, "The linear solver and its options"). ``-comove_mat_mumps_icntl_8 77``
#: restores it.
MUMPS_DEFAULTS = {"mat_mumps_icntl_8": 0}


class PETScError(RuntimeError):
    """A PETSc error of a linear solve in one line: its code and PETSc's own words."""


def petsc_reason(err: Exception) -> str:
    """PETSc's own words in one line: the last line of a PETSc error's message (its traceback of
    functions before it), without the rank's ``[0]``."""
    lines = [re.sub(r"^\[\d+\]\s*", "", line).strip() for line in str(err).splitlines()]
    lines = [line for line in lines if line]
    return lines[-1] if lines else str(err)


def refused(options: dict, err: Exception) -> SolverOptionError:
    """The error of options that PETSc refused at the solver's set-up, in one line naming the option
    and value that PETSc's message names (all the options given if it names none) and the fix."""
    why = petsc_reason(err)
    named = [(k, v) for k, v in options.items() if v is not None and re.search(
        rf"(?<![\w.-]){re.escape(_text(v))}(?![\w.-])", why)]
    shown = ", ".join(f"{k}={_text(v)}" for k, v in (named or options.items())) or "none in the settings"
    return SolverOptionError(f"PETSc refused the linear solver's option {shown} (prefix {PREFIX!r}; "
                             f"PETSc: {why}): check the name and value, or remove it (PETSC_OPTIONS too)")


def _text(value) -> str | None:
    """An option's value as PETSc reads it (None: a flag without value)."""
    if value is None:
        return None
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


@contextmanager
def pushed(options: dict):
    """``options`` (keys without the prefix) in PETSc's database under the prefix for the duration;
    whatever the database held before under those names is put back afterwards."""
    db = PETSc.Options()
    saved = {}
    for key, value in options.items():
        name = PREFIX + key.lstrip("-")
        saved[name] = db.getString(name) if db.hasName(name) else False
        db.setValue(name, _text(value))
    try:
        yield
    finally:
        for name, old in saved.items():
            db.delValue(name)
            if old is not False:
                db.setValue(name, old or None)


def with_defaults(options: dict) -> dict:
    """``options`` (keys without the prefix) and those of :data:`MUMPS_DEFAULTS` that neither they nor
    PETSc's database name (the options a solver pushes at each solve)."""
    out = dict(options)
    named = {str(key).lstrip("-") for key in options}
    db = PETSc.Options()
    for key, value in MUMPS_DEFAULTS.items():
        if key not in named and not db.hasName(PREFIX + key):
            out[key] = value
    return out


def make_ksp(comm, A: PETSc.Mat | None, options: dict) -> PETSc.KSP:
    """The KSP on A (none yet when None): the defaults, then the options of the database and
    ``options``."""
    why = petsc_options_error(options)
    if why is not None:
        raise SolverOptionError(why)
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix(PREFIX)
    if A is not None:
        ksp.setOperators(A)
    configure(ksp, options)
    return ksp


def configure(ksp: PETSc.KSP, options: dict) -> None:
    """The KSP's type and its preconditioner's: the defaults, then the options of the database
    and ``options`` (SolverOptionError if PETSc refuses one)."""
    ksp.setType(DEFAULTS["ksp_type"])
    pc = ksp.getPC()
    pc.setOptionsPrefix(ksp.getOptionsPrefix())
    pc.setType(DEFAULTS["pc_type"])
    pc.setFactorSolverType(DEFAULTS["pc_factor_mat_solver_type"])
    try:
        with pushed(options):
            ksp.setFromOptions()
    except PETSc.Error as err:
        raise refused(options, err) from None


#: the factorisations (PCFactorSetMatSolverType) that take PETSc's blocked matrix BAIJ in an LU
#: solve: there the assembly inserts one 2 x 2 block per pair of nodes instead of four entries,
#: which halves the cost of assembling the tangent (docs/performance.md, the linear solver). SuperLU_dist,
#: UMFPACK and the iterative solvers get dolfinx's default matrix (AIJ).
BLOCKED_FACTORS = ("mumps", "petsc")


def matrix_kind(ksp: PETSc.KSP) -> str | None:
    """The PETSc matrix type for the operator of ``ksp`` (its options already read): "baij" for an LU
    factorisation by MUMPS or PETSc, None (dolfinx's default, AIJ) for anything else."""
    pc = ksp.getPC()
    if ksp.getType() == "preonly" and pc.getType() == "lu" and \
            pc.getFactorSolverType() in BLOCKED_FACTORS:
        return "baij"
    return None


def make_solver(comm, a, options: dict) -> tuple[PETSc.KSP, PETSc.Mat, dict]:
    """(KSP, matrix, options): the KSP of :func:`make_ksp` under ``options`` with the defaults of
    :func:`with_defaults`, and as its operator a matrix for the bilinear form ``a`` of the type that
    solver takes (:func:`matrix_kind`); the options are those to push at each solve."""
    options = with_defaults(options)
    ksp = make_ksp(comm, None, options)
    A = compat.create_matrix(a, matrix_kind(ksp))
    ksp.setOperators(A)
    return ksp, A, options


#: the largest workspace the solver raises ICNTL(14) to on its own (per cent over the analysis's
#: estimate; MUMPS's default is 20)
MAX_WORKSPACE = 640
#: what MUMPS's commonest error codes (INFOG(1), its user guide's section 8) ask of the user
_WORKSPACE = ("its workspace was too small at {icntl_14} % over its estimate, the most the solver "
              "raises it to on its own (many delayed pivots: a nearly singular tangent?): raise "
              "-comove_mat_mumps_icntl_14 further")
MUMPS_HINTS = {
    -8: _WORKSPACE,
    -9: _WORKSPACE,
    -10: "the tangent is numerically singular (a rigid-body motion that no support or contact holds?)",
    -13: "it could not allocate its memory",
    -19: "its memory limit -comove_mat_mumps_icntl_23 is too low",
    -38: "a parallel analysis (-comove_mat_mumps_icntl_28 2) that this MUMPS was built without: drop it",
}


#: the MUMPS codes a factorisation with a larger workspace (ICNTL(14), per cent over its estimate)
#: cures: delayed pivots outgrew the estimate of the analysis
WORKSPACE_CODES = (-8, -9)
#: the codes no smaller increment cures: the machine's memory, the user's memory limit, the build
HOPELESS_CODES = (-13, -19, -38)


def mumps_code(ksp: PETSc.KSP) -> int:
    """MUMPS's INFOG(1) after the KSP's last factorisation (the same on every rank), or 0 (another
    solver, no error, or a petsc4py without the call)."""
    pc = ksp.getPC()
    try:
        if pc.getType() not in ("lu", "cholesky") or pc.getFactorSolverType() != "mumps":
            return 0
        return int(pc.getFactorMatrix().getMumpsInfog(1))
    except (AttributeError, PETSc.Error):
        return 0


def grow_workspace(ksp: PETSc.KSP, options: dict) -> int | None:
    """After MUMPS ran out of workspace (INFOG(1) = -8 or -9): ICNTL(14) doubled (to at least 20 %,
    at most :data:`MAX_WORKSPACE`) in ``options`` (the settings' options, keys without the prefix,
    pushed at every solve) and the factorisation dropped, so that the next solve analyses and
    factorises again with it (collective: INFOG is global, so every rank takes the same branch).
    Returns the new percentage, or None (another failure, or the workspace is at its largest)."""
    if mumps_code(ksp) not in WORKSPACE_CODES:
        return None
    pc = ksp.getPC()
    now = int(pc.getFactorMatrix().getMumpsIcntl(14))
    if now >= MAX_WORKSPACE:
        return None
    new = min(max(2 * now, 20), MAX_WORKSPACE)
    options["mat_mumps_icntl_14"] = new
    A, P = ksp.getOperators()
    pc.reset()                         # the factor goes; the operators must be set again
    ksp.setOperators(A, P)
    return new


def solve(ksp: PETSc.KSP, options: dict, rhs: PETSc.Vec, x: PETSc.Vec, comm) -> tuple[str | None, list]:
    """``ksp.solve(rhs, x)`` with ``options`` pushed; when MUMPS runs out of workspace, again with
    more (:func:`grow_workspace`) until it factorises or the workspace is at its largest. Returns
    (None, or PETSc's error if any rank raised one: the same on every rank; the workspaces raised
    to, per cent). A negative KSP reason without an error is the caller's to read."""
    grown = []
    if ksp.getConvergedReason() < 0:                 # the last solve failed (read by the caller)
        _fresh_pc(ksp, options)
    while True:
        err = None
        try:
            with pushed(options):
                ksp.solve(rhs, x)
        except PETSc.Error as e:
            err = PETScError(f"error code {e.ierr}: {petsc_reason(e)}")      # (one line)
        failure = first_failure(comm, err)
        if failure is not None:
            _fresh_pc(ksp, options)                  # on every rank, wherever PETSc raised
        if failure is not None or ksp.getConvergedReason() >= 0:
            return failure, grown
        pct = grow_workspace(ksp, options)
        if pct is None:
            return None, grown
        grown.append(pct)


def _fresh_pc(ksp: PETSc.KSP, options: dict) -> None:
    """``ksp`` set up again from ``options``, as :func:`make_ksp` set it up, with its operators,
    after a failed solve: a factorisation that failed (a tangent with NaN) is not redone for the
    next matrix, whose solve then fails in MUMPS's solve phase (INFOG(1) = -3), and a solve that
    PETSc cut short with an error leaves its preconditioner counting a pre-solve that never ended,
    so that from the second one on PETSc refuses every solve ("Cannot embed PCPreSolve() more than
    twice"): each smaller increment would fail for the first one's reason. Collective."""
    operators = ksp.getOperators()
    ksp.setPC(PETSc.PC().create(ksp.getComm()))
    configure(ksp, options)
    ksp.setOperators(*operators)


def factor_error(ksp: PETSc.KSP) -> str:
    """MUMPS's own account of a failed factorisation, "MUMPS INFOG(1) = code, INFOG(2) = detail" and
    what the code asks for, or "" (another solver, no error, or a petsc4py without the call)."""
    code = mumps_code(ksp)
    if code >= 0:
        return ""
    F = ksp.getPC().getFactorMatrix()
    detail = F.getMumpsInfog(2)
    hint = MUMPS_HINTS.get(code, "").format(icntl_14=F.getMumpsIcntl(14))
    return f"MUMPS INFOG(1) = {code}, INFOG(2) = {detail}" + (f": {hint}" if hint else "")


def is_direct(ksp: PETSc.KSP) -> bool:
    """A factorisation applied once (preonly with LU or Cholesky)."""
    return ksp.getType() == "preonly" and ksp.getPC().getType() in ("lu", "cholesky")


def rigid_body_modes(V, A: PETSc.Mat) -> PETSc.NullSpace:
    """The two translations and the in-plane rotation of the 2-D displacement space V (blocked,
    2 components per node; the rotation about the centroid, better conditioned), orthonormalised,
    as a PETSc null space on A's layout."""
    values = rigid_motions(V)[0]
    modes = []
    for k in range(3):
        vec = A.createVecRight()
        vec.array[:] = values[:, :, k].ravel()
        modes.append(vec)
    for k, vec in enumerate(modes):             # Gram-Schmidt (collective dots and norms)
        for prev in modes[:k]:
            vec.axpy(-prev.dot(vec), prev)
        vec.normalize()
    return PETSc.NullSpace().create(vectors=modes, comm=A.getComm())
