"""The training objective of trainer.rs `step()` and crate/model/loss.rs.

Per value the Gaussian NLL ½·log(2π) + log σ + (x − μ)²/(2σ²) (σ² clamped at 1e-6, as burn's
GaussianNLLLoss), averaged over a modality; total = image + joint_weight · joint. With β > 0
each value's NLL is weighed by σ^(2β), held constant (β-NLL): the pixels a model is sure of
would otherwise outweigh the moving arm in the mean's gradient. The reported NLL parts stay
plain. Added to the total: joint_weight · the (β-)NLL of the joint-only targets, and for the
attentive model drawn_frame_weight · the squared error of the frame it draws before its gate.
"""
import math

import torch

HALF_LN_TWO_PI = 0.5 * math.log(2 * math.pi)
PARTS = ["total", "image_nll", "joint_nll", "image_mse", "joint_mse"]


def nll(mean, sigma, target, beta):
    """(plain mean NLL, detached; the objective's, β-weighted when β > 0)."""
    var = sigma.square().clamp_min(1e-6)
    values = 0.5 * (var.log() + (mean - target).square() / var) + HALF_LN_TWO_PI
    plain = values.mean()
    weighted = (values * sigma.detach().pow(2 * beta)).mean() if beta > 0 else plain
    return plain.detach(), weighted


def objective(network, batch, joint_weight, beta=0.0, drawn_frame_weight=0.0):
    """The loss of one batch (a dict of tensors as `sampler.sample` draws them): the total,
    carrying the graph, and the five parts as a detached tensor (PARTS' order)."""
    from .model import Contexts

    contexts = Contexts(batch["context_images"], batch["context_joints"],
                        batch["context_times"], batch["context_mask"], batch["blend"])
    r = network.encode(contexts)
    p = network.decode(r, batch["target_times"])
    images, joints = batch["target_images"], batch["target_joints"]
    image_nll, image_weighted = nll(p["image_mean"], p["image_sigma"], images, beta)
    joint_nll, joint_weighted = nll(p["joint_mean"], p["joint_sigma"], joints, beta)
    total = image_weighted + joint_weight * joint_weighted
    if p["image_drawn"] is not None and drawn_frame_weight > 0:
        total = total + drawn_frame_weight * (p["image_drawn"] - images).square().mean()
    times = batch.get("joint_target_times")
    if times is not None and times.shape[1] > 0:
        mean, sigma = network.decode_joints(r, times)
        total = total + joint_weight * nll(mean, sigma, batch["joint_target_joints"], beta)[1]
    with torch.no_grad():
        image_mse = (p["image_mean"] - images).square().mean()
        joint_mse = (p["joint_mean"] - joints).square().mean()
    return total, torch.stack([total.detach(), image_nll, joint_nll, image_mse, joint_mse])


def tensors(batch, device):
    """A sampled batch's arrays as float32 tensors on `device`."""
    return {k: torch.as_tensor(v, device=device) for k, v in batch.items()}


def gradients(model_path, batch_path, out_path):
    """Loss and gradients of the exported model at `model_path` on the batch a test wrote at
    `batch_path` (the sampler's arrays, the loss settings in its `dmbn` metadata), written to
    `out_path`: `loss` (PARTS' order) and every gradient under its tensor's export name."""
    import json

    from safetensors import safe_open
    from safetensors.torch import load_file, save_file

    from .model import load

    with safe_open(batch_path, "pt") as f:
        settings = json.loads(f.metadata()["dmbn"])
    batch = load_file(batch_path)
    model = load(model_path).train()
    total, parts = objective(model.network, batch, settings["joint_weight"],
                             settings["beta"], settings["drawn_frame_weight"])
    total.backward()
    grads = {k: p.grad if p.grad is not None else torch.zeros_like(p)
             for k, p in model.network.named_parameters()}
    save_file({"loss": parts, **{k: g.contiguous() for k, g in grads.items()}}, out_path)
