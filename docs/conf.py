"""Sphinx configuration of the flexgear documentation.

Build (warnings are errors, as in CI)::

    pip install -e ".[docs]"
    python -m sphinx -W --keep-going -n -b html docs docs/_build/html

The configuration reference is generated from the loader's schema at every build
(:mod:`flexgear.config.reference`), and the examples in ``examples/`` run as the gallery.
"""
import importlib
import re
import sys
from pathlib import Path

import flexgear

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(DOCS / "_ext"))

project = "flexgear"
author = "the flexgear developers"
copyright = "the flexgear developers"
version = release = flexgear.__version__

extensions = [
    "myst_parser",
    "numpydoc",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.intersphinx",
    "sphinx.ext.mathjax",
    "sphinx_gallery.gen_gallery",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "_generated", "auto_examples/*.ipynb", "auto_examples/*.py",
                    "auto_examples/*.zip", "auto_examples/*.json", "auto_examples/*.codeobj.json"]
templates_path = ["_templates"]

# Markdown pages (MyST): $...$ and $$...$$ math, as GitHub renders them too
myst_enable_extensions = ["dollarmath", "amsmath", "deflist"]
myst_heading_anchors = 3

# API reference
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"members": True, "undoc-members": True, "ignore-module-all": True}
autodoc_typehints = "none"
autodoc_member_order = "bysource"
numpydoc_show_class_members = False
numpydoc_xref_param_type = False
numpydoc_validation_checks = set()
add_module_names = False

# intersphinx resolves from local inventories only: the build runs without network
intersphinx_mapping = {}

# examples/*.py run as the gallery (tests/test_examples.py runs each of them too)
sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": str(DOCS / "auto_examples"),
    "filename_pattern": r"ex\d\d_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "matplotlib_animations": False,
    "show_memory": False,
    "plot_gallery": "True",
    "image_scrapers": ("png_scraper.png_scraper",),
}

html_theme = "pydata_sphinx_theme"
html_title = f"flexgear {release}"
html_theme_options = {"navigation_with_keys": False, "show_toc_level": 2, "secondary_sidebar_items": ["page-toc"]}
html_static_path = []
nitpicky = True
nitpick_ignore_regex = [
    # other packages (no intersphinx: the build runs offline)
    (r"py:.*", r"(numpy|np|scipy|h5py|xarray|pathlib|os|ast|collections|typing|numba|matplotlib|dask|meshio)(\..*)?"),
    # private names are not documented
    (r"py:.*", r"(.*\.)?_[A-Za-z]\w*"),
]


def write_config_reference(app):
    """docs/_generated/configuration_keys.md from the loader's schema (rewritten only when it changes,
    so that an unchanged schema rebuilds nothing)."""
    from flexgear.config.reference import reference_markdown

    out = DOCS / "_generated" / "configuration_keys.md"
    text = reference_markdown()
    if not out.exists() or out.read_text() != text:
        out.parent.mkdir(exist_ok=True)
        out.write_text(text)


_LITERAL = re.compile(r"(``.+?``|`[^`\n]*`)", re.S)
_TABLE_ROW = re.compile(r"^(\s*)\|.*\|\s*$")
_DOT = re.compile(r"(\s)\.(\s)")


def _escape_bars(text: str) -> str:
    """``|x|`` in running text is an absolute value, not a reST substitution; `` . `` in a
    literal is a dot product (shown as a middle dot, so that a summary does not end there)."""
    parts = _LITERAL.split(text)
    return "".join(_DOT.sub("\\1\u00b7\\2", p) if i % 2 else p.replace("|", "\\|") for i, p in enumerate(parts))


def _list_table(rows: list[str], indent: str) -> list[str]:
    """A Markdown pipe table (header, separator, rows) as a reST list-table."""
    cells = [[c.strip() for c in r.strip().strip("|").split("|")] for r in rows if not set(r.strip()) <= set("|-: ")]
    out = ["", f"{indent}.. list-table::", f"{indent}   :header-rows: 1", ""]
    for row in cells:
        out += [f"{indent}   {'*' if k == 0 else ' '} - {c}" for k, c in enumerate(row)]
    return out + [""]


def plain_text_habits(app, what, name, obj, options, lines):
    """Read the docstrings' plain-text habits as meant: ``|x|`` as an absolute value and
    Markdown pipe tables as tables; literal blocks (after ``::``) are left alone."""
    out, text, literal_indent, i = [], [], None, 0

    def flush():
        if text:
            out.extend(_escape_bars("\n".join(text)).split("\n"))
            text.clear()

    while i < len(lines):
        line = lines[i]
        indent = len(line) - len(line.lstrip())
        if literal_indent is not None and line.strip() and indent <= literal_indent:
            literal_indent = None
        if literal_indent is not None:
            out.append(line)
        elif _TABLE_ROW.match(line) and i + 1 < len(lines) and set(lines[i + 1].strip()) <= set("|-: "):
            flush()
            j = i
            while j < len(lines) and _TABLE_ROW.match(lines[j]):
                j += 1
            out += _list_table(lines[i:j], _TABLE_ROW.match(line).group(1))
            i = j
            continue
        else:
            text.append(line)
            if line.rstrip().endswith("::"):
                flush()
                literal_indent = indent
        i += 1
    flush()
    lines[:] = out


def skip_foreign_members(app, what, name, obj, skip, options):
    """Document only what flexgear defines (not names it imports, e.g. scipy's cKDTree)."""
    module = getattr(obj, "__module__", None)
    if what == "module" and isinstance(module, str) and not module.startswith("flexgear"):
        return True
    return None


def dynamics_references(app, domain, node):
    """flexgear.dynamics is being regrouped; its docstrings' cross-references are checked once
    it settles, so an unresolved one there is not a build error (True: warning handled)."""
    source = str(node.source or "")
    return "flexgear/dynamics/" in source or "flexgear.dynamics." in source or None


def reexported_names(app, env, node, contnode):
    """Resolve a reference to a name by where it is re-exported (``flexgear.results.Result``,
    ``flexgear.config.load_config``, or a name imported into the current module) to the object's
    own page."""
    if node.get("refdomain") != "py":
        return None
    target = node.get("reftarget", "")
    for candidate in (target, f"{node.get('py:module')}.{target}"):
        if not candidate.startswith("flexgear."):
            continue
        modname, _, attr = candidate.rpartition(".")
        try:
            obj = getattr(importlib.import_module(modname), attr)
        except (ImportError, AttributeError, ValueError):
            continue
        home = f"{getattr(obj, '__module__', '')}.{getattr(obj, '__qualname__', attr)}"
        if home != candidate and home.startswith("flexgear."):
            return env.get_domain("py").resolve_xref(env, node["refdoc"], app.builder, node["reftype"], home,
                                                     node, contnode)
    return None


def setup(app):
    app.connect("builder-inited", write_config_reference)
    app.connect("autodoc-process-docstring", plain_text_habits)
    app.connect("autodoc-skip-member", skip_foreign_members)
    app.connect("missing-reference", reexported_names)
    app.connect("warn-missing-reference", dynamics_references)
