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


def test_render_vs_bare_loop_times_both_on_the_same_poses_and_the_bare_loop_sees_the_same_scene():
    from main_bench.benchmarks.bare_gl import BareGLLoop
    from main_bench.sim.render.gl import GLRenderer, GLUnavailable
    from main_bench.sim.synthetic import box_house

    scene = box_house(0)
    try:
        GLRenderer(scene, CameraSettings()).close()
    except GLUnavailable:
        need(False, "gl renderer needs EGL + Mesa (apt-get install libegl1 libgl1-mesa-dri) or a GPU driver")
    starts = np.array([[1.0, 1.0, 0.0], [3.0, 2.0, 0.0], [5.0, 3.0, 0.0]])
    out = bench.render_vs_bare(scene, None, starts, steps=3, repeats=2)
    assert out["sim_render_ms_per_team_step"] > 0 and out["bare_loop_ms_per_team_step"] > 0
    assert len(out["sim_over_bare_runs"]) == 2 and out["goal_sim_over_bare"] == 1.15
    assert abs(out["sim_over_bare"] - float(np.median(out["sim_over_bare_runs"]))) < 2e-3
    assert out["meets_goal"] == (out["sim_over_bare"] <= 1.15)
    row = {"scene": "box", "triangles": 1, "repeats": 2, "gl": {"agent_steps_per_s": 1.0},
           "tiny": {"agent_steps_per_s": 1.0}, "render_vs_bare": out}
    lines = bench.summary_lines({"machine": {"cpus": 2, "platform": "t", "load_average_1min_at_start": 1.0,
                                             "load_average_1min_at_end": 1.0}, "results": [row]})
    assert f"ratio {out['sim_over_bare']}" in lines[2]
    # The bare loop draws the same scene from the same poses: the same depth wherever no agent is in view.
    cam = CameraSettings()
    bare, sim = BareGLLoop(scene, cam), GLRenderer(scene, cam)
    try:
        (_, d_bare), (_, d_sim) = bare.render(starts[:1], np.zeros(1)), sim.render(starts[:1], np.zeros(1))
    finally:
        bare.close()
        sim.close()
    assert (d_sim < cam.max_depth).mean() > 0.3
    assert (np.abs(d_bare - d_sim) <= 1e-3 * d_sim).mean() > 0.99


def test_bench_sim_missing_gpu_is_one_line_and_exit_2():
    import subprocess
    import sys
    from pathlib import Path

    from main_bench.errors import InputError
    from main_bench.sim.render.gl import check_device

    try:
        check_device(0)
    except InputError:
        need(False, "EGL device enumeration needs libEGL with a driver (Mesa or a GPU's)")
    tool = Path(__file__).resolve().parents[2] / "tools" / "bench_sim.py"
    res = subprocess.run([sys.executable, str(tool), "--quick", "--gpu", "99"], capture_output=True, text=True,
                         timeout=120)
    assert res.returncode == 2 and res.stdout == ""
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "--gpu 99: no such EGL device" in lines[0]
