"""Bad input is refused with a message that names the value and the fix."""
import pathlib

import pytest

from comove_dolfinx import cli
from comove_dolfinx.mechanics.material_data import Elastic, MaterialError
from comove_dolfinx.presets import SceneError, get_scene

ROOT = pathlib.Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("pairs, words", [
    (["nu=0.5"], ["nu", "0.5"]),
    (["nu=0.7"], ["nu", "0.7"]),
    (["E=-10"], ["E", "-10"]),
    (["E=0"], ["E", "0"]),
    (["update=jaumann"], ["jaumann", "sr"]),
    (["size=0"], ["size"]),
    (["n_increments=0"], ["n_increments"]),
    (["degree=3"], ["degree"]),
    (["colour=red"], ["colour", "parameters"]),
    (["lam"], ["key=value"]),
    (["n_increments=ten"], ["n_increments", "int"]),
    (["predictor=secant"], ["predictor", "secant", "tangent"]),
    (["first=0.3"], ["first = 0.3", "0.5, 0.25"]),
    (["nu=0.3", "nu=0.4"], ["--set nu is given twice", "nu=0.4"]),
])
def test_bad_parameters(pairs, words):
    with pytest.raises((SceneError, MaterialError)) as err:
        get_scene("elastica", pairs)
    for w in words:
        assert w in str(err.value)


def test_unknown_scene():
    with pytest.raises(SceneError, match="unknown scene 'bridge'.*beam"):
        get_scene("bridge")


def test_elastic_validation():
    with pytest.raises(MaterialError, match="nu"):
        Elastic(1000.0, 0.5)
    with pytest.raises(MaterialError, match="E"):
        Elastic(-1.0, 0.3)


def test_cli_reports_bad_input_without_traceback(capsys, tmp_path):
    code = cli.main(["run", "elastica", "--out", str(tmp_path), "--set", "nu=0.5"])
    err = capsys.readouterr().err
    assert code == 2
    assert "nu" in err and "Traceback" not in err
    code = cli.main(["run", "nosuch", "--out", str(tmp_path)])
    assert code == 2 and "unknown scene" in capsys.readouterr().err


def test_cli_missing_mesh_and_missing_tags(capsys, tmp_path):
    code = cli.main(["run", "beam", "--out", str(tmp_path / "o"), "--set",
                     f"mesh={tmp_path / 'none.msh'}"])
    assert code == 2 and "none.msh" in capsys.readouterr().err
    # a mesh whose boundary carries no names: the beam needs left, top, bottom
    import gmsh
    path = tmp_path / "untagged.msh"
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("untagged")
    s = gmsh.model.occ.addRectangle(0, 0, 0, 10, 0.5)
    gmsh.model.occ.synchronize()
    gmsh.model.addPhysicalGroup(2, [s], 1)
    gmsh.model.setPhysicalName(2, 1, "body")
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.5)
    gmsh.model.mesh.generate(2)
    gmsh.write(str(path))
    gmsh.finalize()
    code = cli.main(["run", "beam", "--out", str(tmp_path / "o2"), "--set", f"mesh={path}"])
    err = capsys.readouterr().err
    assert code == 2 and "left" in err and "Traceback" not in err


def test_scenes_listing(capsys):
    assert cli.main(["scenes"]) == 0
    out = capsys.readouterr().out
    for word in ("elastica", "beam", "plate", "q_max", "p_max", "lam"):
        assert word in out


def test_the_names_checked_early_are_those_implemented():
    """Scene parameters are checked against comove_dolfinx.choices before dolfinx is loaded; the
    modules that implement the choices must offer exactly those names."""
    from comove_dolfinx import choices
    from comove_dolfinx.mechanics import kinematics, materials, updates
    assert set(updates.UPDATES) == set(choices.UPDATES)
    assert set(materials.LAWS) == set(choices.LAWS)
    assert set(kinematics.MODELS) == set(choices.MODELS)
    # every field of NewtonSettings has its check (a problem file's [newton] keys are those)
    import dataclasses

    from comove_dolfinx.checks import NEWTON_CHECKS
    from comove_dolfinx.solver import NewtonSettings
    assert set(NEWTON_CHECKS) == {f.name for f in dataclasses.fields(NewtonSettings)}


BAD_EARLY = [("ring", "E=-1", "E = -1.0"), ("ring", "size=inf", "size = inf"), ("beam", "L=inf", "L = inf"),
             ("beam", "mu=inf", "mu = inf"), ("beam", "mu=nan", "mu = nan"), ("beam", "gamma0=inf", "gamma0 = inf"),
             ("beam", "q_max=nan", "q_max = nan"), ("ring", "n_increments=100000000000000000000", "1000000"),
             ("ring", "nu=0.5", "nu = 0.5"), ("ring", "hardening=0:2800,0.1:2000", "non-decreasing"),
             ("ring", "hardening=0:2800,0.05:3600,0.01:3000", "hardening = '0:2800,0.05:3600,0.01:3000': row 2"),
             ("elastica", "mesh=nowhere.msh", "nowhere.msh"), ("beam", "E=1e-30", "q_max = 0.5 is not small against E"),
             ("plate", "p_max=2000", "p_max = 2000.0 is not small"), ("ring", "E=2000", "yield stress = 2800.0")]


@pytest.mark.parametrize("scene, pair, words", BAD_EARLY)
def test_bad_values_refused_before_dolfinx_is_loaded(tmp_path, scene, pair, words):
    """One line naming the value, exit code 2, and dolfinx never imported (so it is quick)."""
    import subprocess
    import sys
    code = ("import sys; from comove_dolfinx import cli; rc = cli.main(sys.argv[1:]); "
            "assert 'dolfinx' not in sys.modules, 'dolfinx was imported'; sys.exit(rc)")
    p = subprocess.run([sys.executable, "-c", code, "run", scene, "--set", pair, "--out", str(tmp_path)],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2, p.stdout + p.stderr
    assert words in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr


@pytest.mark.parametrize("case, words", [("file", "not a folder"), ("under_a_file", "is a file"),
                                         ("old_results", "--overwrite"), ("restart_nothing", "no checkpoint")])
def test_bad_output_folder_refused_before_dolfinx_is_loaded(tmp_path, case, words):
    """An --out that cannot take the run: one line with the fix, exit code 2, dolfinx never imported."""
    import subprocess
    import sys
    afile = tmp_path / "a_file"
    afile.write_text("x")
    old = tmp_path / "old"
    old.mkdir()
    (old / "history.csv").write_text("step\n")
    out, extra = {"file": (afile, []), "under_a_file": (afile / "sub", []), "old_results": (old, []),
                  "restart_nothing": (tmp_path / "new", ["--restart"])}[case]
    code = ("import sys; from comove_dolfinx import cli; rc = cli.main(sys.argv[1:]); "
            "assert 'dolfinx' not in sys.modules, 'dolfinx was imported'; sys.exit(rc)")
    p = subprocess.run([sys.executable, "-c", code, "run", "beam", "--out", str(out), *extra],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2, p.stdout + p.stderr
    assert words in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert (old / "history.csv").read_text() == "step\n" and not (tmp_path / "new").exists()


def test_scenes_listing_into_a_closed_pipe():
    """`comove scenes | head -1`: the reader goes away before the listing is written; the command
    ends quietly (no BrokenPipeError traceback)."""
    import subprocess
    import sys
    p = subprocess.Popen([sys.executable, "-m", "comove_dolfinx.cli", "scenes"], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE)
    p.stdout.close()                              # before the command has written anything
    err = p.stderr.read().decode()
    assert p.wait(timeout=120) == 0 and "Traceback" not in err, err


def test_version_is_the_package_metadata(capsys):
    """`comove --version` names the version that pyproject.toml gives the package (and CHANGELOG.md's
    newest released entry, below an "Unreleased" one if there is one), so that the three cannot
    drift apart."""
    import pathlib
    import re
    import tomllib
    root = pathlib.Path(__file__).resolve().parents[1]
    version = tomllib.loads((root / "pyproject.toml").read_text())["project"]["version"]
    with pytest.raises(SystemExit) as exit_:
        cli.main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out.strip() == f"comove {version}"
    newest = re.search(r"^## (?!Unreleased\b)(\S+)", (root / "CHANGELOG.md").read_text(), re.M).group(1)
    assert newest == version


def test_python_dash_m_runs_the_command(tmp_path):
    """`python -m comove_dolfinx` is the `comove` command under that interpreter: its version line and
    a refusal with its exit code (2), one line, no traceback."""
    import subprocess
    import sys
    import tomllib
    version = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    run = subprocess.run([sys.executable, "-m", "comove_dolfinx", "--version"], capture_output=True, text=True)
    assert (run.returncode, run.stdout.strip()) == (0, f"comove {version}")
    bad = subprocess.run([sys.executable, "-m", "comove_dolfinx", "run", "bridge", "--out",
                          str(tmp_path / "out")], capture_output=True, text=True)
    lines = (bad.stdout + bad.stderr).strip().splitlines()
    assert bad.returncode == 2 and len(lines) == 1 and "unknown scene 'bridge'" in lines[0], lines


# A problem file that runs (a strip pulled at its right end, a plate above it), and keys that break it
PROBLEM = """
[mesh]
builder = "rectangle"
L = 1.0
H = 0.5
size = 0.25
[body]
kind = "plane_strain"
material = { E = 100.0, nu = 0.3 }
[[items]]
type = "fixed"
boundary = "left"
[[items]]
type = "displacement"
boundary = "right"
value = 0.01
component = 0
[[items]]
type = "contact"
name = "plate"
boundary = "top"
obstacle = { type = "plane", point = [0.0, 1.0], normal = [0.0, -1.0] }
[[steps]]
n = 2
[newton]
rtol = 1e-8
[[probes]]
type = "contact_force"
item = "plate"
"""

BAD_KEYS = [
    ("rtol = 1e-8", "rtol = -1", "[newton] rtol = -1: give a finite number >= 0"),
    ("rtol = 1e-8", "rtol = nan", "[newton] rtol = nan"),
    ("rtol = 1e-8", "max_it = 0", "[newton] max_it = 0: give a whole number >= 1"),
    ("rtol = 1e-8", "max_it = true", "[newton] max_it = True"),
    ("rtol = 1e-8", 'line_search = "armijo"', "[newton] line_search = 'armijo': choose 'residual', 'energy'"),
    ("rtol = 1e-8", 'scale = "huge"', "[newton] scale = 'huge': choose one of 'initial', 'force'"),
    ("rtol = 1e-8", 'petsc_options = {pc_type = ["lu"]}', "[newton] petsc_options: pc_type = ['lu']"),
    ("rtol = 1e-8", "rtl = 1e-3", "[newton] unknown setting 'rtl'"),
    ("size = 0.25", "size = 1e-5", "[mesh] size = 1e-05 would make about 1e+10 cells, more than the 5000000"),
    ('kind = "plane_strain"', 'kind = "plane"', "[body]: kind = 'plane': choose one of 'plane_strain'"),
    ('kind = "plane_strain"', 'kind = "plane_strain"\ndegree = 3', "[body]: degree = 3: choose one of 1, 2"),
    ("E = 100.0", 'E = "100"', "[body] material: E = '100': give a finite number"),
    ("E = 100.0, nu = 0.3", "E = 100.0, nu = 0.3, hardening = [[0, 1]]", "hardening is for law"),
    ('name = "plate"', 'name = "plate"\nmu = -1', "[[items]] 3 (contact): mu = -1: give a finite number >= 0"),
    ('name = "plate"', 'name = "plate"\ntheta = 2', "[[items]] 3 (contact): theta = 2: choose one of 1, 0, -1"),
    ('name = "plate"', 'name = "plate"\nmax_passes = 0', "max_passes = 0: give a whole number >= 1"),
    ("component = 0", "component = 2", "[[items]] 2 (displacement): component = 2: the body is 2D, give 0 (x) or 1 (y)"),
    ("component = 0", "component = 3", "[[items]] 2 (displacement): component = 3: choose one of 0, 1, 2"),
    ("value = 0.01", "value = true", "[[items]] 2 (displacement): value = True"),
    ("n = 2", "n = 0", "[[steps]] 1: n = 0: give a whole number >= 1 and <= 1e+06 of increments"),
    ("n = 2", 'n = 2\npredictor = "secant"', "[[steps]] 1: predictor = 'secant': choose one of"),
    ('item = "plate"', 'item = "fixed1"', "item = 'fixed1' is not a contact item; the contact items are plate"),
    ("[[steps]]\nn = 2\n", "", "give the steps as [[steps]] tables"),     # with steps = [] on top
    ("normal = [0.0, -1.0]", "normal = [0.0, 0.0]", "normal = [0, 0]: give a direction"),
    ('builder = "rectangle"', 'builder = ["rectangle"]', "builder = ['rectangle']: choose one of rectangle"),
    ('type = "fixed"', 'type = ["fixed"]', "[[items]] 1: type = ['fixed']: choose one of fixed"),
    ('type = "plane", point = [0.0, 1.0], normal = [0.0, -1.0]', 'type = "sphere", centre = [0.0, 2.0], radius = 1.0',
     "[[items]] 3 (contact) obstacle: type = 'sphere' is a 3D obstacle, the body is 2D (kind = 'plane_strain'): "
     "choose one of plane, circle, profile, gmsh_profile"),
    ('type = "contact_force"', 'type = "contact_area"',
     "[[probes]] 1: type = 'contact_area' is not defined when the body is 2D (kind = 'plane_strain'): use contact_length"),
    ('type = "contact_force"', 'type = "contact_radius"',
     "[[probes]] 1: type = 'contact_radius' is not defined when the body is 2D (kind = 'plane_strain'): use contact_length"),
]


def _run_early(tmp_path, problem: str):
    """``comove run`` on the problem text in a process of its own; asserts that dolfinx was not
    imported unless the run went past the checks (exit code 2 only from the checks)."""
    import subprocess
    import sys
    path = tmp_path / "p.toml"
    path.write_text(problem)
    code = ("import sys; from comove_dolfinx import cli; rc = cli.main(sys.argv[1:]); "
            "assert rc != 2 or 'dolfinx' not in sys.modules, 'dolfinx was imported'; sys.exit(rc)")
    return subprocess.run([sys.executable, "-c", code, "run", str(path), "--out", str(tmp_path / "out"),
                           "--no-progress"], capture_output=True, text=True, timeout=300)


def test_the_problem_file_runs(tmp_path):
    """The file the refusals below break runs as it is (so each refusal is that of its one key)."""
    p = _run_early(tmp_path, PROBLEM)
    assert p.returncode == 0, p.stdout + p.stderr


@pytest.mark.parametrize("old, new, words", BAD_KEYS)
def test_bad_problem_keys_refused_before_dolfinx_is_loaded(tmp_path, old, new, words):
    """One line naming the key and its value, exit code 2, dolfinx never imported."""
    assert old in PROBLEM
    top = "steps = []\n" if old.startswith("[[steps]]") else ""        # (a key of the file's top table)
    p = _run_early(tmp_path, top + PROBLEM.replace(old, new, 1))
    assert p.returncode == 2, p.stdout + p.stderr
    assert words in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr


@pytest.mark.parametrize("builder, words", [
    ('builder = "annulus_sector"\nr_in = 6.0\nr_out = 5.0\nsize = 0.25',
     "r_in = 6.0, r_out = 5.0: r_in must be < r_out"),
    ('builder = "plate_section"\nR = 1.0\nt = 0.5\nz_support = 0.5\nsize = 0.1', "z_support = 0.5, t = 0.5"),
    ('builder = "plate_section"\nR = 1.0\nt = 0.5\nz_support = 0.0\nsize = 0.1', "z_support = 0.0: give a number > 0"),
    ('builder = "quarter_disc"\nR = 1.0\nsize = 0.1\nsize_contact = 0.2\ncontact_zone = 0.3',
     "size_contact = 0.2, size = 0.1: size_contact must be <= size"),
    ('builder = "quarter_disc"\nR = 1.0\nsize = 0.1\nsize_contact = 1e-5\ncontact_zone = 0.3',
     "size = 0.1, size_contact = 1e-05 would make about"),
    ('builder = "rectangle"\nL = 1.0\nH = 0.5\nsize = 0.25\norder = 3', "order = 3: choose one of 1, 2"),
])
def test_bad_builder_sizes_refused(tmp_path, builder, words):
    """The builders' sizes in their order (which tracebacks from the builder before), and the cells
    they would make, checked before dolfinx is loaded."""
    text = PROBLEM.replace('builder = "rectangle"\nL = 1.0\nH = 0.5\nsize = 0.25', builder)
    p = _run_early(tmp_path, text)
    assert p.returncode == 2, p.stdout + p.stderr
    assert words in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr


@pytest.mark.parametrize("n", [1, 2])
def test_unknown_petsc_option_value_is_one_line(tmp_path, n):
    """PETSc refuses pc_type = "nosuchpc" when the solver is set up: one line naming the option and
    value, exit code 2 on every rank, and the ranks do not wait for each other (the timeout)."""
    import launch
    path = tmp_path / "p.toml"
    path.write_text(PROBLEM.replace("rtol = 1e-8", 'petsc_options = {pc_type = "nosuchpc"}'))
    p = launch.run(["-m", "comove_dolfinx.cli", "run", path, "--out", tmp_path / "out", "--no-progress"],
                   n=n, timeout=300)
    ours = [line for line in p.stderr.splitlines() if line.startswith("comove:")]
    assert p.returncode == 2, p.stdout + p.stderr
    assert "Traceback" not in p.stderr and len(ours) == 1, p.stderr
    assert "pc_type=nosuchpc" in ours[0] and "Unable to find requested PC type nosuchpc" in ours[0]


def test_too_fine_scene_mesh_refused_before_gmsh(tmp_path):
    """--set size=1e-5 (gmsh ran out of memory with std::bad_alloc) names the size and the smallest
    one allowed; that smallest size is accepted."""
    import re
    with pytest.raises(SceneError, match=r"size = 1e-05 would make about 1.44e\+11 cells") as err:
        get_scene("ring", ["size=1e-5"])
    least = re.search(r"give size >= (\S+)$", str(err.value)).group(1)
    get_scene("ring", [f"size={least}"])
    with pytest.raises(SceneError, match="size = 1e-05"):
        get_scene("beam", ["size=1e-5"])
    with pytest.raises(SceneError, match="size = 1e-05"):
        get_scene("plate", ["size=1e-5"])
    get_scene("beam", ["size=1e-5", f"mesh={ROOT / 'tests' / 'meshes' / 'rectangle_65426506db.msh'}"])



def test_a_one_row_hardening_table_is_read(tmp_path):
    """A perfectly plastic J2 body has a hardening table of one row, [[0, sigma_y]]."""
    from comove_dolfinx import problem
    path = tmp_path / "p.toml"
    path.write_text(PROBLEM.replace("E = 100.0, nu = 0.3", 'law = "j2", E = 100.0, nu = 0.3, hardening = [[0, 5.0]]'))
    assert problem.read(path)["body"]["material"]["hardening"] == [[0, 5.0]]
