"""Every text of a run that reaches README.md or index.html is escaped: hostile strings (table pipes, HTML
tags, newlines that would start a heading, backticks, Markdown links to `javascript:`, TeX) in each text field of
summary.json and in the results folder's name change nothing of either page's structure."""

from __future__ import annotations

import json
import re

from lb_fixtures import episodes_dir, make_results  # noqa: F401  (episodes_dir is a fixture)
from mb_testing import reseal

from main_bench.leaderboard import LeaderboardSettings, TableSettings, build_leaderboard
from main_bench.leaderboard.html import html_escape
from main_bench.leaderboard.markdown import md_escape

HOSTILE = "a|b <script>alert(1)</script>\n# injected `tick` [x](javascript:alert(2)) ![i](http://e.x/i.png) **b** $x$"
FIELDS = {("submission", "name"): "N " + HOSTILE, ("submission", "description"): "D " + HOSTILE,
          ("submission", "date"): "T " + HOSTILE, ("dataset", "path"): "/P " + HOSTILE,
          ("settings", "mode"): "M " + HOSTILE, ("settings", "track"): "K " + HOSTILE}
LINKS = ["javascript:alert(3)", "https://ok.example/a?b=1&c=2", "https://x.example/<b>", "L " + HOSTILE,
         "https://evil.example/\nx"]
UNESCAPED_PIPE = re.compile(r"(?<!\\)\|")


def test_hostile_text_is_escaped_in_every_field(tmp_path, episodes_dir):  # noqa: F811
    run = make_results(tmp_path / "R <b>x</b> | `q`", episodes_dir, "plain", 0.5)
    summary = json.loads((run / "summary.json").read_text())
    for (group, key), value in FIELDS.items():
        summary.setdefault(group, {})[key] = value
    summary["submission"]["links"] = LINKS
    (run / "summary.json").write_text(json.dumps(summary))
    reseal(run)
    report = build_leaderboard([run], tmp_path / "board",
                               LeaderboardSettings(plots=False, tables=TableSettings(n_resamples=100)))
    page, readme = report.index_html.read_text(), report.readme_md.read_text()

    for value in FIELDS.values():
        assert html_escape(value) in page
        assert md_escape(value) in readme
    assert "<script" not in page.lower() and "<b>" not in page and "href=\"javascript" not in page.lower()
    # One link of the submission's own (the run-page link is the report's).
    assert page.count("<a href=") - page.count('<a href="runs/') == 1 and 'href="https://ok.example/a?b=1&amp;c=2"' in page
    assert "<script" not in readme.lower() and "<b>" not in readme
    assert not re.search(r"(?<!\\)\]\(javascript", readme) and "<javascript" not in readme
    assert "\n# injected" not in readme and "\n# injected" not in page
    assert readme.count("<https://") == 1 and "<https://ok.example/a?b=1&c=2>" in readme
    # table structure: every row of a table has as many cell separators as its header
    table: list[str] = []
    for line in [*readme.splitlines(), ""]:
        if line.startswith("|"):
            table.append(line)
            continue
        if table:
            counts = {len(UNESCAPED_PIPE.findall(row)) for row in table}
            assert len(counts) == 1, table
            table = []


def test_escape_functions_leave_plain_text_alone():
    assert md_escape("Strong method 2 (v1.5)") == "Strong method 2 (v1.5)"
    assert html_escape("Strong method 2 (v1.5)") == "Strong method 2 (v1.5)"
    assert md_escape("a\u202eb\x00c\r\nd") == "abc d" and html_escape("a\u202eb") == "ab"
