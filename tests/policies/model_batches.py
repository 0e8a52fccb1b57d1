"""Synthetic batches and a short training loop for the policy model tests (ACT and Diffusion Policy)."""

import torch

from policies.models.shapes import ModelShapes


def synthetic_batch(shapes: ModelShapes, batch_size: int, seed: int = 0, *, bounded: bool = False,
                    padded_tail: int = 0) -> dict[str, torch.Tensor]:
    """A random batch for `shapes`, drawn from one generator seeded with `seed`.

    bounded: images in [0, 1] and actions in [-1, 1] (normalised, as Diffusion Policy sees them);
    otherwise both are standard normal. padded_tail: how many of the first sample's last action rows
    are padding (its episode ended that many steps before the chunk did); the other samples have none.
    """
    g = torch.Generator().manual_seed(seed)
    s = shapes
    image_shape = (batch_size, s.n_obs_steps, s.n_views, 3, s.image_height, s.image_width)
    action_shape = (batch_size, s.horizon, s.action_dim)
    batch = {
        "images": torch.rand(*image_shape, generator=g) if bounded else torch.randn(*image_shape, generator=g),
        "state": torch.randn(batch_size, s.n_obs_steps, s.state_dim, generator=g),
        "actions": (torch.rand(*action_shape, generator=g) * 2 - 1 if bounded
                    else torch.randn(*action_shape, generator=g)),
        "action_pad": torch.zeros(batch_size, s.horizon, dtype=torch.bool),
    }
    if padded_tail:
        batch["action_pad"][0, -padded_tail:] = True
    if s.n_tactile:
        batch["tactile"] = torch.rand(batch_size, s.n_obs_steps, s.n_tactile, s.tactile_height, s.tactile_width,
                                      generator=g)
    return batch


def train_steps(model: torch.nn.Module, batch: dict[str, torch.Tensor], steps: int,
                lr: float = 1e-3) -> list[tuple[torch.Tensor, dict]]:
    """`steps` Adam steps on one batch; each step's (detached loss, stats) from `model.compute_loss`."""
    optimizer = torch.optim.Adam(model.parameters(), lr=lr)
    history = []
    for _ in range(steps):
        loss, stats = model.compute_loss(batch)
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
        history.append((loss.detach(), stats))
    return history
