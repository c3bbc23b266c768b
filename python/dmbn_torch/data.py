"""The DMBN layout read as crate/data/reader.rs reads it, and the joint normalisation.

`<root>/<id>/<action>/` folders (decimal ids, non-hidden action folders, sorted by id then
action), each with `joint_<id>.txt` (T rows of D numbers, D the first row's, the same for every
sequence of a dataset) and frames `<k>.png|.jpeg|.jpg` for k = 0..T-1 (png preferred when a
step has several; frames past the joint rows ignored), those of another camera in
`<camera>/<k>.png`. `object_<id>.txt` and `endpoint_<id>.txt` (optional) are not read: training
needs joints and frames alone. An optional `dataset.json` at the root may name the joint
values (`joint_names`). Frames are resized on reading to a square: an exact, rounded area
average when a square frame's size divides the stored one (128 → 64), otherwise image's
triangle filter (stretching another aspect). PNG frames decode here without Pillow (zlib and
numpy, exact); JPEG frames need Pillow, which decodes everything faster where installed.
"""
import json
import math
import os
import struct
import zlib

import numpy as np

# Joint values a step of the original arm (6 angles, gripper): a fit with no rows gets as many.
JOINTS = 7
FRAME_EXTENSIONS = ["png", "jpeg", "jpg"]
# Standard deviations below this are replaced by 1 (a column that never moves).
MIN_STD = 1e-6


class Sequence:
    """One recorded action: `joints` float32 [T, D], `frames` uint8 [T, S, S, 3]."""

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


def read_sequence(folder, id, image_size=None, camera=None):
    """The sequence in `folder`, frames (`camera`'s, default the folder's own) resized to
    `image_size` pixels a side when given."""
    return read_sequences([(id, folder)], image_size, camera)[0]


def read_sequences(listed, image_size=None, camera=None):
    """The sequences of (id, folder) pairs, `camera`'s frames (the sub-folder `<camera>/`;
    None: those in the folder itself); their frames decode together (faster). Every sequence
    must have the first's joint values a step (an error names the first file that differs).
    Without `image_size`, square frames stay as stored and others are stretched to the square
    of their longer side (as the Rust reader)."""
    joints, first = [], None
    for id, folder in listed:
        path = os.path.join(folder, f"joint_{id}.txt")
        table = read_table(path)
        if first is None:
            first = path
        elif table.shape[1] != joints[0].shape[1]:
            raise ValueError(f"{path}: {table.shape[1]} joint values a step, expected "
                             f"{joints[0].shape[1]} as in {first} (every sequence of a "
                             "dataset, and the model, has the same joints)")
        joints.append(table)
    if camera is not None and listed:
        check_camera(listed[0][1], camera)
    paths = [frame_paths(camera_folder(folder, camera), len(j))
             for (_, folder), j in zip(listed, joints)]
    decoded = decode_frames([p for ps in paths for p in ps])
    out, at = [], 0
    for j, ps in zip(joints, paths):
        mine, at = decoded[at:at + len(ps)], at + len(ps)
        size = mine[0].shape
        for path, frame in zip(ps, mine):
            if frame.shape != size:
                h, w = frame.shape[:2]
                raise ValueError(f"{path}: a {w}x{h} frame, expected {size[1]}x{size[0]} "
                                 "(as the sequence's first)")
        frames = np.stack(mine)
        side = image_size or max(size[:2])
        if (side, side) != size[:2]:
            frames = resize(frames, side)
        out.append(Sequence(j, frames))
    return out


def camera_folder(folder, camera):
    """The folder holding `camera`'s frames: `<folder>/<camera>/`, or `folder` itself."""
    return folder if camera is None else os.path.join(folder, camera)


def check_camera(folder, camera):
    """An error naming the cameras of `folder` (a sequence's) unless it has `camera`."""
    cameras = sorted(c for c in os.listdir(folder) if os.path.isdir(os.path.join(folder, c)))
    if camera.startswith(".") or "/" in camera or camera not in cameras:
        raise ValueError(f"{folder}: no camera {camera!r}: expected a sub-folder of that name "
                         "holding its frames; the cameras here are the default (<k>.png)"
                         + "".join(f", {c}" for c in cameras))


def dataset_names(root, joints):
    """The joint names of `root`'s `dataset.json` (None where it has no file or no names),
    checked against the data's `joints` values a step."""
    path = os.path.join(root, "dataset.json")
    if not os.path.isfile(path):
        return None
    try:
        with open(path, encoding="utf-8") as f:
            meta = json.load(f)
    except ValueError as e:
        raise ValueError(f"{path}: {e}: expected a JSON object with optional joint_names "
                         "(a list of strings), cameras, fps, source") from None
    names = meta.get("joint_names") if isinstance(meta, dict) else None
    if names is None:
        return None
    if (not isinstance(names, list) or not names
            or not all(isinstance(n, str) and n.strip() for n in names)):
        raise ValueError(f"{path}: joint_names: expected a non-empty name for every joint value")
    if len(names) != joints:
        raise ValueError(f"{path}: joint_names: {len(names)} names, expected {joints} (the "
                         "joint values a step of its sequences)")
    return names


def read_table(path, columns=None):
    """Whitespace-separated rows of `columns` finite numbers (None: as many as the first row
    has); trailing blank lines allowed."""
    with open(path, encoding="utf-8") as f:
        lines = f.read().splitlines()
    while lines and not lines[-1].strip():
        lines.pop()
    rows = []
    for i, line in enumerate(lines, 1):
        fields = line.split()
        columns = columns or len(fields)
        if len(fields) != columns or not columns:
            raise ValueError(f"{path}:{i}: {len(fields)} values, expected {max(columns, 1)}")
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
    """[T, H, W, 3] uint8 frames to `target` pixels a side, as reader.rs `resize`: an exact,
    rounded area average when the frames are square and `target` divides their size,
    otherwise image's triangle filter (rows, then columns, each axis by its own ratio: another
    aspect is stretched to the square; within a level of image's own, float summation order
    aside, and for non-square frames possibly another level or so by interpolation
    rounding)."""
    t, h, w = frames.shape[:3]
    if h == w and target < h and h % target == 0:
        f = h // target
        blocks = frames.reshape(t, target, f, target, f, 3).astype(np.uint32).sum((2, 4))
        return ((blocks + f * f // 2) // (f * f)).astype(np.uint8)
    rows, cols = _triangle_weights(h, target), _triangle_weights(w, target)
    columns = np.einsum("ys,tsxc->tyxc", rows, frames.astype(np.float32))
    out = np.einsum("xs,tysc->tyxc", cols, columns)
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
    def fit(cls, joint_arrays, joints=None):
        """Normalization::fit: sums in f64, a column with std below MIN_STD gets 1; no rows
        give the identity of `joints` values (default: the arrays', else 7)."""
        arrays = [np.asarray(j, np.float64) for j in joint_arrays]
        joints = joints or (arrays[0].shape[1] if arrays else JOINTS)
        rows = np.concatenate(arrays) if arrays else np.zeros((0, joints))
        if not len(rows):
            return cls(np.zeros(joints), np.ones(joints))
        mean = rows.sum(0) / len(rows)
        var = np.maximum((rows * rows).sum(0) / len(rows) - mean * mean, 0.0)
        std = np.sqrt(var).astype(np.float32)
        return cls(mean.astype(np.float32), np.where(std < MIN_STD, np.float32(1), std))

    def scaled(self, joint_scale):
        """Normalization::scaled: "shared" divides all values but the last (the original's six
        arm angles) by one scale, the root mean square of their standard deviations; the last
        (the gripper, by the layout's convention) keeps its own. One value: unchanged."""
        if joint_scale not in ("per-joint", "shared"):
            raise ValueError(f"joint_scale {joint_scale!r}: expected per-joint or shared")
        std = self.std.copy()
        arm = max(len(std) - 1, 1)
        if joint_scale == "shared":
            std[:arm] = np.sqrt((std[:arm] * std[:arm]).sum(dtype=np.float32) / np.float32(arm))
        return Normalization(self.mean, std)

    def normalize(self, joints):
        return (np.asarray(joints, np.float32) - self.mean) / self.std

    def to_json(self):
        return {"mean": [float(v) for v in self.mean], "std": [float(v) for v in self.std]}


class Split:
    """Training and validation sequences split by id (both actions of an id on one side): the
    last `val_fraction` of the ids, at least one when there are two or more; none for 0."""

    def __init__(self, root, image_size, val_fraction, camera=None):
        if not 0.0 <= val_fraction < 1.0:
            raise ValueError(f"--val-fraction {val_fraction}: expected a value in [0, 1)")
        listed = sequences(root)
        ids = sorted({i for i, _, _ in listed})
        held = 0
        if len(ids) >= 2 and val_fraction > 0:
            held = max(1, math.ceil(len(ids) * val_fraction))
        self.val_ids = ids[len(ids) - held:]
        self.train, self.val = [], []
        read = read_sequences([(id, folder) for id, _, folder in listed], image_size, camera)
        # The data's joint values a step (D) and, from dataset.json, their names.
        self.joints = read[0].joints.shape[1]
        self.joint_names = dataset_names(root, self.joints)
        for (id, _, _), seq in zip(listed, read):
            (self.val if id in self.val_ids else self.train).append(seq)
        if not self.train:
            raise ValueError(f"{root}: no training sequences")
