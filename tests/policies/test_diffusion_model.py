"""Diffusion Policy model (policies/models/diffusion.py): shapes, learning, masking, determinism, config."""

import copy
import functools

import pydantic
import pytest
import torch
from model_batches import synthetic_batch, train_steps

from policies.models.diffusion import EMA, DiffusionConfig, DiffusionModel
from policies.models.shapes import ModelShapes

SHAPES = ModelShapes(n_views=2, image_height=48, image_width=64, state_dim=6, action_dim=5, n_obs_steps=2, horizon=8)
# horizon 6 is not a multiple of 4 (3 U-Net levels): exercises the padding path
TACTILE_SHAPES = ModelShapes(n_views=1, image_height=48, image_width=64, state_dim=6, action_dim=5, n_obs_steps=2,
                             horizon=6, n_tactile=3, tactile_height=12, tactile_width=10)

# normalised images in [0, 1] and actions in [-1, 1]; no padded rows
make_batch = functools.partial(synthetic_batch, batch_size=3, bounded=True)


def make_model(shapes: ModelShapes = SHAPES, seed: int = 0, **cfg) -> DiffusionModel:
    torch.manual_seed(seed)
    return DiffusionModel(DiffusionConfig(**cfg), shapes)


def seeded_loss(model: DiffusionModel, batch: dict, seed: int) -> torch.Tensor:
    torch.manual_seed(seed)
    return model.compute_loss(batch)[0]


@pytest.fixture
def deterministic():
    previous = torch.are_deterministic_algorithms_enabled()
    torch.use_deterministic_algorithms(True)
    yield
    torch.use_deterministic_algorithms(previous)


@pytest.mark.parametrize("shapes", [SHAPES, TACTILE_SHAPES], ids=["images", "tactile"])
def test_shapes(shapes):
    model = make_model(shapes)
    batch = make_batch(shapes)
    loss, info = model.compute_loss(batch)
    assert loss.dim() == 0 and torch.isfinite(loss)
    assert set(info) == {"mse", "loss"} and info["loss"] == pytest.approx(loss.item())
    chunk = model.predict_chunk(batch, torch.Generator().manual_seed(0))
    assert chunk.shape == (3, shapes.horizon, shapes.action_dim)
    assert chunk.abs().max() <= 1 + 1e-5      # DDIM ends on the clipped clean-sample estimate
    with pytest.raises(ValueError, match="images"):
        model.compute_loss(dict(batch, images=batch["images"][:, :1]))


def test_tactile_maps_condition_the_model():
    model = make_model(TACTILE_SHAPES)
    batch = make_batch(TACTILE_SHAPES)
    touched = dict(batch, tactile=torch.zeros_like(batch["tactile"]))
    assert seeded_loss(model, batch, 1) != seeded_loss(model, touched, 1)


@pytest.mark.parametrize("prediction_type, max_ratio", [("epsilon", 0.95), ("sample", 0.1)])
def test_loss_falls_when_overfitting_one_batch(prediction_type, max_ratio):
    # noise prediction learns slowly (DP trains for many thousand steps); clean-sample prediction memorizes fast
    shapes = ModelShapes(n_views=1, image_height=48, image_width=64, state_dim=6, action_dim=5, n_obs_steps=1,
                         horizon=8)
    model = make_model(shapes, prediction_type=prediction_type)
    batch = make_batch(shapes)
    before = sum(seeded_loss(model, batch, s).item() for s in range(4))
    train_steps(model, batch, 40)
    after = sum(seeded_loss(model, batch, s).item() for s in range(4))
    assert after < max_ratio * before, (before, after)


def test_padded_rows_do_not_change_the_loss():
    model = make_model()
    batch = make_batch(SHAPES)
    pad = batch["action_pad"].clone()
    pad[0, -3:] = True      # episode end
    pad[1, :2] = True       # episode start
    padded = dict(batch, action_pad=pad)
    garbage = dict(padded, actions=torch.where(pad[..., None], torch.full_like(batch["actions"], 50.0), batch["actions"]))
    assert torch.equal(seeded_loss(model, padded, 3), seeded_loss(model, garbage, 3))
    assert not torch.equal(seeded_loss(model, padded, 3), seeded_loss(model, batch, 3))   # the mask is used


def train_three_steps(seed: int) -> tuple[dict, float]:
    model = make_model(seed=seed)
    batch = make_batch(SHAPES)
    _, info = train_steps(model, batch, 3)[-1]
    return model.state_dict(), info["loss"]


def test_same_seed_same_training(deterministic):
    (state_a, loss_a), (state_b, loss_b) = train_three_steps(0), train_three_steps(0)
    assert loss_a == loss_b
    assert state_a.keys() == state_b.keys()
    assert all(torch.equal(state_a[k], state_b[k]) for k in state_a)
    state_c, _ = train_three_steps(1)
    assert not all(torch.equal(state_a[k], state_c[k]) for k in state_a)


@pytest.mark.parametrize("scheduler", ["ddim", "ddpm"])
def test_predict_chunk_follows_the_generator(deterministic, scheduler):
    model = make_model(inference_scheduler=scheduler)
    batch = make_batch(SHAPES, batch_size=1)

    def chunk(seed: int) -> torch.Tensor:
        return model.predict_chunk(batch, torch.Generator().manual_seed(seed))

    first = chunk(7)
    assert torch.equal(first, chunk(7))
    with torch.inference_mode():      # as the closed-loop runner calls it
        assert torch.equal(first, chunk(7))
    assert not torch.equal(first, chunk(8))


def test_config_validation():
    with pytest.raises(pydantic.ValidationError, match="extra"):
        DiffusionConfig(unknown_key=1)
    with pytest.raises(pydantic.ValidationError, match="num_inference_steps"):
        DiffusionConfig(num_train_timesteps=10, num_inference_steps=20)
    with pytest.raises(pydantic.ValidationError, match="n_groups"):
        DiffusionConfig(down_dims=[32, 60], n_groups=8)
    with pytest.raises(pydantic.ValidationError):
        DiffusionConfig(kernel_size=0)
    assert DiffusionConfig(num_train_timesteps=10, num_inference_steps=10).num_inference_steps == 10


def test_ema_averages_parameters():
    model = make_model()
    ema = EMA(model, decay=0.9)
    start = copy.deepcopy(model.state_dict())
    with torch.no_grad():
        for p in model.parameters():
            p.add_(1.0)
    ema.update(model)     # diffusers' ramp: the first update copies, later ones average
    with torch.no_grad():
        for p in model.parameters():
            p.add_(1.0)
    ema.update(model)
    averaged = make_model(seed=5)
    ema.copy_to(averaged)
    name, value = next(iter(averaged.named_parameters()))
    assert torch.all(value > start[name] + 1) and torch.all(value < start[name] + 2)
    restored = EMA(make_model(seed=6), decay=0.9)
    restored.load_state_dict(ema.state_dict())
    other = make_model(seed=7)
    restored.copy_to(other)
    assert all(torch.equal(a, b) for a, b in zip(other.parameters(), averaged.parameters()))
