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
