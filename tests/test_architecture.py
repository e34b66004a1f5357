"""The package's shape: one-way imports between layers, no reaching into private names.

Layers, lowest first (``flexgear/__init__.py`` explains them)::

    base (errors, units, files, style, kernels) -> gears -> config -> fe -> stiffness -> reduction
    -> dynamics -> results -> monitoring -> app

A module may import from its own layer or below. Importing a ``_private`` name of another
module is an error at any layer. The package ``__init__`` (lazy convenience functions) is
exempt from the layer rule.
"""
import ast
import functools
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


@functools.lru_cache(maxsize=None)
def _parsed(name: str, text: str) -> ast.Module:
    return ast.parse(text, filename=name)


def parse(path: Path) -> ast.Module:
    """The syntax tree of a file, parsed once per text (the checks here walk every module several
    times)."""
    return _parsed(str(path), path.read_text())


def imports(path: Path):
    """(imported module, imported name or None, line) of every import in a file."""
    mod = module_name(path)
    is_pkg = path.name == "__init__.py"
    tree = parse(path)
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
        tree = parse(f)
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


# ----------------------------------------------------------------------------- rooms and kernels
#: a compiled function takes at most this many parameters: more go into named tables
MAX_KERNEL_PARAMETERS = 12
#: a module is at most this long, unless listed in LONG_MODULES with the reason
MAX_MODULE_LINES = 800
LONG_MODULES = {
    "flexgear.config.loader": "the configuration schema and its validation, one table and one check per block, "
                              "read together",
    "flexgear.fe.meshing": "gmsh meshing of a gear body in one place: outline loops, size fields, the checksummed "
                           "disk cache",
}
COMPILING = {"kernel", "njit", "jit"}  # decorators that compile (flexgear.kernels.kernel, numba's)


def compiled_functions(path: Path):
    """(name, parameter count, line) of every function in a file decorated to be compiled."""
    tree = parse(path)
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef):
            for d in node.decorator_list:
                f = d.func if isinstance(d, ast.Call) else d
                name = f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", "")
                if name in COMPILING:
                    a = node.args
                    n = len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs) + bool(a.vararg) + bool(a.kwarg)
                    yield node.name, n, node.lineno
                    break


def too_many_parameters(files, limit=MAX_KERNEL_PARAMETERS):
    return [f"{module_name(f)}.{name} (line {line}): {n} parameters"
            for f in files for name, n, line in compiled_functions(f) if n > limit]


def import_graph(files):
    """{module: modules it imports} of package files (a ``from pkg import sub`` counts as
    importing ``pkg.sub``; imports inside functions count too)."""
    graph = {}
    for f in files:
        m = module_name(f)
        deps = set()
        for target, name, _ in imports(f):
            sub = f"{target}.{name}" if name else target
            base = PKG / Path(*sub.split(".")[1:])
            deps.add(sub if name and (base.with_suffix(".py").exists() or (base / "__init__.py").exists())
                     else target)
        deps.discard(m)
        graph[m] = deps
    return graph


def import_cycles(graph, exempt=("flexgear",)):
    """The strongly connected groups of more than one module of an import graph (Tarjan); the
    ``exempt`` modules are left out (the top package's lazy convenience functions)."""
    graph = {m: {d for d in deps if d in graph and d not in exempt} for m, deps in graph.items() if m not in exempt}
    index, low, stack, on, cycles = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                cycles.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return cycles


def long_modules(lengths, limit=MAX_MODULE_LINES, allowed=None):
    """Modules ({module: lines}) over ``limit`` lines that ``allowed`` ({module: reason}) does not list."""
    allowed = LONG_MODULES if allowed is None else allowed
    return [f"{m}: {n} lines" for m, n in sorted(lengths.items()) if n > limit and m not in allowed]


def module_lengths(files):
    return {module_name(f): len(f.read_text().splitlines()) for f in files}


def test_compiled_functions_take_a_few_named_tables():
    """A compiled function takes at most MAX_KERNEL_PARAMETERS parameters: the arrays it reads
    come in named tables (flexgear.dynamics.model.tables, integrator.buffers)."""
    found = [name for f in all_files() for name, _, _ in compiled_functions(f)]
    assert len(found) >= 100, "the scan of the compiled functions finds them"
    bad = too_many_parameters(all_files())
    assert not bad, "compiled functions with more than 12 parameters:\n" + "\n".join(bad)


def test_the_kernel_scan_sees_every_registered_kernel():
    """Every kernel flexgear.kernels registers is found by the AST scan (it cannot miss one)."""
    import importlib
    import pkgutil

    from flexgear.kernels import KERNELS

    for m in pkgutil.walk_packages(flexgear.__path__, "flexgear."):
        if not m.name.endswith("__main__"):
            importlib.import_module(m.name)
    scanned = {(module_name(f), name) for f in all_files() for name, _, _ in compiled_functions(f)}
    registered = {(d.py_func.__module__, d.py_func.__name__) for d in KERNELS
                  if d.py_func.__module__.startswith("flexgear.")}  # not a test's own kernels
    assert registered <= scanned, registered - scanned


def test_no_import_cycles():
    cycles = import_cycles(import_graph(all_files()))
    assert not cycles, "modules importing each other (directly or around a circle):\n" + "\n".join(map(str, cycles))


def test_modules_are_short_or_say_why_not():
    bad = long_modules(module_lengths(all_files()))
    assert not bad, f"modules over {MAX_MODULE_LINES} lines, not listed in LONG_MODULES with a reason:\n" + "\n".join(bad)
    lengths = module_lengths(all_files())
    stale = [m for m in LONG_MODULES if lengths.get(m, 0) <= MAX_MODULE_LINES]
    assert not stale, f"LONG_MODULES lists modules that are not long (any more): {stale}"


def test_the_room_checks_catch_violations():
    """Each check fails on a violation fed to it: a compiled function with 13 parameters, an
    import circle (also around three modules, and through an import inside a function), a
    module over the line limit."""
    a = PKG / "gears" / "_probe_a_tmp.py"
    b = PKG / "gears" / "_probe_b_tmp.py"
    a.write_text("from ..kernels import kernel\nfrom . import _probe_b_tmp\n\n\n"
                 "@kernel(error_model='numpy')\ndef wide(a, b, c, d, e, f, g, h, i, j, k, l, m):\n    return a\n\n\n"
                 "@kernel()\ndef narrow(a, b, c, d, e, f, g, h, i, j, k, l):\n    return a\n")
    b.write_text("def f():\n    from ._probe_a_tmp import narrow\n    return narrow\n")
    try:
        assert too_many_parameters([a]) == ["flexgear.gears._probe_a_tmp.wide (line 6): 13 parameters"]
        graph = import_graph([a, b])
        assert import_cycles(graph) == [["flexgear.gears._probe_a_tmp", "flexgear.gears._probe_b_tmp"]]
    finally:
        a.unlink()
        b.unlink()
    assert import_cycles({"p.x": {"p.y"}, "p.y": {"p.z"}, "p.z": {"p.x"}, "p.w": {"p.x"}}) == [["p.x", "p.y", "p.z"]]
    assert import_cycles({"p.x": {"p.y"}, "p.y": set()}) == []
    assert import_cycles({"flexgear": {"p.x"}, "p.x": {"flexgear"}}) == []  # the top package is exempt
    assert long_modules({"p.x": 801, "p.y": 800}, allowed={}) == ["p.x: 801 lines"]
    assert long_modules({"p.x": 801}, allowed={"p.x": "a reason"}) == []
