"""The contact radius of 3D bodies along a meridian of the contact boundary (contact/radial.py,
``cm.ContactRadius``): a whole face in contact, the same on two ranks, the refusals, and the
reference cells' tables against basix. Hertz's sphere: tests/test_contact3d.py."""
import numpy as np
import pytest
from mpi4py import MPI

import comove_dolfinx as cm
from comove_dolfinx.contact import ContactError
from comove_dolfinx.probes import ProbeError

E, NU = 1000.0, 0.3


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return str(MPI.COMM_WORLD.bcast(str(tmp_path_factory.mktemp("meshes")), root=0))


def test_reference_cells_are_basix_numbering():
    """The tables of the 3D reference cells (vertices, edges, faces with their outward normals)
    are basix's, whose numbering dolfinx's topology follows."""
    import basix
    from comove_dolfinx.contact.profile import _CELLS_3D
    for name, (vertices, edges, faces) in _CELLS_3D.items():
        cell = getattr(basix.CellType, name)
        topology = basix.topology(cell)
        np.testing.assert_array_equal(basix.geometry(cell), vertices)
        assert [list(e) for e in edges] == [list(e) for e in topology[1]]
        assert [list(f) for f, _ in faces] == [list(f) for f in topology[2]]
        normals = [np.array(n, float) / np.linalg.norm(n) for _, n in faces]
        np.testing.assert_allclose(normals, basix.cell.facet_outward_normals(cell), atol=1e-15)


# -- a whole face in contact ----------------------------------------------------------------------
@pytest.mark.parametrize("hexahedra", [False, True], ids=["tetrahedra", "hexahedra"])
def test_a_whole_face_in_contact_has_the_face_as_its_radius(cache, hexahedra):
    """A block (1 x 1 x 0.5, P2) on its symmetry planes x = 0, y = 0, its top moved down by 1e-3
    in three increments onto the frictionless plane z = -5e-4 (Nitsche): out of contact in the
    first increment (radius 0), then uniaxially compressed, which the elements hold exactly, so
    the whole bottom is in contact at the uniform pressure E eps. The zone reaches the meridian's
    end: the radius along y = 0 is the current x of the bottom's far corner, 1 + u_x, and along
    x = 0 its current y, the same by symmetry; u_x = nu eps (to O(eps^2)), eps = 5e-4 / 0.5. Across
    the face, from the axis x = y = 0.5 (edges of two facets each), it is the distance from the
    axis of the point (1, 0.5, 0) displaced: |(0.5 + u_x, u_y)|."""
    md = cm.box(1.0, 1.0, 0.5, 0.25, order=2, cache_dir=cache, hexahedra=hexahedra)
    body = cm.Body(md, "solid", cm.Elastic(E, NU), degree=2)
    c = cm.Contact("bottom", cm.Plane((0.0, 0.0, -5e-4), (0.0, 0.0, 1.0)), method="nitsche")
    items = [cm.Fixed("left", component=0), cm.Fixed("front", component=1),
             cm.Displacement("top", -1e-3, component=2), c]
    probes = [cm.ContactRadius(c, "ax"), cm.ContactRadius(c, "ay", direction=(0.0, 1.0, 0.0)),
              cm.NodeDisplacement("corner", (1.0, 1.0, 0.0)), cm.NodeDisplacement("side", (1.0, 0.5, 0.0))]
    res = cm.Job(body, items, [cm.Step(3)], probes).run()
    assert res.completed, res.message
    assert res["ax"][0] == 0.0 and res["ay"][0] == 0.0
    last = res.last
    assert last["ax"] == pytest.approx(1.0 + last["corner_ux"], rel=1e-12)
    assert last["ay"] == pytest.approx(1.0 + last["corner_uy"], rel=1e-12)
    assert last["corner_ux"] == pytest.approx(NU * 5e-4 / 0.5, rel=2e-3)
    for origin in ((0.0, 0.0, 0.0), (0.5, 0.5, 0.0)):
        prof = c.meridian(origin=origin, direction=(1.0, 0.0, 0.0)).profile()
        assert np.all(np.diff(prof.X[:, 0]) > 0)
        np.testing.assert_allclose(prof.X[:, 1:], np.broadcast_to(origin[1:], (len(prof.X), 2)), atol=1e-12)
        np.testing.assert_allclose(prof.p, E * 5e-4 / 0.5, rtol=2e-3)
    across = c.radius(origin=(0.5, 0.5, 0.0), direction=(1.0, 0.0, 0.0))
    assert across == pytest.approx(np.hypot(0.5 + last["side_ux"], last["side_uy"]), rel=1e-12)


# -- a partial contact, on one and two ranks --------------------------------------------------------
def _indented(cache, comm):
    """A block (0.5 x 0.5 x 0.25, P2, size 0.05) on its symmetry planes x = 0, y = 0, its top moved
    down by 0.01 onto the rigid sphere of radius 2 that touches its bottom at the origin (penalty):
    a contact disc about the z axis, some three elements across; the history."""
    md = cm.box(0.5, 0.5, 0.25, 0.05, order=2, comm=comm, cache_dir=cache)
    body = cm.Body(md, "solid", cm.Elastic(E, NU), degree=2)
    c = cm.Contact("bottom", cm.Sphere((0.0, 0.0, -2.0), 2.0), gamma0=10.0)
    items = [cm.Fixed("left", component=0), cm.Fixed("front", component=1),
             cm.Displacement("top", -0.01, component=2), c]
    probes = [cm.ContactRadius(c, "ax"), cm.ContactRadius(c, "ay", direction=(0.0, 1.0, 0.0)),
              cm.ContactArea(c, "A")]
    res = cm.Job(body, items, [cm.Step(2)], probes).run()
    assert res.completed, res.message
    return res, c


def test_the_radius_of_a_partial_contact_lies_beyond_the_last_point_in_contact(cache):
    """Along each meridian the edge lies between the last sampled point in contact (p > 0) and the
    first one out, by their current distances from the axis, and the quarter disc of that radius
    has about the contact area (the area counts the facets cut by the edge by their quadrature
    points: within the band of one element, 0.05, of the radius)."""
    res, c = _indented(cache, MPI.COMM_WORLD)
    last = res.last
    for name, direction in (("ax", (1.0, 0.0, 0.0)), ("ay", (0.0, 1.0, 0.0))):
        a = last[name]
        prof = c.meridian(direction=direction).profile()
        r = np.hypot(prof.x[:, 0], prof.x[:, 1])
        inside, outside = r[prof.p > 0.0], r[prof.p == 0.0]
        assert inside.size and outside.size and inside.max() < outside.min()
        assert inside.max() <= a <= outside.min()
        assert np.sqrt(4.0 * last["A"] / np.pi) == pytest.approx(a, abs=0.05)


@pytest.mark.mpi
def test_the_radius_on_two_ranks_is_the_serial_one(cache):
    """The same job distributed over the ranks and, on every rank, on its own (COMM_SELF)."""
    par, _ = _indented(cache, MPI.COMM_WORLD)
    ser, _ = _indented(cache, MPI.COMM_SELF)
    for col in ("ax", "ay", "A"):
        np.testing.assert_allclose(par[col], ser[col], rtol=1e-7, atol=1e-12, err_msg=col)


# -- refusals --------------------------------------------------------------------------------------
def _block_job(cache, probe_of, boundary="bottom"):
    md = cm.box(1.0, 1.0, 0.5, 0.25, order=1, cache_dir=cache)
    body = cm.Body(md, "solid", cm.Elastic(E, NU), degree=1)
    c = cm.Contact(boundary, cm.Plane((0.0, -1.0, -1.0), (0.0, 0.0, 1.0)))
    return cm.Job(body, [cm.Fixed("top"), c], [cm.Step(1)], [probe_of(c)]), c


def test_a_meridian_off_the_boundary_edges_is_refused(cache):
    job, _ = _block_job(cache, lambda c: cm.ContactRadius(c, "a", direction=(1.0, 0.3, 0.0)))
    with pytest.raises(ProbeError, match=r"^ContactRadius 'a': no facet of the contact boundary has an edge on "
                       r"the meridian from the axis through \(0.0, 0.0, 0.0\) along \(0.0, 0.0, 1.0\) towards "
                       r"\(1.0, 0.3, 0.0\): give a half-plane that runs along edges of the boundary's mesh "
                       r"\(a symmetry plane's\)$"):
        job.run()


def test_a_facet_in_the_half_plane_is_refused(cache):
    job, _ = _block_job(cache, lambda c: cm.ContactRadius(c, "a"), boundary="front")
    with pytest.raises(ProbeError, match=r"ContactRadius 'a': a facet of the contact boundary lies in the "
                       r"half-plane of the meridian .*: give a half-plane across the boundary, along its edges$"):
        job.run()


def test_a_2d_body_is_refused(cache):
    md = cm.rectangle(1.0, 0.5, 0.25, order=1, cache_dir=cache)
    body = cm.Body(md, "plane_strain", cm.Elastic(E, NU), degree=1)
    c = cm.Contact("bottom", cm.Plane((0, 0), (0, 1)))
    with pytest.raises(ProbeError, match=r"^ContactRadius 'a' is not defined for a 2D body: use ContactLength "
                       r"\(the contact length\)$"):
        cm.Job(body, [cm.Fixed("top"), c], [cm.Step(1)], [cm.ContactRadius(c, "a")]).run()
    with pytest.raises(ContactError, match=r"^the contact radius is a 3D result, the body is 2D: ask for the "
                       r"contact length \(ContactLength\)$"):
        c.radius()


@pytest.mark.parametrize("kwargs, message", [
    (dict(origin=(0.0, 0.0)), r"origin = \(0.0, 0.0\): give 3 finite numbers \(a point on the axis\)"),
    (dict(axis=(0, 0, 0)), r"axis = \(0, 0, 0\): give 3 finite numbers, not all zero \(the axis's direction\)"),
    (dict(direction=(0.0, 0.0, -2.0)), r"direction = \(0.0, 0.0, -2.0\) is parallel to axis = \(0.0, 0.0, 1.0\): "
     r"give a direction across the axis"),
    (dict(direction="x"), r"direction = 'x': give 3 finite numbers, not all zero"),
    (dict(scale=float("nan")), r"scale = nan: give a finite number")])
def test_bad_meridians_are_refused_when_the_probe_is_made(kwargs, message):
    c = cm.Contact("bottom", cm.Plane((0, 0, 0), (0, 0, 1)))
    with pytest.raises(ProbeError, match=message):
        cm.ContactRadius(c, "a", **kwargs)
