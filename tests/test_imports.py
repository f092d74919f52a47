"""The package's import structure: no cycle between files, no import from a stage above.

Every module of ``main_bench`` is parsed with ``ast``; each ``import`` and ``from ... import`` anywhere in it
(inside functions too) is resolved to the package's files. The stage order below is the one
``docs/architecture.md`` documents; a module may import from its own stage and from stages below it only.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = "main_bench"
ROOT = Path(__file__).resolve().parent.parent / PACKAGE

# Lowest first. A module's stage is the longest prefix listed here (the package's own `__init__` is on the
# ground); every other module needs one.
STAGES: tuple[tuple[str, ...], ...] = (
    # shared ground: errors, files, the kernels' compiler, caches, the task rules of a data set
    ("main_bench.errors", "main_bench.io", "main_bench.jit", "main_bench.cache_root", "main_bench.parquet_read",
     "main_bench.worker_threads", "main_bench.task_rules", "main_bench.numfmt", "main_bench.portable",
     "main_bench.suggest"),
    ("main_bench.scenes",),
    ("main_bench.navmesh",),
    ("main_bench.episodes",),
    ("main_bench.sim",),
    ("main_bench.evaluation",),
    ("main_bench.leaderboard", "main_bench.stats"),
    ("main_bench.env", "main_bench.vector"),
    ("main_bench.training",),
    ("main_bench.challenge",),
    ("main_bench.benchmarks",),
    ("main_bench.cli",),
)


def module_name(path: Path, root: Path) -> str:
    """The dotted name of the module in ``path``, a file under ``root`` (the package folder)."""
    parts = list(path.relative_to(root.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def import_targets(tree: ast.Module, name: str, is_package: bool, known: set[str]) -> set[str]:
    """The modules of ``known`` that the module ``name`` imports anywhere in ``tree``.

    ``from X import Y`` counts as an import of ``X.Y`` where that is a module, else of ``X``. A package's
    ``__init__`` counts where it is named (``from main_bench.navmesh import NavMesh``), not as a side effect of
    importing one of its submodules.
    """
    found: set[str] = set()
    package = name if is_package else name.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                found.add(alias.name)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base_parts = package.split(".")
                base_parts = base_parts[: len(base_parts) - (node.level - 1)]
                base = ".".join(base_parts + ([node.module] if node.module else []))
            else:
                base = node.module or ""
            for alias in node.names:
                sub = f"{base}.{alias.name}"
                found.add(sub if sub in known else base)
    targets: set[str] = set()
    for target in found:
        # the longest known prefix: "main_bench.navmesh.field.X" is "main_bench.navmesh.field"
        parts = target.split(".")
        while parts and ".".join(parts) not in known:
            parts.pop()
        if parts and ".".join(parts) != name:
            targets.add(".".join(parts))
    return targets


def package_graph(root: Path = ROOT) -> dict[str, set[str]]:
    """Every module of the package under ``root`` with the package modules it imports."""
    files = {module_name(path, root): path for path in sorted(root.rglob("*.py"))}
    known = set(files)
    return {
        name: import_targets(ast.parse(path.read_text(), str(path)), name, path.name == "__init__.py", known)
        for name, path in files.items()
    }


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of ``graph`` with more than one module (Tarjan's algorithm)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(start: str) -> None:
        work = [(start, iter(sorted(graph.get(start, ()))))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph.get(child, ())))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return sorted(found)


def stage_of(module: str, stages: tuple[tuple[str, ...], ...] = STAGES) -> int:
    """The index in ``stages`` of the longest prefix of ``module`` listed there (0 for the root package)."""
    if "." not in module:
        return 0
    best, best_length = -1, -1
    for level, prefixes in enumerate(stages):
        for prefix in prefixes:
            if (module == prefix or module.startswith(prefix + ".")) and len(prefix) > best_length:
                best, best_length = level, len(prefix)
    if best < 0:
        raise AssertionError(f"{module} belongs to no stage: add it to STAGES in tests/test_imports.py")
    return best


def upward_imports(graph: dict[str, set[str]], stages: tuple[tuple[str, ...], ...] = STAGES) -> list[str]:
    """Each import, as ``importer -> imported``, from a module into a stage above its own."""
    return sorted(
        f"{module} -> {target}"
        for module, targets in graph.items()
        for target in targets
        if stage_of(target, stages) > stage_of(module, stages)
    )


def test_no_import_cycle_between_files() -> None:
    found = cycles(package_graph())
    assert not found, "import cycles between files:\n" + "\n".join(" <-> ".join(c) for c in found)


def test_no_import_from_a_stage_above() -> None:
    found = upward_imports(package_graph())
    assert not found, "imports from a stage above:\n" + "\n".join(found)


def test_the_graph_sees_every_kind_of_import() -> None:
    graph = package_graph()
    # relative, function-level and `from package import submodule` imports all count
    assert "main_bench.errors" in graph["main_bench.io"]
    assert len(graph) > 150 and sum(map(len, graph.values())) > 400


def test_the_checks_fail_on_a_synthetic_package(tmp_path: Path) -> None:
    root = tmp_path / "pkg"
    (root / "low").mkdir(parents=True)
    (root / "high").mkdir()
    for folder in (root, root / "low", root / "high"):
        (folder / "__init__.py").write_text("")
    (root / "low" / "a.py").write_text("from . import b\n")
    (root / "low" / "b.py").write_text("def f():\n    from .c import x\n    return x\n")
    (root / "low" / "c.py").write_text("import pkg.low.a\nfrom pkg.high.d import y\n")
    (root / "high" / "d.py").write_text("from ..low import c\ny = 1\n")
    (root / "high" / "e.py").write_text("from pkg.low.c import x\n")
    graph = package_graph(root)
    assert graph["pkg.low.a"] == {"pkg.low.b"}
    assert graph["pkg.low.b"] == {"pkg.low.c"}
    assert cycles(graph) == [["pkg.high.d", "pkg.low.a", "pkg.low.b", "pkg.low.c"]]
    stages = (("pkg", "pkg.low"), ("pkg.high",))
    assert upward_imports(graph, stages) == ["pkg.low.c -> pkg.high.d"]
    del graph["pkg.low.c"]
    assert cycles(graph) == []
    with pytest.raises(AssertionError, match="belongs to no stage"):
        stage_of("other.module", stages)


def test_no_folder_holds_more_than_fifteen_modules() -> None:
    """A folder past about 15 files splits by idea (the project's layout rule)."""
    counts: dict[str, int] = {}
    for path in ROOT.rglob("*.py"):
        folder = str(path.parent.relative_to(ROOT.parent))
        counts[folder] = counts.get(folder, 0) + 1
    crowded = {folder: n for folder, n in sorted(counts.items()) if n > 15}
    assert not crowded, f"folders with more than 15 modules (split them by idea): {crowded}"


def test_the_architecture_page_names_every_module() -> None:
    page = (ROOT.parent / "docs" / "architecture.md").read_text()
    missing = [str(path.relative_to(ROOT)) for path in sorted(ROOT.rglob("*.py"))
               if path.name != "__init__.py" and path.name not in page]
    assert not missing, "docs/architecture.md does not name: " + ", ".join(missing)
