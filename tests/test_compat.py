"""One compatibility module: no other file of the package (or of the tests and demos) touches an API
that differs between the supported dolfinx versions, or a private attribute of dolfinx, basix or ufl.
The patterns are those that changed between 0.5, 0.9 and 0.11 (comove_dolfinx/compat.py)."""
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
VERSIONED = [
    r"VectorFunctionSpace", r"TensorFunctionSpace", r"fem\.FunctionSpace\(", r"fem\.functionspace\(",
    r"ufl\.(Finite|Vector|Tensor|Mixed)Element", r"basix\.ufl", r"\.vector\b", r"petsc_vec",
    r"jit_(params|options)\s*=", r"gmshio", r"dolfinx\.io\.gmsh\b", r"dofmap\.(list|array)", r"geometry\.dofmap", r"geometry\.cmaps?\b",
    r"apply_lifting", r"set_bc\(", r"cpp\.mesh", r"\._mesh\b", r"_sub_element", r"\._cpp_object",
    r"\.sub_elements\(", r"\.degree\(\)", r"basix\.create_element", r"fem\.Expression\(",
    r"\.eval\(", r"\.cellname\(", r"create_vector\(", r"create_matrix\(", r"assemble_matrix\(",
]
FILES = [p for d in ("comove_dolfinx", "tests", "demos") for p in sorted((ROOT / d).rglob("*.py"))
         if p.name not in ("compat.py", "test_compat.py")]


@pytest.mark.parametrize("path", FILES, ids=[str(p.relative_to(ROOT)) for p in FILES])
def test_versioned_apis_only_in_compat(path):
    bad = []
    for n, line in enumerate(path.read_text().splitlines(), 1):
        code = re.sub(r"compat\.\w+", "", line.split("#", 1)[0])   # calls into compat are the point
        bad += [f"{path.name}:{n}: {line.strip()}" for pat in VERSIONED if re.search(pat, code)]
    assert not bad, "\n".join(bad)


def test_the_version_check_names_the_tested_levels(monkeypatch):
    """The installed level passes; any other (an older, a between, a newer one) is refused with a
    message naming the three tested levels and the version found."""
    from comove_dolfinx import compat
    compat.check_version()
    for level in ("0.7", "0.10", "0.12"):
        monkeypatch.setattr(compat, "LEVEL", level)
        monkeypatch.setattr(compat.dolfinx, "__version__", level + ".0")
        with pytest.raises(SystemExit) as err:
            compat.check_version()
        assert all(v in str(err.value) for v in ("0.5", "0.9", "0.11", f"found {level}.0")), str(err.value)


def test_importing_the_package_loads_nothing_heavy():
    """``import comove_dolfinx`` loads none of MPI, PETSc, dolfinx, gmsh or numpy (the command
    takes Ctrl-C before they load, and a script pays for them only when it uses the API); the
    first use of the API then loads them in the order the PyPI wheel needs (MPI first)."""
    import launch
    code = ("import sys, comove_dolfinx as cm\n"
            "heavy = ('mpi4py', 'petsc4py', 'dolfinx', 'gmsh', 'numpy', 'ufl')\n"
            "assert not [m for m in heavy if m in sys.modules], [m for m in heavy if m in sys.modules]\n"
            "mesh = cm.rectangle(1.0, 0.5, 0.5)\n"
            "assert mesh.mesh.topology.index_map(2).size_global > 0\n")
    proc = launch.run(["-c", code], timeout=300)
    assert proc.returncode == 0, proc.stderr
