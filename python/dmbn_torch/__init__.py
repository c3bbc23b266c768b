"""The PyTorch twin of dmbn: DMBN, DMBN-PTE and the attentive model, layer for layer, and
their training.

Load the weights `dmbn export` writes and predict as `dmbn predict` does:

    import dmbn_torch
    model = dmbn_torch.load("dmbn-sim.safetensors")          # eval mode, on the CPU
    out = model.predict(frames, joints, times, target_times, blend=0.5)
    out["joint_mean"], out["joint_sigma"]                     # [T, D], joint units
    out["image_mean"], out["image_sigma"]                     # [T, S, S, 3], in [0, 1]

`frames` are the observed RGB frames as uint8 `[N, S, S, 3]`, `joints` the observed joint
values `[N, D]` (not normalised; D the file's `joints`, 7 — 6 arm angles in radians and the
gripper — for files without it), `times` their phases in [0, 1], `target_times` the phases to
predict; `blend` is c: 1 = frames only, 0 = joints only. `save(model, path)` writes weights
changed here in the file `dmbn import` reads.

Train as the Rust `train` does (same flags, same objective, same optimiser; DDP with torchrun):

    cd python && python -m dmbn_torch.train --data DIR --model pte --steps 2000 --out runs/pte
    torchrun --nproc_per_node 2 -m dmbn_torch.train ...   # each process a share of the batch

Modules: `model` (the networks, load, save), `init` (fresh weights), `data` (the DMBN-layout
reader, the joint normalisation), `sampler` (context/target batches, the paper's time warps),
`loss` (the objective), `train` (the loop and its command line). `python -m dmbn_torch check`
compares a prediction with `dmbn predict --arrays`.

Needs torch, safetensors and numpy (pip install torch safetensors numpy); Pillow, where
installed, decodes frames faster and is needed for JPEG frames.
"""
from .model import (  # noqa: F401
    KINDS, Contexts, Dmbn, DmbnAttn, DmbnPte, Predictor, load, save,
)
