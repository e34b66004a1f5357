"""The package's shape: one-way imports between layers, no reaching into private names.

Layers, lowest first (``flexgear/__init__.py`` explains them)::

    base (errors, units, files, style, kernels) -> gears -> config -> fe -> stiffness -> reduction
    -> dynamics -> results -> monitoring -> app

A module may import from its own layer or below. Importing a ``_private`` name of another
module is an error at any layer. The package ``__init__`` (lazy convenience functions) is
exempt from the layer rule.
"""
import ast
from collections import defaultdict
from pathlib import Path

import flexgear

PKG = Path(flexgear.__file__).parent
LAYERS = ["base", "gears", "config", "fe", "stiffness", "reduction", "dynamics", "results", "monitoring", "app"]
BASE_MODULES = {"errors", "units", "files", "style", "kernels"}


def module_name(path: Path) -> str:
    parts = list(path.relative_to(PKG.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def layer_of(module: str) -> int:
    parts = module.split(".")
    if len(parts) < 2:
        raise AssertionError(f"{module}: not inside the package")
    top = parts[1]
    if top in BASE_MODULES:
        return LAYERS.index("base")
    if top not in LAYERS:
        raise AssertionError(f"{module}: '{top}' is in no layer; add it to LAYERS or BASE_MODULES")
    return LAYERS.index(top)


def imports(path: Path):
    """(imported module, imported name or None, line) of every import in a file."""
    mod = module_name(path)
    is_pkg = path.name == "__init__.py"
    tree = ast.parse(path.read_text(), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("flexgear"):
                    yield a.name, None, node.lineno
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = mod.split(".") if is_pkg else mod.split(".")[:-1]
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if not target.startswith("flexgear"):
                continue
            for a in node.names:
                yield target, a.name, node.lineno


def all_files():
    return sorted(PKG.rglob("*.py"))


def test_every_module_is_in_a_layer():
    for f in all_files():
        m = module_name(f)
        if m != "flexgear":
            layer_of(m)


def test_imports_never_reach_up_a_layer():
    bad = []
    for f in all_files():
        m = module_name(f)
        if m == "flexgear":
            continue
        own = layer_of(m)
        for target, name, line in imports(f):
            sub = f"{target}.{name}" if name and (PKG / Path(*target.split(".")[1:], f"{name}.py")).exists() else target
            if sub == "flexgear":
                if name == "__version__":
                    continue
                bad.append(f"{m}:{line} imports from the top package")
                continue
            if layer_of(sub) > own:
                bad.append(f"{m}:{line} ({LAYERS[own]}) imports {sub} ({LAYERS[layer_of(sub)]})")
    assert not bad, "imports reaching up a layer:\n" + "\n".join(bad)


def test_no_private_names_across_modules():
    bad = []
    for f in all_files():
        m = module_name(f)
        for target, name, line in imports(f):
            if name and name.startswith("_") and not name.startswith("__") and target != m:
                bad.append(f"{m}:{line} imports {target}.{name}")
    assert not bad, "private names imported from another module:\n" + "\n".join(bad)


def test_public_names_are_unique():
    """One meaning per public name: two modules defining ``build_model`` is a trap."""
    where = defaultdict(list)
    for f in all_files():
        if f.name in ("__init__.py", "__main__.py"):
            continue
        tree = ast.parse(f.read_text())
        for node in tree.body:
            if isinstance(node, (ast.FunctionDef, ast.ClassDef)) and not node.name.startswith("_"):
                if node.name != "main":
                    where[node.name].append(module_name(f))
    dup = {k: v for k, v in where.items() if len(v) > 1}
    assert not dup, f"public names defined in more than one module: {dup}"


def test_the_checker_catches_a_violation(tmp_path):
    """The walker sees relative imports that climb, and private names."""
    p = PKG / "gears" / "_probe_tmp.py"
    p.write_text("from ..dynamics.solver import _profile\n")
    try:
        found = list(imports(p))
    finally:
        p.unlink()
    assert found == [("flexgear.dynamics.solver", "_profile", 1)]
    assert layer_of("flexgear.dynamics.solver") > layer_of("flexgear.gears._probe_tmp")
