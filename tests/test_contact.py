"""Contact with rigid obstacles against closed forms: Hertz, uniform pressure, Coulomb, lift-off."""
import numpy as np
import pytest
from mpi4py import MPI

from comove_dolfinx import geometry
from comove_dolfinx.contact import Circle, Contact, ContactError, Plane, Profile
from comove_dolfinx.loads import Displacement, Fixed, Pressure, Traction
from comove_dolfinx.mechanics.body import Body
from comove_dolfinx.mechanics.material_data import Elastic, Hardening
from comove_dolfinx.mechanics.materials import as_material
from comove_dolfinx.mechanics.model import Model
from comove_dolfinx.solver import IncrementalSolver, StepSettings

E, NU = 1000.0, 0.3


def _solve(model, n_increments=1, callbacks=(), max_cutbacks=3):
    model.finalize()
    res = IncrementalSolver(model, StepSettings(n_increments=n_increments, max_cutbacks=max_cutbacks)).run(callbacks)
    assert res.completed, res.message
    return res


@pytest.fixture(scope="module")
def hertz_mesh(tmp_path_factory):
    cache = tmp_path_factory.mktemp("meshes")
    return geometry.quarter_disc(1.0, 0.1, 0.01, 0.25, order=2, comm=MPI.COMM_WORLD,
                                 cache_dir=str(cache))


@pytest.mark.mpi
@pytest.mark.parametrize("method, theta", [("penalty", 0), ("nitsche", 0), ("nitsche", 1)])
def test_hertz_line_contact(hertz_mesh, method, theta):
    """Half-cylinder R = 1 (plane strain) pushed onto a rigid flat: half-width a = sqrt(4 P R/(pi E*))
    and peak pressure p0 = 2 P/(pi a) for the measured load P per unit length (docs/theory.md section 8.3).
    With a/R ~ 0.1 and ~10 elements across a, a mesh-level error of a few percent is expected."""
    c = Contact("contact", Plane((0.0, 0.0), (0.0, 1.0)), method=method, theta=theta,
                gamma0=100.0 if method == "penalty" else 10.0)
    m = Model(Body(hertz_mesh, "plane_strain", Elastic(E, NU)),
              [Fixed("xsym", component=0), Displacement("top", -0.0095, component=1), c])
    _solve(m, 2)
    P = 2.0 * c.force()[1]                               # full cylinder (the quarter carries half)
    Es = E / (1 - NU ** 2)
    a = np.sqrt(4 * P * 1.0 / (np.pi * Es))
    z = c.zone()
    assert 0.05 < a < 0.15                                # the intended regime a << R
    assert z.extent == pytest.approx(a, rel=0.04)
    c.update_fields()
    p_max = c.boundary_values(c.pressure)[1].max()
    assert p_max == pytest.approx(2 * P / (np.pi * a), rel=0.05)


@pytest.mark.mpi
@pytest.mark.parametrize("method, theta", [("penalty", 0), ("nitsche", -1)])
def test_hertz_against_a_rigid_cylinder(hertz_mesh, method, theta):
    """The half-cylinder R1 = 1 pressed onto a rigid cylinder R2 = 4 (a Circle obstacle, the two
    convex): Hertz with the effective radius R* = R1 R2 / (R1 + R2) = 0.8, half-width
    a = sqrt(4 P R* / (pi E*)) and peak pressure p0 = 2 P / (pi a) (docs/theory.md section 8.3)."""
    c = Contact("contact", Circle((0.0, -4.0), 4.0), method=method, theta=theta,
                gamma0=100.0 if method == "penalty" else 10.0)
    m = Model(Body(hertz_mesh, "plane_strain", Elastic(E, NU)),
              [Fixed("xsym", component=0), Displacement("top", -0.0095, component=1), c])
    _solve(m, 2)
    P = 2.0 * c.force()[1]                 # the halves' horizontal forces cancel in the whole
    Es = E / (1 - NU ** 2)
    a = np.sqrt(4 * P * 0.8 / (np.pi * Es))
    assert 0.05 < a < 0.15
    assert c.zone().extent == pytest.approx(a, rel=0.04)
    c.update_fields()
    assert c.boundary_values(c.pressure)[1].max() == pytest.approx(2 * P / (np.pi * a), rel=0.05)


ARC_GEO = """SetFactory("OpenCASCADE");
Circle(1) = {0, -4, 0, 3.99, Pi/2 - 0.1, Pi/2};
Circle(2) = {0, -4, 0, 3.99, Pi/2, Pi/2 + 0.1};
Physical Curve("face") = {2, 1};
"""


def test_a_profile_from_a_gmsh_curve(hertz_mesh, tmp_path):
    """The top of a rigid cylinder R = 4 given as two arcs of radius 3.99 in a Gmsh script (listed
    in the wrong order, so the chain must turn one), sampled every 0.02 and rounded by 0.01: its gap
    is the cylinder's to within the sampling's sag s^2 / (8 R) = 1.25e-5, and the half-cylinder of
    the Hertz test pressed onto it carries the load it carries on the exact Circle (0.1 % measured:
    40 segments, whose compiled contact term once grew exponentially with their number). Unknown
    names and missing files are refused in one line."""
    geo = tmp_path / "arc.geo"
    geo.write_text(ARC_GEO)
    prof = Profile.from_gmsh(geo, "face", radius=0.01, spacing=0.02)
    assert len(prof.points) == 41 and np.allclose(prof.points[20], (0.0, -0.01), atol=1e-12)
    rng = np.random.default_rng(0)
    th = rng.uniform(np.pi / 2 - 0.09, np.pi / 2 + 0.09, 200)
    x = np.c_[np.cos(th), np.sin(th)] * rng.uniform(4.0, 4.1, 200)[:, None] + (0.0, -4.0)
    exact = Circle((0.0, -4.0), 4.0).gap_np(x, np.zeros(2))
    sag = 0.02 ** 2 / (8 * 3.99)
    err = prof.gap_np(x, np.zeros(2)) - exact
    assert np.all(err >= -1e-12) and err.max() <= 1.05 * sag      # the chords lie inside the arc
    forces = []
    for obstacle in (Circle((0.0, -4.0), 4.0), prof):
        c = Contact("contact", obstacle, method="penalty", gamma0=100.0)
        m = Model(Body(hertz_mesh, "plane_strain", Elastic(E, NU)),
                  [Fixed("xsym", component=0), Displacement("top", -0.0095, component=1), c])
        _solve(m, 2)
        forces.append(c.force()[1])
    assert forces[1] == pytest.approx(forces[0], rel=3e-3)
    # the same obstacle from a problem file (its path relative to the file)
    from comove_dolfinx import problem
    toml = tmp_path / "p.toml"
    toml.write_text("[mesh]\nbuilder = 'rectangle'\nL = 1.0\nH = 0.5\nsize = 0.5\n[body]\nkind = 'plane_strain'\n"
                    "material = {E = 1.0, nu = 0.3}\n[[items]]\ntype = 'contact'\nboundary = 'top'\n"
                    "obstacle = {type = 'gmsh_profile', file = 'arc.geo', curve = 'face', radius = 0.01, "
                    "spacing = 0.02, motion = [0, -0.1]}\n")
    job = problem.build(problem.read(toml), MPI.COMM_WORLD)
    assert np.array_equal(job.items[0].obstacle.points, prof.points)
    with pytest.raises(ContactError, match="no physical curve named 'edge'; the named curves are face"):
        Profile.from_gmsh(geo, "edge", radius=0.01)
    with pytest.raises(ContactError, match="no such file"):
        Profile.from_gmsh(tmp_path / "none.geo", "face", radius=0.01)


@pytest.fixture(scope="module")
def block(tmp_path_factory):
    cache = tmp_path_factory.mktemp("meshes")
    return geometry.rectangle(2.0, 1.0, 0.25, order=2, comm=MPI.COMM_WORLD, cache_dir=str(cache))


@pytest.mark.mpi
@pytest.mark.parametrize("method", ["penalty", "nitsche"])
def test_block_uniform_pressure(block, method):
    """A block pressed by a follower pressure p onto a frictionless plane: the contact pressure is p
    everywhere and the contact force (from the residual) is p times the width, exactly."""
    p = 20.0
    out = {}
    for gamma0 in (10.0, 100.0):
        c = Contact("bottom", Plane((0.0, 0.0), (0.0, 1.0)), method=method, gamma0=gamma0)
        m = Model(Body(block, "plane_stress", Elastic(E, NU)),
                  [Fixed("left", component=0), Pressure("top", p), c])
        _solve(m, 1)
        c.update_fields()
        np.testing.assert_allclose(c.boundary_values(c.pressure)[1], p, rtol=1e-8)
        width = 2.0 + m.comm.allreduce(float(m.u.x.array.reshape(-1, 2)[:, 0].max()), op=MPI.MAX)
        F = c.force()
        assert F[1] == pytest.approx(p * width, rel=1e-9)        # the follower load on the widened top
        assert abs(F[0]) < 1e-9 * F[1]
        out[gamma0] = c.zone().max_penetration
        assert width > 2.0
    if method == "penalty":
        # penetration = p / gamma, gamma = gamma0 E / h: inversely proportional to the stiffness
        assert out[10.0] / out[100.0] == pytest.approx(10.0, rel=1e-3)
    else:
        assert max(out.values()) < 1e-8                          # Nitsche: consistent, no penetration


def _friction_block(block, mu, pull, relag=False, friction="lagged"):
    """A dead pressure p on top for t <= 1/2, then a pull on the right face (dead traction or
    displacement). Dead loads keep the equilibrium of the horizontal forces exact: friction = -pull."""
    p = 10.0
    press = Traction("top", (0.0, -p))
    press.ramp(lambda t: min(1.0, 2 * t))
    kind, amount = pull
    if kind == "traction":
        pull_item = Traction("right", (amount, 0.0))
    else:
        pull_item = Displacement("right", amount, component=0)
    pull_item.ramp(lambda t: max(0.0, 2 * t - 1))
    c = Contact("bottom", Plane((0.0, 0.0), (0.0, 1.0)), mu=mu, gamma0=100.0, relag=relag, friction=friction)
    m = Model(Body(block, "plane_stress", Elastic(E, NU)), [press, pull_item, c])
    forces, ux = [], {}          # read inside the increment: the slip increment is still visible

    def record(m, inc):
        forces.append(c.force())
        ux[round(inc.load, 9)] = m.u.x.array.reshape(-1, 2)[c.nodes, 0].copy()

    _solve(m, 8, [record])
    # bottom slip during the pull only, away from the pulled edge (where the shear concentrates and
    # a small zone slips first, as in Cattaneo-Mindlin partial slip)
    pull_slip = np.abs(ux[1.0] - ux[0.5])[c.outputs.boundary.X[:, 0] <= 1.0]      # the trailing half
    slip = m.comm.allreduce(float(pull_slip.max()) if pull_slip.size else 0.0, op=MPI.MAX)
    return slip, p, forces[-1]


@pytest.mark.mpi
def test_friction_stick_and_slip(block):
    mu = 0.3
    # stick: a pull of half the friction limit; the interface moves only within the stick spring
    N = 10.0 * 2.0
    slip, p, F = _friction_block(block, mu, ("traction", 0.5 * mu * N / 1.0))
    assert F[0] == pytest.approx(-0.5 * mu * N, rel=1e-8)         # equilibrium
    h = 0.25 * np.sqrt(2)                                         # cell diameter
    # within the stick spring q / gamma_t, gamma_t = gamma0_t E / h with gamma0_t = min(gamma0, 10)
    assert slip <= 2 * mu * p / (10.0 * E / h)
    # slip: a prescribed pull far beyond the elastic stick range; T / N -> mu with the pressure of
    # the previous increment (lagged, the default), exactly mu with the pressure re-lagged to
    # convergence, and with the current pressure (the coulomb law) to round-off
    slip, p, F = _friction_block(block, mu, ("displacement", 0.05))
    assert slip > 0.01                                            # it really slides
    assert -F[0] / F[1] == pytest.approx(mu, rel=1e-3)
    slip, p, F = _friction_block(block, mu, ("displacement", 0.05), friction="coulomb")
    assert -F[0] / F[1] == pytest.approx(mu, rel=1e-9)
    slip, p, F = _friction_block(block, mu, ("displacement", 0.05), relag=True)
    assert -F[0] / F[1] == pytest.approx(mu, rel=1e-6)


@pytest.mark.mpi
@pytest.mark.parametrize("method", ["penalty", "nitsche"])
def test_lagged_friction_with_a_moving_obstacle(block, method):
    """The floor rises under the block (top held in y) while the right face is pulled far: the
    block slides, and with the pressure lagged the friction is mu times the normal force of the
    previous increment, whatever the floor did since, to round-off: the lag pressure is the pressure
    that increment converged with. (Reading the lag state's body against the floor's new position
    would count the whole rise of an increment as pressure.)"""
    mu = 0.3
    pull = Displacement("right", 0.05, component=0)
    pull.ramp(lambda t: max(0.0, 2 * t - 1))
    c = Contact("bottom", Plane((0.0, 0.0), (0.0, 1.0), motion=(0.0, 0.01)), method=method, mu=mu,
                gamma0=100.0 if method == "penalty" else 10.0, friction="lagged")
    m = Model(Body(block, "plane_stress", Elastic(E, NU)), [Fixed("top", component=1), pull, c])
    forces = []
    _solve(m, 8, [lambda m, inc: forces.append(c.force())])
    normal = [f[1] for f in forces]
    assert all(b > a > 0 for a, b in zip(normal, normal[1:]))      # pressed harder each increment
    for prev, now in zip(forces[5:], forces[6:]):                  # sliding increments
        assert -now[0] == pytest.approx(mu * prev[1], rel=1e-9)


@pytest.mark.mpi
def test_lagged_friction_with_nitsche_and_plasticity(block):
    """The same slide with a J2 block that yields under the rising floor. Nitsche's pressure comes
    from the stress on the facets, which is evaluated from the converged state of the increment's
    start; the lag pressure is that of the last converged increment evaluated again from the state it
    was solved from (a FacetBase captured at the commit), so the lag state's normal force is the last
    increment's normal force to round-off and, the contact slipping everywhere, the friction is mu
    times it. Evaluated from the state after the commit instead (its facet fits describe the same
    solution only to the fit's error), the lag's normal force was up to 1.2e-3 off; following the
    current iterate, it would give mu times the current normal force, which moves by more than 1 %
    between the sliding increments."""
    mu = 0.3
    pull = Displacement("right", 0.05, component=0)
    pull.ramp(lambda t: max(0.0, 2 * t - 1))
    c = Contact("bottom", Plane((0.0, 0.0), (0.0, 1.0), motion=(0.0, 0.01)), method="nitsche", mu=mu,
                gamma0=10.0, friction="lagged")
    table = Hardening((0.0, 0.1), (8.0, 20.0))             # yields at 0.8 % strain; the floor gives 1 %
    m = Model(Body(block, "plane_stress", as_material(E, NU, "j2", table)), [Fixed("top", component=1), pull, c])
    forces, lags = [], []                                   # at each converged increment, before its commit
    _solve(m, 8, [lambda m, inc: (forces.append(c.force()), lags.append(c.lag_force()))])
    assert m.comm.allreduce(float(m.p.x.array.max(initial=0.0)), op=MPI.MAX) > 1e-3   # yielded
    normal = [f[1] for f in forces]
    assert all(n > 0 for n in normal)
    # the lag state of each increment is the previous increment, pressure included
    assert lags[0][1] == 0.0
    for prev, lag in zip(forces, lags[1:]):
        assert lag[1] == pytest.approx(prev[1], rel=1e-12) and abs(lag[0]) < 1e-12 * prev[1]
    # the normal force moves between sliding increments (up as the floor rises, down where the
    # block flows plastically), so a friction that followed it would leave the band
    assert max(abs(b / a - 1) for a, b in zip(normal[5:], normal[6:])) > 0.01, normal
    for prev, now in zip(forces[5:], forces[6:]):                  # sliding increments
        assert -now[0] == pytest.approx(mu * prev[1], rel=1e-9)


@pytest.mark.mpi
@pytest.mark.parametrize("method", ["penalty", "nitsche"])
def test_cantilever_lift_off_length(tmp_path_factory, method):
    """Thin cantilever clamped at height d over a flat, dead load q per length: it touches down at
    s = (72 E I d / q)^(1/4) from the clamp (small deflection, docs/theory.md section 8.4) with a reaction q s/3
    there, and the rest lies flat, so the contact force is q (L - s) + q s/3 (h/s = 0.02: beam theory
    holds to a fraction of a percent). The front itself is a weak measure: beyond it the gap opens
    only as (s - x)^3 R/(6 E I) and the continuum spreads the reaction over about the depth h."""
    L, h, d, s_ref = 20.0, 0.2, 0.1, 10.0
    EI = E * h ** 3 / 12
    q = 72 * EI * d / s_ref ** 4
    md = geometry.rectangle(L, h, 0.1, order=2, comm=MPI.COMM_WORLD,
                            cache_dir=str(tmp_path_factory.mktemp("meshes")))
    c = Contact("bottom", Plane((0.0, -d), (0.0, 1.0)), method=method, gamma0=1.0)
    m = Model(Body(md, "plane_stress", Elastic(E, 0.0)), [Fixed("left"), Traction("top", (0.0, -q)), c])
    _solve(m, 2, max_cutbacks=12)
    s_force = 1.5 * (L - c.force()[1] / q)
    assert s_force == pytest.approx(s_ref, rel=5e-3)
    assert L - c.zone().extent == pytest.approx(s_ref, abs=1.5 * h)


def test_contact_input_errors(block):
    with pytest.raises(ContactError, match="mu"):
        Contact("bottom", Plane((0, 0), (0, 1)), mu=-0.1)
    with pytest.raises(ContactError, match="unknown"):
        Contact("bottom", Plane((0, 0), (0, 1)), method="lagrange")
    with pytest.raises(ContactError, match="theta"):
        Contact("bottom", Plane((0, 0), (0, 1)), theta=2)
    with pytest.raises(ContactError, match="friction = 'tresca' is unknown: choose coulomb"):
        Contact("bottom", Plane((0, 0), (0, 1)), mu=0.1, friction="tresca")
    with pytest.raises(ContactError, match="relag = True re-solves the lagged law"):
        Contact("bottom", Plane((0, 0), (0, 1)), mu=0.1, friction="coulomb", relag=True)
    with pytest.raises(ContactError, match="gamma0_t = -1.0"):
        Contact("bottom", Plane((0, 0), (0, 1)), mu=0.1, gamma0_t=-1.0)
    with pytest.raises(ContactError, match="radius"):
        Circle((0, 0), -1.0)
    c = Contact("bottom", Plane((0.0, 0.5), (0.0, 1.0)))        # the plane cuts through the block
    m = Model(Body(block, "plane_stress", Elastic(E, NU)), [c])
    m.finalize()
    with pytest.raises(ContactError, match="starts inside"):
        c.check_start()


@pytest.mark.mpi
@pytest.mark.parametrize("degree", [1, 2])
def test_boundary_fields_interpolate_like_dolfinx(tmp_path_factory, degree):
    """The contact output fields take a P1 field into their space in numpy (vertex values, edge
    midpoints as means): the same values as dolfinx's own interpolation, at every dof."""
    md = geometry.rectangle(2.0, 1.0, 0.25, order=degree, comm=MPI.COMM_WORLD,
                            cache_dir=str(tmp_path_factory.mktemp("meshes")))
    c = Contact("bottom", Plane((0.0, 0.0), (0.0, 1.0)))
    m = Model(Body(md, "plane_strain", Elastic(E, NU), degree=degree), [Fixed("top"), c])
    m.finalize()
    g = c.outputs.fields.p1_field
    g.x.array[:] = np.random.default_rng(3).random(g.x.array.size)
    expect = c.pressure.copy()
    expect.interpolate(g)
    dofs, a, b = c.outputs.fields.p1_to_s
    got = np.full_like(expect.x.array, np.nan)
    got[dofs] = 0.5 * (g.x.array[a] + g.x.array[b])
    assert np.abs(got - expect.x.array).max() <= 1e-15
