"""A DMBN-layout dataset written as a LeRobot v2.1 dataset (the reverse direction).

Reads `<id>/<action>/<k>.png` (+ camera sub-folders) and `joint_<id>.txt`; object_/endpoint_
files are ignored. Writes, by the documented v2.1 layout, with pyarrow and PyAV:
meta/info.json, meta/episodes.jsonl, meta/tasks.jsonl (one task per action name),
meta/episodes_stats.jsonl, data/chunk-000/episode_NNNNNN.parquet (`observation.state` as a
fixed-size list, `action` = the next state (the last row repeats), `timestamp`,
`frame_index`, `episode_index`, `index`, `task_index`) and one mp4 per episode and camera.
"""

import json
import os
import re
import shutil
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
from PIL import Image

from . import ConvertError
from .video import encoder, write_frames
from .writer import progress

DATA_PATH = "data/chunk-{episode_chunk:03d}/episode_{episode_index:06d}.parquet"
VIDEO_PATH = "videos/chunk-{episode_chunk:03d}/{video_key}/episode_{episode_index:06d}.mp4"
CHUNK = 1000
DEFAULT_CAMERA = "image"  # the default camera's name when SRC has no dataset.json


def scan(src):
    """[(id, action, folder)] in (numeric id, action) order, and SRC's camera names."""
    meta = {}
    if (src / "dataset.json").is_file():
        try:
            meta = json.loads((src / "dataset.json").read_text())
        except ValueError as e:
            raise ConvertError(f"{src / 'dataset.json'}: not valid JSON ({e})") from None
    episodes = []
    ids = sorted(
        (p for p in src.iterdir() if p.is_dir() and p.name.isdigit()), key=lambda p: int(p.name)
    )
    for folder in ids:
        for act in sorted(p for p in folder.iterdir() if p.is_dir() and not p.name.startswith(".")):
            if (act / f"joint_{folder.name}.txt").is_file():
                episodes.append((int(folder.name), act.name, act))
    if not episodes:
        raise ConvertError(
            f"{src}: no episodes (expected <id>/<action>/joint_<id>.txt and <k>.png)"
        )
    cameras = list(meta.get("cameras") or [])
    if not cameras:
        extra = {
            p.name
            for _, _, f in episodes
            for p in f.iterdir()
            if p.is_dir() and (p / "0.png").is_file()
        }
        cameras = [DEFAULT_CAMERA] + sorted(extra)
    return episodes, cameras, meta


def read_png_sequence(folder, count, where):
    """Frames 0..count-1 of a folder, RGB, one size (else an error naming the file)."""
    frames = []
    for k in range(count):
        path = folder / f"{k}.png"
        if not path.is_file():
            raise ConvertError(
                f"{path}: missing frame ({where} has {count} joint rows, so frames 0..{count - 1})"
            )
        image = np.asarray(Image.open(path).convert("RGB"))
        if frames and image.shape != frames[0].shape:
            raise ConvertError(
                f"{path}: {image.shape[1]}x{image.shape[0]}, frame 0 of the sequence is "
                f"{frames[0].shape[1]}x{frames[0].shape[0]} (expected one size per sequence)"
            )
        frames.append(image)
    return frames


def read_joints(path):
    rows = [line.split() for line in path.read_text().splitlines() if line.strip()]
    try:
        joints = np.array(rows, dtype=np.float32)
    except ValueError:
        raise ConvertError(f"{path}: expected T rows of D numbers each") from None
    if joints.ndim != 2 or len(joints) == 0 or not np.isfinite(joints).all():
        raise ConvertError(f"{path}: expected T rows of D finite numbers each")
    return joints


def stats(values):
    """LeRobot's per-episode stats of a [T, ...] array over the first axis."""
    values = values.astype(np.float64)
    return {
        "min": values.min(0).tolist(),
        "max": values.max(0).tolist(),
        "mean": values.mean(0).tolist(),
        "std": values.std(0).tolist(),
        "count": [len(values)],
    }


def image_stats(frames):
    """Per-channel stats in [0, 1], shaped [3, 1, 1] as LeRobot writes them."""
    pixels = np.stack(frames).reshape(-1, 3).astype(np.float64) / 255.0
    s = {
        k: np.asarray(getattr(pixels, k)(0)).reshape(3, 1, 1).tolist()
        for k in ("min", "max", "mean", "std")
    }
    s["count"] = [len(frames)]
    return s


def convert(src, out, fps=None, cameras=None, crf=18):
    src, out = Path(src), Path(out)
    if not src.is_dir():
        raise ConvertError(f"{src}: missing (expected a DMBN-layout dataset folder)")
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise ConvertError(f"{out}: exists and is not empty (refusing to overwrite it)")
    episodes, have, meta = scan(src)
    chosen = list(cameras or have)
    for name in chosen:
        if name not in have:
            raise ConvertError(f"{src}: no camera {name!r} (it has: {', '.join(have)})")
    fps = int(fps or meta.get("fps") or 30)
    if fps < 1:
        raise ConvertError(f"--fps {fps}: expected a positive integer")
    tmp = out.parent / f"{out.name}.tmp-{os.getpid()}"
    out.parent.mkdir(parents=True, exist_ok=True)
    shutil.rmtree(tmp, ignore_errors=True)
    try:
        info = write(src, tmp, episodes, have, chosen, fps, meta, crf)
        (tmp / "meta" / "info.json").write_text(json.dumps(info, indent=4) + "\n")
        if out.exists():
            out.rmdir()
        os.rename(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return len(episodes)


def write(src, tmp, episodes, have, chosen, fps, meta, crf):
    (tmp / "meta").mkdir(parents=True)
    tasks, width, shapes, index, lines, stat_lines = {}, None, {}, 0, [], []
    pix_fmts = {}
    for e, (ident, act, folder) in enumerate(progress(episodes, "to-lerobot")):
        where = f"{folder}"
        joints = read_joints(folder / f"joint_{ident}.txt")
        if width is None:
            width = joints.shape[1]
        elif joints.shape[1] != width:
            raise ConvertError(
                f"{folder / f'joint_{ident}.txt'}: {joints.shape[1]} values per row, "
                f"earlier episodes have {width}"
            )
        t = len(joints)
        task = tasks.setdefault(act, len(tasks))
        action = np.concatenate([joints[1:], joints[-1:]])
        chunk = e // CHUNK
        columns = {
            "observation.state": pa.FixedSizeListArray.from_arrays(pa.array(joints.ravel()), width),
            "action": pa.FixedSizeListArray.from_arrays(pa.array(action.ravel()), width),
            "timestamp": pa.array(np.arange(t, dtype=np.float32) / fps),
            "frame_index": pa.array(np.arange(t, dtype=np.int64)),
            "episode_index": pa.array(np.full(t, e, dtype=np.int64)),
            "index": pa.array(np.arange(index, index + t, dtype=np.int64)),
            "task_index": pa.array(np.full(t, task, dtype=np.int64)),
        }
        path = tmp / DATA_PATH.format(episode_chunk=chunk, episode_index=e)
        path.parent.mkdir(parents=True, exist_ok=True)
        pq.write_table(pa.table(columns), path)
        episode_stats = {
            "observation.state": stats(joints),
            "action": stats(action),
            "timestamp": stats(columns["timestamp"].to_numpy()[:, None]),
            "frame_index": stats(np.arange(t)[:, None]),
            "episode_index": stats(np.full((t, 1), e)),
            "index": stats(np.arange(index, index + t)[:, None]),
            "task_index": stats(np.full((t, 1), task)),
        }
        for name in chosen:
            sub = folder if name == have[0] else folder / name
            frames = read_png_sequence(sub, t, where)
            shape = frames[0].shape
            if shapes.setdefault(name, shape) != shape:
                raise ConvertError(
                    f"{sub / '0.png'}: {shape[1]}x{shape[0]}, camera {name!r} of earlier "
                    f"episodes is {shapes[name][1]}x{shapes[name][0]} (one size per camera)"
                )
            key = f"observation.images.{name}"
            video = tmp / VIDEO_PATH.format(episode_chunk=chunk, video_key=key, episode_index=e)
            video.parent.mkdir(parents=True, exist_ok=True)
            pix_fmts[name] = write_frames(video, frames, fps, crf)
            episode_stats[key] = image_stats(frames)
        lines.append({"episode_index": e, "tasks": [act], "length": t})
        stat_lines.append({"episode_index": e, "stats": episode_stats})
        index += t
    write_jsonl(tmp / "meta" / "episodes.jsonl", lines)
    write_jsonl(tmp / "meta" / "episodes_stats.jsonl", stat_lines)
    write_jsonl(
        tmp / "meta" / "tasks.jsonl", [{"task_index": i, "task": a} for a, i in tasks.items()]
    )
    names = list(meta.get("joint_names") or [])
    if len(names) != width:
        names = [f"j{i}" for i in range(width)]
    vector = {"dtype": "float32", "shape": [width], "names": names}
    features = {}
    _, codec = encoder()
    for name in chosen:
        h, w, c = shapes[name]
        features[f"observation.images.{name}"] = {
            "dtype": "video",
            "shape": [h, w, c],
            "names": ["height", "width", "channels"],
            "info": {
                "video.fps": fps,
                "video.height": h,
                "video.width": w,
                "video.channels": c,
                "video.codec": codec,
                "video.pix_fmt": pix_fmts[name],
                "video.is_depth_map": False,
                "has_audio": False,
            },
        }
    features["observation.state"] = vector
    features["action"] = dict(vector)
    for key, dtype in (
        ("timestamp", "float32"),
        ("frame_index", "int64"),
        ("episode_index", "int64"),
        ("index", "int64"),
        ("task_index", "int64"),
    ):
        features[key] = {"dtype": dtype, "shape": [1], "names": None}
    n = len(episodes)
    return {
        "codebase_version": "v2.1",
        "robot_type": re.sub(r"[^a-z0-9_]+", "_", str(meta.get("robot_type") or "dmbn")),
        "total_episodes": n,
        "total_frames": index,
        "total_tasks": len(tasks),
        "total_videos": n * len(chosen),
        "total_chunks": (n + CHUNK - 1) // CHUNK,
        "chunks_size": CHUNK,
        "fps": fps,
        "splits": {"train": f"0:{n}"},
        "data_path": DATA_PATH,
        "video_path": VIDEO_PATH,
        "features": features,
    }


def write_jsonl(path, rows):
    path.write_text("".join(json.dumps(r) + "\n" for r in rows))
