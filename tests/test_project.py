"""Project-level checks: lint, and the README's two set-up commands stay what CI runs."""

from __future__ import annotations

import re
import shutil
import subprocess

from mb_testing import REPO, need


def _quick_start_commands() -> list[str]:
    text = (REPO / "README.md").read_text(encoding="utf-8")
    section = text.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```(?:bash|sh)?\n(.*?)```", section, flags=re.S)
    return [line.strip() for block in blocks for line in block.strip().splitlines() if line.strip()]


def test_readme_has_exactly_two_setup_commands():
    commands = _quick_start_commands()
    assert len(commands) == 2, commands
    assert commands[0].startswith("pip install") and commands[0].endswith("main-bench demo")
    assert commands[1].startswith("pip install") and "pytest" in commands[1]


def test_ci_runs_the_readme_test_command_verbatim():
    ci = (REPO / ".ci" / "run").read_text(encoding="utf-8")
    test_command = _quick_start_commands()[1]
    assert any(line.strip() == test_command for line in ci.splitlines()), test_command
    assert "MAIN_BENCH_REAL_SCENES" in ci


def test_ruff_is_clean():
    ruff = shutil.which("ruff")
    need(ruff is not None, "ruff is not installed (pip install -e '.[test]')")
    proc = subprocess.run([ruff, "check", "main_bench", "tests", "tools"], cwd=REPO, capture_output=True, text=True,
                          check=False)
    assert proc.returncode == 0, proc.stdout + proc.stderr


#: Third-party modules that only optional extras provide: main_bench imports them inside the functions that need
#: them, and each must be declared by an extra. Everything else main_bench imports must be a base requirement.
EXTRA_MODULES = {"ray": "ray", "torch": "torch", "networkx": "bench", "tensorboard": "train", "starlette": "serve",
                 "uvicorn": "serve", "anyio": "serve"}


def _requirement_names(requirements: list[str]) -> set[str]:
    return {_norm(re.split(r"[\s<>=!~;\[(]", r.strip(), maxsplit=1)[0]) for r in requirements}


def _norm(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _third_party_imports() -> dict[str, set[str]]:
    """{top-level module: files of main_bench importing it} for every absolute non-stdlib import."""
    import ast
    import sys

    found: dict[str, set[str]] = {}
    for path in sorted((REPO / "main_bench").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            else:
                continue
            for name in names:
                top = name.split(".")[0]
                if top not in sys.stdlib_module_names and top != "main_bench":
                    found.setdefault(top, set()).add(str(path.relative_to(REPO)))
    return found


def test_every_third_party_import_is_a_declared_requirement():
    import tomllib
    from importlib.metadata import packages_distributions

    project = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    base = _requirement_names(project["dependencies"])
    extras = {name: _requirement_names(reqs) for name, reqs in project["optional-dependencies"].items()}
    dists = packages_distributions()
    problems = []
    for module, files in sorted(_third_party_imports().items()):
        if module in EXTRA_MODULES:
            extra = EXTRA_MODULES[module]
            if _norm(module) not in extras.get(extra, set()):
                problems.append(f"{module} (imported by {sorted(files)}) is not declared by the [{extra}] extra")
            continue
        owners = {_norm(d) for d in dists.get(module, [module])}
        if not owners & base:
            problems.append(f"{module} (imported by {sorted(files)}) is not a base requirement of pyproject.toml")
    assert not problems, "\n".join(problems)


def test_ci_runs_both_readme_commands_in_fresh_environments():
    ci = (REPO / ".ci" / "run").read_text(encoding="utf-8")
    demo, tests = _quick_start_commands()
    lines = [line.strip() for line in ci.splitlines()]
    assert demo in lines and tests in lines, (demo, tests)
    assert ci.count("-m venv") >= 2, "each README command runs in its own fresh virtual environment"
