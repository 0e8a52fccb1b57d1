"""ACT model (policies.models.act) and its ResNet-18 encoder: shapes, training, padding, determinism,
tactile conditioning and config validation, on tiny real models."""

import functools

import pydantic
import pytest
import torch
from model_batches import synthetic_batch, train_steps

from policies.models.act import ACTConfig, ACTModel
from policies.models.resnet import ResNet18
from policies.models.shapes import ModelShapes

SHAPES = ModelShapes(n_views=2, image_height=32, image_width=64, state_dim=6, action_dim=5, n_obs_steps=2, horizon=8)
TACTILE_SHAPES = ModelShapes(**{**SHAPES.__dict__, "n_tactile": 3, "tactile_height": 8, "tactile_width": 8})

# standard-normal images and actions; the first sample's episode ended 3 steps before the chunk did
make_batch = functools.partial(synthetic_batch, batch_size=2, padded_tail=3)


def build(shapes: ModelShapes = SHAPES, seed: int = 0, **cfg) -> ACTModel:
    torch.manual_seed(seed)
    return ACTModel(ACTConfig(**cfg), shapes)


@pytest.mark.parametrize("shapes", [SHAPES, TACTILE_SHAPES], ids=["vision", "tactile"])
@pytest.mark.parametrize("use_vae", [True, False])
def test_output_shapes(shapes, use_vae):
    model = build(shapes, use_vae=use_vae)
    batch = make_batch(shapes, batch_size=3)
    loss, stats = model.compute_loss(batch)
    assert loss.shape == () and torch.isfinite(loss)
    assert set(stats) == {"l1", "kl", "loss"} and all(type(v) is float for v in stats.values())
    assert (stats["kl"] == 0.0) == (not use_vae)
    chunk = model.eval().predict_chunk({k: batch[k] for k in ("images", "state", "tactile") if k in batch})
    assert chunk.shape == (3, shapes.horizon, shapes.action_dim) and not chunk.requires_grad


@pytest.mark.parametrize("height,width", [(48, 64), (50, 70), (33, 31)])
def test_resnet_feature_map(height, width):
    torch.manual_seed(0)
    net = ResNet18(width=8)
    out = net(torch.randn(2, 3, height, width))
    assert out.shape == (2, 8 * 8, *ResNet18.output_size(height, width)) and net.out_channels == 64
    assert ResNet18.output_size(48, 64) == (2, 2)


def test_resnet_batch_norm_and_bad_norm():
    assert ResNet18(width=4, norm="batch")(torch.randn(2, 3, 32, 32)).shape == (2, 32, 1, 1)
    with pytest.raises(ValueError):
        ResNet18(norm="layer")


def test_overfits_one_batch():
    model = build(SHAPES, dropout=0.0)  # no dropout noise in 30 steps
    batch = make_batch(SHAPES)
    history = [stats for _, stats in train_steps(model, batch, 30)]
    first, last = history[0], history[-1]
    # Random targets: the best chunk that ignores the observation still has an L1 of about 0.56.
    assert last["l1"] < 0.65 * first["l1"] and last["loss"] < 0.65 * first["loss"], history
    model.eval()
    predicted = model.predict_chunk(batch)
    assert (predicted - batch["actions"]).abs()[~batch["action_pad"]].mean() < 0.65 * first["l1"]


@pytest.mark.parametrize("train", [True, False])
def test_padded_rows_do_not_count(train):
    model = build(SHAPES).train(train)
    batch = make_batch(SHAPES)
    torch.manual_seed(1)  # same dropout masks and latent noise for both calls
    loss, stats = model.compute_loss(batch)
    changed = dict(batch, actions=batch["actions"].clone())
    changed["actions"][0, -3:] = torch.tensor(float("nan"))  # padded rows only
    torch.manual_seed(1)
    loss_changed, stats_changed = model.compute_loss(changed)
    assert torch.equal(loss, loss_changed) and stats == stats_changed
    changed["actions"][0, 0] += 1.0  # a real row does count
    torch.manual_seed(1)
    assert model.compute_loss(changed)[1]["l1"] != stats["l1"]


def test_same_seed_same_model_and_training():
    torch.use_deterministic_algorithms(True)
    try:
        runs = []
        for _ in range(2):
            model = build(TACTILE_SHAPES, seed=3)
            batch = make_batch(TACTILE_SHAPES)
            initial = {k: v.clone() for k, v in model.state_dict().items()}
            torch.manual_seed(4)
            losses = [loss for loss, _ in train_steps(model, batch, 3)]
            runs.append((initial, losses, model.state_dict()))
        (init_a, losses_a, final_a), (init_b, losses_b, final_b) = runs
        assert init_a.keys() == init_b.keys() and all(torch.equal(init_a[k], init_b[k]) for k in init_a)
        assert all(torch.equal(a, b) for a, b in zip(losses_a, losses_b))
        assert all(torch.equal(final_a[k], final_b[k]) for k in final_a)
    finally:
        torch.use_deterministic_algorithms(False)


def test_tactile_input_changes_the_chunk():
    model = build(TACTILE_SHAPES).eval()
    batch = make_batch(TACTILE_SHAPES)
    pressed = dict(batch, tactile=batch["tactile"].clone())
    pressed["tactile"][:, -1, 1] = 1.0  # one site fully pressed at the current step
    assert not torch.allclose(model.predict_chunk(batch), model.predict_chunk(pressed))


def test_only_the_last_observation_step_is_read():
    model = build(TACTILE_SHAPES).eval()
    batch = make_batch(TACTILE_SHAPES)
    older = {k: v.clone() for k, v in batch.items()}
    for key in ("images", "state", "tactile"):
        older[key][:, 0] = 7.0
    assert torch.equal(model.predict_chunk(batch), model.predict_chunk(older))


def test_config_validation():
    assert ACTConfig().dim_model == 64
    with pytest.raises(pydantic.ValidationError, match="extra"):
        ACTConfig(dim_modle=64)
    with pytest.raises(pydantic.ValidationError, match="divisible"):
        ACTConfig(dim_model=66, n_heads=4)
    with pytest.raises(pydantic.ValidationError):
        ACTConfig(n_encoder_layers=0)
    with pytest.raises(pydantic.ValidationError):
        ACTConfig(dropout=1.0)


def test_shapes_validation():
    with pytest.raises(ValueError, match="tactile_height"):
        ModelShapes(n_views=1, image_height=8, image_width=8, state_dim=1, action_dim=1, n_obs_steps=1, horizon=1,
                    n_tactile=2)
    with pytest.raises(ValueError):
        ModelShapes(n_views=1, image_height=-8, image_width=8, state_dim=1, action_dim=1, n_obs_steps=1, horizon=1)
    with pytest.raises(ValueError, match="camera"):
        ACTModel(ACTConfig(), ModelShapes(n_views=0, image_height=8, image_width=8, state_dim=1, action_dim=1,
                                          n_obs_steps=1, horizon=1))
