"""DMBN in PyTorch (python/dmbn_torch/, the twin of crate/model), timed on the same shapes as
`cargo bench --bench model`: a training step (Gaussian NLL, Adam with gradient clipping) and
inference of one and of 100 target times.

Usage: python bench/torch_dmbn.py --threads N  (prints one JSON line of medians in ms)
"""
import argparse
import json
import pathlib
import statistics
import sys
import time

import torch
import torch.nn.functional as F

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent / "python"))
import dmbn_torch  # noqa: E402

S, B, N, M = 64, 8, 5, 4
CONFIG = {"kind": "dmbn", "image_size": S, "hidden": 128, "sigma_floor": 0.01}


def median_ms(fn, repeats, warmup=2):
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append((time.perf_counter() - start) * 1e3)
    return statistics.median(times)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--threads", type=int, required=True)
    parser.add_argument("--repeats", type=int, default=10)
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    torch.manual_seed(0)
    model = dmbn_torch.Dmbn(CONFIG)
    opt = torch.optim.Adam(model.parameters(), lr=1e-4)
    contexts = dmbn_torch.Contexts(torch.rand(B, N, 3, S, S), torch.randn(B, N, 7),
                                   torch.rand(B, N), torch.ones(B, N), torch.rand(B))
    t_times = torch.rand(B, M)
    t_images, t_joints = torch.rand(B * M, 3, S, S), torch.randn(B * M, 7)

    def train_step():
        opt.zero_grad()
        p = model.decode(model.encode(contexts), t_times)
        mean, sigma = p["image_mean"].reshape(B * M, 3, S, S), p["image_sigma"].reshape(B * M, 3, S, S)
        jm, js = p["joint_mean"].reshape(B * M, 7), p["joint_sigma"].reshape(B * M, 7)
        loss = F.gaussian_nll_loss(mean, t_images, sigma ** 2, full=True) + \
            0.01 * F.gaussian_nll_loss(jm, t_joints, js ** 2, full=True)
        loss.backward()
        torch.nn.utils.clip_grad_norm_(model.parameters(), 1.0)
        opt.step()

    one = dmbn_torch.Contexts(*(x[:1] for x in (contexts.frames, contexts.joints, contexts.times,
                                                 contexts.mask, contexts.blend)))

    def infer(targets):
        def run():
            with torch.no_grad():
                r = model.encode(one)
                for chunk in torch.linspace(0, 1, targets).split(25):
                    model.decode(r, chunk.unsqueeze(0))
        return run

    result = {
        "framework": f"pytorch {torch.__version__}",
        "threads": args.threads,
        "train_step_ms": median_ms(train_step, args.repeats),
        "infer_one_ms": median_ms(infer(1), args.repeats * 5),
        "infer_sequence100_ms": median_ms(infer(100), args.repeats),
    }
    print(json.dumps(result))


if __name__ == "__main__":
    main()
