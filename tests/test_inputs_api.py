"""The API's constructors refuse bad values with the project's own error, in one line that names the
value and the fix: Newton's settings, the body, the items, the contact, the probes, the job's parts,
the mesh builders and the VTK writer's folder."""
import numpy as np
import pytest

import comove_dolfinx as cm
from comove_dolfinx.checks import SettingsError, SolverOptionError, mesh_cells
from comove_dolfinx.io.folder import FolderError
from comove_dolfinx.probes import ProbeError


@pytest.fixture(scope="module")
def strip():
    return cm.rectangle(1.0, 0.5, 0.25, cache_dir="meshes")


def _refused(error, call, *words):
    """``call()`` raises exactly ``error`` (or a subclass), in one line holding every one of ``words``."""
    with pytest.raises(error) as info:
        call()
    text = str(info.value)
    assert "\n" not in text, text
    for w in words:
        assert w in text, text
    return text


@pytest.mark.parametrize("kwargs, words", [
    (dict(rtol=-1), ["rtol = -1", ">= 0"]),
    (dict(atol=float("inf")), ["atol = inf"]),
    (dict(stol="1e-10"), ["stol = '1e-10'"]),
    (dict(rtol=0.0, atol=0.0), ["rtol = 0 and atol = 0"]),
    (dict(max_it=0), ["max_it = 0", "whole number >= 1"]),
    (dict(max_it=2.5), ["max_it = 2.5"]),
    (dict(max_it=True), ["max_it = True"]),
    (dict(divergence=0.0), ["divergence = 0.0", "> 0"]),
    (dict(backtracks=-1), ["backtracks = -1"]),
    (dict(free_its=1.0), ["free_its = 1.0"]),
    (dict(line_search="armijo"), ["line_search = 'armijo'", "'residual', 'energy' or 'none'"]),
    (dict(energy_eta=1.5), ["energy_eta = 1.5", "<= 1"]),
    (dict(scale="huge"), ["scale = 'huge'", "'initial', 'force'"]),
])
def test_newton_settings_fields(kwargs, words):
    _refused(SettingsError, lambda: cm.NewtonSettings(**kwargs), *words)


def test_newton_settings_petsc_options_and_what_is_accepted():
    _refused(SolverOptionError, lambda: cm.NewtonSettings(petsc_options=["pc_type", "lu"]), "petsc_options = [")
    _refused(SolverOptionError, lambda: cm.NewtonSettings(petsc_options={"pc_type": ["lu"]}),
             "pc_type = ['lu']")
    _refused(SolverOptionError, lambda: cm.NewtonSettings(petsc_options={"": 1}), "'' is not an option name")
    _refused(SolverOptionError, lambda: cm.NewtonSettings(petsc_options={"ksp_rtol": float("nan")}),
             "ksp_rtol = nan")
    assert issubclass(SolverOptionError, SettingsError) and issubclass(SettingsError, ValueError)
    # 0 turns a test off; the names of the docs; numbers, strings, flags and bare options as values
    cm.NewtonSettings(atol=0.0, stol=0.0, line_search=False, scale="force",
                      petsc_options={"pc_type": "lu", "mat_mumps_icntl_14": 50, "ksp_rtol": 1e-8,
                                     "ksp_view": None, "pc_factor_reuse_ordering": True})
    # a field changed after the settings were made is checked when a Newton takes them
    s = cm.NewtonSettings()
    s.max_it = 0
    _refused(SettingsError, s.check, "max_it = 0")


def test_body_values(strip):
    E = cm.Elastic(100.0, 0.3)
    _refused(cm.BodyError, lambda: cm.Body(strip, "plane_strain", E, quadrature_degree=-3),
             "quadrature_degree = -3", ">= 1")
    _refused(cm.BodyError, lambda: cm.Body(strip, "plane_strain", E, quadrature_degree=2.0), "quadrature_degree = 2.0")
    _refused(cm.BodyError, lambda: cm.Body(strip, "plane_strain", E, thickness=True), "thickness = True")
    _refused(cm.BodyError, lambda: cm.Body(strip, "plane_strain", E, thickness=float("nan")), "thickness = nan")
    _refused(cm.BodyError, lambda: cm.Body(strip, "plane_strain", E, degree=2.0), "degree = 2.0")
    _refused(cm.BodyError, lambda: cm.Body(strip.mesh, "plane_strain", E), "cm.from_dolfinx")
    _refused(cm.BodyError, lambda: cm.Body(strip, ["plane_strain"], E), "kind = ['plane_strain']")
    assert cm.Body(strip, "plane_strain", E, quadrature_degree=4).rule_degree() == 4


def test_contact_values():
    plane = cm.Plane((0.0, 1.0), (0.0, -1.0))
    _refused(cm.ContactError, lambda: cm.Contact("top", plane, mu="0.1"), "mu = '0.1'", "friction coefficient")
    _refused(cm.ContactError, lambda: cm.Contact("top", plane, max_passes=0), "max_passes = 0", ">= 1")
    _refused(cm.ContactError, lambda: cm.Contact("top", plane, relag_tol=-1), "relag_tol = -1", "> 0")
    _refused(cm.ContactError, lambda: cm.Contact("top", plane, gamma0="100"), "gamma0 = '100'")
    _refused(cm.ContactError, lambda: cm.Contact("top", plane, theta=True), "theta = True")
    _refused(cm.ContactError, lambda: cm.Contact("top", plane, relag="yes"), "relag = 'yes'", "True or False")
    _refused(cm.ContactError, lambda: cm.Contact(None, plane), "boundary = None")
    assert cm.Contact("top", plane, theta=np.int64(1), mu=np.float64(0.2)).mu == 0.2


def test_material_and_obstacle_values():
    _refused(cm.MaterialError, lambda: cm.Elastic("100", 0.3), "E = '100'")
    _refused(cm.MaterialError, lambda: cm.Elastic(100.0, True), "nu = True")
    _refused(cm.MaterialError, lambda: cm.Hardening(["0"], ["2800"]), "strain = ['0']")
    _refused(cm.ContactError, lambda: cm.Circle((0.0, 0.0), "1"), "radius = '1'")
    _refused(cm.ContactError, lambda: cm.Plane(("0", "1"), (0.0, 1.0)), "point = ('0', '1')")
    _refused(cm.ContactError, lambda: cm.Profile([0.0, 1.0, 2.0], 0.1), "points = [0.0, 1.0, 2.0]")
    assert cm.Elastic(np.float64(100.0), np.array(0.3)).nu == 0.3


def test_item_values():
    _refused(cm.ItemError, lambda: cm.Pressure("top", "1"), "'1'", "finite number")
    _refused(cm.ItemError, lambda: cm.Pressure("top", True), "True")
    _refused(cm.ItemError, lambda: cm.Pressure(3, 1.0), "boundary = 3")
    _refused(cm.ItemError, lambda: cm.Traction("right", ("1", "2")), "('1', '2')", "2 finite numbers")
    _refused(cm.ItemError, lambda: cm.Fixed("left", component=True), "component = True")
    _refused(cm.ItemError, lambda: cm.Displacement("right", field=3), "field = 3")
    _refused(cm.ItemError, lambda: cm.BodyForce((0.0, -1.0), name=""), "name = ''")
    assert cm.Displacement("right", np.float64(0.1), component=np.int64(0)).value == 0.1


def test_probe_values():
    c = cm.Contact("top", cm.Plane((0.0, 1.0), (0.0, -1.0)))
    _refused(ProbeError, lambda: cm.ContactForce("plate"), "contact = 'plate'", "the Contact item itself")
    _refused(ProbeError, lambda: cm.ContactLength(c, scale=float("nan")), "scale = nan")
    _refused(ProbeError, lambda: cm.ContactForce(c, component=2), "component = 2")
    _refused(ProbeError, lambda: cm.NodeDisplacement("tip", (1.0,)), "point = (1.0,)")
    _refused(ProbeError, lambda: cm.NodeDisplacement("tip", (1.0, 0.0), component=2), "component = 2")
    _refused(ProbeError, lambda: cm.Reaction(""), "boundary = ''")
    _refused(ProbeError, lambda: cm.Value("gap", 3), "fn = 3")


def test_job_parts(strip):
    body = cm.Body(strip, "plane_strain", cm.Elastic(100.0, 0.3))
    fixed = cm.Fixed("left")
    other = cm.Contact("top", cm.Plane((0.0, 1.0), (0.0, -1.0)))
    _refused(cm.JobError, lambda: cm.Job(body, fixed), "items = Fixed(left)", "give a list, [Fixed(left)]")
    _refused(cm.JobError, lambda: cm.Job(body, [fixed], steps=[]), "steps = []", "leave steps out")
    _refused(cm.JobError, lambda: cm.Job(body, [fixed], steps=cm.Step(2)), "steps = <Step>", "give a list")
    _refused(cm.JobError, lambda: cm.Job(body, [fixed, "right"]), "items[1] = 'right'")
    _refused(cm.JobError, lambda: cm.Job(body, [fixed, fixed]), "Fixed(left) is listed twice")
    _refused(cm.JobError, lambda: cm.Job(body, [fixed], probes=cm.MaxPlasticStrain()), "probes = ", "give a list")
    _refused(cm.JobError, lambda: cm.Job(body, [fixed], writers=[None]), "writers[0] = None")
    _refused(cm.JobError, lambda: cm.Job(body, [fixed], newton={"rtol": 1e-6}), "newton = {'rtol': 1e-06}")
    _refused(cm.JobError, lambda: cm.Job(strip, [fixed]), "body = ")
    _refused(ProbeError, lambda: cm.Job(body, [fixed], probes=[cm.ContactForce(other, "push")]),
             "ContactForce 'push'", "boundary 'top'", "not one of the job's items")
    assert len(cm.Job(body, [fixed]).steps) == 1            # steps left out: one Step()


def test_builders_refuse_with_mesh_error():
    _refused(cm.MeshError, lambda: cm.annulus_sector(6.0, 5.0, 0.25), "r_in=6.0, r_out=5.0")
    _refused(cm.MeshError, lambda: cm.rectangle(1.0, 0.5, "0.1"), "size must be a finite number > 0")
    text = _refused(cm.MeshError, lambda: cm.annulus_sector(4.849, 5.715, 1e-5), "size = 1e-05", "give size >= ")
    least = float(text.rsplit(">= ", 1)[1])
    # the smallest size allowed gives at most 5 million cells, 1 % less than it more
    assert mesh_cells("annulus_sector", dict(r_in=4.849, r_out=5.715, size=least)) <= 5_000_000
    assert mesh_cells("annulus_sector", dict(r_in=4.849, r_out=5.715, size=0.99 * least)) > 5_000_000
    _refused(cm.MeshError, lambda: cm.quarter_disc(1.0, 0.1, 1e-5, 0.3), "size_contact = 1e-05",
             "give size_contact >= ")


def test_cell_estimates_are_the_builders_counts(strip):
    """The counts the size check uses: exact for the structured builders, within 10 % for the
    unstructured quarter disc (against the meshes gmsh makes)."""
    def n(md):
        return md.mesh.topology.index_map(2).size_global
    assert n(strip) == mesh_cells("rectangle", dict(L=1.0, H=0.5, size=0.25))
    ring = cm.annulus_sector(4.849, 5.715, 0.22, cache_dir="meshes")
    assert n(ring) == mesh_cells("annulus_sector", dict(r_in=4.849, r_out=5.715, size=0.22))
    plate = cm.plate_section(10.0, 2.0, 0.25, 0.5, cache_dir="meshes")
    assert n(plate) == mesh_cells("plate_section", dict(R=10.0, t=2.0, z_support=0.25, size=0.5))
    for half in (False, True):
        disc = cm.quarter_disc(1.0, 0.1, 0.01, 0.3, half=half, cache_dir="meshes")
        est = mesh_cells("quarter_disc", dict(R=1.0, size=0.1, size_contact=0.01, contact_zone=0.3, half=half))
        assert abs(est / n(disc) - 1) < 0.1, (est, n(disc))


def _pull(strip, writers, n=2):
    body = cm.Body(strip, "plane_strain", cm.Elastic(100.0, 0.3))
    return cm.Job(body, [cm.Fixed("left"), cm.Displacement("right", 0.01, component=0)], [cm.Step(n)],
                  writers=writers).run()


def test_vtk_refuses_an_earlier_runs_folder_unless_overwrite(strip, tmp_path):
    """A second run into a folder with another run's datasets is refused before it writes anything
    (the first run's files stay); with overwrite=True they are replaced, and none of the first run's
    increments is left beside the new ones."""
    import xml.etree.ElementTree as ET
    out = tmp_path / "vtk"
    assert _pull(strip, [cm.VTK(out)], n=3).completed
    first = sorted(p.name for p in out.iterdir())
    assert first == ["results.pvd", "results_00000.vtu", "results_00001.vtu", "results_00002.vtu"]
    text = _refused(FolderError, lambda: _pull(strip, [cm.VTK(out)]), str(out), "overwrite=True")
    assert "results.pvd" in text
    assert sorted(p.name for p in out.iterdir()) == first
    assert _pull(strip, [cm.VTK(out, overwrite=True)], n=1).completed
    assert sorted(p.name for p in out.iterdir()) == ["results.pvd", "results_00000.vtu"]
    assert len(list(ET.parse(out / "results.pvd").getroot().iter("DataSet"))) == 1
    _refused(FolderError, lambda: cm.VTK(out, True), "name = True")     # overwrite is a keyword
    _refused(FolderError, lambda: cm.VTK(out, overwrite="yes"), "overwrite = 'yes'")
