"""The simulator benchmark's timing harness (tools/bench_sim.py, `main-bench bench sim`), on a tiny run."""

from __future__ import annotations

import numpy as np
from mb_testing import need

from main_bench.benchmarks import sim as bench
from main_bench.sim import CameraSettings
from main_bench.sim.synthetic import room


def test_time_backends_reports_every_backend_side_by_side():
    from main_bench.sim.render.gl import GLRenderer, GLUnavailable

    try:
        GLRenderer(room(), CameraSettings()).close()
    except GLUnavailable:
        need(False, "gl renderer needs EGL + Mesa (apt-get install libegl1 libgl1-mesa-dri) or a GPU driver")
    starts = np.array([[1.0, 1.0, 0.0], [3.0, 2.0, 0.0], [5.0, 3.0, 0.0]])
    out = bench.time_backends(room(), None, starts, steps=4, repeats=2)
    assert list(out) == ["gl", "tiny"]
    for res in out.values():
        assert len(res["agent_steps_per_s_runs"]) == 2 and res["agent_steps_per_s"] > 0, res
        assert res["team_steps_per_repeat"] == 4 and res["render_ms_per_team_step"] > 0
    assert out["gl"]["device"] not in ("", "gl", "unknown")  # the GL_RENDERER string is recorded
    row = {"scene": "room", **out}
    bench._verdict(row)
    assert row["fastest"] in ("gl", "tiny")
    assert row["gl_over_tiny"] == round(out["gl"]["agent_steps_per_s"] / out["tiny"]["agent_steps_per_s"], 2)
    result = {"machine": {"cpus": 2, "platform": "test", "load_average_1min_at_start": 1.0,
                          "load_average_1min_at_end": 1.5}, "results": [{**row, "triangles": 1, "repeats": 2}]}
    lines = bench.summary_lines(result)
    assert len(lines) == 2 and f"gl {out['gl']['agent_steps_per_s']} agent-steps/s" in lines[1]
    broken = bench.time_backends(room(), None, starts, steps=2, repeats=1, backends=("tiny", "vulkan"))
    assert "agent_steps_per_s" in broken["tiny"] and "vulkan" in broken["vulkan"]["error"]
