"""The networks of dmbn in PyTorch: DMBN, DMBN-PTE and the attentive model, layer for layer.

Modules and tensor names follow the Rust sources (crate/model/), so `Predictor.state_dict()`
holds exactly the tensors `dmbn export` writes; `load` reads such a file, `save` writes one
`dmbn import` reads. The networks are differentiable end to end (`train.py` trains them);
`Predictor.predict` maps dataset units in and out as `dmbn predict` does.
"""
import json
import math

import torch
import torch.nn as nn
import torch.nn.functional as F

from .joint_stage import JointStage

# Architecture constants of crate/model (the original DMBN's widths).
ENCODER_FILTERS = {64: [32, 64, 128, 128, 256], 128: [32, 64, 64, 128, 128, 256]}
DECODER_FILTERS = {64: [256, 128, 64, 64, 32], 128: [256, 128, 128, 64, 64, 32]}
JOINT_ENCODER_LAYERS = [32, 64, 64, 128, 128, 256]
JOINT_DECODER_LAYERS = [512, 216, 128, 32]
IMAGE_DECODER_TAIL = [16, 8]
SHARED = 1024
# Joint values a step (D) of files without `joints`: the original arm's 6 angles and gripper.
JOINTS = 7
ATTENTION_HEADS = 8
# How fast the attentive model's own predictions fade in away from an observation (start.rs).
OBSERVED_WIDTH = 0.02
# Score of a padding slot before the attention softmax (burn's MultiHeadAttention min_float).
MASKED_SCORE = -1.0e4
# Target times decoded per forward pass (Predictor::CHUNK).
CHUNK = 25


def joint_count(config):
    """Joint values a step (D): the header's `joints`, 7 for files written before other robots."""
    return config.get("joints") or JOINTS


def start_features(joints):
    """Width of the attentive model's start features: the interpolated joints and 2 gaps."""
    return joints + 2


def image_encoder_filters(config):
    """The image encoder's filters: the header's `encoder_filters` or the original's."""
    return config.get("encoder_filters") or ENCODER_FILTERS[config["image_size"]]


def image_decoder_shape(config):
    """The image decoder's (blocks, tail, coarse_tail): the header's `decoder_filters` (blocks,
    then the two tail convolutions) or the original's, and whether the tail runs at half
    resolution (`coarse_tail`; absent in older files: no)."""
    blocks = DECODER_FILTERS[config["image_size"]]
    coarse = bool(config.get("coarse_tail"))
    filters = config.get("decoder_filters")
    if filters is None:
        return blocks, IMAGE_DECODER_TAIL, coarse
    return filters[: len(blocks)], filters[len(blocks):], coarse


def bounded_sigma(raw, floor):
    """σ = floor + (1 − floor)·softplus(raw)."""
    return floor + (1.0 - floor) * F.softplus(raw)


def conv3x3(inputs, outputs):
    return nn.Conv2d(inputs, outputs, 3, padding=1)


class ImageEncoder(nn.Module):
    """Conv 3x3 + ReLU + MaxPool 2x2 blocks down to 2x2, flatten, Dense H + ReLU."""

    def __init__(self, channels, filters, hidden):
        super().__init__()
        convs = []
        for f in filters:
            convs.append(conv3x3(channels, f))
            channels = f
        self.convs = nn.ModuleList(convs)
        self.dense = nn.Linear(channels * 4, hidden)

    def forward(self, x):
        for conv in self.convs:
            x = F.max_pool2d(F.relu(conv(x)), 2)
        return F.relu(self.dense(x.flatten(1)))


class JointEncoder(nn.Module):
    """Dense 32, 64, 64, 128, 128, 256, H, all ReLU."""

    def __init__(self, inputs, hidden):
        super().__init__()
        layers = []
        for width in JOINT_ENCODER_LAYERS + [hidden]:
            layers.append(nn.Linear(inputs, width))
            inputs = width
        self.layers = nn.ModuleList(layers)

    def forward(self, x):
        for layer in self.layers:
            x = F.relu(layer(x))
        return x


class TimeProjection(nn.Module):
    """DMBN-PTE's P(t): Linear 1 → H."""

    def __init__(self, hidden):
        super().__init__()
        self.linear = nn.Linear(1, hidden)

    def forward(self, times):
        return self.linear(times.unsqueeze(-1))


class ContextProjection(nn.Module):
    """g_m: Linear H → H, LayerNorm, tanh."""

    def __init__(self, hidden):
        super().__init__()
        self.linear = nn.Linear(hidden, hidden)
        self.norm = nn.LayerNorm(hidden, eps=1e-5)

    def forward(self, x):
        return torch.tanh(self.norm(self.linear(x)))


class TimeEmbedding(nn.Module):
    """The attentive model's queries and keys: Linear 1 → H, ReLU, Linear H → H."""

    def __init__(self, hidden):
        super().__init__()
        self.hidden = nn.Linear(1, hidden)
        self.output = nn.Linear(hidden, hidden)

    def forward(self, times):
        return self.output(F.relu(self.hidden(times.unsqueeze(-1))))


class MultiHeadAttention(nn.Module):
    """burn's MultiHeadAttention (no dropout at inference): per-head scaled dot products,
    padding scored MASKED_SCORE, softmax, output projection."""

    def __init__(self, hidden, heads):
        super().__init__()
        self.heads = heads
        self.query = nn.Linear(hidden, hidden)
        self.key = nn.Linear(hidden, hidden)
        self.value = nn.Linear(hidden, hidden)
        self.output = nn.Linear(hidden, hidden)

    def forward(self, query, key, value, padding):
        b, m, h = query.shape
        d = h // self.heads

        def split(x, linear):
            return linear(x).reshape(b, x.shape[1], self.heads, d).transpose(1, 2)

        q, k, v = split(query, self.query), split(key, self.key), split(value, self.value)
        scores = q @ k.transpose(-1, -2) / math.sqrt(d)
        scores = scores.masked_fill(padding[:, None, None, :], MASKED_SCORE)
        context = torch.softmax(scores, -1) @ v
        return self.output(context.transpose(1, 2).reshape(b, m, h))


class ImageDecoder(nn.Module):
    """2x2 start, Conv 3x3 + ReLU + nearest UpSampling x2 blocks, two full-resolution convs
    (the original's Conv 16, Conv 8; `image_decoder_shape` gives both widths; with
    `coarse_tail` they come before the last upsampling), mean (sigmoid) and σ heads; gated (the
    attentive model), a gate head mixes the mean with the interpolated observed frames.
    Returns (mean, σ, drawn): drawn is the gated decoder's own frame before the mix (what
    `--drawn-frame-weight` supervises), None otherwise."""

    def __init__(self, blocks, tail_filters, coarse_tail, sigma_floor, gated):
        super().__init__()
        channels, convs = SHARED // 4, []
        for f in blocks:
            convs.append(conv3x3(channels, f))
            channels = f
        self.blocks = nn.ModuleList(convs)
        tail = []
        for f in tail_filters:
            tail.append(conv3x3(channels, f))
            channels = f
        self.tail = nn.ModuleList(tail)
        self.mean = conv3x3(channels, 3)
        self.sigma = conv3x3(channels, 3)
        self.gate = conv3x3(channels, 1) if gated else None
        self.sigma_floor = sigma_floor
        self.coarse_tail = coarse_tail

    def forward(self, x, start=None):
        y = x.reshape(x.shape[0], SHARED // 4, 2, 2)
        # The last block's output is upsampled after the tail when the tail is coarse.
        last = len(self.blocks) - int(self.coarse_tail)
        for i, conv in enumerate(list(self.blocks) + list(self.tail)):
            if 0 < i <= last:
                y = F.interpolate(y, scale_factor=2, mode="nearest")
            y = F.relu(conv(y))
        if self.coarse_tail:
            y = F.interpolate(y, scale_factor=2, mode="nearest")
        drawn = torch.sigmoid(self.mean(y))
        sigma = bounded_sigma(self.sigma(y), self.sigma_floor)
        if self.gate is None or start is None:
            return drawn, sigma, None
        frames, observed, near = start
        g = (torch.sigmoid(self.gate(y)) * (1 - near) + near) * observed
        return frames * g + drawn * (1 - g), sigma, drawn


class JointDecoder(nn.Module):
    """Dense 512, 216, 128, 32 (ReLU), mean and σ heads (D outputs each); given a start, the
    mean is a scaled correction of the interpolated observations."""

    def __init__(self, sigma_floor, joints):
        super().__init__()
        inputs, layers = SHARED, []
        for width in JOINT_DECODER_LAYERS:
            layers.append(nn.Linear(inputs, width))
            inputs = width
        self.layers = nn.ModuleList(layers)
        self.mean = nn.Linear(inputs, joints)
        self.sigma = nn.Linear(inputs, joints)
        self.sigma_floor = sigma_floor

    def forward(self, x, start=None):
        for layer in self.layers:
            x = F.relu(layer(x))
        mean = self.mean(x)
        if start is not None:
            joints, scale = start
            mean = joints + mean * scale
        return mean, bounded_sigma(self.sigma(x), self.sigma_floor)


class Decoder(nn.Module):
    """The shared Dense 1024 + ReLU, then the image and joint decoders (`image_shape`: the
    image decoder's (blocks, tail, coarse_tail), as `image_decoder_shape` returns them;
    `joints`: D)."""

    def __init__(self, inputs, image_shape, sigma_floor, joints, gated=False):
        super().__init__()
        self.shared = nn.Linear(inputs, SHARED)
        self.image = ImageDecoder(*image_shape, sigma_floor, gated)
        self.joint = JointDecoder(sigma_floor, joints)
        self.joint_values = joints  # D (`joints` is the joint-only decoding)

    def forward(self, x, start=None):
        b, m, _ = x.shape
        x = F.relu(self.shared(x.reshape(b * m, -1)))
        image_mean, image_sigma, drawn = self.image(x, start and start.frames())
        joint_mean, joint_sigma = self.joint(x, start and start.joints())
        s = image_mean.shape[-1]
        return {
            "image_mean": image_mean.reshape(b, m, 3, s, s),
            "image_sigma": image_sigma.reshape(b, m, 3, s, s),
            "image_drawn": None if drawn is None else drawn.reshape(b, m, 3, s, s),
            "joint_mean": joint_mean.reshape(b, m, self.joint_values),
            "joint_sigma": joint_sigma.reshape(b, m, self.joint_values),
        }

    def joints(self, x, start=None):
        """Only the joints' mean and σ, [B, M, D] each: the image decoder, most of a target's
        cost, is skipped (joint-only training targets)."""
        b, m, _ = x.shape
        x = F.relu(self.shared(x.reshape(b * m, -1)))
        mean, sigma = self.joint(x, start and start.joints())
        return mean.reshape(b, m, self.joint_values), sigma.reshape(b, m, self.joint_values)


def masked_mean(z, mask):
    """Mean over each sequence's real contexts: [B, N, H] and a [B, N] 0/1 mask to [B, H]."""
    count = mask.sum(1, keepdim=True).clamp_min(1.0)
    return (z * mask.unsqueeze(2)).sum(1) / count


def blend(image, joint, c):
    """r = c·image + (1 − c)·joint, c of shape [B]."""
    c = c.reshape(-1, *([1] * (image.dim() - 1)))
    return image * c + joint * (1 - c)


class Contexts:
    """One batch of observations, as the model sees them: `frames` [B, N, 3, S, S] in [0, 1],
    normalised `joints` [B, N, D], `times` [B, N], `mask` [B, N] (1 real, 0 padding) and the
    blending coefficient `blend` [B]."""

    def __init__(self, frames, joints, times, mask, blend):
        self.frames, self.joints, self.times, self.mask, self.blend = frames, joints, times, mask, blend


class Dmbn(nn.Module):
    """DMBN, time as an input channel: [t plane, RGB] and (t, joints) encoded, masked mean per
    modality, blended, [r, t_target] decoded."""

    def __init__(self, config):
        super().__init__()
        h, d = config["hidden"], joint_count(config)
        self.image_encoder = ImageEncoder(4, image_encoder_filters(config), h)
        self.joint_encoder = JointEncoder(d + 1, h)
        self.decoder = Decoder(h + 1, image_decoder_shape(config), config["sigma_floor"], d)

    def encode(self, c):
        b, n, _, s, _ = c.frames.shape
        plane = c.times.reshape(b, n, 1, 1, 1).expand(b, n, 1, s, s)
        images = torch.cat([plane, c.frames], 2).reshape(b * n, 4, s, s)
        image = self.image_encoder(images).reshape(b, n, -1)
        joint = self.joint_encoder(torch.cat([c.times.unsqueeze(2), c.joints], 2))
        return blend(masked_mean(image, c.mask), masked_mean(joint, c.mask), c.blend)

    def condition(self, r, target_times):
        m = target_times.shape[1]
        return torch.cat([r.unsqueeze(1).expand(-1, m, -1), target_times.unsqueeze(2)], 2), None

    def decode(self, r, target_times):
        return self.decoder(*self.condition(r, target_times))

    def decode_joints(self, r, target_times):
        return self.decoder.joints(*self.condition(r, target_times))


class _PteEncoders(nn.Module):
    """DMBN-PTE's context encoding z_m = g_m(e_m(x) + P(t)), shared with the attentive model."""

    def _pte_init(self, config):
        h = config["hidden"]
        self.image_encoder = ImageEncoder(3, image_encoder_filters(config), h)
        self.joint_encoder = JointEncoder(joint_count(config), h)
        self.time = TimeProjection(h)
        self.image_projection = ContextProjection(h)
        self.joint_projection = ContextProjection(h)

    def encode_contexts(self, c):
        b, n, _, s, _ = c.frames.shape
        image = self.image_encoder(c.frames.reshape(b * n, 3, s, s)).reshape(b, n, -1)
        time = self.time(c.times)
        joint = self.joint_encoder(c.joints)
        return self.image_projection(image + time), self.joint_projection(joint + time)


class DmbnPte(_PteEncoders):
    """DMBN-PTE, time as context: masked mean of z per modality, blended, r − P(t_target)
    decoded."""

    def __init__(self, config):
        super().__init__()
        self._pte_init(config)
        self.decoder = Decoder(config["hidden"], image_decoder_shape(config),
                               config["sigma_floor"], joint_count(config))

    def encode(self, c):
        image, joint = self.encode_contexts(c)
        return blend(masked_mean(image, c.mask), masked_mean(joint, c.mask), c.blend)

    def condition(self, r, target_times):
        return r.unsqueeze(1) - self.time(target_times), None

    def decode(self, r, target_times):
        return self.decoder(*self.condition(r, target_times))

    def decode_joints(self, r, target_times):
        return self.decoder.joints(*self.condition(r, target_times))


class Start:
    """Where the attentive model's decoders start: the observations linearly interpolated to
    the target times (held outside them), nothing for an unobserved modality — or, for a model
    that reads joints from frames, the joints read (`joints`, `joints_read`)."""

    def __init__(self, c, target_times, joints, joints_read):
        self.weights, self.gaps = interpolation(target_times, c.times, c.mask)
        self.observed = torch.stack([(c.blend > 0).float(), (c.blend < 1).float()], 1)
        self.known = torch.ones_like(self.observed[:, 1]) if joints_read else self.observed[:, 1]
        self.c, self.start_joints = c, joints

    def interpolated_joints(self):
        return (self.weights @ self.start_joints) * self.known[:, None, None]

    def features(self):
        return torch.cat([self.interpolated_joints(), self.gaps], 2)

    def nearness(self):
        return torch.exp(-self.gaps.min(2).values / OBSERVED_WIDTH)

    def frames(self):
        b, m, n = self.weights.shape
        frames = self.c.frames
        k, (ch, s) = b * m, frames.shape[2:4]
        interpolated = (self.weights @ frames.reshape(b, n, -1)).reshape(k, ch, s, s)
        observed = self.observed[:, 0, None].expand(b, m).reshape(k, 1, 1, 1)
        return interpolated, observed, self.nearness().reshape(k, 1, 1, 1)

    def joints(self):
        b, m, _ = self.weights.shape
        scale = 1 - self.nearness() * self.observed[:, 1, None]
        return self.interpolated_joints().reshape(b * m, -1), scale.reshape(b * m, 1)


def interpolation(target_times, times, mask):
    """Per target, each context's linear interpolation weight [B, M, N] and the distances to
    the nearest observation before and after it [B, M, 2] (capped at 1), as
    crate/model/interpolation.rs: between the nearest real observations before and after a
    target, held outside them. Times alone decide them: no gradient."""
    with torch.no_grad():
        t = times.unsqueeze(1)                                  # [B, 1, N]
        target = target_times.unsqueeze(2)                      # [B, M, 1]
        real = (mask > 0.5).unsqueeze(1)
        before, after = real & (t <= target), real & (t >= target)
        inf = torch.tensor(math.inf, device=times.device)
        t_a, a = torch.where(before, t, -inf).max(2)            # nearest before (or −inf)
        t_z, z = torch.where(after, t, inf).min(2)              # nearest after (or +inf)
        has_a, has_z = before.any(2), after.any(2)
        both = has_a & has_z & (t_z > t_a)
        w = torch.where(both, (target_times - t_a) / torch.where(both, t_z - t_a, 1.0), 0.0)
        one_hot = lambda i: F.one_hot(i, times.shape[1]).to(times.dtype)  # noqa: E731
        # Between two observations: 1 − w and w; on one side only: 1 at the nearest.
        weights = torch.where(
            both.unsqueeze(2), one_hot(a) * (1 - w).unsqueeze(2) + one_hot(z) * w.unsqueeze(2),
            torch.where(has_a.unsqueeze(2), one_hot(a),
                        torch.where(has_z.unsqueeze(2), one_hot(z), 0.0)))
        gaps = torch.stack([target_times - t_a, t_z - target_times], 2).clamp(max=1.0)
    return weights, gaps


class LatentPath(nn.Module):
    """The attentive model's global latent z (`latent` in the config): a Gaussian from the
    contexts' blended encodings (per point Linear + ReLU, masked mean, Linear to the mean and
    a σ in (0.1, 1)), whose projection is added to the decoder input at every target."""

    def __init__(self, h, latent):
        super().__init__()
        self.point = nn.Linear(h, h)
        self.statistics = nn.Linear(h, 2 * latent)
        self.projection = nn.Linear(latent, h)

    def distribution(self, points, mask):
        stats = self.statistics(masked_mean(torch.relu(self.point(points)), mask))
        mean, raw = stats.chunk(2, dim=1)
        return mean, 0.1 + 0.9 * torch.sigmoid(raw)


class DmbnAttn(_PteEncoders):
    """The attentive model: DMBN-PTE's z per context, cross-attention over the context times
    per target and modality, blended, − P(t_target), + the observed modalities' embedding and
    a projection of where the decoders start; the decoders start from the interpolated
    observations (where joints are not observed, those read from the frames by
    `frame_joints`, when the model has it)."""

    def __init__(self, config):
        super().__init__()
        self._pte_init(config)
        h, d = config["hidden"], joint_count(config)
        heads = config.get("heads") or ATTENTION_HEADS
        self.time_embedding = TimeEmbedding(h)
        self.image_attention = MultiHeadAttention(h, heads)
        self.joint_attention = MultiHeadAttention(h, heads)
        self.observed = nn.Parameter(torch.zeros(2, h))
        self.start_projection = nn.Linear(start_features(d), h)
        self.decoder = Decoder(h, image_decoder_shape(config), config["sigma_floor"], d,
                               gated=True)
        self.frame_joints = nn.Linear(h, d) if config.get("frame_joints") else None
        latent = config.get("latent")
        self.latent = LatentPath(h, latent) if latent else None

    def encode(self, c):
        image, joint = self.encode_contexts(c)
        joints = c.joints
        if self.frame_joints is not None:
            observed = (c.blend < 1).float()[:, None, None]
            joints = c.joints * observed + self.frame_joints(image) * (1 - observed)
        r = {"contexts": c, "image": image, "joint": joint, "joints": joints,
             "keys": self.time_embedding(c.times)}
        if self.latent is not None:
            # A prediction takes z at its prior's mean.
            mean, _ = self.latent.distribution(blend(image, joint, c.blend), c.mask)
            r["latent"] = self.latent.projection(mean)
        return r

    def decode(self, r, target_times):
        return self.decoder(*self.condition(r, target_times))

    def decode_joints(self, r, target_times):
        return self.decoder.joints(*self.condition(r, target_times))

    def condition(self, r, target_times):
        """The decoder input at [B, M] target times, and where the decoders start."""
        c = r["contexts"]
        queries = self.time_embedding(target_times)
        padding = c.mask < 0.5
        image = self.image_attention(queries, r["keys"], r["image"], padding)
        joint = self.joint_attention(queries, r["keys"], r["joint"], padding)
        start = Start(c, target_times, r["joints"], self.frame_joints is not None)
        x = (blend(image, joint, c.blend) - self.time(target_times)
             + (start.observed @ self.observed).unsqueeze(1)
             + self.start_projection(start.features()))
        if "latent" in r:
            x = x + r["latent"].unsqueeze(1)
        return x, start


KINDS = {"dmbn": Dmbn, "pte": DmbnPte, "attn": DmbnAttn}


class Predictor(nn.Module):
    """A model with the joint normalisation it was trained with: `predict` takes and returns
    dataset units, as the Rust `Predictor`."""

    def __init__(self, header):
        super().__init__()
        self.header = header
        self.config = header["config"]
        self.normalization = header["normalization"]
        self.joints = joint_count(self.config)
        for field in ["mean", "std"]:
            if len(self.normalization[field]) != self.joints:
                raise ValueError(f"normalization {field}: {len(self.normalization[field])} "
                                 f"values, expected {self.joints} (the model's joints)")
        names = self.config.get("joint_names")
        if names is not None and len(names) != self.joints:
            raise ValueError(f"joint_names: {len(names)} names, expected {self.joints}")
        self.network = KINDS[self.config["kind"]](self.config)
        # The joint stage, where the file has one: the joints from frames alone (blend 1).
        # Under its old name, `mirror`, as in the file: the config key and the tensors' prefix.
        width = self.config.get("mirror")
        self.mirror = JointStage(width, self.joints) if width else None

    def state_dict_for_export(self):
        return {k.removeprefix("network."): v for k, v in self.state_dict().items()}

    @torch.no_grad()
    def predict(self, frames, joints, times, target_times, blend=0.5):
        s = self.config["image_size"]
        device = next(self.parameters()).device
        frames = torch.as_tensor(frames)
        if tuple(frames.shape[1:]) != (s, s, 3):
            raise ValueError(f"frames: expected [N, {s}, {s}, 3] uint8, found {list(frames.shape)}")
        mean = torch.tensor(self.normalization["mean"], device=device)
        std = torch.tensor(self.normalization["std"], device=device)
        joints = torch.as_tensor(joints, dtype=torch.float32, device=device)
        if joints.dim() != 2 or joints.shape[1] != self.joints:
            raise ValueError(f"joints: expected [N, {self.joints}], found {list(joints.shape)}")
        joints = (joints - mean) / std
        n = joints.shape[0]
        contexts = Contexts(
            frames=(frames.to(device).float() / 255.0).permute(0, 3, 1, 2).unsqueeze(0),
            joints=joints.unsqueeze(0),
            times=torch.as_tensor(times, dtype=torch.float32, device=device).reshape(1, n),
            mask=torch.ones(1, n, device=device),
            blend=torch.tensor([float(blend)], device=device),
        )
        r = self.network.encode(contexts)
        target_times = torch.as_tensor(target_times, dtype=torch.float32, device=device)
        parts = [self.network.decode(r, chunk.unsqueeze(0)) for chunk in target_times.split(CHUNK)]
        out = {k: torch.cat([p[k][0] for p in parts]) for k in parts[0] if k != "image_drawn"}
        joint_mean = out["joint_mean"] * std + mean
        joint_sigma = out["joint_sigma"] * std * self.joint_sigma_scale(contexts.times, target_times)
        if self.mirror is not None and float(blend) == 1.0:
            # As the Rust Predictor: the stage answers between the first and the last
            # observation, its σ its own (fitted on held-out reads).
            observed = contexts.times[0]
            reads = self.network.decode_joints(r, observed.unsqueeze(0))[0][0] * std + mean
            stage_mean, stage_sigma = (v.to(device) for v in self.mirror.predict(
                observed.cpu(), reads.cpu(), target_times.cpu()))
            within = ((target_times >= observed.min()) & (target_times <= observed.max())).unsqueeze(1)
            joint_mean = torch.where(within, stage_mean, joint_mean)
            joint_sigma = torch.where(within, stage_sigma, joint_sigma)
        return {
            "image_mean": out["image_mean"].permute(0, 2, 3, 1),
            "image_sigma": out["image_sigma"].permute(0, 2, 3, 1),
            "joint_mean": joint_mean.to(device),
            "joint_sigma": joint_sigma.to(device),
        }

    def joint_sigma_scale(self, observed_times, target_times):
        """A calibrated file's factors on the joint σ (`dmbn calibrate`; absent: 1), one per
        target as a column: `joint_sigma_scale` within the span of the observed times,
        `forecast_joint_sigma_scale` (absent: the other) outside it."""
        between = float(self.header.get("joint_sigma_scale") or 1.0)
        forecast = float(self.header.get("forecast_joint_sigma_scale") or between)
        inside = (target_times >= observed_times.min()) & (target_times <= observed_times.max())
        return torch.where(inside, between, forecast).unsqueeze(1)


def load(path, device="cpu"):
    """The model in a safetensors file written by `dmbn export` (or `save`), in eval mode."""
    from safetensors import safe_open
    from safetensors.torch import load_file

    with safe_open(path, "pt") as f:
        metadata = f.metadata() or {}
    if "dmbn" not in metadata:
        raise ValueError(f"{path}: no `dmbn` metadata: not written by `dmbn export`")
    model = Predictor(json.loads(metadata["dmbn"]))
    tensors = {("" if k.startswith("mirror.") else "network.") + k: v.float()
               for k, v in load_file(path).items()}
    model.load_state_dict(tensors, strict=True)
    return model.to(device).eval()


def save(model, path, half=False):
    """Writes `model` (a Predictor) for `dmbn import`: its tensors (f16 with `half`) and its
    header, atomically (a temporary file renamed over `path`)."""
    import os

    from safetensors.torch import save as serialize

    header = dict(model.header, producer="dmbn_torch")
    dtype = torch.float16 if half else torch.float32
    tensors = {k: v.detach().to("cpu", dtype).contiguous()
               for k, v in model.state_dict_for_export().items()}
    with open(f"{path}.tmp", "wb") as f:
        f.write(serialize(tensors, metadata={"dmbn": json.dumps(header)}))
    os.replace(f"{path}.tmp", path)
