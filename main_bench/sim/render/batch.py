"""Batch rendering: the views of many teams, in any of several scenes, in one call and one GL context.

    renderer = BatchRenderer(camera, kind="auto")
    rgb, depth = renderer.render([(scene_a, feet_a, yaws_a), (scene_b, feet_b, yaws_b)], rgb=False)
    # rgb (sum N, H, W, 3) uint8 (zeros with rgb=False), depth (sum N, H, W, 1) float32 metres

Each team sees its own agents only (as `Renderer.render` draws them); teams never see each other, also in the
same scene. With the `gl` backend every scene is baked once into one shared context (`GLRenderer(context=...)`),
all views go into one framebuffer as tiles, and one readback per attachment returns them (depth only when
`rgb=False`, which halves the readback); a call splits into passes only where the framebuffer's height limit
(`GL_MAX_RENDERBUFFER_SIZE`) is reached. With `tiny` each team is one call of its scene's renderer. The images
equal those of a one-scene renderer of the same backend (`tests/sim/test_batch_render.py`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ...scenes.loader import Scene
from ..settings import CameraSettings
from .base import make_renderer
from .protocol import Renderer

#: One team's views to render: (its scene, feet (N, 3) metres, yaws (N,) radians).
Team = tuple[Scene, np.ndarray, np.ndarray]


class BatchRenderer:
    """Renders many teams' views per call (see the module docstring). `kind` and `gpu` as `make_renderer`'s;
    the first scene decides the backend (`name`, `reason`, `device`), and later scenes join its context."""

    def __init__(self, camera: CameraSettings, kind: str = "auto", *, agent_radius: float = 0.18,
                 agent_height: float = 1.5, gpu: int | None = None) -> None:
        self.camera, self.kind, self.gpu = camera, kind, gpu
        self._shape = {"agent_radius": agent_radius, "agent_height": agent_height}
        self._renderers: dict[int, tuple[Scene, Renderer]] = {}
        self._first: Renderer | None = None
        self._fbo: Any = None
        self._rbs: tuple = ()
        self._tiles = 0
        self.name = self.reason = self.device = ""

    def _renderer(self, scene: Scene) -> Renderer:
        key = id(scene)
        if key in self._renderers:
            return self._renderers[key][1]
        if self._first is None:
            made = make_renderer(self.kind, scene, self.camera, gpu=self.gpu, **self._shape)
            self._first = made
            self.name, self.reason, self.device = made.name, made.reason, made.device
        elif self.name == "gl":
            from .gl import GLRenderer

            ctx = self._first._ctx  # type: ignore[attr-defined]
            with ctx:
                made = GLRenderer(scene, self.camera, reason=self.reason, device_index=self.gpu, context=ctx,
                                  **self._shape)
        else:
            made = make_renderer(self.name, scene, self.camera, gpu=self.gpu, **self._shape)
        self._renderers[key] = (scene, made)  # the scene is kept, so its id is not reused while cached
        return made

    @property
    def max_tiles(self) -> int:
        """Views per pass of the gl backend (the framebuffer's height limit over the image height)."""
        first = self._first
        return max(1, int(first._ctx.info.get("GL_MAX_RENDERBUFFER_SIZE", 4096)) // self.camera.height)  # type: ignore[union-attr]

    def _framebuffer(self, tiles: int) -> Any:
        if self._fbo is None or self._tiles < tiles:
            ctx = self._first._ctx  # type: ignore[union-attr]
            self._release_framebuffer()
            size = (self.camera.width, self.camera.height * tiles)
            self._rbs = (ctx.renderbuffer(size, 4), ctx.renderbuffer(size, 1, dtype="f4"), ctx.depth_renderbuffer(size))
            self._fbo = ctx.framebuffer(color_attachments=self._rbs[:2], depth_attachment=self._rbs[2])
            self._tiles = tiles
        return self._fbo

    def render(self, teams: Sequence[Team], rgb: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """Every view of every team, in order: rgb (sum N, H, W, 3) uint8 (zeros when `rgb` is False),
        depth (sum N, H, W, 1) float32 z-depth in metres, `max_depth` where nothing lies within range."""
        for scene, _, _ in teams:
            self._renderer(scene)
        sizes = [len(np.asarray(feet).reshape(-1, 3)) for _, feet, _ in teams]
        total, w, h = sum(sizes), self.camera.width, self.camera.height
        out_rgb = (np.empty if rgb else np.zeros)((total, h, w, 3), dtype=np.uint8)
        out_depth = np.empty((total, h, w, 1), dtype=np.float32)
        if total == 0:
            return out_rgb, out_depth
        if self.name != "gl":
            start = 0
            for (scene, feet, yaws), n in zip(teams, sizes, strict=True):
                views, out_depth[start:start + n] = self._renderer(scene).render(feet, yaws)
                if rgb:
                    out_rgb[start:start + n] = views
                start += n
            return out_rgb, out_depth
        for first, last, group in _passes(sizes, self.max_tiles):
            self._draw_pass(teams[group.start:group.stop], sizes[group.start:group.stop],
                            out_rgb[first:last] if rgb else None, out_depth[first:last])
        out_depth *= np.float32(self.camera.max_depth)
        return out_rgb, out_depth

    def _draw_pass(self, teams: Sequence[Team], sizes: list[int], rgb: np.ndarray | None, depth: np.ndarray) -> None:
        views, w, h = sum(sizes), self.camera.width, self.camera.height
        with self._first._ctx:  # type: ignore[union-attr]
            fbo = self._framebuffer(views)
            fbo.use()
            area = (0, 0, w, h * views)
            fbo.clear(1.0, 1.0, 1.0, 1.0, depth=1.0, viewport=area)
            tile = 0
            for (scene, feet, yaws), n in zip(teams, sizes, strict=True):
                self._renderer(scene).draw_team(feet, yaws, tile)  # type: ignore[attr-defined]
                tile += n
            if rgb is not None:
                fbo.read_into(rgb, viewport=area, components=3, attachment=0)
            fbo.read_into(depth, viewport=area, components=1, attachment=1, dtype="f4")

    def _release_framebuffer(self) -> None:
        for obj in (self._fbo, *self._rbs):
            if obj is not None:
                obj.release()
        self._fbo, self._rbs, self._tiles = None, (), 0

    def close(self) -> None:
        """Release every scene's renderer, then the shared context."""
        if self.name == "gl" and self._first is not None:
            with self._first._ctx:  # type: ignore[attr-defined]
                self._release_framebuffer()
        for _, renderer in self._renderers.values():
            if renderer is not self._first:
                renderer.close()
        if self._first is not None:
            self._first.close()
        self._renderers, self._first = {}, None


def _passes(sizes: list[int], max_tiles: int) -> list[tuple[int, int, slice]]:
    """Whole teams per pass, at most `max_tiles` views each (a larger team gets a pass of its own): (first view,
    end view, teams)."""
    out, start, team, first, tiles = [], 0, 0, 0, 0
    for k, n in enumerate(sizes):
        if tiles and tiles + n > max_tiles:
            out.append((first, start, slice(team, k)))
            team, first, tiles = k, start, 0
        tiles += n
        start += n
    out.append((first, start, slice(team, len(sizes))))
    return out
