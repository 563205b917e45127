"""The package in layers: each folder of ``gsrwt_cli`` is a layer, and a module imports only
modules of its own layer or of the layers below it, with no circle anywhere.

Read from the source (``ast``), so every import counts: at module level, inside functions
(the lazy ones), under ``if TYPE_CHECKING``, relative or absolute.
"""

from __future__ import annotations

import ast
from pathlib import Path

import gsrwt_cli

#: The layers, lowest first: a module may import its own layer and the layers before it.
LAYERS = ("base", "geometry", "io", "imaging", "vision", "inputs", "api", "tables", "batch",
          "cli")
#: Modules outside the layers: the package itself (``__version__`` and the lazy exports, by
#: name) and ``python -m gsrwt_cli``. They may import any layer and any layer may import them.
ENTRY = ("gsrwt_cli", "gsrwt_cli.__main__")

PACKAGE_DIR = Path(gsrwt_cli.__file__).parent


def module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def package_imports(package_dir: Path) -> dict[str, list[tuple[str, int]]]:
    """Each module of the package (dotted name) and the package's modules it imports, with
    the line of each import."""
    root = package_dir.parent
    files = sorted(package_dir.rglob("*.py"))
    known = {module_name(path, root) for path in files}
    graph: dict[str, list[tuple[str, int]]] = {}
    for path in files:
        name = module_name(path, root)
        here = name if path.name == "__init__.py" else name.rpartition(".")[0]
        found = []
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = here.split(".")[: len(here.split(".")) - node.level + 1]
                    stem = ".".join([*base, *([node.module] if node.module else [])])
                else:
                    stem = node.module or ""
                submodules = [f"{stem}.{a.name}" for a in node.names
                              if f"{stem}.{a.name}" in known]
                # `from pkg import module`: the module; `from pkg import name`: pkg itself
                targets = submodules + ([stem] if len(submodules) < len(node.names) else [])
            else:
                continue
            for target in targets:
                while target not in known and "." in target:
                    target = target.rpartition(".")[0]  # an attribute: its module
                if target in known and target != name:
                    found.append((target, node.lineno))
        graph[name] = found
    return graph


def layer_of(module: str) -> str | None:
    """The layer of a module, None for the :data:`ENTRY` modules."""
    if module in ENTRY:
        return None
    return module.split(".")[1]


def circles(graph: dict[str, list[tuple[str, int]]]) -> list[list[str]]:
    """The import circles: strongly connected sets of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found: list[list[str]] = []

    def visit(module: str) -> None:
        index[module] = low[module] = len(index)
        stack.append(module)
        for target, _ in graph.get(module, ()):
            if target not in index:
                visit(target)
                low[module] = min(low[module], low[target])
            elif target in stack:
                low[module] = min(low[module], index[target])
        if low[module] == index[module]:
            members = []
            while not members or members[-1] != module:
                members.append(stack.pop())
            if len(members) > 1:
                found.append(sorted(members))

    for module in sorted(graph):
        if module not in index:
            visit(module)
    return found


GRAPH = package_imports(PACKAGE_DIR)


def test_every_module_lives_in_a_layer():
    """A new module goes into the folder of its layer, not beside them."""
    outside = [m for m in GRAPH if m not in ENTRY and layer_of(m) not in LAYERS]
    assert outside == [], f"modules in no layer of {LAYERS}: {outside}"


def test_no_import_circle():
    assert circles(GRAPH) == []


def test_no_layer_imports_a_layer_above_it():
    upward = [
        f"{module} ({layer_of(module)}) line {line} imports {target} ({layer_of(target)})"
        for module, imports in sorted(GRAPH.items()) if layer_of(module) in LAYERS
        for target, line in imports if layer_of(target) in LAYERS
        and LAYERS.index(layer_of(target)) > LAYERS.index(layer_of(module))
    ]
    assert upward == [], "\n".join(upward)


def test_a_layer_package_imports_nothing():
    """Importing one module of a layer loads none of its siblings (start-up stays lazy).
    Not ``cli``, the top: its ``__init__`` is the command group, which loads each command
    only when it is used."""
    assert {layer: GRAPH[f"gsrwt_cli.{layer}"] for layer in LAYERS[:-1]
            if GRAPH.get(f"gsrwt_cli.{layer}")} == {}


def test_the_walk_sees_every_kind_of_import(tmp_path):
    """The walk itself, on a package written here: a circle made of relative, function-level
    and `from package import module` imports, and an import of a layer above."""
    package = tmp_path / "gsrwt_cli"
    for folder in ("geometry", "io"):
        (package / folder).mkdir(parents=True)
        (package / folder / "__init__.py").write_text("")
    (package / "__init__.py").write_text("")
    (package / "geometry" / "a.py").write_text("def f():\n    from ..io import b\n")
    (package / "io" / "b.py").write_text("from gsrwt_cli.geometry.a import f\n")
    graph = package_imports(package)
    assert graph["gsrwt_cli.geometry.a"] == [("gsrwt_cli.io.b", 2)]
    assert graph["gsrwt_cli.io.b"] == [("gsrwt_cli.geometry.a", 1)]
    assert circles(graph) == [["gsrwt_cli.geometry.a", "gsrwt_cli.io.b"]]
