"""Training in PyTorch, as the Rust `train` does: the same flags where they mean the same, the
same objective (loss.py), batches (sampler.py), fresh weights (init.py) and optimiser: Adam
(β 0.9, 0.999, ε 1e-5, burn's defaults), each parameter's gradient clipped to norm
--clip-norm as burn's GradientClipping::Norm does (per tensor), the learning rate a function
of the step (constant; cosine to 5% at the last step; ×0.3 every third of the run).

    cd python
    python -m dmbn_torch.train --data DIR --model pte --steps 2000 --out runs/pte --seed 1
    torchrun --nproc_per_node N -m dmbn_torch.train ...      # DDP: gloo on CPUs, nccl on GPUs

The joint values a step (D) come from the data (the model's config gets `joints`, and
`joint_names` from the dataset's dataset.json where it names them); --camera picks another
camera's frames (`<seq>/<camera>/<k>.png`).

--out gets metrics.jsonl (as train's), checkpoint.pt every --checkpoint-every steps (written
to a temporary file and renamed over the last) and, at the end, model.safetensors, which
`dmbn import --from model.safetensors --out model.dmbn` turns into a model file. Under DDP each
process draws its share of the global --batch (the same global batch as one process draws),
gradients are averaged, and rank 0 writes the files.
"""
import argparse
import json
import math
import os
import sys
import time

import torch
import torch.distributed as dist
from torch import nn

from .data import Normalization, Split
from .init import initialise
from .loss import PARTS, objective, tensors
from .model import Predictor, joint_count, load, save
from .sampler import VAL_STREAM, SamplerConfig, TimeWarp, contexts_as_targets, sample

F32_MIN_POSITIVE = 1.1754944e-38


def rate(schedule, lr, step, steps):
    """Learning rate at 0-based `step` of `steps` (Schedule::rate)."""
    if schedule["kind"] == "cosine":
        progress = min(step / max(steps - 1, 1), 1.0)
        floor = lr * schedule["final_fraction"]
        return floor + 0.5 * (lr - floor) * (1 + math.cos(math.pi * progress))
    if schedule["kind"] == "step":
        return lr * schedule["gamma"] ** (step // max(schedule["every"], 1))
    return lr


def clip_per_tensor(parameters, max_norm):
    """Each gradient scaled to norm <= max_norm on its own (burn's clip_by_norm per param)."""
    with torch.no_grad():
        for p in parameters:
            if p.grad is not None:
                p.grad.mul_((max_norm / (p.grad.norm() + F32_MIN_POSITIVE)).clamp(max=1.0))


class Objective(nn.Module):
    """The network and its loss as one module, so that DDP sees one forward per step."""

    def __init__(self, network, config):
        super().__init__()
        self.network, self.config = network, config

    def forward(self, batch, scale):
        c = self.config
        total, parts = objective(self.network, batch, c["model"]["joint_weight"],
                                 c["beta_nll"], c["drawn_frame_weight"])
        return total * scale, parts


class World:
    """This process's place in a DDP run (torchrun's environment), or a run of one."""

    def __init__(self, device):
        self.size = int(os.environ.get("WORLD_SIZE", "1"))
        self.rank = int(os.environ.get("RANK", "0"))
        local = int(os.environ.get("LOCAL_RANK", "0"))
        if device == "auto":
            device = "cuda" if torch.cuda.is_available() else "cpu"
        self.device = torch.device(f"cuda:{local}" if device == "cuda" else device)
        if self.device.type == "cuda":
            torch.cuda.set_device(self.device)
        if self.size > 1:
            dist.init_process_group("nccl" if self.device.type == "cuda" else "gloo")

    def share(self, batch):
        """This process's slots of a global batch of `batch` sequences."""
        if batch < self.size:
            raise ValueError(f"--batch {batch} is smaller than the {self.size} processes")
        return range(self.rank * batch // self.size, (self.rank + 1) * batch // self.size)

    def sum(self, x):
        if self.size > 1:
            dist.all_reduce(x)
        return x


def train_config(args):
    """The run's settings (TrainConfig's fields) from the command line."""
    model = {"kind": args.model, "image_size": args.image_size, "hidden": 128,
             "sigma_floor": args.sigma_floor, "joint_weight": args.joint_weight, "heads": None,
             "decoder_filters": args.decoder_filters, "coarse_tail": args.coarse_tail or None,
             "encoder_filters": args.encoder_filters, "frame_joints": args.frame_joints or None,
             "joints": None, "joint_names": None}  # from the data (Run)
    if args.init:
        header = load(args.init).header
        file = header["config"]
        if args.model and args.model != file["kind"]:
            raise ValueError(f"--init holds a {file['kind']} model, not {args.model}: "
                             "leave --model out to train it")
        if file.get("latent"):
            raise ValueError(f"--init {args.init}: the model has a latent path, which the "
                             "PyTorch twin predicts with but does not train (its KL term): "
                             "train it with the Rust `train`")
        # A joint stage (the config's `mirror`) learnt the file's network's reads: training the
        # network leaves it behind (`train --init FILE --steps 0 --joint-stage` fits one to the
        # result).
        model = dict(file, joint_weight=args.joint_weight, mirror=None,
                     frame_joints=True if args.frame_joints else file.get("frame_joints"))
    elif not args.model:
        raise ValueError("--model missing: pass --model dmbn|pte|attn")
    schedule = {"constant": {"kind": "constant"},
                "cosine": {"kind": "cosine", "final_fraction": 0.05},
                "step": {"kind": "step", "every": max(args.steps // 3, 1), "gamma": 0.3}}
    warp = TimeWarp(freeze_fraction=args.freeze_fraction) if args.augment else None
    config = {
        "model": model, "seed": args.seed, "steps": args.steps, "batch": args.batch,
        "max_contexts": args.max_contexts, "targets_per_sequence": args.targets_per_sequence,
        "contexts_in_targets": args.contexts_in_targets, "joint_targets": args.joint_targets,
        "single_modality": args.single_modality, "prefix_contexts": args.prefix_contexts,
        "lr": args.lr, "schedule": schedule[args.schedule], "clip_norm": args.clip_norm,
        "drawn_frame_weight": args.drawn_frame_weight, "beta_nll": args.beta_nll,
        "val_fraction": args.val_fraction, "val_every": args.val_every, "val_batches": 8,
        "checkpoint_every": args.checkpoint_every,
        "augment": warp.to_json() if warp else None, "init": args.init, "half": args.half,
        "initialization": args.initialization, "joint_scale": args.joint_scale,
        "camera": args.camera,
    }
    for field in ["steps", "batch", "max_contexts", "targets_per_sequence", "val_every",
                  "checkpoint_every"]:
        if config[field] < 1:
            raise ValueError(f"--{field.replace('_', '-')} is {config[field]}: expected at least 1")
    if not (config["lr"] > 0 and config["clip_norm"] > 0 and 0 <= config["beta_nll"] <= 1):
        raise ValueError("expected --lr > 0, --clip-norm > 0 and --beta-nll in [0, 1]")
    return config


def sampler(config, training):
    warp = config["augment"]
    return SamplerConfig(
        batch=config["batch"], max_contexts=config["max_contexts"],
        targets=config["targets_per_sequence"], contexts_in_targets=config["contexts_in_targets"],
        joint_targets=config["joint_targets"] if training else 0,
        single_modality=config["single_modality"], prefix_contexts=config["prefix_contexts"],
        warp=TimeWarp(**{k: tuple(v) if isinstance(v, list) else v for k, v in warp.items()})
        if training and warp else None)


def write_atomic(path, write):
    tmp = f"{path}.tmp"
    write(tmp)
    os.replace(tmp, path)


class Run:
    """A training run: the model, Adam, the data, and --out's files (rank 0 writes them)."""

    def __init__(self, args, world):
        self.world, self.out = world, args.out
        checkpoint = os.path.join(args.out, "checkpoint.pt")
        if args.resume:
            if not os.path.exists(checkpoint):
                raise ValueError(f"{checkpoint}: no checkpoint to resume from (run without "
                                 "--resume first)")
            state = torch.load(checkpoint, map_location=world.device, weights_only=False)
            self.config = state["config"]
            trained = self.config["model"]["kind"]
            if args.model and args.model != trained:
                raise ValueError(f"the checkpoint in {args.out} trains {trained}, not "
                                 f"{args.model}: leave --model out to resume it")
            if args.camera is not None:
                raise ValueError("--camera: a resumed run keeps its run's camera")
            self.config["steps"] = args.steps or self.config["steps"]
            self.config["half"] = self.config["half"] or args.half
            self.data = args.data or state["data"]
        else:
            if os.path.exists(checkpoint):
                raise ValueError(f"{args.out} already holds a checkpoint: pass --resume to "
                                 "continue it, or choose another --out")
            if not (args.data and args.steps):
                raise ValueError("--data and --steps are needed (unless --resume)")
            self.config, self.data, state = train_config(args), os.path.abspath(args.data), None
        c = self.config
        self.split = Split(self.data, c["model"]["image_size"], c["val_fraction"],
                           c.get("camera"))
        self.sized_by_data(c["model"], state, args)
        if state:
            self.normalization = Normalization(**state["normalization"])
        else:
            self.normalization = Normalization.fit(s.joints for s in self.split.train).scaled(
                c.get("joint_scale", "per-joint"))
        header = {"config": c["model"], "normalization": self.normalization.to_json()}
        self.predictor = Predictor(header).to(world.device)
        network = self.predictor.network
        torch.manual_seed(c["seed"])
        initialise(network, c.get("initialization", "he"))
        if state:
            network.load_state_dict(state["model"])
        elif c["init"]:
            # A joint read-out the file lacks keeps its fresh weights: it reads nothing yet.
            fresh = {k: v for k, v in network.state_dict().items() if k.startswith("frame_joints.")}
            network.load_state_dict({**fresh, **load(c["init"]).network.state_dict()})
        self.objective = Objective(network, c).to(world.device)
        if world.size > 1:
            ids = [world.device.index] if world.device.type == "cuda" else None
            self.objective = nn.parallel.DistributedDataParallel(self.objective, device_ids=ids)
        self.optimizer = torch.optim.Adam(network.parameters(), lr=c["lr"], betas=(0.9, 0.999),
                                          eps=1e-5)
        self.step, self.best_val = 0, None
        if state:
            self.optimizer.load_state_dict(state["optimizer"])
            self.step, self.best_val = state["step"], state["best_val"]
        self.slots = world.share(c["batch"])
        self.scale = len(self.slots) * world.size / c["batch"]
        pool = self.split.val or self.split.train
        plain = sampler(c, training=False)
        val = [sample(plain, pool, self.normalization, c["seed"], i, self.slots, VAL_STREAM)
               for i in range(c["val_batches"])]
        # Each batch on its targets, and on reconstructing its contexts.
        self.val_set = [[tensors(b, world.device) for b in (v, contexts_as_targets(v))]
                        for v in val]
        self.train_sampler = sampler(c, training=True)
        if world.rank == 0:
            os.makedirs(args.out, exist_ok=True)
            self.keep_metrics_through(self.step)

    def sized_by_data(self, model, state, args):
        """The model's joint values a step (D) and their names: the data's (fresh weights),
        held to the file's (--init, which keeps its names) or to the run's (--resume)."""
        width = self.split.joints
        if state is None and not self.config["init"]:
            model["joints"], model["joint_names"] = width, self.split.joint_names
            return
        if joint_count(model) != width:
            source = (f"the run in {args.out}" if state is not None
                      else f"--init {self.config['init']}")
            raise ValueError(f"{source}: the model has {joint_count(model)} joint values a "
                             f"step, the data at {self.data} has {width}: start from a model "
                             "of this robot")
        model["joints"], model["joint_names"] = width, model.get("joint_names")

    def keep_metrics_through(self, step):
        """metrics.jsonl without the lines of steps after `step` (those a resume repeats)."""
        path = os.path.join(self.out, "metrics.jsonl")
        lines = open(path).read().splitlines() if os.path.exists(path) else []
        kept = [line for line in lines if line.strip() and json.loads(line)["step"] <= step]
        write_atomic(path, lambda tmp: open(tmp, "w").write("".join(line + "\n" for line in kept)))

    def train_step(self):
        """One optimiser step on a fresh batch; a non-finite loss stops before the weights
        change. Returns the global batch's loss parts and the learning rate."""
        c = self.config
        batch = tensors(sample(self.train_sampler, self.split.train, self.normalization,
                               c["seed"], self.step, self.slots), self.world.device)
        total, parts = self.objective(batch, self.scale)
        parts = self.world.sum(parts * (len(self.slots) / c["batch"]))
        if not torch.isfinite(parts[0]):
            raise FloatingPointError(f"the loss is {float(parts[0])} at step {self.step + 1}")
        self.optimizer.zero_grad(set_to_none=True)
        total.backward()
        clip_per_tensor(self.predictor.network.parameters(), c["clip_norm"])
        lr = rate(c["schedule"], c["lr"], self.step, c["steps"])
        for group in self.optimizer.param_groups:
            group["lr"] = lr
        self.optimizer.step()
        self.step += 1
        return parts.tolist(), lr

    @torch.no_grad()
    def validate(self):
        """Mean loss parts over the fixed validation batches (β = 0, as Trainer::validate)."""
        c, network = self.config, self.predictor.network
        sums = torch.zeros(2, len(PARTS), device=self.world.device)
        for batches in self.val_set:
            for row, batch in enumerate(batches):
                sums[row] += objective(network, batch, c["model"]["joint_weight"])[1]
        sums = self.world.sum(sums * (len(self.slots) / c["batch"]))
        return (sums / len(self.val_set)).tolist()

    def checkpoint(self):
        state = {"step": self.step, "config": self.config, "data": self.data,
                 "normalization": {"mean": self.normalization.mean, "std": self.normalization.std},
                 "model": self.predictor.network.state_dict(),
                 "optimizer": self.optimizer.state_dict(), "best_val": self.best_val}
        write_atomic(os.path.join(self.out, "checkpoint.pt"), lambda tmp: torch.save(state, tmp))

    def run(self):
        """Train to the run's steps, validating, logging and checkpointing on the way; writes
        --out/model.safetensors and returns its path."""
        c, rank0 = self.config, self.world.rank == 0
        timer = (time.perf_counter(), self.step)
        log = open(os.path.join(self.out, "metrics.jsonl"), "a") if rank0 else None
        last_val = None
        while self.step < c["steps"]:
            parts, lr = self.train_step()
            step = self.step
            elapsed = time.perf_counter() - timer[0]
            steps_per_s = (step - timer[1]) / max(elapsed, 1e-9)
            metrics = {"step": step, "lr": lr, **dict(zip(["loss"] + PARTS[1:], parts))}
            if step % c["val_every"] == 0 or step == c["steps"]:
                val, ctx = self.validate()
                last_val = val[0]
                if self.best_val is None or val[0] < self.best_val[1]:
                    self.best_val = (step, val[0])
                metrics.update(val_loss=val[0], val_image_mse=val[3], val_joint_mse=val[4],
                               val_context_loss=ctx[0], val_context_image_mse=ctx[3],
                               val_context_joint_mse=ctx[4])
            metrics["steps_per_s"] = steps_per_s
            if rank0:
                log.write(json.dumps(metrics) + "\n")
                log.flush()
                if step % c["checkpoint_every"] == 0 or step == c["steps"]:
                    self.checkpoint()
                if step % 10 == 0 or step == c["steps"] or "val_loss" in metrics:
                    val = "-" if last_val is None else f"{last_val:.4f}"
                    print(f"step {step}/{c['steps']} loss {parts[0]:.4f} val {val} "
                          f"{steps_per_s:.2f} steps/s", flush=True)
            if elapsed > 5.0:
                timer = (time.perf_counter(), step)
        path = os.path.join(self.out, "model.safetensors")
        if rank0:
            save(self.predictor, path, half=c["half"])
        return path


def arguments(argv=None):
    p = argparse.ArgumentParser(
        prog="python -m dmbn_torch.train",
        description="Train DMBN, DMBN-PTE or the attentive model in PyTorch (as dmbn's `train`; "
                    "under torchrun with DDP).")
    a = p.add_argument
    a("--data", help="dataset root in the DMBN layout (with --resume: the run's unless given)")
    a("--model", choices=["dmbn", "pte", "attn"], help="which network (--init: the file's)")
    a("--init", help="start from this safetensors file's weights (`dmbn export` or this twin)")
    a("--out", required=True, help="folder for metrics.jsonl, checkpoint.pt, model.safetensors")
    a("--steps", type=int, help="optimiser steps in the whole run (--resume: may extend it)")
    a("--seed", type=int, default=0, help="seed of the weights and of the batches")
    a("--batch", type=int, default=8, help="sequences per (global) batch")
    a("--max-contexts", type=int, default=5)
    a("--targets-per-sequence", type=int, default=4)
    a("--contexts-in-targets", action="store_true")
    a("--joint-targets", type=int, default=0)
    a("--single-modality", type=float, default=0.0)
    a("--prefix-contexts", type=float, default=0.0)
    a("--image-size", type=int, default=64, choices=[64, 128])
    a("--decoder-filters", type=lambda s: [int(v) for v in s.split(",")])
    a("--coarse-tail", action="store_true")
    a("--encoder-filters", type=lambda s: [int(v) for v in s.split(",")])
    a("--frame-joints", action="store_true")
    a("--camera", help="the camera whose frames the model sees: the sub-folder of that name in "
                       "each sequence folder (default: the frames in the folder itself)")
    a("--lr", type=float, default=1e-4)
    a("--schedule", choices=["constant", "cosine", "step"], default="constant")
    a("--clip-norm", type=float, default=1.0, help="largest norm of each parameter's gradient")
    a("--joint-weight", type=float, default=0.01)
    a("--drawn-frame-weight", type=float, default=0.0)
    a("--beta-nll", type=float, default=0.0)
    a("--sigma-floor", type=float, default=0.01)
    a("--val-fraction", type=float, default=0.1)
    a("--val-every", type=int, default=200)
    a("--checkpoint-every", type=int, default=500)
    a("--resume", action="store_true", help="continue the run in --out from its checkpoint")
    a("--augment", action="store_true", help="the paper's time warps on training sequences")
    a("--freeze-fraction", type=lambda s: tuple(float(v) for v in s.split("-")),
      help="with --augment: freeze lengths as a LOW-HIGH fraction of the warped sequence")
    a("--half", action="store_true", help="write model.safetensors with f16 weights")
    a("--initialization", choices=["he", "glorot"], default="he",
      help="fresh weights: he (the project's) or glorot (the original Keras model's; dmbn, pte)")
    a("--joint-scale", choices=["per-joint", "shared"], default="per-joint",
      help="per-joint standardises each joint; shared divides the six arm angles by one scale")
    a("--device", default="auto", help="auto (cuda when there is one), cpu or cuda")
    return p.parse_args(argv)


def main(argv=None):
    args = arguments(argv)
    world = World(args.device)
    try:
        run = Run(args, world)
        if world.rank == 0:
            print(f"training {run.config['model']['kind']} on {run.data} ({world.device}, "
                  f"{world.size} process{'es' if world.size > 1 else ''}; validation ids "
                  f"{run.split.val_ids or 'none'}), output in {args.out}", flush=True)
            if not run.split.val_ids:
                print("note: no id is held out (--val-fraction 0, or one id in the dataset): "
                      "the validation loss is measured on training sequences", flush=True)
        path = run.run()
        if world.rank == 0:
            print(f"wrote {path}")
        if world.size > 1:
            # Every process waits for rank 0's files before any tears the group down (gloo
            # aborts a process whose peer is gone mid-teardown).
            dist.barrier()
    except (ValueError, FloatingPointError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        sys.exit(1)
    finally:
        if world.size > 1:
            dist.destroy_process_group()


if __name__ == "__main__":
    main()
