"""Training from real episodes into safetensors checkpoints, and closed-loop evaluation through the policy
interface: byte-identical checkpoints for the same seed, clear errors for corrupt or mismatched
checkpoints, error episodes recorded while the others go on."""

import json

import numpy as np
import pytest

from policies.checkpoint import MANIFEST, STATS, WEIGHTS, load_checkpoint
from policies.closed_loop import IncompatiblePolicy, run_episode
from policies.config import load_policy_config
from policies.dataset import PolicyDataset
from policies.learned import LearnedPolicy, TemporalEnsembler
from policies.rollouts import run_rollouts
from policies.train import train_policy
from sim.errors import SpecError
from sim.scene.builder import demonstration_scene

TASK, EMBODIMENT = "citrus_plate_loading", "ur5_rh5dg2"

STEPS = 3


@pytest.fixture(scope="module")
def act_checkpoint(policy_episodes, tmp_path_factory):
    out = tmp_path_factory.mktemp("ckpt") / "act"
    train_policy(load_policy_config("act", "tiny"), policy_episodes, out, steps=STEPS)
    return out


def test_dataset_windows_and_padding(policy_episodes):
    cfg = load_policy_config("dp", "tiny")          # T_o 3, chunk from the frame before the newest
    ds = PolicyDataset(policy_episodes, cfg)
    first = ds.batch(np.array([0]))
    assert first["images"].shape == (1, 3, 4, 48, 64, 3) and first["images"].dtype == np.uint8
    assert first["state"].shape[:2] == (1, 3) and first["actions"].shape[:2] == (1, 8)
    # frame 0: the window repeats frame 0, the row before the start is padding
    assert (first["state"][0, 0] == first["state"][0, 2]).all()
    assert first["action_pad"][0].tolist() == [True] + [False] * 7
    last = ds.batch(np.array([ds.episodes[0].num_frames - 1]))
    assert last["action_pad"][0].tolist() == [False, False] + [True] * 6


def test_training_on_zero_episodes_fails_fast(tmp_path):
    with pytest.raises(ValueError, match="no training episodes"):
        train_policy(load_policy_config("act", "tiny"), [], tmp_path / "ckpt", steps=1)


def test_same_seed_and_data_give_the_same_checkpoint_bytes(policy_episodes, act_checkpoint, tmp_path):
    again = tmp_path / "again"
    train_policy(load_policy_config("act", "tiny"), policy_episodes, again, steps=STEPS)
    for name in (WEIGHTS, MANIFEST, STATS, "train_log.json", "loss.png"):
        assert (again / name).read_bytes() == (act_checkpoint / name).read_bytes(), name
    manifest = json.loads((again / MANIFEST).read_text())
    assert manifest["setting"] == {"task": TASK, "embodiment": EMBODIMENT}
    assert [e["episode"] for e in manifest["training_set"]] == sorted(p.name for p in policy_episodes)


def test_a_flipped_byte_in_the_weights_is_a_clear_error(act_checkpoint, tmp_path):
    import shutil
    broken = tmp_path / "broken"
    shutil.copytree(act_checkpoint, broken)
    data = bytearray((broken / WEIGHTS).read_bytes())
    data[len(data) // 2] ^= 0x10
    (broken / WEIGHTS).write_bytes(bytes(data))
    with pytest.raises(SpecError, match="corrupt"):
        load_checkpoint(broken)
    (broken / WEIGHTS).write_bytes(b"not safetensors")
    manifest = json.loads((broken / MANIFEST).read_text())
    from episodes.atomic import file_sha256
    manifest["weights_sha256"] = file_sha256(broken / WEIGHTS)
    (broken / MANIFEST).write_text(json.dumps(manifest))
    with pytest.raises(SpecError, match="readable safetensors"):
        load_checkpoint(broken)
    (broken / STATS).unlink()
    with pytest.raises(SpecError, match="stats.json"):
        load_checkpoint(broken)


def test_statistics_that_do_not_fit_the_specs_are_refused_naming_both(act_checkpoint, tmp_path):
    import shutil
    broken = tmp_path / "stats"
    shutil.copytree(act_checkpoint, broken)
    stats = json.loads((broken / STATS).read_text())
    stats["action"]["mean"] = stats["action"]["mean"][:-2]
    (broken / STATS).write_text(json.dumps(stats))
    with pytest.raises(SpecError, match=r"action.mean.*actuators of policy.json"):
        load_checkpoint(broken)


def test_closed_loop_counts_steps_and_queries(act_checkpoint):
    policy = LearnedPolicy(act_checkpoint)
    rows = run_rollouts(policy, TASK, EMBODIMENT, "inv_equi", [], 2, max_steps=9)
    # 20 Hz policy: one query every third control step, ACT re-plans every policy step
    assert [(r["control_steps"], r["policy_queries"], r["termination"]) for r in rows] == [(9, 3, "horizon")] * 2
    assert {r["policy"] for r in rows} == {"act_tiny"}
    runs = [run_episode(LearnedPolicy(act_checkpoint), demonstration_scene(TASK, EMBODIMENT), seed=3, max_steps=9)
            for _ in range(2)]
    assert runs[0].recording.action.tobytes() == runs[1].recording.action.tobytes()


class _Failing:
    """A policy that returns `bad` at its third query."""

    def __init__(self, inner, bad):
        self.inner, self.bad, self.calls = inner, bad, 0
        self.name, self.observation_spec = "failing", inner.observation_spec
        self.action_spec, self.actions_per_query = inner.action_spec, 1

    def reset(self, seed, instruction):
        self.calls = 0
        self.inner.reset(seed, instruction)

    def act(self, observation):
        self.calls += 1
        if self.calls == 3:
            if self.bad == "raise":
                raise RuntimeError("the model fell over")
            return self.bad
        return self.inner.act(observation)


@pytest.mark.parametrize("bad", ["raise", np.zeros((1, 3)), np.full((1, 40), np.nan)])
def test_a_failing_policy_ends_its_episode_as_an_error_and_the_others_go_on(act_checkpoint, bad):
    policy = _Failing(LearnedPolicy(act_checkpoint), bad)
    if isinstance(bad, np.ndarray) and bad.shape[1] == 40:
        bad = np.full((1, policy.action_spec.dim), np.nan)
        policy.bad = bad
    rows = run_rollouts(policy, TASK, EMBODIMENT, "inv_equi", [], 2, max_steps=12)
    assert [r["termination"] for r in rows] == ["error", "error"]
    assert all("failing" in r["error"] for r in rows)
    # two queries' worth of control steps ran before the failure and stay in the record
    assert [r["n_steps"] for r in rows] == [6, 6]


def test_a_checkpoint_for_another_embodiment_is_refused_before_the_first_step(act_checkpoint):
    policy = LearnedPolicy(act_checkpoint)
    other = demonstration_scene("sports_ball_cup_sort", "panda_allegro")
    with pytest.raises(IncompatiblePolicy, match="act_tiny vs setting sports_ball_cup_sort on panda_allegro"):
        run_episode(policy, other, seed=0, max_steps=3)
    with pytest.raises(IncompatiblePolicy):
        run_rollouts(policy, "sports_ball_cup_sort", "panda_allegro", "inv_equi", [], 2, max_steps=3)


def test_temporal_ensembling_weights_the_oldest_prediction_most():
    ens = TemporalEnsembler(coeff=1.0)
    first = ens.update(np.array([[0.0], [0.0], [0.0]]))
    second = ens.update(np.array([[1.0], [1.0], [1.0]]))
    assert first[0] == 0.0
    w = np.exp(-np.arange(2.0))
    assert np.isclose(second[0], (w[1] * 1.0) / w.sum())


def test_diffusion_policy_pops_queued_chunks_and_repeats_with_the_seed(policy_episodes, tmp_path):
    out = tmp_path / "dp"
    train_policy(load_policy_config("dp", "tiny"), policy_episodes, out, steps=2)
    rows = run_rollouts(LearnedPolicy(out), TASK, EMBODIMENT, "inv_equi", [], 1, max_steps=24)
    # 24 control steps = 8 policy steps; T_exec 6: queried at policy steps 0 and 6
    assert (rows[0]["control_steps"], rows[0]["policy_queries"], rows[0]["policy"]) == (24, 2, "dp_tiny")
    runs = [run_episode(LearnedPolicy(out), demonstration_scene(TASK, EMBODIMENT), seed=7, max_steps=24)
            for _ in range(2)]
    assert runs[0].recording.action.tobytes() == runs[1].recording.action.tobytes()
    assert runs[0].recording.robot_qpos.tobytes() == runs[1].recording.robot_qpos.tobytes()
    other = run_episode(LearnedPolicy(out), demonstration_scene(TASK, EMBODIMENT), seed=8, max_steps=24)
    assert other.recording.action.tobytes() != runs[0].recording.action.tobytes()    # the seed draws the noise


def test_the_tactile_variant_reads_every_tacmap_site_in_training_and_in_closed_loop(policy_episodes, tmp_path):
    out = tmp_path / "act_tactile"
    train_policy(load_policy_config("act", "tiny_tactile"), policy_episodes, out, steps=2)
    policy = LearnedPolicy(out)
    spec = policy.observation_spec
    assert len(spec.tactile_sites) >= 4 and spec.tactile_shape == (30, 30) and spec.tactile_step == 8
    outcome = run_episode(policy, demonstration_scene(TASK, EMBODIMENT), seed=1, max_steps=6)
    assert outcome.record["termination"] == "horizon" and outcome.timing.queries == 2
    vision_only = LearnedPolicy(out)
    observation = {"images": {v: np.zeros((1, 48, 64, 3), np.uint8) for v in spec.views},
                   "state": np.zeros((1, len(spec.state_names)))}
    from policies.interface import PolicyError
    with pytest.raises(PolicyError, match="lacks 'tactile'"):
        vision_only.act(observation)


def test_the_closed_loop_renders_exactly_the_training_images(policy_episodes, act_checkpoint):
    """Online views (posed from the state, as the runner does after each step) equal the episode's frames,
    rendered offline from the replay under the same profile (coarse tessellation included)."""
    import h5py
    import mujoco

    from episodes.reader import EpisodeReader
    from policies.observe import ObservationSource

    spec = LearnedPolicy(act_checkpoint).observation_spec
    assert spec.tessellation == (8, 4)
    episode = policy_episodes[0]
    with h5py.File(episode.parent / ".work" / "episode_0000.replay.h5") as f:
        qpos = f["qpos"][()]
    with EpisodeReader(episode) as r:
        steps = r.read("time/sim_step") - 1
        stored = {v: r.read(f"cameras/{v}/rgb") for v in spec.views}
    scene = demonstration_scene(TASK, EMBODIMENT, 0)
    data = mujoco.MjData(scene.model)
    source = ObservationSource(scene, spec)
    try:
        for k in (0, len(steps) - 1):
            data.qpos[:] = qpos[steps[k]]
            source.capture(data)
            frame = source.observation(scene.task.instruction, k)
            for v in spec.views:
                assert frame["images"][v][-1].tobytes() == stored[v][k].tobytes(), (v, k)
    finally:
        source.close()


def test_the_cosine_schedule_spans_the_run_budget_not_the_config_steps():
    # `b2d train --steps N` sets the budget apart from the config's; the cosine must reach zero at N,
    # not at the config's step count (it did: DP trained 100 steps, then 3,900 at a learning rate of 0)
    from policies.train import lr_factor

    cfg = load_policy_config("dp", "tiny")
    assert cfg.train.lr_schedule == "cosine" and cfg.train.steps == 100
    factor = lr_factor(cfg, 4000)
    assert factor(cfg.train.warmup_steps) == pytest.approx(1.0)
    assert factor(2000) == pytest.approx(0.5, abs=0.01)
    assert factor(3000) > 0.1
    assert factor(4000) == pytest.approx(0.0, abs=1e-9)
