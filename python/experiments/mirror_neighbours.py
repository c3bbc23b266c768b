"""Experiment (docs/results.md, *The mirror*): does an interpolator of the glimpses around each
target do what one of all five glimpses does?

As `mirror_interpolation.py`, but the MLP sees, per target, only the joints of the 2 glimpses
at or before it and the 2 after it (each with its phase less the target's and whether it is
there), as a model decoder would for any number and placement of glimpses. It trains either
on the joints a model read from the training frames at 5 evenly spaced steps (`--read-train`)
or on true joints with noise at 2-8 glimpses, evenly spaced or one in each of n equal
stretches (`--draws` layouts a sequence), and is tested on a model's reads at 5 evenly spaced
steps (`--read-test`), writing joint files for `cargo run --release --example
perform_trajectories`.

    python python/experiments/mirror_neighbours.py --train data/sim2000 --read-train runs/read-train \
        --test data/imitate-val --read-test runs/read-val --out runs/mlp-neighbours

Needs numpy and torch (the PyTorch twin's environment).
"""
import argparse

import numpy as np
import torch

from mirror_interpolation import FREQUENCIES, fit_correction, joints, write


def evenly_spaced(t, k):
    return [round(i * (t - 1) / (k - 1)) for i in range(k)]


def examples(steps, observed, t, flag):
    """Per step of a t-step sequence: the 2 + 2 glimpses around it (7 joints, phase less the
    step's, 1; zeros where there is none), the glimpses linearly interpolated there, the
    step's phase features and the action flag; and the interpolation, where the MLP's
    correction starts."""
    order = np.argsort(steps)
    steps, observed = np.asarray(steps)[order], observed[order]
    phase, at = np.arange(t) / (t - 1), steps / (t - 1)
    start = np.stack([np.interp(phase, at, observed[:, j]) for j in range(7)], 1)
    around = []
    for s in range(t):
        before = [i for i in range(len(steps)) if steps[i] <= s][-2:]
        after = [i for i in range(len(steps)) if steps[i] > s][:2]
        slots = [None] * (2 - len(before)) + before + after + [None] * (2 - len(after))
        around.append(np.concatenate(
            [np.zeros(9) if i is None else [*observed[i], at[i] - phase[s], 1.0] for i in slots]))
    features = np.concatenate([phase[:, None], np.sin(np.pi * phase[:, None] * FREQUENCIES),
                               np.cos(np.pi * phase[:, None] * FREQUENCIES), np.full((t, 1), flag)], 1)
    return np.concatenate([np.array(around), start, features], 1).astype(np.float32), start.astype(np.float32)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--train", required=True)
    p.add_argument("--train-ids", default="0-1799")
    p.add_argument("--read-train", help="a model's reads of the training frames; else true joints")
    p.add_argument("--noise", type=float, default=0.02, help="rad, on true joints (the gripper 5%% of it)")
    p.add_argument("--draws", type=int, default=6, help="glimpse layouts a sequence, on true joints")
    p.add_argument("--test", required=True)
    p.add_argument("--test-ids", default="0-99")
    p.add_argument("--read-test", required=True)
    p.add_argument("--steps", type=int, default=20000)
    p.add_argument("--out", required=True)
    a = p.parse_args()
    torch.manual_seed(0)
    torch.set_num_threads(1)
    rng = np.random.default_rng(0)
    span = lambda s: range(int(s.split("-")[0]), int(s.split("-")[1]) + 1)  # noqa: E731
    x, start, truth = [], [], []
    for i in span(a.train_ids):
        for action, flag in (("move", 1.0), ("grasp", 0.0)):
            y = joints(a.train, i, action)
            t = len(y)
            if a.read_train:
                layouts = [(evenly_spaced(t, 5), joints(a.read_train, i, action))]
            else:
                layouts = []
                for d in range(a.draws):
                    k = int(rng.integers(2, 9))
                    steps = evenly_spaced(t, k) if d % 2 == 0 else [
                        int(rng.integers(j * t // k, (j + 1) * t // k)) for j in range(k)]
                    noise = rng.normal(0, a.noise, (k, 7)) * np.array([1.0] * 6 + [0.05])
                    layouts.append((steps, y[steps] + noise.astype(np.float32)))
            for steps, observed in layouts:
                xs, s = examples(steps, observed, t, flag)
                x.append(xs), start.append(s), truth.append(y)
    net, scale = fit_correction(x, start, truth, a.steps)
    for action, flag in (("move", 1.0), ("grasp", 0.0)):
        se, n = 0.0, 0
        for i in span(a.test_ids):
            y = joints(a.test, i, action)
            xs, s = examples(evenly_spaced(len(y), 5), joints(a.read_test, i, action), len(y), flag)
            with torch.no_grad():
                pred = (torch.tensor(s) + net(torch.tensor(xs) / scale)).numpy()
            se, n = np.add((se, n), write(a.out, i, action, pred, y))
        print(f"{action}: joint RMSE {(se / n) ** 0.5:.4f} rad on {a.test}")


if __name__ == "__main__":
    main()
