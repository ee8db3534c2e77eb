"""Sphinx configuration of the documentation site (``make docs`` builds it into docs/_build/html).

The Markdown pages of docs/ are read by MyST; the API reference comes from the docstrings (autodoc,
numpy style through napoleon; docs/reference/ is generated, one page per package); each demo (demos/demo_*.py, jupytext's percent format) is run once
into docs/_build/demos/ and becomes a page with the pictures of that run (the demos take 5 to 60 s
each; a demo whose script has not changed since its last successful run is not run again).
"""
import os
import pathlib
import sys

DOCS = pathlib.Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))

project = "comove_dolfinx"
author = "the comove_dolfinx authors"
copyright = "the comove_dolfinx authors"

extensions = ["myst_parser", "sphinx.ext.autodoc", "sphinx.ext.napoleon", "sphinx.ext.mathjax",
              "sphinx.ext.viewcode"]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "**/*.csv"]

myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3
smartquotes = False                # options (--out) and quotes stay as typed

napoleon_numpy_docstring = True
napoleon_google_docstring = False
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "ignore-module-all": True, "show-inheritance": True}

html_theme = "furo"
html_title = "comove_dolfinx"
html_static_path = []


def _run_demo(script: pathlib.Path, out: pathlib.Path) -> None:
    """Runs the demo into ``out`` unless ``out`` already holds a run of this script (its exit status
    0 recorded after the script's last change); a demo that fails its own check fails the build."""
    import subprocess

    from sphinx.util import logging

    stamp = out / ".ran"
    if stamp.is_file() and stamp.stat().st_mtime >= script.stat().st_mtime:
        return
    logging.getLogger(__name__).info(f"running {script.name} into {out.relative_to(ROOT)}")
    out.mkdir(parents=True, exist_ok=True)
    p = subprocess.run([sys.executable, str(script), "--out", str(out)], cwd=ROOT, capture_output=True,
                       text=True)
    (out / "stdout.txt").write_text(p.stdout.replace(f"{ROOT}{os.sep}", ""))
    (out / "stderr.txt").write_text(p.stderr)
    if p.returncode != 0:
        raise RuntimeError(f"{script.name} failed (exit {p.returncode}); its output is in "
                           f"{out.relative_to(ROOT)}/stdout.txt and stderr.txt")
    stamp.touch()


def _demo_page(script: pathlib.Path, out: pathlib.Path) -> str:
    """The demo ``script`` (percent format) as a MyST page: its Markdown cells as text, its code
    cells as Python blocks, then the pictures its run left in ``out``."""
    import jupytext

    parts = []
    for cell in jupytext.read(script).cells:
        text = cell.source.strip("\n")
        if text.strip():
            parts.append(text if cell.cell_type == "markdown" else f"```python\n{text}\n```")
    pictures = sorted(out.glob("*.png"))
    if not pictures:
        raise RuntimeError(f"{script.name} drew no picture into {out.relative_to(ROOT)}")
    printed = (out / "stdout.txt").read_text().strip()
    parts.append("## What it prints and draws\n\nThe run at the demo's defaults, made when this page "
                 f"was built:\n\n```text\n{printed}\n```")
    parts += [f"![{p.stem}]({os.path.relpath(p, DOCS / 'demos')})" for p in pictures]
    return "\n\n".join(parts) + "\n"


def write_demo_pages(app):
    """Runs each demo (demos/demo_*.py) into docs/_build/demos/NAME and writes its page,
    docs/demos/NAME.md (generated, not kept in git), and the demos' index."""
    pages = DOCS / "demos"
    pages.mkdir(exist_ok=True)
    scripts = sorted((ROOT / "demos").glob("demo_*.py"))
    for script in scripts:
        out = DOCS / "_build" / "demos" / script.stem
        _run_demo(script, out)
        _write_if_changed(pages / f"{script.stem}.md", _demo_page(script, out))
    index = ["# Demos", "",
             "Each demo is a literate script in jupytext's percent format (it opens as a notebook "
             "too): it states the physics, builds its problem with the public API, runs it, draws it "
             "and checks its own result. Run one with `python demos/demo_NAME.py --out DIR`, also "
             "under `mpirun -n 2`. Each page is the script with the pictures of its run at its "
             "defaults, made when the site was built (`make docs` runs the demos once; deleting "
             "docs/_build runs them again).", "",
             "```{toctree}", ":maxdepth: 1", "", *[s.stem for s in scripts], "```", ""]
    _write_if_changed(pages / "index.md", "\n".join(index))


def _write_if_changed(path: pathlib.Path, text: str) -> None:
    """Writes ``text`` unless the file holds it already (Sphinx rebuilds only changed pages)."""
    if not path.is_file() or path.read_text() != text:
        path.write_text(text)


def write_reference_pages(app):
    """docs/reference/: one page per package of comove_dolfinx (the package and each of its
    modules, from their docstrings), generated at every build so that a new module has its page;
    not kept in git."""
    package = ROOT / "comove_dolfinx"
    out = DOCS / "reference"
    out.mkdir(exist_ok=True)
    packages = [package] + sorted(d for d in package.iterdir() if (d / "__init__.py").is_file())
    pages = []
    for pkg in packages:
        name = ".".join(pkg.relative_to(ROOT).parts)
        modules = [name] + [f"{name}.{f.stem}" for f in sorted(pkg.glob("*.py"))
                            if not f.name.startswith("__")]
        lines = [f"# `{name}`", ""]                  # the package's docstring follows (automodule)
        for module in modules:
            if module != name:
                lines += [f"## `{module}`", ""]
            lines += ["```{eval-rst}", f".. automodule:: {module}", "```", ""]
        page = "index" if pkg == package else pkg.name
        pages.append(page)
        if page != "index":
            _write_if_changed(out / f"{page}.md", "\n".join(lines))
        else:
            top = lines
    index = ["# API reference", "",
             "Every module of the package, from its docstrings: the package itself below, each of its "
             "packages on a page of its own. `import comove_dolfinx as cm` gives the public names "
             "(`comove_dolfinx`'s list below); [The public API, by example](../api.md) shows them in "
             "use.", "",
             "```{toctree}", ":maxdepth: 1", "", *pages[1:], "```", "", *top[2:]]
    _write_if_changed(out / "index.md", "\n".join(index))
    for old in out.glob("*.md"):                   # the page of a package that is gone
        if old.stem not in pages:
            old.unlink()


def setup(app):
    app.connect("builder-inited", write_demo_pages)
    app.connect("builder-inited", write_reference_pages)
