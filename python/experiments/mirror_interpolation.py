"""Experiment (docs/results.md, *The mirror*): how well *could* the mirror's joints go from 5
glimpses to a whole action, and what does reading them from frames cost?

A plain MLP is given the joints at K evenly spaced steps of a simulator demonstration (the
true ones, plus Gaussian noise of NOISE rad, fresh every batch: an imperfect reading of the
frames; or those a model read from the frames, `--read-train`/`--read-test`) and the phase of a target step, and predicts the joints (and the gripper column) there as a correction of the
observations linearly interpolated (where the attentive model's joint decoder starts too). It
trains on one dataset's ids and writes its trajectories for another's (observed with the same
noise) as joint files in the DMBN layout (`OUT/<id>/<action>/joint_<id>.txt`), for `cargo run
--release --example perform_trajectories` to perform.

    python python/experiments/mirror_interpolation.py --train data/sim2000 --train-ids 0-1799 \
        --test data/imitate --noise 0.03 --out runs/mlp-0.03

Needs numpy and torch (the PyTorch twin's environment).
"""
import argparse
import os

import numpy as np
import torch

K = 5
FREQUENCIES = np.arange(1, 9)


def joints(root, i, action):
    return np.loadtxt(f"{root}/{i}/{action}/joint_{i}.txt", dtype=np.float32)


def observed_steps(t):
    return [round(i * (t - 1) / (K - 1)) for i in range(K)]


def examples(sequence, flag, read=None):
    """Per step: the observed joints (K x 7: the true ones, or `read`, those a model read
    from the frames), the weights that interpolate them to the step (K), the step's phase
    features, and its true joints."""
    t = len(sequence)
    steps = observed_steps(t)
    phase = np.arange(t) / (t - 1)
    weights = np.stack([np.interp(phase, np.array(steps) / (t - 1), np.eye(K)[i]) for i in range(K)], 1)
    features = np.concatenate([phase[:, None], np.sin(np.pi * phase[:, None] * FREQUENCIES),
                               np.cos(np.pi * phase[:, None] * FREQUENCIES), np.full((t, 1), flag)], 1)
    contexts = np.repeat((sequence[steps] if read is None else read)[None], t, 0)
    return contexts, weights.astype(np.float32), features.astype(np.float32), sequence


def read_joints(folder, i, action):
    return None if folder is None else joints(folder, i, action)


def stack(root, ids, read):
    parts = [examples(joints(root, i, a), f, read_joints(read, i, a))
             for i in ids for a, f in (("move", 1.0), ("grasp", 0.0))]
    return [torch.tensor(np.concatenate([p[j] for p in parts])) for j in range(4)]


class Interpolator(torch.nn.Module):
    def __init__(self, inputs, width):
        super().__init__()
        self.net = torch.nn.Sequential(
            torch.nn.Linear(inputs, width), torch.nn.GELU(), torch.nn.Linear(width, width),
            torch.nn.GELU(), torch.nn.Linear(width, width), torch.nn.GELU(), torch.nn.Linear(width, 7))

    def forward(self, contexts, weights, features, scale):
        start = torch.einsum("bk,bkj->bj", weights, contexts)
        x = torch.cat([contexts.flatten(1), start, features], 1)
        return start + self.net(x / scale)


def noisy(contexts, noise, gripper_noise, generator):
    """Gaussian noise of `noise` rad on the six arm joints and of `gripper_noise` on the
    gripper column (metres of finger travel: a push's column is 0 throughout, so a model's read
    of about a millimetre lies far outside what an interpolator of true columns has seen)."""
    n = torch.randn(contexts.shape, generator=generator)
    n[..., :6] *= noise
    n[..., 6] *= gripper_noise
    return contexts + n


def fit(net, loss, size, steps, generator):
    """Adam (1e-3, cosine schedule) on `loss(indices)` of random batches of 512 of `size`
    examples."""
    opt = torch.optim.Adam(net.parameters(), 1e-3)
    schedule = torch.optim.lr_scheduler.CosineAnnealingLR(opt, steps)
    for step in range(steps):
        value = loss(torch.randint(0, size, (512,), generator=generator))
        opt.zero_grad()
        value.backward()
        opt.step()
        schedule.step()
        if step % 5000 == 0 or step == steps - 1:
            print(f"step {step}: training RMSE {value.item() ** 0.5:.4f}", flush=True)


def fit_correction(x, start, truth, steps):
    """An MLP (3 x 256) fitted to correct `start` to `truth` from the features `x` (per-sequence
    arrays, one row a step); returns it with the scale its inputs are divided by."""
    x, start, truth = (torch.tensor(np.concatenate(v)) for v in (x, start, truth))
    scale = x.abs().amax(0).clamp(min=1e-3)
    net = torch.nn.Sequential(
        torch.nn.Linear(x.shape[1], 256), torch.nn.GELU(), torch.nn.Linear(256, 256), torch.nn.GELU(),
        torch.nn.Linear(256, 256), torch.nn.GELU(), torch.nn.Linear(256, 7))
    fit(net, lambda i: ((start[i] + net(x[i] / scale) - truth[i]) ** 2).mean(), len(x), steps,
        torch.Generator().manual_seed(1))
    return net, scale


def write(out, i, action, pred, truth):
    """Writes a predicted trajectory as its joint file; returns its squared error on the six
    arm joints and how many values that sums."""
    os.makedirs(f"{out}/{i}/{action}", exist_ok=True)
    np.savetxt(f"{out}/{i}/{action}/joint_{i}.txt", pred)
    return float(((pred - truth)[:, :6] ** 2).sum()), pred[:, :6].size


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--train", required=True)
    p.add_argument("--train-ids", default="0-1799")
    p.add_argument("--test", required=True)
    p.add_argument("--test-ids", default="0-99")
    p.add_argument("--noise", type=float, default=0.0)
    p.add_argument("--gripper-noise", type=float, default=0.0)
    p.add_argument("--read-train", help="the joints a model read from the training frames "
                   "(`cargo run --release --example read_joints`), instead of the true ones")
    p.add_argument("--read-test", help="... and from the test frames")
    p.add_argument("--steps", type=int, default=20000)
    p.add_argument("--width", type=int, default=256)
    p.add_argument("--out", required=True)
    a = p.parse_args()
    torch.manual_seed(0)
    torch.set_num_threads(1)
    rng = torch.Generator().manual_seed(1)
    span = lambda s: range(int(s.split("-")[0]), int(s.split("-")[1]) + 1)
    contexts, weights, features, truth = stack(a.train, span(a.train_ids), a.read_train)
    inputs = K * 7 + 7 + features.shape[1]
    scale = torch.cat([contexts.flatten(1), truth, features], 1).abs().amax(0).clamp(min=1e-3)
    net = Interpolator(inputs, a.width)
    fit(net, lambda i: ((net(noisy(contexts[i], a.noise, a.gripper_noise, rng), weights[i],
                             features[i], scale) - truth[i]) ** 2).mean(), len(truth), a.steps, rng)
    for action, flag in (("move", 1.0), ("grasp", 0.0)):
        se, n = 0.0, 0
        for i in span(a.test_ids):
            c, w, f, y = (torch.tensor(v) for v in examples(joints(a.test, i, action), flag, read_joints(a.read_test, i, action)))
            # A model's reads are tested as read; true joints with the training's noise.
            observed = c[:1] if a.read_test else noisy(c[:1], a.noise, a.gripper_noise, rng)
            with torch.no_grad():
                pred = net(observed.expand_as(c), w, f, scale).numpy()
            se, n = np.add((se, n), write(a.out, i, action, pred, y.numpy()))
        print(f"{action}: joint RMSE {(se / n) ** 0.5:.4f} rad on {a.test}")


if __name__ == "__main__":
    main()
