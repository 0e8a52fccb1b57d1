"""The reference b2d's renderer is compared with byte for byte (MuJoCo's own `mujoco.Renderer`), and a
count of the render calls it makes."""

import mujoco
import numpy as np

GEOM = int(mujoco.mjtObj.mjOBJ_GEOM)


def mujoco_renderer_images(model, data, camera, width, height):
    """mujoco.Renderer's RGB, depth and geom ids (-1: no geom), shadows and reflections off as in the rig."""
    with mujoco.Renderer(model, height=height, width=width) as renderer:
        def update():
            renderer.update_scene(data, camera=camera)
            renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
            renderer.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = False

        update()
        rgb = renderer.render()
        renderer.enable_depth_rendering()
        update()
        depth = renderer.render()
        renderer.enable_segmentation_rendering()
        update()
        seg = renderer.render()
    return rgb, depth, np.where(seg[..., 1] == GEOM, seg[..., 0], -1).astype(np.int32)


def count_render_calls(monkeypatch) -> list[tuple[bool, int]]:
    """A list that gains (segmentation pass?, geoms drawn) per mjr_render call from now on."""
    calls = []
    real = mujoco.mjr_render

    def spy(rect, scene, con):
        calls.append((bool(scene.flags[mujoco.mjtRndFlag.mjRND_SEGMENT]), scene.ngeom))
        real(rect, scene, con)

    monkeypatch.setattr(mujoco, "mjr_render", spy)
    return calls
