"""A small ResNet-18 image encoder (He et al. 2016, "Deep Residual Learning"), written from scratch.

No torchvision and no pretrained weights: the benchmark trains policies from scratch on CPU, so the
width is a parameter (``width`` = 64 is the standard ResNet-18) and normalization defaults to
GroupNorm, which behaves the same in train and eval and with tiny batches.
"""

from __future__ import annotations

import torch
from torch import nn

STAGE_BLOCKS = (2, 2, 2, 2)
STAGE_WIDTH_FACTORS = (1, 2, 4, 8)


def group_count(channels: int, max_groups: int = 8) -> int:
    """The largest group count up to ``max_groups`` that divides ``channels``."""
    return next(g for g in range(min(max_groups, channels), 0, -1) if channels % g == 0)


def make_norm(kind: str, channels: int) -> nn.Module:
    if kind == "group":
        return nn.GroupNorm(group_count(channels), channels)
    if kind == "batch":
        return nn.BatchNorm2d(channels)
    raise ValueError(f"norm must be 'group' or 'batch', got {kind!r}")


def conv_output_size(size: int, kernel: int, stride: int, padding: int) -> int:
    return (size + 2 * padding - kernel) // stride + 1


class BasicBlock(nn.Module):
    """Two 3x3 convs with a residual connection; a 1x1 conv projects the shortcut when shapes change."""

    def __init__(self, in_channels: int, out_channels: int, stride: int, norm: str):
        super().__init__()
        self.conv1 = nn.Conv2d(in_channels, out_channels, 3, stride=stride, padding=1, bias=False)
        self.norm1 = make_norm(norm, out_channels)
        self.conv2 = nn.Conv2d(out_channels, out_channels, 3, padding=1, bias=False)
        self.norm2 = make_norm(norm, out_channels)
        self.relu = nn.ReLU(inplace=True)
        self.shortcut: nn.Module = nn.Identity()
        if stride != 1 or in_channels != out_channels:
            self.shortcut = nn.Sequential(
                nn.Conv2d(in_channels, out_channels, 1, stride=stride, bias=False), make_norm(norm, out_channels)
            )

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        out = self.relu(self.norm1(self.conv1(x)))
        out = self.norm2(self.conv2(out))
        return self.relu(out + self.shortcut(x))


class ResNet18(nn.Module):
    """ResNet-18 trunk without the classifier: (B, 3, H, W) -> (B, 8 * width, ~H/32, ~W/32)."""

    def __init__(self, width: int = 64, norm: str = "group"):
        super().__init__()
        if width <= 0:
            raise ValueError(f"width must be positive, got {width}")
        self.stem = nn.Sequential(
            nn.Conv2d(3, width, 7, stride=2, padding=3, bias=False),
            make_norm(norm, width),
            nn.ReLU(inplace=True),
            nn.MaxPool2d(3, stride=2, padding=1),
        )
        stages = []
        in_channels = width
        for i, (n_blocks, factor) in enumerate(zip(STAGE_BLOCKS, STAGE_WIDTH_FACTORS)):
            out_channels = width * factor
            stride = 1 if i == 0 else 2
            blocks = [BasicBlock(in_channels, out_channels, stride, norm)]
            blocks += [BasicBlock(out_channels, out_channels, 1, norm) for _ in range(n_blocks - 1)]
            stages.append(nn.Sequential(*blocks))
            in_channels = out_channels
        self.stages = nn.Sequential(*stages)
        self.out_channels = in_channels

    @staticmethod
    def output_size(height: int, width: int) -> tuple[int, int]:
        """Spatial size of the feature map for an input of ``height`` x ``width``, without running it."""

        def shrink(n: int) -> int:
            n = conv_output_size(n, 7, 2, 3)  # stem conv
            n = conv_output_size(n, 3, 2, 1)  # max pool
            for _ in STAGE_BLOCKS[1:]:
                n = conv_output_size(n, 3, 2, 1)  # first conv of each strided stage
            return n

        return shrink(height), shrink(width)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.stages(self.stem(x))
