"""What the renderers draw of a scene: triangle soup with per-corner colours, UVs and texture images.

Both backends read the scene's parts (`Scene.meshes`) through `scene_surfaces`: colours come from
ColorVisuals (face or vertex colours) or from a material's base colour; TextureVisuals with an image keep
their UVs and image so a backend can sample it (`gl`) or average it per face (`tiny`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from PIL import Image

from ...scenes.loader import Scene

if TYPE_CHECKING:
    import trimesh

#: Colour of surfaces that carry no colour at all (light grey).
DEFAULT_RGBA = np.array([200, 200, 200, 255], dtype=np.uint8)
#: Side of the square every texture is resampled to (one layer of a texture array).
TEXTURE_SIZE = 256


@dataclass(frozen=True, eq=False)
class Surfaces:
    """A scene as unindexed triangles in the canonical frame.

    `corners` (F, 3, 3) float32 metres; `colors` (F, 3, 4) uint8 RGBA per corner (already multiplied by the
    material's base colour); `uvs` (F, 3, 2) float32; `layer` (F,) int32: index into `textures`, -1 = none;
    `textures`: RGBA uint8 images, each TEXTURE_SIZE x TEXTURE_SIZE, row 0 = top of the image; `closed` (F,)
    bool: the face belongs to a closed, outward-wound surface (`closed_outward`), so it is never seen from
    behind unless the viewer is inside a solid, and a renderer may cull it when it faces away.
    """

    corners: np.ndarray
    colors: np.ndarray
    uvs: np.ndarray
    layer: np.ndarray
    textures: tuple[np.ndarray, ...]
    closed: np.ndarray

    def face_colors(self) -> np.ndarray:
        """(F, 4) uint8 colour per face: mean corner colour, times the mean texel around the face's UVs."""
        base = self.colors.astype(np.float32).mean(axis=1)
        textured = np.nonzero(self.layer >= 0)[0]
        if len(textured):
            uv = self.uvs[textured].mean(axis=1)
            u = np.mod(uv[:, 0], 1.0)
            v = np.mod(uv[:, 1], 1.0)
            col = np.clip((u * TEXTURE_SIZE).astype(np.int64), 0, TEXTURE_SIZE - 1)
            row = np.clip(((1.0 - v) * TEXTURE_SIZE).astype(np.int64), 0, TEXTURE_SIZE - 1)
            stack = np.stack(self.textures)
            texel = stack[self.layer[textured], row, col].astype(np.float32)
            base[textured] = base[textured] * texel / 255.0
        return np.clip(np.rint(base), 0, 255).astype(np.uint8)


def _rgba(color: object) -> np.ndarray:
    arr = np.asarray(color, dtype=np.float64).ravel()
    if arr.size == 3:
        arr = np.append(arr, 255.0 if arr.max() > 1.0 else 1.0)
    if arr.size != 4:
        return DEFAULT_RGBA.copy()
    if arr.max() <= 1.0:
        arr = arr * 255.0
    return np.clip(np.rint(arr), 0, 255).astype(np.uint8)


def _material_color_and_image(material: object) -> tuple[np.ndarray, Image.Image | None]:
    import trimesh

    if isinstance(material, trimesh.visual.material.PBRMaterial):
        color = DEFAULT_RGBA if material.baseColorFactor is None else _rgba(material.baseColorFactor)
        return color, material.baseColorTexture
    if isinstance(material, trimesh.visual.material.SimpleMaterial):
        if material.image is not None:  # OBJ/MTL practice: map_Kd replaces Kd (trimesh defaults Kd to grey)
            return np.full(4, 255, dtype=np.uint8), material.image
        color = DEFAULT_RGBA if material.diffuse is None else _rgba(material.diffuse)
        return color, None
    return DEFAULT_RGBA.copy(), None


def _texture_array(image: Image.Image) -> np.ndarray:
    img = image.convert("RGBA").resize((TEXTURE_SIZE, TEXTURE_SIZE), Image.Resampling.BILINEAR)
    return np.asarray(img, dtype=np.uint8).copy()


def scene_surfaces(scene: Scene) -> Surfaces:
    """Flatten the scene's parts into one triangle soup with colours, UVs and texture layers."""
    if scene.meshes:
        import trimesh  # here: a scene read from the cache has no parts and needs no trimesh
    corners, colors, uvs, layers, closed = [], [], [], [], []
    textures: list[np.ndarray] = []
    image_ids: dict[int, int] = {}
    for mesh in scene.meshes:
        faces = np.asarray(mesh.faces, dtype=np.int64)
        if len(faces) == 0:
            continue
        nf = len(faces)
        corners.append(np.asarray(mesh.vertices, dtype=np.float32)[faces])
        uv = np.zeros((nf, 3, 2), dtype=np.float32)
        layer = np.full(nf, -1, dtype=np.int32)
        visual = mesh.visual
        if isinstance(visual, trimesh.visual.TextureVisuals):
            color, image = _material_color_and_image(visual.material)
            col = np.broadcast_to(color, (nf, 3, 4)).copy()
            if image is not None and visual.uv is not None and len(visual.uv) == len(mesh.vertices):
                key = id(image)
                if key not in image_ids:
                    image_ids[key] = len(textures)
                    textures.append(_texture_array(image))
                uv = np.asarray(visual.uv, dtype=np.float32)[faces]
                layer[:] = image_ids[key]
        elif isinstance(visual, trimesh.visual.ColorVisuals) and visual.defined:
            if visual.kind == "vertex":
                col = np.asarray(visual.vertex_colors, dtype=np.uint8)[faces]
            else:
                col = np.repeat(np.asarray(visual.face_colors, dtype=np.uint8)[:, None, :], 3, axis=1)
        else:
            col = np.broadcast_to(DEFAULT_RGBA, (nf, 3, 4)).copy()
        colors.append(col)
        uvs.append(uv)
        layers.append(layer)
        closed.append(closed_outward(mesh))
    return Surfaces(
        corners=np.concatenate(corners).astype(np.float32),
        colors=np.concatenate(colors).astype(np.uint8),
        uvs=np.concatenate(uvs),
        layer=np.concatenate(layers),
        textures=tuple(textures),
        closed=np.concatenate(closed),
    )


def closed_outward(mesh: trimesh.Trimesh) -> np.ndarray:
    """(F,) bool: faces of connected components that are closed (the mesh is watertight with consistent
    winding) and wound outward (positive enclosed volume). All False for an open or inconsistent mesh."""
    faces = np.asarray(mesh.faces, dtype=np.int64)
    out = np.zeros(len(faces), dtype=bool)
    if len(faces) == 0 or not (mesh.is_watertight and mesh.is_winding_consistent):
        return out
    import trimesh

    labels = trimesh.graph.connected_component_labels(mesh.face_adjacency, node_count=len(faces))
    tri = np.asarray(mesh.vertices, dtype=np.float64)[faces]
    signed = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])) / 6.0
    volume = np.bincount(labels, weights=signed)
    return volume[labels] > 1e-9


def face_normals(corners: np.ndarray) -> np.ndarray:
    """(F, 3) unit normals (float64) of triangles given as corners (F, 3, 3); degenerate faces get (0, 0, 0)."""
    c = np.asarray(corners, dtype=np.float64)
    normals = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])
    return normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)


def agent_colors(n: int) -> np.ndarray:
    """(n, 3) float RGB in [0, 1]: a distinct, saturated colour per agent index (fixed, not random)."""
    hues = (np.arange(n) * 0.618033988749895 + 0.05) % 1.0
    out = np.empty((n, 3))
    for i, h in enumerate(hues):
        k = (np.array([5.0, 3.0, 1.0]) + h * 6.0) % 6.0
        out[i] = 1.0 - 0.85 * np.clip(np.minimum(k, 4.0 - k), 0.0, 1.0)
    return out
