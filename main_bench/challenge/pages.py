"""The server's own HTML pages (the leaderboards are the toolkit's report pages): the challenge's front page, a
team's page of its submissions, the token form. Every text from a team or a file is escaped."""

from __future__ import annotations

from html import escape
from typing import Any

_STYLE = ("body{font-family:system-ui,sans-serif;margin:2em;max-width:72em;color:#222}"
          "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:.3em .6em;text-align:left}"
          "th{background:#eee}.failed{color:#a00}.scored{color:#070}")


def page(title: str, body: str) -> str:
    """A complete HTML document."""
    return (f"<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>{escape(title)}</title>"
            f"<style>{_STYLE}</style></head><body><h1>{escape(title)}</h1>{body}</body></html>")


def front(name: str, phases: list[dict[str, Any]]) -> str:
    """The front page: the phases and links to their leaderboards, and to the team page."""
    rows = "".join(
        f"<tr><td>{escape(p['name'])}</td><td>{'hidden' if p['hidden'] else 'public'}</td>"
        f"<td>{escape(p['show'])}</td><td>{p['published']}</td>"
        f"<td><a href=\"/leaderboard/{escape(p['name'])}/\">leaderboard</a></td></tr>" for p in phases)
    return page(name, "<table><tr><th>phase</th><th>kind</th><th>publishes</th><th>submissions shown</th>"
                      f"<th></th></tr>{rows}</table><p><a href=\"/team\">Your team's submissions</a></p>")


def login(name: str, message: str = "") -> str:
    """The token form of the team page."""
    note = f"<p class=\"failed\">{escape(message)}</p>" if message else ""
    return page(name, f"{note}<form method=\"post\" action=\"/login\"><label>Team token "
                      "<input type=\"password\" name=\"token\" size=\"50\"></label> <button>Show my submissions"
                      "</button></form>")


def team(name: str, team_name: str, subs: list[dict[str, Any]]) -> str:
    """A team's submissions: state, reason, scores (where published to it) and a link to the logs."""
    rows = []
    for s in subs:
        scores = s.get("scores")
        cells = "<br>".join(
            f"{escape(k)}: SPL {t['spl']['mean']:.3f} [{t['spl']['ci_low']:.3f}, {t['spl']['ci_high']:.3f}], "
            f"success {t['success']['mean']:.3f}" for k, t in (scores or {}).get("tracks", {}).items()
            if t["spl"]["mean"] is not None) if scores else ("not published" if s["state"] == "scored" else "")
        rows.append(f"<tr id=\"submission-{s['id']}\"><td>{s['id']}</td><td>{escape(s['phase'])}</td>"
                    f"<td>{escape(s['mode'])}</td><td class=\"{escape(s['state'])}\">{escape(s['state'])}</td>"
                    f"<td>{escape(s['reason'])}</td><td>{cells}</td>"
                    f"<td><a href=\"/team/log/{s['id']}\">log</a></td></tr>")
    return page(f"{name}: {team_name}",
                "<table><tr><th>id</th><th>phase</th><th>mode</th><th>state</th><th>reason</th><th>scores</th>"
                f"<th></th></tr>{''.join(rows)}</table>")


def empty_board(name: str, phase: str, why: str) -> str:
    """The leaderboard page of a phase with nothing published."""
    return page(f"{name}: {phase}", f"<p>{escape(why)}</p>")
