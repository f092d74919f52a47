"""`main-bench bench`: the benchmarks run through the CLI and report versioned JSON (no speed is asserted here)."""

from __future__ import annotations

import json


def test_bench_navmesh_quick_reports_every_measure(cli):
    r = cli("bench", "navmesh", "--quick", "--json")
    assert r.code == 0, r.err
    doc = json.loads(r.out)
    assert doc["schema_version"] == 1 and doc["quick"] is True
    res = doc["results"]["navmesh"]
    assert {f["scene"].split(" ")[1] for f in res["fields"] if f["scene"].startswith("builtin")} >= {"house_0001"}
    assert any(f["navigable_area_m2"] >= 200 for f in res["fields"])
    for f in res["fields"]:
        assert f["field_ms"] > 0 and f["lookups_per_s"] > 0 and f["networkx_over_field"] > 0
    assert set(res["goals_met"]) >= {"field_ms_per_200m2<=50 (cpu)", "lookups_per_s>=1e6"}
