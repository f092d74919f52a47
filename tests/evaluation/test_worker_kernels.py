"""`worker.load_kernels`: the navmesh kernels a worker needs, loaded before its first chunk without a file."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

SAMPLE = Path(__file__).resolve().parents[2] / "episodes" / "sample"


def test_kernels_loaded_on_a_flat_square_serve_a_stored_navmesh_as_they_are():
    """`load_kernels` warms on `NavMesh.flat_square`, made in memory. A navmesh read from the data set then needs
    no kernel signature beyond those (so nothing more to load or compile), and its field answers as usual.
    In a fresh process, so no other test has loaded a signature before."""
    code = (
        "import json, numpy as np\n"
        "from main_bench.benchmarks.compiles import kernels\n"
        "from main_bench.evaluation.run.worker import load_kernels, warm_kernels\n"
        "from main_bench.episodes.dataset import load_navmesh, read_manifest\n"
        "def signatures():\n"
        "    return {k: sorted(map(str, v.signatures)) for k, v in kernels().items()}\n"
        "load_kernels()\n"
        "warmed = signatures()\n"
        f"manifest = read_manifest({str(SAMPLE)!r})\n"
        "navmesh = load_navmesh(manifest, sorted(manifest.scenes)[-1])\n"
        "warm_kernels(navmesh)\n"
        "a, b = navmesh.cells(np.array([0, len(navmesh.cells()) - 1]))\n"
        "print(json.dumps([warmed, signatures(), float(navmesh.geodesic_distance(a, b))]))\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    warmed, after, distance = json.loads(proc.stdout.strip().splitlines()[-1])
    assert after == warmed
    assert sum(len(v) for v in warmed.values()) >= 5  # the field's seed, settle, locate, look-up kernels at least
    assert distance > 0


def test_a_flat_square_is_one_floor_of_linked_cells():
    from main_bench.navmesh import NavMesh

    square = NavMesh.flat_square(4)
    cells = square.cells()
    assert cells.shape == (16, 3) and (cells[:, 2] == 0).all()
    assert len(square.floors) == 1 and len(square.islands) == 1
    corner, far = cells[0], cells[-1]
    step = square.cell_size
    # the diagonal across three cells: three diagonal steps of sqrt(2) cells each
    assert abs(float(square.geodesic_distance(corner, far)) - 3 * step * 2 ** 0.5) < 1e-6
