"""The docs describe the product as it is: no diary of attempts, a short speed page, and links that resolve."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from mb_testing import REPO

DOCS = REPO / "docs"
PAGES = sorted(DOCS.glob("*.md"))
LINKED = [*PAGES, REPO / "README.md"]

_ORDINALS = ("first|second|third|fourth|fifth|sixth|seventh|eighth|ninth|tenth|eleventh|twelfth|thirteenth|"
             "fourteenth|fifteenth|sixteenth|seventeenth|eighteenth|nineteenth|twentieth|last|previous|next|"
             "earlier|later|this|that|today's|\\d+(?:st|nd|rd|th)")

#: Phrases that narrate who tried what and when, rather than say what the product does.
DIARY = {
    "numbered or named session": re.compile(rf"\b(?:{_ORDINALS})[- ](?:session|working period|period)s?\b", re.I),
    "a session's work": re.compile(r"\bsession'?s\b|\bsessions\b|\bworking period\b", re.I),
    "tried and dropped": re.compile(r"\btried\b[^.]{0,40}\bnot kept\b|\bnot kept\b|\btried today\b", re.I),
    "a correction notice": re.compile(r"\*\*correction\b|^>\s*\**correction", re.I | re.M),
    "a bisect story": re.compile(r"\bgit bisect\b|\bbisected\b", re.I),
    "an uncommitted run": re.compile(r"\(not committed\)|scripts? not committed", re.I),
    "a first-person account": re.compile(r"\bI (?:used|tried|measured|ran|did|found|left|noticed)\b|\bby my reading\b"),
    "a story marker": re.compile(r"\bfor the record\b|\ba false lead\b", re.I),
}
DATED_HEADING = re.compile(r"^#+ .*\b20\d\d-\d\d-\d\d\b", re.M)
SPEED_PAGE_MAX_LINES = 300


def diary_findings(text: str) -> list[str]:
    """Each line of `text` that narrates an attempt, as 'line N (kind): text'."""
    found = [f"line {text.count(chr(10), 0, m.start()) + 1} (a dated heading): {m.group(0)}"
             for m in DATED_HEADING.finditer(text)]
    for number, line in enumerate(text.splitlines(), start=1):
        found += [f"line {number} ({kind}): {line.strip()[:100]}" for kind, rule in DIARY.items() if rule.search(line)]
    return found


def test_the_diary_rules_catch_a_diary_and_pass_a_description():
    diary = ("### 2026-11-26, fourteenth session: the bar once more\n"
             "The tenth session's figures were taken on this session's machine.\n"
             "Tried, not kept: pinning each process to its own CPU.\n"
             "> **Correction (2026-11-26).** Not every field came out the same.\n"
             "Measured in the second working period (scripts not committed).\n"
             "I measured it twice, for the record.\n")
    for line in diary.splitlines():
        assert diary_findings(line + "\n"), line
    description = ("## Rules\n"
                   "A policy runs in a new process (its own session id, no controlling terminal).\n"
                   "Positions are refined by bisection to 2 mm. Measured 2026-11-27 00:14 UTC on the 2-core VM.\n"
                   "Pinning processes to CPUs measured no gain (10 interleaved pairs).\n")
    assert diary_findings(description) == []


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_no_page_narrates_attempts(page: Path):
    findings = diary_findings(page.read_text(encoding="utf-8"))
    assert not findings, f"{page.relative_to(REPO)} narrates attempts (history belongs in git log):\n" + \
        "\n".join(findings)


def test_the_speed_page_is_one_page():
    lines = (DOCS / "speed.md").read_text(encoding="utf-8").count("\n")
    assert lines < SPEED_PAGE_MAX_LINES, f"docs/speed.md has {lines} lines; keep it under {SPEED_PAGE_MAX_LINES}"


_MD_LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")
#: A file named in backticks: data and results by their repository path, modules also by their path in the package.
_CODE_PATH = re.compile(r"`((?:docs|tools|tests|main_bench|episodes|leaderboard)/[\w./-]+\.(?:md|json|py|parquet)"
                        r"|[\w-]+/[\w./-]+\.py)`")
_PLACEHOLDER_FOLDERS = ("dir/", "path/")
_TEST_NAME = re.compile(r"\btest_\w+")


#: Where a named path may start: the repository, the package and the tests, and their folders (a page's section
#: says which stage, so `render/gl.py` under `sim/`, `policies/hog.py` under the evaluation tests).
_ROOTS = (REPO, REPO / "main_bench", REPO / "tests",
          *sorted(p for p in (*(REPO / "main_bench").iterdir(), *(REPO / "tests").iterdir()) if p.is_dir()))


def _file_exists(named: str) -> bool:
    return named.startswith(_PLACEHOLDER_FOLDERS) or any((root / named).exists() for root in _ROOTS)


def _broken_references(path: Path) -> list[str]:
    text = path.read_text(encoding="utf-8")
    broken = []
    for target in _MD_LINK.findall(text):
        if re.match(r"[a-z]+:", target) or target.startswith("#"):
            continue
        if not (path.parent / target.split("#", 1)[0]).exists():
            broken.append(f"link {target}")
    return broken + [f"path {p}" for p in _CODE_PATH.findall(text) if not _file_exists(p)]


@pytest.mark.parametrize("page", LINKED, ids=lambda p: p.name)
def test_every_relative_link_and_named_file_exists(page: Path):
    broken = _broken_references(page)
    assert not broken, f"{page.relative_to(REPO)} points to files that do not exist: {broken}"


def test_every_benchmark_result_is_described():
    text = "\n".join(p.read_text(encoding="utf-8") for p in PAGES)
    unnamed = [f.name for f in sorted((DOCS / "bench").glob("*.json")) if f.name not in text]
    assert not unnamed, f"docs/bench files no page names (keep the latest run of each benchmark): {unnamed}"


def test_every_test_a_page_names_exists():
    tests = REPO / "tests"
    defined = {p.stem for p in tests.rglob("test_*.py")}
    for path in tests.rglob("*.py"):
        defined |= set(re.findall(r"^\s*def (test_\w+)", path.read_text(encoding="utf-8"), flags=re.M))
    named = {(page.name, name) for page in LINKED for name in _TEST_NAME.findall(page.read_text(encoding="utf-8"))}
    missing = sorted(f"{page}: {name}" for page, name in named if name not in defined)
    assert not missing, f"docs name tests that do not exist (renamed or removed?): {missing}"
