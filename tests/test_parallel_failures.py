"""A failure on one MPI rank is a failure on every rank, never a deadlock.

Each case runs a small plastic block on two ranks in a process of its own (mpirun or mpiexec, with a time limit:
a deadlock shows as a timeout) and injects a failure on one rank only: the return map raising at that
rank's points, a callback (a file write) failing on rank 0, an error out of one rank's share of the
linear solve, the mesh cache's file written by rank 0 alone. The ranks must agree: a failed constitutive update or linear solve is a failed Newton
iteration, so every rank cuts the increment back and the run goes on to the same end; a failed
callback stops every rank with the same error.
"""
import pathlib
import subprocess
import textwrap

import launch
import pytest

COMMON = """
import logging, sys
logging.disable(logging.INFO)
from mpi4py import MPI
from comove_dolfinx import geometry
from comove_dolfinx.loads import Displacement, Fixed
from comove_dolfinx.mechanics import return_maps
from comove_dolfinx.mechanics.body import Body
from comove_dolfinx.mechanics.materials import J2, Hardening
from comove_dolfinx.mechanics.model import Model
from comove_dolfinx.solver import IncrementalSolver, StepSettings
comm = MPI.COMM_WORLD
md = geometry.rectangle(1.0, 0.5, 0.125, order=2, comm=comm, cache_dir=sys.argv[1])
body = Body(md, "plane_strain", J2(1000.0, 0.3, Hardening.linear(15.0, 100.0)))
m = Model(body, [Fixed("left"), Displacement("right", (0.05, 0.02))])
m.finalize(compiled_return=False)     # the return map in NumPy, where a failure is injected
solver = IncrementalSolver(m, StepSettings(n_increments=3, max_cutbacks=2))
def report(text):
    lines = comm.gather(f"rank {comm.rank}: {text}")
    if comm.rank == 0:
        print(chr(10).join(lines), flush=True)
"""

RETURN_MAP = COMMON + """
calls = [0]
j2 = return_maps.j2_return_points
def flaky(*args, **kw):
    calls[0] += 1
    if comm.rank == 1 and 4 <= calls[0] <= 9:      # longer than the step halvings of Newton
        raise RuntimeError("injected return-map failure")
    return j2(*args, **kw)
return_maps.j2_return_points = flaky
res = solver.run()
report(f"completed={res.completed} increments={len(res.increments)} "
       f"cutbacks={sum(i.cutbacks for i in res.increments)}")
"""

CALLBACK = COMMON + """
def write(model, inc):
    if comm.rank == 0 and inc.number == 2:
        raise OSError("injected: disk full")
try:
    solver.run([write])
    report("no error")
except OSError as err:
    report(f"OSError {err}")
"""

LINEAR_SOLVE = COMMON + """
from petsc4py import PETSc
class Flaky:
    # the real (collective) solve on every rank, then an error out of rank 1's part, once
    def __init__(self, ksp):
        self.ksp, self.calls = ksp, 0
    def solve(self, b, x):
        self.ksp.solve(b, x)
        self.calls += 1
        if comm.rank == 1 and self.calls == 3:
            raise PETSc.Error(76)
    def __getattr__(self, name):
        return getattr(self.ksp, name)
solver.newton.ksp = Flaky(solver.newton.ksp)
res = solver.run()
report(f"completed={res.completed} increments={len(res.increments)} "
       f"cutbacks={sum(i.cutbacks for i in res.increments)}")
"""


MESH_CACHE = """
import sys
from mpi4py import MPI
from comove_dolfinx import geometry
from comove_dolfinx.geometry import meshes
comm = MPI.COMM_WORLD
if comm.rank == 0:                   # rank 0 alone writes the cache: its write fails
    def full(*args, **kwargs):
        raise OSError("injected: disk full")
    meshes.gmsh.write = full
try:
    geometry.rectangle(1.0, 0.5, 0.25, order=2, comm=comm, cache_dir=sys.argv[1])
    text = "no error"
except geometry.MeshError as err:
    text = f"MeshError {'disk full' in str(err)}"
lines = comm.gather(f"rank {comm.rank}: {text}")
if comm.rank == 0:
    print(chr(10).join(lines), flush=True)
"""


def _run_two_ranks(tmp_path, script, *args):
    path = tmp_path / "case.py"
    path.write_text(textwrap.dedent(script))
    try:
        p = launch.run([path, tmp_path, *args], n=2, timeout=240)
    except subprocess.TimeoutExpired as err:
        pytest.fail(f"deadlock: the two ranks did not finish ({err.stdout!r})")
    lines = sorted(line for line in p.stdout.splitlines() if line.startswith("rank "))
    assert len(lines) == 2, p.stdout + p.stderr
    return p, [line.split(": ", 1)[1] for line in lines]


def test_return_map_failure_on_one_rank_cuts_back_on_both(tmp_path):
    p, (r0, r1) = _run_two_ranks(tmp_path, RETURN_MAP)
    assert p.returncode == 0, p.stderr
    assert r0 == r1
    assert "completed=True" in r0 and "cutbacks=0" not in r0


def test_callback_failure_on_rank_0_stops_both_with_its_error(tmp_path):
    _, (r0, r1) = _run_two_ranks(tmp_path, CALLBACK)
    assert r0 == r1 == "OSError injected: disk full"


def test_mesh_cache_failure_on_rank_0_is_every_rank_s_error(tmp_path):
    _, (r0, r1) = _run_two_ranks(tmp_path, MESH_CACHE)
    assert r0 == r1 == "MeshError True"


def test_linear_solve_failure_on_one_rank_cuts_back_on_both(tmp_path):
    p, (r0, r1) = _run_two_ranks(tmp_path, LINEAR_SOLVE)
    assert p.returncode == 0, p.stderr
    assert r0 == r1
    assert "completed=True" in r0 and "cutbacks=1" in r0



INTERRUPT = """
import sys
sys.path.insert(0, sys.argv[2])                    # the tests: the strip job of test_safety
from mpi4py import MPI
from test_safety import KickInNewton, _interrupted
comm = MPI.COMM_WORLD
steps, closed = _interrupted(monitor=KickInNewton(rank=1))
lines = comm.gather(f"rank {comm.rank}: interrupted steps={steps} closed={closed}")
if comm.rank == 0:
    print(chr(10).join(lines), flush=True)
"""


def test_ctrl_c_on_one_rank_stops_both_at_the_same_point(tmp_path):
    """A signal that reaches one rank only (here sent to itself in the middle of increment 3's
    Newton iterations) stops both ranks at the same iteration, with the same two increments
    written and the writers closed as interrupted, and no rank waits for ever in a collective call."""
    p, (r0, r1) = _run_two_ranks(tmp_path, INTERRUPT, pathlib.Path(__file__).resolve().parent)
    assert r0 == r1 == "interrupted steps=[1, 2] closed=(True, 2)", p.stdout + p.stderr
