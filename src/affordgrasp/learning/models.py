"""The networks (conventions: Vision, paper §III-B): a CNN on the depth image, PointNet (full, with
T-Nets, and slim, T-Nets fixed to the identity) on the equivalent point cloud, and a pose-only
baseline; each fuses the pregrasp p0 and the use direction d late, before a fully connected
head that outputs one logit (classifier) or one value (regressor, the [0, 1] target scale).

Sized for CPU training (the paper's sizes are not stated; a paper-size PointNet trains at
~17 samples/s on 2 cores). Every size is in the model's config, so a saved model rebuilds
itself exactly.
"""

from __future__ import annotations

import numpy as np

from .torch_support import require_torch
from .views import VIEW_CHANNELS

ARCHITECTURES = ("cnn", "pointnet", "pointnet-slim", "pose")
DEPTH_SCALE = 2.0  # network input = depth in m × 2 (objects of 0.1–0.4 m sit at 0.1–0.6 m)


def pose_features(p0: np.ndarray, use_dir: np.ndarray) -> np.ndarray:
    """The fused pose features of each sample.

    Parameters
    ----------
    p0 : (n, 6) float ndarray
        Pregrasps (conventions: Pregrasp), each entry in [0, 1].
    use_dir : (n, 2) float ndarray
        Use directions d, in [0, 1].

    Returns
    -------
    (n, 14) float32 ndarray
        p0 (6), d (2), then the cosine and the sine of the three angles that wrap around
        (approach azimuth π·u1, roll π·u3, use azimuth π·d1).
    """
    p0 = np.asarray(p0, dtype=np.float64)
    d = np.asarray(use_dir, dtype=np.float64)
    ang = np.pi * np.stack([p0[:, 0], p0[:, 2], d[:, 0]], axis=1)
    return np.concatenate([p0, d, np.cos(ang), np.sin(ang)], axis=1).astype(np.float32)


N_POSE = 14


def depth_input(depth_mm: np.ndarray, canonical: bool) -> np.ndarray:
    """The network's image input from depth images.

    Plain: one channel, the depth in m × 2, 0 where the ray missed. Canonical: two
    channels, the depth relative to the image's nearest point in m × 10 (0 at the first
    surface) and the hit mask; the nearest depth itself goes to the fused features
    (:func:`nearest_depth`).

    Parameters
    ----------
    depth_mm : (b, h, w) uint16 ndarray
        Depth images, mm, 0 for no return.
    canonical : bool
        Two channels relative to the nearest point, else one absolute channel.

    Returns
    -------
    (b, c, h, w) float32 ndarray
        c = 2 when canonical, else 1.
    """
    d = np.asarray(depth_mm, dtype=np.float32) / 1000.0
    if not canonical:
        return (d * DEPTH_SCALE)[:, None]
    hit = d > 0
    near = np.where(hit, d, np.inf).reshape(len(d), -1).min(axis=1)
    near = np.where(np.isfinite(near), near, 0.0).astype(np.float32)
    rel = np.where(hit, d - near[:, None, None], 0.0) * 10.0
    return np.stack([rel, hit.astype(np.float32)], axis=1).astype(np.float32)


def nearest_depth(depth_mm: np.ndarray) -> np.ndarray:
    """The nearest hit depth of each image, scaled as the network's depth input.

    Parameters
    ----------
    depth_mm : (b, h, w) uint16 ndarray
        Depth images, mm, 0 for no return.

    Returns
    -------
    (b, 1) float32 ndarray
        Nearest depth in m × 2 (``DEPTH_SCALE``); 0 for an image without a hit.
    """
    d = np.asarray(depth_mm, dtype=np.float32) / 1000.0
    near = np.where(d > 0, d, np.inf).reshape(len(d), -1).min(axis=1)
    return (np.where(np.isfinite(near), near, 0.0) * DEPTH_SCALE).astype(np.float32)[:, None]


def build_model(config: dict):
    """The torch module a config describes (:func:`.training.default_config` makes one).

    Parameters
    ----------
    config : dict
        ``arch`` (one of ``ARCHITECTURES``), ``width`` (16), ``dropout`` (0.3) and
        ``canonical`` (two-channel depth and the nearest depth as an extra pose feature),
        ``view`` (``"hand"``: the CNN reads the hand view's channels,
        :func:`~affordgrasp.learning.views.hand_view`),
        ``n_pose`` (the number of fused features, default the 14 pose features),
        ``members`` (1; more gives an ensemble: that many networks of the same
        architecture, trained with different seeds, whose outputs are averaged).

    Returns
    -------
    torch.nn.Module
        Its forward pass takes (image or points, pose features) — for ``"pose"`` the pose
        features alone — and returns (b,) outputs: a logit (classifier) or a value on the
        target's [0, 1] scale (regressor).

    Raises
    ------
    InputError
        For an unknown ``arch``.
    """
    torch = require_torch()
    nn = torch.nn
    members = int(config.get("members", 1))
    if members > 1:
        single = dict(config, members=1)

        class Ensemble(nn.Module):
            """The mean output of ``members`` networks."""

            def __init__(self):
                super().__init__()
                self.members = nn.ModuleList([build_model(single) for _ in range(members)])

            @property
            def last_feature_transform(self):
                return None

            def forward(self, *inputs):
                return torch.stack([m(*inputs) for m in self.members]).mean(dim=0)

        return Ensemble()
    arch = config["arch"]
    dropout = float(config.get("dropout", 0.3))
    width = int(config.get("width", 16))
    extra = 1 if config.get("canonical") and arch != "pose" else 0
    n_pose = int(config.get("n_pose", N_POSE))  # another input's own features (scorer)

    class Head(nn.Module):
        """Late fusion: encoder features ++ pose features → FC → one output."""

        def __init__(self, n_features: int):
            super().__init__()
            self.pose = nn.Sequential(nn.Linear(n_pose + extra, 64), nn.ReLU())
            self.fc = nn.Sequential(
                nn.Linear(n_features + 64, 128),
                nn.ReLU(),
                nn.Dropout(dropout),
                nn.Linear(128, 64),
                nn.ReLU(),
                nn.Linear(64, 1),
            )

        def forward(self, features, pose):
            return self.fc(torch.cat([features, self.pose(pose)], dim=1)).squeeze(1)

    class DepthCNN(nn.Module):
        def __init__(self):
            super().__init__()
            c_in = 2 if config.get("canonical") else 1
            if config.get("view") == "hand":
                c_in = VIEW_CHANNELS
            w = width
            self.encoder = nn.Sequential(
                nn.Conv2d(c_in, w // 2, 5, stride=2, padding=2),
                nn.ReLU(),
                nn.Conv2d(w // 2, w, 3, stride=2, padding=1),
                nn.ReLU(),
                nn.Conv2d(w, 2 * w, 3, stride=2, padding=1),
                nn.ReLU(),
                nn.Conv2d(2 * w, 2 * w, 3, stride=2, padding=1),
                nn.ReLU(),
                nn.AdaptiveAvgPool2d(4),
                nn.Flatten(),
                nn.Dropout(dropout),
                nn.Linear(2 * w * 16, 128),
                nn.ReLU(),
            )
            self.head = Head(128)

        def forward(self, image, pose):
            return self.head(self.encoder(image), pose)

    class TNet(nn.Module):
        """Predicts a k×k transform, initialised to the identity (PointNet's T-Net)."""

        def __init__(self, k: int):
            super().__init__()
            self.k = k
            self.mlp = nn.Sequential(
                nn.Conv1d(k, w1, 1), nn.ReLU(), nn.Conv1d(w1, 2 * w1, 1), nn.ReLU()
            )
            self.fc = nn.Sequential(nn.Linear(2 * w1, w1), nn.ReLU(), nn.Linear(w1, k * k))
            nn.init.zeros_(self.fc[-1].weight)
            nn.init.zeros_(self.fc[-1].bias)

        def forward(self, x):  # x: (b, k, n)
            feat = self.mlp(x).max(dim=2).values
            eye = torch.eye(self.k, dtype=x.dtype, device=x.device)
            return self.fc(feat).view(-1, self.k, self.k) + eye

    w1 = width

    class PointNet(nn.Module):
        def __init__(self, full: bool):
            super().__init__()
            self.full = full
            self.input_tnet = TNet(3) if full else None
            self.mlp1 = nn.Sequential(nn.Conv1d(3, w1, 1), nn.ReLU(), nn.Conv1d(w1, 2 * w1, 1))
            self.feature_tnet = TNet(2 * w1) if full else None
            self.mlp2 = nn.Sequential(
                nn.ReLU(), nn.Conv1d(2 * w1, 4 * w1, 1), nn.ReLU(), nn.Conv1d(4 * w1, 8 * w1, 1)
            )
            self.proj = nn.Sequential(nn.Dropout(dropout), nn.Linear(8 * w1, 128), nn.ReLU())
            self.head = Head(128)
            self.last_feature_transform = None

        def forward(self, points, pose):  # points: (b, n, 3)
            x = points.transpose(1, 2) * DEPTH_SCALE
            if self.full:
                x = torch.bmm(self.input_tnet(x).transpose(1, 2), x)
            x = self.mlp1(x)
            if self.full:
                t = self.feature_tnet(x)
                self.last_feature_transform = t
                x = torch.bmm(t.transpose(1, 2), x)
            x = self.mlp2(x).max(dim=2).values
            return self.head(self.proj(x), pose)

    class PoseOnly(nn.Module):
        def __init__(self):
            super().__init__()
            self.head = Head(0)

        def forward(self, pose):
            return self.head(pose[:, :0], pose)

    if arch == "cnn":
        return DepthCNN()
    if arch == "pointnet":
        return PointNet(full=True)
    if arch == "pointnet-slim":
        return PointNet(full=False)
    if arch == "pose":
        return PoseOnly()
    from ..errors import InputError

    raise InputError(f"unknown model {arch!r}; choose one of: {', '.join(ARCHITECTURES)}")


def count_parameters(model) -> int:
    """Number of parameters of a torch module.

    Parameters
    ----------
    model : torch.nn.Module

    Returns
    -------
    int
        Trainable and frozen alike.
    """
    return int(sum(p.numel() for p in model.parameters()))
