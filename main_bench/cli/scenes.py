"""`main-bench scenes`: inspect scene files, generate and preview the built-in procedural houses."""

from __future__ import annotations

import time
from pathlib import Path

import typer

from ..io import refuse_output_over_inputs
from .common import JsonOption, ScaleOption, UpOption, emit

app = typer.Typer(help="Inspect scenes; generate and preview built-in procedural houses.", rich_markup_mode=None, no_args_is_help=True)



@app.command("info", short_help="Triangles, bounds, up axis, units, hash and objects of a scene.")
def info(
    scene: Path = typer.Argument(..., help="Scene file (.glb, .gltf, .obj, .ply)."),
    up: str = UpOption,
    scale: float | None = ScaleOption,
    as_json: bool = JsonOption,
) -> None:
    """Triangle count, bounds in the canonical +Z-up frame, up axis, units, content hash and objects."""
    from ..scenes import load_scene

    loaded = load_scene(scene, up=up, scale=scale)  # type: ignore[arg-type]
    emit("scenes info", loaded.info(), as_json, _render_info)


def _render_info(d: dict) -> str:
    lines = [
        f"scene      {d['scene_id']}  ({d['path']})",
        f"triangles  {d['triangles']:,}",
        f"bounds     {d['bounds_min']} .. {d['bounds_max']} m (+Z up)",
        f"size       {d['size'][0]:.2f} x {d['size'][1]:.2f} x {d['size'][2]:.2f} m",
        f"up axis    +{d['up_axis'].upper()} in the file ({d['up_reason']})",
        f"units      x{d['scale']} ({d['scale_reason']})",
        f"hash       {d['content_hash']}",
        f"objects    {d['object_count']}" + (f" in {len(d['categories'])} categories" if d["categories"] else ""),
    ]
    for cat, n in d["categories"].items():
        lines.append(f"  {cat:<20} {n}")
    return "\n".join(lines)


@app.command("generate", short_help="Write built-in procedural houses (.glb and .objects.json).")
def generate(
    out: Path = typer.Argument(..., help="Folder to write the houses into (created if missing)."),
    count: int = typer.Option(1, "--count", "-n", min=1, max=100000, help="Number of houses."),
    seed: int = typer.Option(0, "--seed", min=0, help="Seed of the first house; the others take seed+1, seed+2, ..."),
    quiet: bool = typer.Option(False, "--quiet", help="No progress bar."),
    as_json: bool = JsonOption,
) -> None:
    """Write built-in procedural houses: `house_NNNN.glb` (+Y up) and `house_NNNN.objects.json` per seed."""
    from ..scenes.procedural import GENERATOR_VERSION, generate_house, write_house
    from .common import progress

    if out.exists() and not out.is_dir():
        from ..errors import InputError

        raise InputError("exists and is not a folder; give a folder for the houses", path=out)
    houses = []
    start = time.perf_counter()
    with progress("houses", count, enabled=not (quiet or as_json)) as advance:
        for s in range(seed, seed + count):
            house = generate_house(s)
            glb = write_house(house, out)
            houses.append({
                "scene_id": house.house_id, "seed": s, "path": str(glb), "floors": len(house.floors),
                "rooms": len(house.rooms), "area_m2": round(house.total_area, 2), "objects": len(house.furniture),
                "categories": len(house.categories), "triangles": house.triangle_count(),
            })
            advance(1)
    seconds = time.perf_counter() - start
    payload = {"out": str(out), "generator_version": GENERATOR_VERSION, "count": count, "houses": houses,
               "seconds": round(seconds, 3), "seconds_per_house": round(seconds / count, 4)}
    emit("scenes generate", payload, as_json, _render_generate)


def _render_generate(d: dict) -> str:
    lines = [f"wrote {d['count']} house(s) to {d['out']} (generator {d['generator_version']}) in "
             f"{d['seconds']:.1f} s, {d['seconds_per_house']:.2f} s per house"]
    shown = d["houses"][:20]
    lines += [f"  {h['scene_id']}  {h['floors']} floor(s), {h['rooms']:2d} rooms, {h['area_m2']:6.1f} m^2, "
              f"{h['objects']:3d} objects in {h['categories']} categories" for h in shown]
    if hidden := len(d["houses"]) - len(shown):
        lines.append(f"  ... and {hidden} more")
    return "\n".join(lines)


@app.command("preview", short_help="Top-down picture of a scene: rooms and objects.")
def preview(
    scene: Path = typer.Argument(..., help="Scene file (.glb, .gltf, .obj, .ply)."),
    out: Path = typer.Option(..., "--out", "-o", help="PNG file to write."),
    up: str = UpOption,
    scale: float | None = ScaleOption,
    as_json: bool = JsonOption,
) -> None:
    """Draw a top-down picture: obstacles, rooms by type and objects by category, one panel per floor."""
    from ..errors import InputError
    from ..scenes import load_scene
    from ..scenes.preview import find_levels, render_preview

    refuse_output_over_inputs(out, {"SCENE": scene})
    if out.suffix.lower() != ".png":
        raise InputError("the preview is a PNG; give --out a name ending in .png", path=out)
    loaded = load_scene(scene, up=up, scale=scale)  # type: ignore[arg-type]
    render_preview(loaded, out)
    payload = {"scene_id": loaded.scene_id, "out": str(out), "floors": [lv.z for lv in find_levels(loaded)],
               "objects": len(loaded.objects), "rooms": len(loaded.rooms)}
    emit("scenes preview", payload, as_json,
         lambda d: f"wrote {d['out']}: {len(d['floors'])} floor(s), {d['rooms']} rooms, {d['objects']} objects")


@app.command("import", short_help="Read a dataset's object annotations into sidecar files.")
def import_(
    src: Path = typer.Argument(..., help="Downloaded dataset folder (Habitat layout) or one annotation file."),
    fmt: str = typer.Option(..., "--format", "-f", help="mp3d, hm3d, replicacad or hssd."),
    out: Path | None = typer.Option(None, "--out", help="Folder for composed scenes (replicacad, hssd)."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace objects sidecars not written by an import."),
    up: str = UpOption,
    scale: float | None = ScaleOption,
    as_json: bool = JsonOption,
) -> None:
    """Read a dataset's object annotations into `<scene>.objects.json` sidecars (categories, boxes, rooms)."""
    from ..scenes.importers import import_scenes
    from ..scenes.importers.categories import CATEGORY_TABLE_VERSION
    from .common import check_up

    if out is not None:
        refuse_output_over_inputs(out, {"SRC": src})
    done = import_scenes(fmt, src, out=out, up=check_up(up), scale=scale, overwrite=overwrite)
    payload = {"format": fmt, "src": str(src), "category_table_version": CATEGORY_TABLE_VERSION,
               "scenes": [d.summary() for d in done]}
    emit("scenes import", payload, as_json, _render_import)


def _render_import(d: dict) -> str:
    lines = [f"imported {len(d['scenes'])} scene(s) from {d['src']} ({d['format']}, category table "
             f"v{d['category_table_version']})"]
    for s in d["scenes"]:
        skipped = ", ".join(f"{n} {why}" for why, n in s["skipped"].items())
        lines.append(f"  {s['scene_id']}: {s['objects']} objects in {len(s['categories'])} categories, "
                     f"{s['rooms']} rooms, {s['floors']} floors -> {s['sidecar']}"
                     + (f" (left out: {skipped})" if skipped else ""))
        lines += [f"    note: {n}" for n in s["notes"]]
    return "\n".join(lines)
