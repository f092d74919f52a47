"""The report page in headless Chromium: no console errors, a non-blank screenshot, hostile names as text."""

from __future__ import annotations

import re
from pathlib import Path

import lb_fixtures
import numpy as np
import pytest
from lb_fixtures import make_results
from mb_testing import chromium, console_lines
from PIL import Image

from main_bench.leaderboard import LeaderboardSettings, TableSettings, build_leaderboard

episodes_dir = lb_fixtures.episodes_dir
three_results = lb_fixtures.three_results
EVIL = "<script>alert(1)</script>"
# Injected only into a probe copy of the page: records errors and alert() calls on the <html> element.
PROBE = ("<script>window.addEventListener('error',function(e){var h=document.documentElement;"
         "h.setAttribute('data-errors',(h.getAttribute('data-errors')||'')+e.message+';')});"
         "window.alert=function(m){document.documentElement.setAttribute('data-alert',String(m))};</script>")


def with_probe(page: Path, out: Path) -> Path:
    text = page.read_text()
    out.write_text(text.replace("<head>", "<head>" + PROBE, 1))
    return out


@pytest.fixture(scope="module")
def report(tmp_path_factory, episodes_dir, three_results):
    base = tmp_path_factory.mktemp("browser")
    evil = make_results(base / "evil", episodes_dir, EVIL, 0.6, seed=4, description="<b>bold?</b> & co")
    settings = LeaderboardSettings(pictures=0, tables=TableSettings(n_resamples=200))
    return build_leaderboard([*three_results, evil], base / "lb", settings)


def test_checks_catch_a_broken_page(tmp_path):
    bad = tmp_path / "bad.html"
    bad.write_text("<!DOCTYPE html><html><head></head><body><script>alert(5); nope();</script></body></html>")
    res = chromium(tmp_path, "--dump-dom", with_probe(bad, tmp_path / "probe.html").as_uri())
    html_tag = re.search(r"<html[^>]*>", res.stdout).group(0)
    assert 'data-alert="5"' in html_tag and "nope is not defined" in html_tag
    assert console_lines(res.stderr)


def test_page_renders_without_console_errors(tmp_path, report):
    shot = tmp_path / "shot.png"
    res = chromium(tmp_path, f"--screenshot={shot}", "--window-size=1280,2000", report.index_html.as_uri())
    assert res.returncode == 0, res.stderr[-2000:]
    assert console_lines(res.stderr) == [], console_lines(res.stderr)
    img = np.asarray(Image.open(shot).convert("L"), dtype=np.float64)
    assert img.shape == (2000, 1280)
    assert img.std() > 10, "screenshot is blank"
    # Text in the top band, and the plots (colour) further down are not all white either.
    assert img[:300].std() > 5 and (img < 128).mean() > 0.01


def test_hostile_submission_name_shows_as_text(tmp_path, report):
    res = chromium(tmp_path, "--dump-dom", with_probe(report.index_html, tmp_path / "probe.html").as_uri())
    assert res.returncode == 0, res.stderr[-2000:]
    dom = res.stdout
    html_tag = re.search(r"<html[^>]*>", dom).group(0)
    assert "data-alert" not in html_tag and "data-errors" not in html_tag, html_tag
    assert console_lines(res.stderr) == []
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in dom
    assert "&lt;b&gt;bold?&lt;/b&gt; &amp; co" in dom
    assert dom.count("<script") == 1  # only the probe
    run_page = next(p for p in report.run_pages if "script" in p.name)
    res = chromium(tmp_path, "--dump-dom", with_probe(run_page, tmp_path / "probe_run.html").as_uri())
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in res.stdout and res.stdout.count("<script") == 1


# Appended to a copy of a page: after layout, records the page's width and which table wrappers scroll.
WIDTH_PROBE = ("<script>(function(){var h=document.documentElement,over=[];"
               "document.querySelectorAll('div.table').forEach(function(d,i){if(d.scrollWidth>d.clientWidth+1)"
               "over.push(i)});h.setAttribute('data-page-width',String(h.scrollWidth));"
               "h.setAttribute('data-view-width',String(h.clientWidth));"
               "h.setAttribute('data-overflow',over.join(','));})();</script>")


def widths(tmp_path: Path, page: Path, width: int) -> tuple[int, int, str]:
    """(page scroll width, viewport width, indices of tables wider than their box) at a window `width` px wide."""
    probe = tmp_path / f"width_{page.name}"
    probe.write_text(page.read_text().replace("</body>", WIDTH_PROBE + "</body>"))
    res = chromium(tmp_path, "--dump-dom", f"--window-size={width},1000", probe.as_uri())
    tag = re.search(r"<html[^>]*>", res.stdout).group(0)
    get = dict(re.findall(r'data-([a-z-]+)="([^"]*)"', tag))
    return int(get["page-width"]), int(get["view-width"]), get["overflow"]


#: The paper's Table 2 rows (issue 36): seven algorithms and random, teams of 2 and 3.
TABLE2_METHODS = ("Multi-PPO (silent)", "IPPO (silent)", "MAPPO (silent)", "Comm-S (comm)", "Comm-V (comm)",
                  "Comm-RM (comm)", "Comm-RV (comm)", "random (silent)")


def test_table2_shaped_board_fits_1400_px(tmp_path, episodes_dir):
    runs = [make_results(tmp_path / f"r{k}", episodes_dir, name, 0.1 + 0.1 * k, seed=k)
            for k, name in enumerate(TABLE2_METHODS)]
    report = build_leaderboard(runs, tmp_path / "lb", LeaderboardSettings(plots=False, pictures=0,
                                                                          tables=TableSettings(n_resamples=100)))
    page = report.index_html.read_text()
    assert page.count("Table 2 shape") == 2 and all(escape_name(n) in page for n in TABLE2_METHODS)
    for shown in (report.index_html, report.run_pages[0]):
        page_width, view, over = widths(tmp_path, shown, 1400)
        assert page_width <= view and over == "", (shown.name, page_width, view, over)
    # The check sees an overflow where there is one: the same board in a 900 px window.
    page_width, view, over = widths(tmp_path, report.index_html, 900)
    assert over != ""


def escape_name(name: str) -> str:
    from html import escape

    return escape(name)
