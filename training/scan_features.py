"""A policy's features with its LIDAR scan read by a convolution over the beams' azimuth (``ppo.scan_conv``).

An MLP on a flattened scan must learn what a gap or a wall edge looks like at each of the scan's angles
separately; a 1D convolution along the azimuth learns one local filter and applies it at every angle, as
LIDAR-reading navigation policies in the literature do. The ``lidar`` entry is read as (channels, beams): a 2D
LIDAR's (beams,) is one channel, a multi-channel LIDAR's (channels, beams) keeps its elevation rows as input
channels; a polar scan memory, laid out beam by beam, adds its own channel (``scans``). Each layer is a ``Conv1d``
of kernel :data:`KERNEL`, zero-padded to keep the beam count, and a ReLU; the last layer's maps are flattened (so
the hidden layers still know at which angle a feature lies) and concatenated with the other entries, flattened, in
sorted key order (SB3's ``CombinedExtractor`` order).
"""

from __future__ import annotations

from collections.abc import Sequence

import torch as th
from gymnasium import spaces
from stable_baselines3.common.preprocessing import get_flattened_obs_dim
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
from torch import nn

#: the entry the convolution reads
SCAN_KEY = "lidar"
#: beams each filter spans
KERNEL = 5


def scan_layout(space: spaces.Box) -> tuple[int, int]:
    """(channels, beams) of a LIDAR entry's space: (1, n) for (n,), (c, n) for (c, n)."""
    shape = space.shape
    if len(shape) == 1:
        return 1, shape[0]
    if len(shape) == 2:
        return shape[0], shape[1]
    raise ValueError(f"ppo.scan_conv reads a LIDAR entry of shape (beams,) or (channels, beams), got {shape}")


class ScanFeatures(BaseFeaturesExtractor):
    """The entries ``keys`` of a Dict observation, those in ``scans`` through the convolution (module docstring).

    Args:
        observation_space: the policy's observation space.
        keys: the entries read; must include :data:`SCAN_KEY`.
        widths: output channels of each convolution layer.
        scans: the entries read as scans, their channels stacked: :data:`SCAN_KEY` first, then any entry laid out
            beam by beam as the LIDAR is (a polar scan memory, :mod:`clutter_gym.training.scan_memory`).
    """

    def __init__(self, observation_space: spaces.Dict, keys: Sequence[str], widths: Sequence[int],
                 scans: Sequence[str] = (SCAN_KEY,)) -> None:
        keys = tuple(sorted(keys))
        missing = [k for k in dict.fromkeys((SCAN_KEY, *scans)) if k not in keys]
        if missing:
            raise ValueError(f"ppo.scan_conv needs the entries {missing} in what the policy reads; it reads "
                             f"{list(keys)}")
        layouts = [scan_layout(observation_space[k]) for k in scans]
        beams = layouts[0][1]
        if any(n != beams for _, n in layouts):
            raise ValueError(f"ppo.scan_conv reads {list(scans)} beam by beam, but their beams differ: "
                             f"{[n for _, n in layouts]}")
        others = [k for k in keys if k not in scans]
        super().__init__(observation_space,
                         widths[-1] * beams + sum(get_flattened_obs_dim(observation_space[k]) for k in others))
        channels = sum(c for c, _ in layouts)
        layers: list[nn.Module] = []
        for width in widths:
            layers += [nn.Conv1d(channels, width, KERNEL, padding=KERNEL // 2), nn.ReLU()]
            channels = width
        self.conv = nn.Sequential(*layers, nn.Flatten())
        self.scans, self.others, self.beams = tuple(scans), tuple(others), beams

    def forward(self, observations: dict[str, th.Tensor]) -> th.Tensor:
        batch = observations[SCAN_KEY].shape[0]
        scan = th.cat([observations[k].reshape(batch, -1, self.beams) for k in self.scans], dim=1)
        return th.cat([self.conv(scan), *(th.flatten(observations[k], start_dim=1) for k in self.others)], dim=1)
