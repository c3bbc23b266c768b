"""Experiment (docs/results.md, *The mirror*): a second, joint-space stage for the mirror.

An MLP sees, per target, every glimpse side by side (up to 8, in time order: the joints a
model read from its frame, its phase less the target's, 1; zeros in empty slots), the glimpses
linearly interpolated there, the target's phase features and (unless `--no-action`) whether
the action is a push, and predicts the joints there as a correction of the interpolation.
It trains on a model's reads of the training frames at random layouts of 2-8 glimpses
(`cargo run --release --example read_layouts`), and is tested on its reads at 5 evenly spaced
steps of other demonstrations (`cargo run --release --example read_joints`), each test set
written as joint files for `cargo run --release --example perform_trajectories`.

    python python/experiments/mirror_stage.py --train data/sim2000 --layouts runs/layouts.jsonl \
        --test data/imitate runs/read-test runs/stage-test --test data/imitate-val runs/read-val runs/stage-val

Needs numpy and torch (the PyTorch twin's environment).
"""
import argparse
import json

import numpy as np
import torch

from mirror_interpolation import FREQUENCIES, fit_correction, joints, write

SLOTS = 8


def examples(steps, reads, t, push):
    """Per step of a t-step sequence: the input features, and the interpolation of the reads."""
    order = np.argsort(steps)
    steps, reads = np.asarray(steps)[order], np.asarray(reads, np.float32)[order]
    phase, at = np.arange(t) / (t - 1), steps / (t - 1)
    start = np.stack([np.interp(phase, at, reads[:, j]) for j in range(7)], 1)
    slots = np.zeros((t, SLOTS, 9), np.float32)
    slots[:, :len(steps), :7] = reads[None]
    slots[:, :len(steps), 7] = at[None] - phase[:, None]
    slots[:, :len(steps), 8] = 1
    features = np.concatenate([phase[:, None], np.sin(np.pi * phase[:, None] * FREQUENCIES),
                               np.cos(np.pi * phase[:, None] * FREQUENCIES), np.full((t, 1), push)], 1)
    return np.concatenate([slots.reshape(t, -1), start, features], 1).astype(np.float32), start.astype(np.float32)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--train", required=True, help="the dataset the layouts were read from")
    p.add_argument("--layouts", required=True, help="read_layouts' JSON lines")
    p.add_argument("--test", nargs=3, action="append", required=True, metavar=("DATA", "READS", "OUT"),
                   help="a dataset, the reads at its evenly spaced steps, where to write (ids 0-99)")
    p.add_argument("--no-action", action="store_true", help="not told whether it is a push")
    p.add_argument("--observations", type=int, default=5, help="glimpses the test reads are at, evenly spaced")
    p.add_argument("--steps", type=int, default=20000)
    a = p.parse_args()
    torch.manual_seed(0)
    torch.set_num_threads(1)
    action = lambda name: 0.0 if a.no_action else float(name == "move")  # noqa: E731
    x, start, truth, cache = [], [], [], {}
    for line in open(a.layouts):
        r = json.loads(line)
        key = (r["id"], r["action"])
        if key not in cache:
            cache[key] = joints(a.train, *key)
        y = cache[key]
        xs, s = examples(r["steps"], r["reads"], len(y), action(r["action"]))
        x.append(xs), start.append(s), truth.append(y)
    net, scale = fit_correction(x, start, truth, a.steps)
    for data, reads, out in a.test:
        for name in ("move", "grasp"):
            se, n = 0.0, 0
            for i in range(100):
                y = joints(data, i, name)
                t = len(y)
                k = a.observations
                steps = [round(j * (t - 1) / (k - 1)) for j in range(k)]
                xs, s = examples(steps, joints(reads, i, name), t, action(name))
                with torch.no_grad():
                    pred = (torch.tensor(s) + net(torch.tensor(xs) / scale)).numpy()
                se, n = np.add((se, n), write(out, i, name, pred, y))
            print(f"{data} {name}: joint RMSE {(se / n) ** 0.5:.4f} rad")


if __name__ == "__main__":
    main()
