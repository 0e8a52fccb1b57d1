"""episode_qpos assembles the scene's full positions by joint name, articulated joints included."""

import mujoco
import numpy as np
import pytest

from episode_media.qpos import episode_qpos
from episode_media.source import FrameRange
from episodes import schema
from episodes.writer import EpisodeWriter
from sim import physics
from sim.errors import SpecError
from sim.scene.builder import build_scene
from sim.scene.sample import demonstration_sample
from sim.tasks import load_task

TASK, JOINT = "trash_disposal", "trash_can/lid"


@pytest.fixture(scope="module")
def lid_falling(tmp_path_factory):
    """A real trash-disposal scene whose lid, let go half open, falls shut over three frames; the
    frames written in the episode layout (robot, free-object poses, articulated joints by name)."""
    task = load_task(TASK)
    scene = build_scene(task, task.paper_embodiment, demonstration_sample(task, 7))
    data = scene.home_data()
    data.qpos[scene.joint_qpos_adr[JOINT]] = 1.2
    mujoco.mj_forward(scene.model, data)
    objects = {}
    for joint in scene.joint_names:
        objects.setdefault(joint.split("/")[0], []).append(joint)
    static = {"meta/schema_version": schema.SCHEMA_VERSION, "robot/joint_names": list(scene.layout.joint_names),
              **{f"objects/{obj}/joint_names": joints for obj, joints in objects.items()}}
    path, states = tmp_path_factory.mktemp("articulated") / "episode_lid.hdf5", []
    with EpisodeWriter(path, static) as writer:
        for k in range(3):
            for _ in range(10):
                physics.step_control(scene.model, data, scene.layout.home_ctrl)
            frame = {"time/frame_index": np.int64(k), "robot/qpos": data.qpos[scene.robot_qpos_adr]}
            for name, adr in scene.object_qpos_adr.items():
                frame[f"objects/{name}/pose_world"] = data.qpos[adr: adr + 7]
            for obj, joints in objects.items():
                frame[f"objects/{obj}/qpos"] = data.qpos[[scene.joint_qpos_adr[j] for j in joints]]
            writer.append(frame)
            states.append(data.qpos.copy())
    return scene, path, np.array(states)


def test_positions_come_back_exactly_by_joint_name(lid_falling):
    scene, path, states = lid_falling
    lid = states[:, scene.joint_qpos_adr[JOINT]]
    assert lid[0] > lid[2] + 0.05                 # the lid really moves between frames
    np.testing.assert_array_equal(episode_qpos(path, scene.model), states)
    np.testing.assert_array_equal(episode_qpos(path, scene.model, FrameRange(1, 3, 1)), states[1:])


def test_a_missing_articulated_joint_is_named(lid_falling, tmp_path):
    import h5py

    scene, path, _ = lid_falling
    broken = tmp_path / "episode_no_joint.hdf5"
    broken.write_bytes(path.read_bytes())
    with h5py.File(broken, "a") as f:
        del f["objects/trash_can/joint_names"]
    with pytest.raises(SpecError, match=r"objects/trash_can/joint_names.*trash_can/lid"):
        episode_qpos(broken, scene.model)
