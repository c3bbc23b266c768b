"""The same DMBN in PyTorch, timed on the same shapes as `cargo bench --bench model`.

Architecture as crate/model (64 px): image encoder Conv3x3+ReLU+MaxPool blocks
(32, 64, 128, 128, 256) to 2x2, dense 128; joint encoder (t, 7 joints) -> 32, 64, 64, 128, 128, 256 -> 128; masked mean
per modality, blend; [r, t] -> dense 1024; image decoder Conv3x3+ReLU+Upsample blocks
(256, 128, 64, 64, 32), conv 16, conv 8, mean/σ heads; joint decoder 512, 216, 128, 32 ->
mean/σ heads. Gaussian NLL, Adam with gradient clipping.

Usage: python bench/torch_dmbn.py --threads N  (prints one JSON line of medians in ms)
"""
import argparse
import json
import statistics
import time

import torch
import torch.nn as nn
import torch.nn.functional as F

S, H, B, N, M = 64, 128, 8, 5, 4
ENC = [32, 64, 128, 128, 256]
DEC = [256, 128, 64, 64, 32]


def bounded_sigma(raw, floor=0.01):
    return floor + (1 - floor) * F.softplus(raw)


class Dmbn(nn.Module):
    def __init__(self):
        super().__init__()
        convs, c = [], 4
        for f in ENC:
            convs.append(nn.Conv2d(c, f, 3, padding=1))
            c = f
        self.enc_convs = nn.ModuleList(convs)
        self.enc_dense = nn.Linear(c * 4, H)
        layers, c = [], 8
        for f in [32, 64, 64, 128, 128, 256, H]:
            layers += [nn.Linear(c, f), nn.ReLU()]
            c = f
        self.joint_enc = nn.Sequential(*layers)
        self.shared = nn.Linear(H + 1, 1024)
        blocks, c = [], 1024 // 4
        for f in DEC:
            blocks.append(nn.Conv2d(c, f, 3, padding=1))
            c = f
        self.dec_blocks = nn.ModuleList(blocks)
        self.tail = nn.ModuleList([nn.Conv2d(c, 16, 3, padding=1), nn.Conv2d(16, 8, 3, padding=1)])
        self.mean = nn.Conv2d(8, 3, 3, padding=1)
        self.sigma = nn.Conv2d(8, 3, 3, padding=1)
        self.joint_dec = nn.Sequential(
            nn.Linear(1024, 512), nn.ReLU(), nn.Linear(512, 216), nn.ReLU(),
            nn.Linear(216, 128), nn.ReLU(), nn.Linear(128, 32), nn.ReLU())
        self.joint_mean = nn.Linear(32, 7)
        self.joint_sigma = nn.Linear(32, 7)

    def encode(self, images, joints, times, mask, blend):
        b, n = times.shape
        plane = times.reshape(b, n, 1, 1, 1).expand(b, n, 1, S, S)
        x = torch.cat([plane, images], 2).reshape(b * n, 4, S, S)
        for conv in self.enc_convs:
            x = F.max_pool2d(F.relu(conv(x)), 2)
        z_img = F.relu(self.enc_dense(x.flatten(1))).reshape(b, n, H)
        z_joint = self.joint_enc(torch.cat([times.unsqueeze(2), joints], 2))
        w = mask.unsqueeze(2) / mask.sum(1, keepdim=True).unsqueeze(2)
        r_img, r_joint = (z_img * w).sum(1), (z_joint * w).sum(1)
        c = blend.unsqueeze(1)
        return c * r_img + (1 - c) * r_joint

    def decode(self, r, target_times):
        b, m = target_times.shape
        x = torch.cat([r.unsqueeze(1).expand(b, m, H), target_times.unsqueeze(2)], 2)
        x = F.relu(self.shared(x.reshape(b * m, H + 1)))
        y = x.reshape(b * m, 256, 2, 2)
        for conv in self.dec_blocks:
            y = F.interpolate(F.relu(conv(y)), scale_factor=2, mode="nearest")
        for conv in self.tail:
            y = F.relu(conv(y))
        j = self.joint_dec(x)
        return (torch.sigmoid(self.mean(y)), bounded_sigma(self.sigma(y)),
                self.joint_mean(j), bounded_sigma(self.joint_sigma(j)))


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
    model = Dmbn()
    opt = torch.optim.Adam(model.parameters(), lr=1e-4)
    images = torch.rand(B, N, 3, S, S)
    joints, times = torch.randn(B, N, 7), torch.rand(B, N)
    mask, blend = torch.ones(B, N), torch.rand(B)
    t_times = torch.rand(B, M)
    t_images, t_joints = torch.rand(B * M, 3, S, S), torch.randn(B * M, 7)

    def train_step():
        opt.zero_grad()
        mean, sigma, jm, js = model.decode(model.encode(images, joints, times, mask, blend), t_times)
        loss = F.gaussian_nll_loss(mean, t_images, sigma ** 2, full=True) + \
            0.01 * F.gaussian_nll_loss(jm, t_joints, js ** 2, full=True)
        loss.backward()
        torch.nn.utils.clip_grad_norm_(model.parameters(), 1.0)
        opt.step()

    one = [x[:1] for x in (images, joints, times, mask, blend)]

    def infer(targets):
        def run():
            with torch.no_grad():
                r = model.encode(*one)
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
