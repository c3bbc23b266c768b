"""Context/target batches as crate/augment draws them (sampler.rs, time_warp.rs, batch.rs):
the same rules and defaults, not the same random numbers.

Every sequence slot of a batch draws from its own generator, seeded by (seed, stream, step,
slot): a batch depends on the step alone, so a resumed run needs no random state, and a
process of a DDP run draws only its share of the global batch yet the global batch is the
one a single process draws.
"""
import math
from dataclasses import dataclass

import numpy as np

TRAIN_STREAM, VAL_STREAM = 0, 0x5851_F42D_4C95_7F2D


def round_half_away(x):
    """Rust's f64::round for the non-negative values used here."""
    return int(math.floor(x + 0.5))


@dataclass
class TimeWarp:
    """The paper's augmentation (§3.2), TimeWarpConfig's fields and defaults: random sections
    sped up or slowed down (log-uniform factor) and a freeze (a step repeated), so that a
    frame's content stops telling its time exactly."""
    probability: float = 0.8
    sections: tuple = (1, 3)
    section_fraction: tuple = (0.1, 0.4)
    speed: tuple = (0.5, 2.0)
    freeze_probability: float = 0.5
    freeze_length: tuple = (3, 15)
    freeze_fraction: tuple = None

    def indices(self, n, rng):
        """Steps of a warped n-step sequence: non-decreasing, first 0, last n − 1."""
        if n < 3 or not rng.random() < self.probability:
            return np.arange(n)
        speed = np.ones(n)
        for _ in range(rng.integers(self.sections[0], self.sections[1] + 1)):
            fraction = rng.uniform(*self.section_fraction)
            width = min(max(round_half_away(fraction * n), 1), n)
            start = rng.integers(0, n - width + 1)
            speed[start:start + width] = math.exp(rng.uniform(*np.log(self.speed)))
        indices, position = [], 0.0
        while position < n - 1:
            indices.append(round_half_away(position))
            position += speed[round_half_away(position)]
        indices.append(n - 1)
        if rng.random() < self.freeze_probability:
            at = int(rng.integers(len(indices)))
            if self.freeze_fraction:
                fraction = rng.uniform(*self.freeze_fraction)
                copies = round_half_away(fraction / (1 - fraction) * len(indices))
            else:
                copies = int(rng.integers(self.freeze_length[0], self.freeze_length[1] + 1))
            indices[at:at] = [indices[at]] * copies
        return np.array(indices)

    def to_json(self):
        return {"probability": self.probability, "sections": list(self.sections),
                "section_fraction": list(self.section_fraction), "speed": list(self.speed),
                "freeze_probability": self.freeze_probability,
                "freeze_length": list(self.freeze_length),
                "freeze_fraction": list(self.freeze_fraction) if self.freeze_fraction else None}


@dataclass
class SamplerConfig:
    """SamplerConfig: B sequences, 1..max_contexts contexts and `targets` targets each (the
    contexts first with `contexts_in_targets`), `joint_targets` joint-only targets,
    blend c ~ U(0, 1) (one modality alone for a `single_modality` fraction), contexts in a
    10-90% prefix for a `prefix_contexts` fraction, time-warped with `warp`."""
    batch: int
    max_contexts: int = 5
    targets: int = 4
    contexts_in_targets: bool = False
    joint_targets: int = 0
    single_modality: float = 0.0
    prefix_contexts: float = 0.0
    warp: TimeWarp = None


def sample(cfg, pool, norm, seed, step, slots, stream=TRAIN_STREAM):
    """The batch's sequence slots `slots` (a range of 0..cfg.batch) as numpy arrays, shaped
    as augment::Batch (N = max_contexts, padding zero with mask 0) plus the joint-only
    targets (D joint values a step, the pool's)."""
    b, n_max, m, mj = len(slots), cfg.max_contexts, cfg.targets, cfg.joint_targets
    s, d = pool[0].frames.shape[1], pool[0].joints.shape[1]
    out = {
        "context_images": np.zeros((b, n_max, 3, s, s), np.float32),
        "context_joints": np.zeros((b, n_max, d), np.float32),
        "context_times": np.zeros((b, n_max), np.float32),
        "context_mask": np.zeros((b, n_max), np.float32),
        "target_images": np.zeros((b, m, 3, s, s), np.float32),
        "target_joints": np.zeros((b, m, d), np.float32),
        "target_times": np.zeros((b, m), np.float32),
        "blend": np.zeros(b, np.float32),
        "joint_target_times": np.zeros((b, mj), np.float32),
        "joint_target_joints": np.zeros((b, mj, d), np.float32),
    }
    for i, slot in enumerate(slots):
        rng = np.random.default_rng([seed, stream, step, slot])
        seq = pool[rng.integers(len(pool))]
        if cfg.warp is not None:
            seq = seq.gather(cfg.warp.indices(len(seq), rng))
        t = len(seq)
        n = int(rng.integers(1, max(min(cfg.max_contexts, t - 1), 1) + 1))
        if cfg.prefix_contexts > 0 and rng.random() < cfg.prefix_contexts:
            steps = prefix_steps(rng, t, n, m)
        else:
            steps = list(rng.choice(t, min(n + m, t), replace=False))
        contexts, rest = steps[:n], steps[n:]
        if cfg.contexts_in_targets:
            order = contexts + rest
            targets = [order[j % len(order)] for j in range(m)]
        else:  # short sequences reuse non-context steps
            targets = [rest[j % len(rest)] if rest else contexts[0] for j in range(m)]
        times, joints = seq.times(), norm.normalize(seq.joints)
        out["context_images"][i, :n] = planar(seq.frames[contexts])
        out["context_joints"][i, :n] = joints[contexts]
        out["context_times"][i, :n] = times[contexts]
        out["context_mask"][i, :n] = 1
        out["target_images"][i] = planar(seq.frames[targets])
        out["target_joints"][i] = joints[targets]
        out["target_times"][i] = times[targets]
        if cfg.single_modality > 0 and rng.random() < cfg.single_modality:
            out["blend"][i] = 1.0 if rng.random() < 0.5 else 0.0
        else:
            out["blend"][i] = rng.random()
        picked = rng.integers(0, t, mj)
        out["joint_target_times"][i] = times[picked]
        out["joint_target_joints"][i] = joints[picked]
    return out


def prefix_steps(rng, t, n, targets):
    """n context steps within a prefix of 10-90% of a t-step sequence, then up to `targets`
    other steps of the whole sequence."""
    lo = max(t // 10, n)
    hi = max(t * 9 // 10, lo)
    length = min(int(rng.integers(lo, hi + 1)), t)
    steps = list(rng.choice(length, min(n, length), replace=False))
    others = [k for k in range(t) if k not in steps]
    picked = rng.choice(len(others), min(targets, len(others)), replace=False)
    return steps + [others[i] for i in picked]


def planar(frames):
    """uint8 [K, S, S, 3] to float32 [K, 3, S, S] in [0, 1] (batch.rs `planar`)."""
    return frames.transpose(0, 3, 1, 2).astype(np.float32) / np.float32(255)


def contexts_as_targets(batch):
    """The same contexts with themselves as targets (N per sequence, each sequence's real
    contexts repeated in order into the padding): how well a model reproduces what it saw."""
    out = dict(batch)
    n = batch["context_mask"].shape[1]
    real = np.maximum(batch["context_mask"].sum(1).astype(int), 1)
    index = np.arange(n)[None, :] % real[:, None]                 # [B, N]
    for name in ["images", "joints", "times"]:
        values = batch[f"context_{name}"]
        at = index.reshape(index.shape + (1,) * (values.ndim - 2))
        out[f"target_{name}"] = np.take_along_axis(values, at, 1)
    return out
