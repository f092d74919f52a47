"""`main-bench navmesh`: build a navmesh file from a scene, inspect it, query distances and paths, draw it."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import typer

from ..errors import InputError
from ..io import refuse_output_over_inputs
from .common import (
    AgentHeightOption,
    AgentRadiusOption,
    CellSizeOption,
    JsonOption,
    MaxClimbOption,
    MaxSlopeOption,
    ScaleOption,
    UpOption,
    check_up,
    emit,
    parse_vec3,
)

app = typer.Typer(help="Build navmeshes and query geodesic distances.", rich_markup_mode=None, no_args_is_help=True)

FileArg = typer.Argument(..., help="Navmesh file written by `main-bench navmesh build`.")
FromOption = typer.Option(..., "--from", help="Start point x,y,z (m, +Z up, feet height).")
ToOption = typer.Option(..., "--to", help="Goal point x,y,z (m, +Z up, feet height).")


@app.command("build", short_help="Build a scene's walkable surface for an agent.")
def build(
    scene: str = typer.Argument(
        ..., help="Scene file (.glb, .gltf, .obj, .ply) or a built-in house id (house_0007)."
    ),
    out: Path = typer.Option(
        ..., "--out", "-o", help="Navmesh file to write (reused if built from the same inputs)."
    ),
    up: str = UpOption,
    scale: float | None = ScaleOption,
    agent_radius: float = AgentRadiusOption,
    agent_height: float = AgentHeightOption,
    max_climb: float = MaxClimbOption,
    max_slope: float = MaxSlopeOption,
    cell_size: float = CellSizeOption,
    cell_height: float = typer.Option(0.05, "--cell-height", help="Vertical resolution (m)."),
    region_min_size: float = typer.Option(0.05, "--region-min-size", help="Smallest island kept (m^2)."),
    force: bool = typer.Option(
        False, "--force", help="Rebuild even when --out was built from the same inputs."
    ),
    as_json: bool = JsonOption,
) -> None:
    """Build the walkable surface of a scene for an agent; write it to --out with settings and scene hash."""
    import time

    from ..navmesh import NavMesh, NavMeshSettings
    from ..navmesh.shared import shared_navmesh_dir, store_shared

    check_up(up)
    refuse_output_over_inputs(out, {"SCENE": scene})
    settings = NavMeshSettings(agent_radius=agent_radius, agent_height=agent_height, max_climb=max_climb,
                               max_slope=max_slope, cell_size=cell_size, cell_height=cell_height,
                               region_min_size=region_min_size)  # fmt: skip
    loaded = _load_scene(scene, up, scale)
    start = time.perf_counter()
    nm, reused = None, False
    if out.is_file() and not force:
        try:
            old = NavMesh.load(out)
        except InputError:
            old = None
        if old is not None and old.build_key == NavMesh.key_of(loaded, settings):
            nm, reused = old, True
    if nm is None:
        nm = NavMesh.build(loaded, settings) if force else NavMesh.build_cached(loaded, settings, shared_navmesh_dir())
        nm.save(out)
    store_shared(nm, loaded)  # episodes generate and evaluate find it there
    payload = {
        "out": str(out),
        "reused": reused,
        "seconds": round(time.perf_counter() - start, 3),
        "up_axis": loaded.up_axis,
        "up_reason": loaded.up_reason,
        "up_rule": loaded.up_rule,
        **nm.info(),
    }
    emit(
        "navmesh build",
        payload,
        as_json,
        lambda d: ("reused" if d["reused"] else "wrote") + f" {d['out']}\n"
        + f"up axis    +{d['up_axis'].upper()} in the file ({d['up_reason']})\n" + _render_info(d),
    )


def _load_scene(scene: str, up: str, scale: float | None) -> Any:
    from ..scenes.cache import load_scene_geometry

    path = Path(scene)
    if not path.exists() and scene.startswith("house_"):
        from ..scenes.builtin import default_cache_dir, ensure_builtin_scenes

        path = ensure_builtin_scenes([scene], default_cache_dir())[scene]
    return load_scene_geometry(path, up=up, scale=scale)  # type: ignore[arg-type]


@app.command("info", short_help="Islands, floors, navigable area and build settings.")
def info(file: Path = FileArg, as_json: bool = JsonOption) -> None:
    """Islands (area, floor, bounds), floors, navigable area and the build settings."""
    from ..navmesh import NavMesh

    nm = NavMesh.load(file)
    emit("navmesh info", {"file": str(file), **nm.info()}, as_json, _render_info)


def _render_info(d: dict[str, Any]) -> str:
    s = d["settings"]
    lines = [
        f"scene      {d['scene_id']}  (hash {d['scene_hash'][:12]})",
        f"settings   radius {s['agent_radius']} m, height {s['agent_height']} m, climb {s['max_climb']} m, "
        f"slope {s['max_slope']} deg, cell {s['cell_size']} m",
        f"navigable  {d['navigable_area']:.2f} m^2 in {d['cell_count']:,} cells",
        f"floors     {len(d['floors'])}",
    ]
    lines += [f"  floor {f['index']}: z = {f['z']:.2f} m, {f['area']:.1f} m^2" for f in d["floors"]]
    lines.append(f"islands    {len(d['islands'])}")
    for isl in d["islands"][:15]:
        lines.append(
            f"  island {isl['index']:3d}: {isl['area']:8.2f} m^2, floor {isl['floor']}, "
            f"z {isl['bounds_min'][2]:.2f}..{isl['bounds_max'][2]:.2f} m"
        )
    if len(d["islands"]) > 15:
        lines.append(f"  ... and {len(d['islands']) - 15} more")
    return "\n".join(lines)


def _query(file: Path, start: str, goal: str) -> tuple[Any, Any, Any]:
    import numpy as np

    from ..navmesh import NavMesh

    a = np.array(parse_vec3(start, "--from"))
    b = np.array(parse_vec3(goal, "--to"))
    return NavMesh.load(file), a, b


@app.command("distance", short_help="Geodesic distance between two points.")
def distance(
    file: Path = FileArg, start: str = FromOption, goal: str = ToOption, as_json: bool = JsonOption
) -> None:
    """Geodesic distance (m) from --from to --to; unreachable when no walkable path joins them."""
    nm, a, b = _query(file, start, goal)
    d = float(nm.geodesic_distance(a, b))
    payload = {
        "from": a.tolist(),
        "to": b.tolist(),
        "reachable": math.isfinite(d),
        "distance": round(d, 4) if math.isfinite(d) else None,
        "euclidean": round(float(((a - b) ** 2).sum() ** 0.5), 4),
    }
    emit(
        "navmesh distance",
        payload,
        as_json,
        lambda p: f"{p['distance']:.3f} m" if p["reachable"] else "unreachable",
    )


@app.command("path", short_help="Shortest path between two points.")
def path(
    file: Path = FileArg, start: str = FromOption, goal: str = ToOption, as_json: bool = JsonOption
) -> None:
    """Shortest path from --from to --to as a polyline of x,y,z points on the walkable surface."""
    import numpy as np

    nm, a, b = _query(file, start, goal)
    pts = nm.shortest_path(a, b)
    length = float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum()) if len(pts) > 1 else 0.0
    payload = {
        "from": a.tolist(),
        "to": b.tolist(),
        "reachable": bool(len(pts)),
        "length": round(length, 4) if len(pts) else None,
        "points": np.round(pts, 4).tolist(),
    }
    emit("navmesh path", payload, as_json, _render_path)


def _render_path(p: dict[str, Any]) -> str:
    if not p["reachable"]:
        return "unreachable"
    pts = "\n".join(f"  {x:.3f},{y:.3f},{z:.3f}" for x, y, z in p["points"])
    return f"{p['length']:.3f} m, {len(p['points'])} points\n{pts}"


@app.command("map", short_help="Top-down picture of a navmesh, optionally with a path.")
def draw_map(
    file: Path = FileArg,
    out: Path = typer.Option(..., "--out", "-o", help="PNG file to write."),
    start: str | None = typer.Option(None, "--from", help="Draw the shortest path from this x,y,z ..."),
    goal: str | None = typer.Option(None, "--to", help="... to this x,y,z."),
    as_json: bool = JsonOption,
) -> None:
    """Top-down picture, one panel per floor, islands coloured, optionally a shortest path."""
    import numpy as np

    from ..navmesh import NavMesh
    from ..navmesh.export import render_map

    refuse_output_over_inputs(out, {"FILE": file})
    if out.suffix.lower() != ".png":
        raise InputError("the map is a PNG; give --out a name ending in .png", path=out)
    if (start is None) != (goal is None):
        raise InputError("give both --from and --to to draw a path, or neither")
    nm = NavMesh.load(file)
    pts = None
    if start is not None and goal is not None:
        pts = nm.shortest_path(np.array(parse_vec3(start, "--from")), np.array(parse_vec3(goal, "--to")))
    panels = render_map(nm, out, pts)
    payload = {
        "out": str(out),
        "floors": panels,
        "islands": len(nm.islands),
        "path_points": None if pts is None else len(pts),
    }
    emit("navmesh map", payload, as_json, lambda d: f"wrote {d['out']}: {d['floors']} floor panel(s)")


@app.command("export", short_help="Write the walkable surface as a mesh.")
def export(
    file: Path = FileArg,
    out: Path = typer.Option(..., "--out", "-o", help="Mesh file to write."),
    fmt: str = typer.Option("obj", "--format", help="obj or glb (glb is written +Y up, as glTF requires)."),
    as_json: bool = JsonOption,
) -> None:
    """Write the walkable surface as a mesh (one square per cell) to inspect in any viewer."""
    from ..navmesh import NavMesh
    from ..navmesh.export import EXPORT_FORMATS, export_surface

    refuse_output_over_inputs(out, {"FILE": file})
    if fmt not in EXPORT_FORMATS:
        raise InputError(f"--format must be one of {', '.join(EXPORT_FORMATS)}, got {fmt!r}")
    nm = NavMesh.load(file)
    counts = export_surface(nm, out, fmt, up="y" if fmt == "glb" else "z")
    payload = {"out": str(out), "format": fmt, **counts}
    emit(
        "navmesh export",
        payload,
        as_json,
        lambda d: f"wrote {d['out']}: {d['triangles']:,} triangles, {d['area']:.2f} m^2",
    )
