"""The contact results (contact/outputs.py) against closed forms: Hertz's half-width and peak pressure,
the force balance of the pressure profile, the square-root edge, and the reaction of a supported face."""
import numpy as np
import pytest
from mpi4py import MPI

from comove_dolfinx.contact.outputs import ContactProfile, edge_fraction, gauss_points, peak_of, zones_of
from comove_dolfinx.probes import ProbeError

# the trapezoidal rule: numpy.trapezoid from NumPy 2 on, numpy.trapz before (gone from recent NumPy)
_trapezoid = getattr(np, "trapezoid", None) or np.trapz

R, E, NU, DEPTH, H = 1.0, 1000.0, 0.3, 0.02, 0.02


@pytest.fixture(scope="module")
def disc(tmp_path_factory):
    """The quarter of a cylinder R = 1 refined to H = 0.02 at the contact (a = 0.114: 5.7 elements)."""
    import comove_dolfinx as cm
    cache = MPI.COMM_WORLD.bcast(str(tmp_path_factory.mktemp("meshes")), root=0)
    return cm.quarter_disc(R, 0.1, H, 0.2, order=2, cache_dir=cache)


def _hertz_job(disc, method, gamma0, probes=(), writers=(), kind="plane_strain", depth=DEPTH):
    import comove_dolfinx as cm
    contact = cm.Contact("contact", cm.Plane((0.0, 0.0), (0.0, 1.0)), method=method, gamma0=gamma0)
    items = [cm.Fixed("xsym", component=0), cm.Displacement("top", -depth, component=1), contact]
    probes = [cm.ContactForce(contact, "force", component=None), cm.ContactEdges(contact, "edge"),
              cm.ContactLength(contact, "length"), cm.ContactPeak(contact, "peak"), *probes]
    job = cm.Job(cm.Body(disc, kind, cm.Elastic(E, NU), update="sr"), items, [cm.Step(2)], probes, writers=list(writers))
    res = job.run()
    assert res.completed, res.message
    return contact, res


def _trapezoid_force(contact) -> float:
    """The vertical force of the profile's traction p n_o + q t_o, integrated by the trapezoidal rule
    in the current arc length from the symmetry line (the first point's value) to the zone's edge
    (zero): independent of the residual's quadrature weights."""
    prof = contact.profile()
    (zone,) = contact.outputs.zones()
    on = prof.s <= zone.s_end
    t = prof.p * prof.normal[:, 1] + prof.q * prof.normal[:, 0]         # t_o = (-n_y, n_x): its y is n_x
    s = np.r_[zone.s_start, prof.s[on], zone.s_end]
    return float(_trapezoid(np.r_[t[0], t[on], 0.0], s))


@pytest.mark.mpi
@pytest.mark.parametrize("method, gamma0", [("penalty", 100.0), ("nitsche", 1000.0)])
def test_hertz_edge_and_peak(disc, method, gamma0):
    """Hertz line contact (plane strain) at the computed load P per unit length (twice the quarter's):
    a = sqrt(4 P R / (pi E*)), p0 = 2 P / (pi a). On this mesh (h = 0.02, a / h = 5.7) the half-width
    errors measured for both methods at gamma0 = 10, 100, 1000 (docs/api.md) lie within 5.7 % of a
    (0.32 h, the spacing of the quadrature points) and the peak's within 0.33 %; the support of the
    smoothed nodal pressure, one node past the edge, overshoots by 12 % (0.67 h) and fails. The zone
    starts at the symmetry line; its length is the current arc length to the edge (the face in
    contact is flat), less the points inside where a stiff gamma0 lets the discrete solution open."""
    contact, res = _hertz_job(disc, method, gamma0)
    P = 2.0 * res.last["force_fy"]
    a = np.sqrt(4.0 * P * R / (np.pi * E / (1.0 - NU ** 2)))
    p0 = 2.0 * P / (np.pi * a)
    edge = res.last["edge_max"]
    assert abs(edge - a) <= 0.06 * a
    assert abs(edge - a) < H / 3
    assert res.last["edge_min"] == pytest.approx(0.0, abs=1e-12)
    zones = contact.outputs.zones()
    if len(zones) == 1:
        assert res.last["length"] == pytest.approx(edge, rel=1e-4)
    else:
        assert res.last["length"] < edge and zones[0].s_start == 0.0
    assert res.last["peak"] == pytest.approx(p0, rel=0.004)
    # the profile: sorted along the boundary from the symmetry line, the same on every rank
    prof = contact.profile()
    assert np.all(np.diff(prof.S) > 0) and np.all(np.diff(prof.s) > 0)
    assert prof.X[0, 0] < prof.X[-1, 0] and np.all(prof.p >= 0.0)
    for arr in (prof.x, prof.p, prof.S):
        np.testing.assert_array_equal(MPI.COMM_WORLD.bcast(arr, root=0), arr)
    assert np.abs(prof.q).max() == 0.0            # frictionless


@pytest.mark.mpi
def test_profile_integrates_to_the_contact_force(disc):
    """The pressure profile, integrated along the current boundary by the trapezoidal rule, gives the
    contact force that the residual gives (F . e = -R_c(u; e)): within 0.35 % on this mesh (the rule's
    error at the square-root edge: 0.14 to 0.35 % at h = 0.02, 0.04 to 0.1 % at h = 0.01 over the
    methods and gamma0 of docs/api.md)."""
    contact, res = _hertz_job(disc, "penalty", 100.0)
    F = res.last["force_fy"]
    assert F > 0
    assert _trapezoid_force(contact) == pytest.approx(F, rel=3.5e-3)


@pytest.mark.mpi
def test_axisymmetric_profile_integrates_to_the_contact_force(disc):
    """The same section as a hemisphere (axisymmetric): the pressure per current area times 2 pi r,
    integrated along the current boundary, gives the total contact force (the hoop stretch r / R is
    in the pressure's area); Hertz's sphere a = (3 P R / (4 E*))^(1/3) to the mesh's 3 %."""
    contact, res = _hertz_job(disc, "nitsche", 100.0, kind="axisymmetric", depth=0.01)
    prof = contact.profile()
    (zone,) = contact.outputs.zones()
    on = prof.s <= zone.s_end
    r = np.r_[zone.start[0], prof.x[on, 0], zone.end[0]]
    t = np.r_[prof.p[0] * prof.normal[0, 1], prof.p[on] * prof.normal[on, 1], 0.0]
    F = _trapezoid(2.0 * np.pi * r * t, np.r_[zone.s_start, prof.s[on], zone.s_end])
    P = res.last["force_fy"]
    assert F == pytest.approx(P, rel=2e-3)
    a = (3.0 * P * R / (4.0 * E / (1.0 - NU ** 2))) ** (1.0 / 3.0)
    assert res.last["edge_max"] == pytest.approx(a, rel=0.03)


@pytest.mark.mpi
def test_pressure_is_current_without_a_writer(disc, mpi_tmp):
    """A probe reading the nodal pressure field gets the same values in a job without writers as in
    one whose VTK writer fills the field: the field is brought up to date when it is read. Its peak
    lies within one smoothing of the profile's (the lumped projection averages over a node's two
    facets: a few per cent below)."""
    import comove_dolfinx as cm
    peaks = []
    for writers in ([], [cm.VTK(mpi_tmp / "vtk")]):
        contact = cm.Contact("contact", cm.Plane((0.0, 0.0), (0.0, 1.0)), gamma0=100.0)
        items = [cm.Fixed("xsym", component=0), cm.Displacement("top", -DEPTH, component=1), contact]
        probes = [cm.Value("nodal_peak", lambda model, c=contact: c.boundary_values("pressure")[1].max()),
                  cm.ContactPeak(contact, "peak")]
        res = cm.Job(cm.Body(disc, "plane_strain", cm.Elastic(E, NU)), items, [cm.Step(2)], probes,
                     writers=writers).run()
        assert res.completed
        peaks.append(res["nodal_peak"])
        assert np.all(res["nodal_peak"] > 0.9 * res["peak"]) and np.all(res["nodal_peak"] < 1.02 * res["peak"])
    np.testing.assert_allclose(peaks[0], peaks[1], rtol=1e-12)
    # the field follows the state: read after a change of u without anything in between
    X, p = contact.boundary_values(contact.pressure)
    contact.u.x.array[:] *= 0.5
    contact.u.x.scatter_forward()
    X2, p2 = contact.boundary_values("pressure")
    assert p2.max() < 0.9 * p.max()
    with pytest.raises(cm.ContactError, match="'stress'"):
        contact.boundary_values("stress")


@pytest.mark.mpi
def test_reaction_of_a_face_is_its_own_supports(disc):
    """A quarter disc pressed by a displacement of its top face (y only), with symmetry on x = 0 (x
    only): the top face's supports exert no horizontal force (the corner node's x reaction is the
    symmetry line's), and their vertical force balances the contact force; a boundary without
    supports has no reaction to report."""
    import comove_dolfinx as cm
    contact, res = _hertz_job(disc, "penalty", 100.0, probes=[cm.Reaction("top"), cm.Reaction("xsym")])
    fy = res.last["force_fy"]
    assert res.last["top_fx"] == 0.0
    assert res.last["top_fy"] == pytest.approx(-fy, rel=1e-7)
    assert res.last["xsym_fy"] == 0.0
    assert abs(res.last["xsym_fx"] + res.last["force_fx"]) <= 1e-7 * fy
    with pytest.raises(ProbeError, match="no support"):
        _hertz_job(disc, "penalty", 100.0, probes=[cm.Reaction("contact")])


def _synthetic(pressure, L=0.2, h=0.02, n=4):
    """A flat boundary 0 <= x <= L of facets h with n Gauss points each, pressure(x) at the points."""
    x = (np.arange(int(round(L / h)))[:, None] * h + h * gauss_points(n)[None, :]).ravel()
    P = np.c_[x, np.zeros_like(x)]
    prof = ContactProfile(X=P, x=P, S=x, s=x, p=pressure(x), q=0 * x, gap=0 * x,
                          normal=np.tile([0.0, 1.0], (len(x), 1)), piece=np.zeros(len(x), dtype=np.int64))
    return prof, [((np.zeros(2), 0.0), (np.array([L, 0.0]), L))]


def test_square_root_edge_is_found_exactly():
    """p = c sqrt(a - x): p^2 is linear, so the edge is found to round-off wherever it falls between
    two points. Hertz's p0 sqrt(1 - x^2 / a^2): p^2 = p0^2 (a - x)(a + x) / a^2 bends over the fit's
    two facets, which moves the edge by less than a tenth of a facet; the parabola through three
    facets at the top of the ellipse finds p0 to 3e-4."""
    for a in (0.1013, 0.1100, 0.1149):
        (z,) = zones_of(*_synthetic(lambda x: 7.0 * np.sqrt(np.maximum(a - x, 0.0))))
        assert z.s_start == 0.0 and z.end[0] == pytest.approx(a, abs=1e-12)
        prof, ends = _synthetic(lambda x: 60.0 * np.sqrt(np.maximum(1.0 - x ** 2 / a ** 2, 0.0)))
        (z,) = zones_of(prof, ends)
        assert abs(z.end[0] - a) < 0.1 * 0.02
        assert peak_of(prof, ends, 4) == pytest.approx(60.0, rel=3e-4)


def test_holes_and_gaps():
    """A point without pressure inside the contact set splits it into two zones, each with its own
    edges, and the length is theirs (the hole left out); a pressure that does not fall towards the
    edge puts it half-way."""
    prof, ends = _synthetic(lambda x: 5.0 * np.sqrt(np.maximum(0.15 - x, 0.0)))
    (whole,) = zones_of(prof, ends)
    assert whole.end[0] == pytest.approx(0.15, abs=1e-12)
    prof.p[10] = 0.0
    z = zones_of(prof, ends)
    assert len(z) == 2 and prof.s[9] < z[0].s_end <= prof.s[10] and prof.s[10] < z[1].s_start < prof.s[11]
    assert z[1].end[0] == pytest.approx(0.15, abs=1e-12)
    assert z[0].length + z[1].length < whole.length
    assert edge_fraction([0.0, 0.01], [5.0, 4.0], 0.005) == 0.5           # rising towards the edge
    assert edge_fraction([0.0], [5.0], 0.005) == 0.5


def test_problem_file_peak_probe(disc, tmp_path):
    """A problem file's contact_peak probe gives the peak of the same job built in Python."""
    from comove_dolfinx import problem
    toml = tmp_path / "hertz.toml"
    toml.write_text(
        "[mesh]\nbuilder = 'quarter_disc'\nR = 1.0\nsize = 0.1\nsize_contact = 0.02\ncontact_zone = 0.2\n"
        "[body]\nkind = 'plane_strain'\nupdate = 'sr'\nmaterial = {E = 1000.0, nu = 0.3}\n"
        "[[items]]\ntype = 'fixed'\nboundary = 'xsym'\ncomponent = 0\n"
        "[[items]]\ntype = 'displacement'\nboundary = 'top'\nvalue = -0.02\ncomponent = 1\n"
        "[[items]]\ntype = 'contact'\nname = 'flat'\nboundary = 'contact'\n"
        "obstacle = {type = 'plane', point = [0.0, 0.0], normal = [0.0, 1.0]}\n"
        "[[steps]]\nn = 2\n[[probes]]\ntype = 'contact_peak'\nitem = 'flat'\ncolumn = 'p_max'\n")
    res = problem.build(problem.read(toml), MPI.COMM_WORLD).run()
    assert res.completed, res.message
    _, ref = _hertz_job(disc, "penalty", 100.0)
    assert res.last["p_max"] == pytest.approx(ref.last["peak"], rel=1e-9)
