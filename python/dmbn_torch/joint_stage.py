"""The joint stage (crate/model/joint_stage.rs): shown only frames (blend 1), the joints the
network reads at each glimpse, seen side by side, correct their linear interpolation at each
target.

`joint_stage_inputs` builds the features exactly as crate/model/joint_stage_inputs.rs does;
`JointStage` holds the tensors `dmbn export` writes under `mirror.`, the stage's old name
(`train --joint-stage` fits them). Sized by the model's D joint values a step (7 for the
original arm).
"""
import math

import torch
import torch.nn as nn
import torch.nn.functional as F

JOINTS = 7
SLOTS = 8
FREQUENCIES = 8
LAYERS = 3
SIGMA_FLOOR = 1e-4


def slot_width(joints):
    """Values per slot: the D read joints, the glimpse's time less the target's, 1 (filled)."""
    return joints + 2


def input_width(joints):
    """Features per target: the slots, the interpolated reads, the phase, its sines and cosines."""
    return SLOTS * slot_width(joints) + joints + 1 + 2 * FREQUENCIES


# The original arm's (D = 7) widths.
SLOT = slot_width(JOINTS)
INPUTS = input_width(JOINTS)


def interpolate(times, reads, targets):
    """`reads` [K, D] at sorted `times` [K] linearly interpolated at `targets` [M], held
    beyond the first and the last."""
    if len(times) == 1:
        return reads[:1].expand(len(targets), -1)
    after = torch.searchsorted(times, targets, right=True).clamp(1, len(times) - 1)
    a, b = after - 1, after
    w = ((targets - times[a]) / (times[b] - times[a])).unsqueeze(1)
    inner = reads[a] + w * (reads[b] - reads[a])
    inner = torch.where((targets <= times[0]).unsqueeze(1), reads[0], inner)
    return torch.where((targets >= times[-1]).unsqueeze(1), reads[-1], inner)


def joint_stage_inputs(times, reads, targets):
    """The features [M, input_width(D)] and the interpolated reads [M, D] at `targets` (phases)
    for glimpses at `times` [K] (any order) read as `reads` [K, D]."""
    order = torch.sort(times, stable=True).indices
    times, reads = times[order], reads[order]
    start = interpolate(times, reads, targets)
    slot = slot_width(reads.shape[1])
    rows = []
    for m, phase in enumerate(targets):
        near = torch.arange(len(times))
        if len(times) > SLOTS:
            near = torch.sort((times - phase).abs(), stable=True).indices[:SLOTS].sort().values
        slots = torch.cat([reads[near], (times[near] - phase).unsqueeze(1),
                           torch.ones(len(near), 1)], 1).flatten()
        angle = math.pi * phase * torch.arange(1, FREQUENCIES + 1, dtype=torch.float32)
        rows.append(torch.cat([slots, torch.zeros((SLOTS - len(near)) * slot), start[m],
                               phase.reshape(1), angle.sin(), angle.cos()]))
    return torch.stack(rows), start


class JointStage(nn.Module):
    """The stage of hidden `width` for D = `joints` values a step."""

    def __init__(self, width, joints=JOINTS):
        super().__init__()
        inputs = input_width(joints)
        self.scale = nn.Parameter(torch.ones(inputs), requires_grad=False)
        self.layers = nn.ModuleList(nn.Linear(w, width) for w in [inputs] + [width] * (LAYERS - 1))
        self.mean = nn.Linear(width, joints)
        self.sigma = nn.Linear(width, joints)

    def forward(self, x, start):
        h = x / self.scale
        for layer in self.layers:
            h = F.gelu(layer(h))
        return start + self.mean(h), F.softplus(self.sigma(h.detach())) + SIGMA_FLOOR

    def predict(self, times, reads, targets):
        """Mean and σ [M, D] (joint units: the original's radians and gripper) at `targets`."""
        return self(*joint_stage_inputs(times, reads, targets))
