"""Bad input is refused with a message that names the value and the fix."""
import pytest

from comove_dolfinx import cli
from comove_dolfinx.mechanics.material_data import Elastic, MaterialError
from comove_dolfinx.presets import SceneError, get_scene


@pytest.mark.parametrize("pairs, words", [
    (["nu=0.5"], ["nu", "0.5"]),
    (["nu=0.7"], ["nu", "0.7"]),
    (["E=-10"], ["E", "-10"]),
    (["E=0"], ["E", "0"]),
    (["update=jaumann"], ["jaumann", "sr"]),
    (["size=0"], ["size"]),
    (["n_steps=0"], ["n_steps"]),
    (["degree=3"], ["degree"]),
    (["colour=red"], ["colour", "parameters"]),
    (["lam"], ["key=value"]),
    (["n_steps=ten"], ["n_steps", "int"]),
    (["predictor=secant"], ["predictor", "secant", "tangent"]),
    (["first=0.3"], ["first = 0.3", "0.5, 0.25"]),
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
    """Scene parameters are checked against comove_dolfinx.names before dolfinx is loaded; the
    modules that implement the choices must offer exactly those names."""
    from comove_dolfinx import names
    from comove_dolfinx.mechanics import kinematics, materials, updates
    assert set(updates.UPDATES) == set(names.UPDATES)
    assert set(materials.LAWS) == set(names.LAWS)
    assert set(kinematics.MODELS) == set(names.MODELS)


BAD_EARLY = [("ring", "E=-1", "E = -1.0"), ("ring", "size=inf", "size = inf"), ("beam", "L=inf", "L = inf"),
             ("beam", "mu=inf", "mu = inf"), ("beam", "mu=nan", "mu = nan"), ("beam", "gamma0=inf", "gamma0 = inf"),
             ("beam", "q_max=nan", "q_max = nan"), ("ring", "n_steps=100000000000000000000", "1000000"),
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
    newest released entry, below the changes not yet released), so that the three cannot drift
    apart."""
    import pathlib
    import re
    import tomllib
    root = pathlib.Path(__file__).resolve().parents[1]
    version = tomllib.loads((root / "pyproject.toml").read_text())["project"]["version"]
    with pytest.raises(SystemExit) as exit_:
        cli.main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out.strip() == f"comove {version}"
    newest = re.search(r"^## (?!Unreleased)(\S+)", (root / "CHANGELOG.md").read_text(), re.M).group(1)
    assert newest == version
