"""The DMBN layout read as crate/data/reader.rs reads it, and the joint normalisation.

`<root>/<id>/<action>/` folders (decimal ids, non-hidden action folders, sorted by id then
action), each with `joint_<id>.txt` (T rows of 7 numbers) and frames `<k>.png|.jpeg|.jpg` for
k = 0..T-1 (png preferred when a step has several; frames past the joint rows ignored). Frames
are resized on reading: an exact, rounded area average when the size divides the stored one
(128 → 64), otherwise image's triangle filter. PNG frames decode here without Pillow (zlib and
numpy, exact); JPEG frames need Pillow, which decodes everything faster where installed.
"""
import math
import os
import struct
import zlib

import numpy as np

JOINTS = 7
FRAME_EXTENSIONS = ["png", "jpeg", "jpg"]
# Standard deviations below this are replaced by 1 (a column that never moves).
MIN_STD = 1e-6


class Sequence:
    """One recorded action: `joints` float32 [T, 7], `frames` uint8 [T, S, S, 3]."""

    def __init__(self, joints, frames):
        self.joints, self.frames = joints, frames

    def __len__(self):
        return len(self.joints)

    def times(self):
        """Phase of each step, linspace(0, 1, T) in f32 as Sequence::times."""
        t = len(self)
        return np.arange(t, dtype=np.float32) / np.float32(max(t - 1, 1))

    def gather(self, indices):
        return Sequence(self.joints[indices], self.frames[indices])


def sequences(root):
    """(id, action, folder) of every sequence under `root`, by id then action."""
    if not os.path.isdir(root):
        raise ValueError(f"{root}: not a directory")
    found = []
    for name in os.listdir(root):
        folder = os.path.join(root, name)
        if not (name.isdigit() and name.isascii() and os.path.isdir(folder)):
            continue
        actions = sorted(a for a in os.listdir(folder)
                         if not a.startswith(".") and os.path.isdir(os.path.join(folder, a)))
        if not actions:
            raise ValueError(f"{folder}: no action folders")
        found += [(int(name), a, os.path.join(folder, a)) for a in actions]
    if not found:
        raise ValueError(f"{root}: no sequences (expected <id>/<action>/ folders)")
    return sorted(found, key=lambda s: (s[0], s[1]))


def read_sequence(folder, id, image_size=None):
    """The sequence in `folder`, frames resized to `image_size` pixels a side when given."""
    return read_sequences([(id, folder)], image_size)[0]


def read_sequences(listed, image_size=None):
    """The sequences of (id, folder) pairs; their frames decode together (faster)."""
    joints = [read_table(os.path.join(folder, f"joint_{id}.txt")) for id, folder in listed]
    paths = [frame_paths(folder, len(j)) for (_, folder), j in zip(listed, joints)]
    decoded = decode_frames([p for ps in paths for p in ps])
    out, at = [], 0
    for j, ps in zip(joints, paths):
        mine, at = decoded[at:at + len(ps)], at + len(ps)
        size = mine[0].shape
        for path, frame in zip(ps, mine):
            if frame.shape != size or size[0] != size[1]:
                h, w = frame.shape[:2]
                raise ValueError(f"{path}: a {w}x{h} frame, expected {size[0]}x{size[0]} "
                                 "(square, as the sequence's first)")
        frames = np.stack(mine)
        if image_size and image_size != frames.shape[1]:
            frames = resize(frames, image_size)
        out.append(Sequence(j, frames))
    return out


def read_table(path, columns=JOINTS):
    """Whitespace-separated rows of `columns` finite numbers; trailing blank lines allowed."""
    with open(path, encoding="utf-8") as f:
        lines = f.read().splitlines()
    while lines and not lines[-1].strip():
        lines.pop()
    rows = []
    for i, line in enumerate(lines, 1):
        fields = line.split()
        if len(fields) != columns:
            raise ValueError(f"{path}:{i}: {len(fields)} values, expected {columns}")
        try:
            row = [float(v) for v in fields]
        except ValueError:
            raise ValueError(f"{path}:{i}: not a number in {line!r}") from None
        if not all(math.isfinite(v) for v in row):
            raise ValueError(f"{path}:{i}: not a finite number in {line!r}")
        rows.append(row)
    if not rows:
        raise ValueError(f"{path}: no rows")
    return np.array(rows, dtype=np.float32)


def frame_paths(folder, rows):
    """Frames 0..rows-1 of `folder` (png before jpeg before jpg); an error names the first
    missing one."""
    best = {}
    for name in os.listdir(folder):
        stem, _, ext = name.rpartition(".")
        if not (stem.isdigit() and stem.isascii()) or ext.lower() not in FRAME_EXTENSIONS:
            continue
        rank = FRAME_EXTENSIONS.index(ext.lower())
        k = int(stem)
        if k not in best or rank < best[k][0]:
            best[k] = (rank, os.path.join(folder, name))
    missing = [k for k in range(rows) if k not in best]
    if missing:
        raise ValueError(f"{folder}: frame {missing[0]} missing ({len(missing)} of {rows})")
    return [best[k][1] for k in range(rows)]


def decode_frames(paths):
    """Each file's RGB frame, uint8 [H, W, 3]: Pillow where installed, else `decode_pngs`."""
    try:
        from PIL import Image
    except ImportError:
        return decode_pngs(paths)
    return [np.asarray(Image.open(p).convert("RGB")) for p in paths]


def decode_pngs(paths, chunk=4096):
    """8-bit PNGs (grey, RGB, palette, with or without alpha; not interlaced) to RGB arrays,
    with zlib and numpy alone. Images of one size are unfiltered together (up to `chunk` at
    a time), row by row: numpy's cost is per operation, whatever the number of images."""
    images = [_png(p) for p in paths]
    out = [None] * len(images)
    groups = {}
    for i, img in enumerate(images):
        groups.setdefault(img["rows"].shape + (img["channels"],), []).append(i)
    for key, members in groups.items():
        for at in range(0, len(members), chunk):
            _unfilter_into(out, images, members[at:at + chunk], key[-1])
    return out


def _unfilter_into(out, images, members, channels):
    pixels = _unfilter(np.stack([images[i]["rows"] for i in members]), channels)
    for j, i in enumerate(members):
            img = images[i]
            p = pixels[j].reshape(img["height"], img["width"], channels)
            if img["palette"] is not None:
                p = img["palette"][p[..., 0]]
            elif channels in (1, 2):
                p = np.repeat(p[..., :1], 3, axis=2)
            out[i] = np.ascontiguousarray(p[..., :3])
    return out


def _png(path):
    """The filtered scanlines [H, 1 + W·C] of a PNG file and what they hold."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        kind = "JPEG" if data[:2] == b"\xff\xd8" else "not a PNG"
        raise ValueError(f"{path}: {kind}: decoding it needs Pillow (pip install pillow)")
    at, idat, palette, header = 8, [], None, None
    while at < len(data):
        length, kind = struct.unpack(">I4s", data[at:at + 8])
        body = data[at + 8:at + 8 + length]
        at += 12 + length
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"PLTE":
            palette = np.frombuffer(body, np.uint8).reshape(-1, 3)
        elif kind == b"IDAT":
            idat.append(body)
        elif kind == b"IEND":
            break
    width, height, depth, color, _, _, interlace = header
    channels = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}.get(color)
    if depth != 8 or interlace or channels is None:
        raise ValueError(f"{path}: a {depth}-bit PNG of colour type {color}"
                         f"{' (interlaced)' if interlace else ''}: "
                         "needs Pillow (pip install pillow)")
    rows = np.frombuffer(zlib.decompress(b"".join(idat)), np.uint8)
    return {"rows": rows.reshape(height, 1 + width * channels), "width": width,
            "height": height, "channels": channels, "palette": palette if color == 3 else None}


def _unfilter(rows, bpp):
    """PNG's five scanline filters undone for F images at once: [F, H, 1 + L] → [F, H, L]."""
    kinds, raw = rows[:, :, 0], rows[:, :, 1:].astype(np.int32)
    n, h, width = raw.shape
    out = np.empty((n, h, width), np.uint8)
    prev = np.zeros((n, width), np.int32)
    zero = np.zeros((n, bpp), np.int32)
    for y in range(h):
        kind, r = kinds[:, y, None], raw[:, y]
        row = np.where(kind == 2, r + prev, r) & 255  # None and Up need no left neighbour
        left_dependent = np.isin(kind[:, 0], (1, 3, 4))
        if left_dependent.any():
            idx = np.nonzero(left_dependent)[0]
            k, r, up_row, cur = kind[idx], r[idx], prev[idx], row[idx]
            for x in range(0, width, bpp):
                left = cur[:, x - bpp:x] if x else zero[idx]
                ul = up_row[:, x - bpp:x] if x else zero[idx]
                up = up_row[:, x:x + bpp]
                p = left + up - ul
                pa, pb, pc = np.abs(p - left), np.abs(p - up), np.abs(p - ul)
                paeth = np.where((pa <= pb) & (pa <= pc), left, np.where(pb <= pc, up, ul))
                predicted = np.where(k == 1, left, np.where(k == 3, (left + up) >> 1, paeth))
                cur[:, x:x + bpp] = (r[:, x:x + bpp] + predicted) & 255
            row[idx] = cur
        out[:, y] = row
        prev = row
    return out


def resize(frames, target):
    """[T, S, S, 3] uint8 frames to `target` pixels a side, as reader.rs `resize`: an exact,
    rounded area average when `target` divides S, otherwise image's triangle filter (rows,
    then columns; within a level of image's own, float summation order aside)."""
    t, s = frames.shape[:2]
    if target < s and s % target == 0:
        f = s // target
        blocks = frames.reshape(t, target, f, target, f, 3).astype(np.uint32).sum((2, 4))
        return ((blocks + f * f // 2) // (f * f)).astype(np.uint8)
    w = _triangle_weights(s, target)
    columns = np.einsum("ys,tsxc->tyxc", w, frames.astype(np.float32))
    out = np.einsum("xs,tysc->tyxc", w, columns)
    return np.floor(np.clip(out, 0, 255) + 0.5).astype(np.uint8)


def _triangle_weights(size, target):
    """[target, size] weights of image's `Triangle` resampling (imageops::sample)."""
    ratio = np.float32(size) / np.float32(target)
    sratio = max(ratio, np.float32(1))
    w = np.zeros((target, size), np.float32)
    for o in range(target):
        centre = (np.float32(o) + np.float32(0.5)) * ratio
        left = min(max(math.floor(centre - sratio), 0), size - 1)
        right = min(max(math.ceil(centre + sratio), left + 1), size)
        x = (np.arange(left, right, dtype=np.float32) - (centre - np.float32(0.5))) / sratio
        k = np.maximum(1 - np.abs(x), 0)
        w[o, left:right] = k / k.sum()
    return w


class Normalization:
    """Per-column joint mean and (population) standard deviation; the model sees
    (joint − mean) / std."""

    def __init__(self, mean, std):
        self.mean = np.asarray(mean, np.float32)
        self.std = np.asarray(std, np.float32)

    @classmethod
    def fit(cls, joint_arrays):
        """Normalization::fit: sums in f64, a column with std below MIN_STD gets 1."""
        rows = np.concatenate([np.asarray(j, np.float64) for j in joint_arrays])
        if not len(rows):
            return cls(np.zeros(JOINTS), np.ones(JOINTS))
        mean = rows.sum(0) / len(rows)
        var = np.maximum((rows * rows).sum(0) / len(rows) - mean * mean, 0.0)
        std = np.sqrt(var).astype(np.float32)
        return cls(mean.astype(np.float32), np.where(std < MIN_STD, np.float32(1), std))

    def scaled(self, joint_scale):
        """Normalization::scaled: "shared" divides the six arm angles by one scale, the root
        mean square of their standard deviations (the gripper keeps its own)."""
        if joint_scale not in ("per-joint", "shared"):
            raise ValueError(f"joint_scale {joint_scale!r}: expected per-joint or shared")
        std = self.std.copy()
        if joint_scale == "shared":
            std[:6] = np.sqrt((std[:6] * std[:6]).sum(dtype=np.float32) / np.float32(6))
        return Normalization(self.mean, std)

    def normalize(self, joints):
        return (np.asarray(joints, np.float32) - self.mean) / self.std

    def to_json(self):
        return {"mean": [float(v) for v in self.mean], "std": [float(v) for v in self.std]}


class Split:
    """Training and validation sequences split by id (both actions of an id on one side): the
    last `val_fraction` of the ids, at least one when there are two or more; none for 0."""

    def __init__(self, root, image_size, val_fraction):
        if not 0.0 <= val_fraction < 1.0:
            raise ValueError(f"--val-fraction {val_fraction}: expected a value in [0, 1)")
        listed = sequences(root)
        ids = sorted({i for i, _, _ in listed})
        held = 0
        if len(ids) >= 2 and val_fraction > 0:
            held = max(1, math.ceil(len(ids) * val_fraction))
        self.val_ids = ids[len(ids) - held:]
        self.train, self.val = [], []
        read = read_sequences([(id, folder) for id, _, folder in listed], image_size)
        for (id, _, _), seq in zip(listed, read):
            (self.val if id in self.val_ids else self.train).append(seq)
        if not self.train:
            raise ValueError(f"{root}: no training sequences")
