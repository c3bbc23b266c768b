"""LeRobot datasets (codebase v2.0, v2.1, v3.0) into the DMBN layout.

Read with pyarrow and PyAV by the documented layout, not with the `lerobot` package (which
pulls in torch, datasets, huggingface_hub and more). Episode boundaries come from the parquet
rows' `episode_index`; frames from the camera's mp4: one per episode in v2.x
(`video_path` with `episode_chunk`), a time range of a shared file in v3.0
(`meta/episodes/*/*.parquet`: `videos/<key>/{chunk,file}_index`, `from_timestamp`,
`to_timestamp`). Image features (`dtype: image`, PNG bytes in the parquet) are read too.
"""

import io
import json
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq
from PIL import Image

from . import ConvertError
from .video import read_frames
from .writer import DmbnWriter, check_stride, parse_range, progress, safe_action

CAMERA_PREFIX = "observation.images."


def load_info(src):
    path = src / "meta" / "info.json"
    if not path.is_file():
        raise ConvertError(
            f"{path}: missing (expected a LeRobot dataset: meta/info.json, data/, videos/)"
        )
    try:
        info = json.loads(path.read_text())
    except ValueError as e:
        raise ConvertError(f"{path}: not valid JSON ({e})") from None
    if not isinstance(info.get("features"), dict):
        raise ConvertError(f"{path}: expected a 'features' object")
    version = str(info.get("codebase_version", ""))
    if not (version.startswith("v2.") or version.startswith("v3.")):
        raise ConvertError(f"{path}: codebase_version {version!r}: expected v2.x or v3.0")
    return info


def pick_cameras(info, wanted, where):
    """Full feature keys of the chosen cameras (short names accepted); default the first."""
    have = [k for k, f in info["features"].items() if f.get("dtype") in ("video", "image")]
    if not wanted:
        default = [k for k in have if k.startswith(CAMERA_PREFIX)] or have
        if not default:
            raise ConvertError(
                f"{where}: no video or image feature (features: {', '.join(info['features'])})"
            )
        return [default[0]]
    keys = []
    for name in wanted:
        key = name if name in have else CAMERA_PREFIX + name
        if key not in have:
            short = [k[len(CAMERA_PREFIX) :] if k.startswith(CAMERA_PREFIX) else k for k in have]
            raise ConvertError(
                f"{where}: no camera {name!r} (it has: {', '.join(short) or 'none'})"
            )
        keys.append(key)
    return keys


def joint_names(feature, width):
    """`names` as a list, or a dict of lists (e.g. {"motors": [...]}), flattened; else j0..."""
    names = feature.get("names")
    if isinstance(names, dict):
        names = [n for v in names.values() if isinstance(v, list) for n in v]
    if (
        isinstance(names, list)
        and len(names) == width
        and all(isinstance(n, str) and n.strip() for n in names)
    ):
        return names
    return [f"j{i}" for i in range(width)]


def column_matrix(column, where):
    """A list (or scalar) column as a [rows, D] array, float32 kept float32."""
    arr = column.combine_chunks() if isinstance(column, pa.ChunkedArray) else column
    if arr.null_count:
        raise ConvertError(f"{where}: the state column has null rows")
    if (
        pa.types.is_list(arr.type)
        or pa.types.is_large_list(arr.type)
        or pa.types.is_fixed_size_list(arr.type)
    ):
        lengths = pc.list_value_length(arr).to_numpy(zero_copy_only=False)
        if len(lengths) and (lengths != lengths[0]).any():
            raise ConvertError(
                f"{where}: state rows of different lengths ({sorted(set(lengths.tolist()))})"
            )
        flat = arr.flatten().to_numpy(zero_copy_only=False)
        return flat.reshape(len(arr), int(lengths[0]) if len(lengths) else 0)
    return arr.to_numpy(zero_copy_only=False).reshape(-1, 1)


def read_tasks(src):
    """task_index -> task text (tasks.jsonl in v2.x, tasks.parquet in v3.0)."""
    jsonl, parquet = src / "meta" / "tasks.jsonl", src / "meta" / "tasks.parquet"
    if jsonl.is_file():
        rows = [json.loads(line) for line in jsonl.read_text().splitlines() if line.strip()]
        return {int(r["task_index"]): str(r["task"]) for r in rows}
    if parquet.is_file():
        table = pq.read_table(parquet)
        text = next((c for c in ("task", "__index_level_0__") if c in table.column_names), None)
        if text is None:
            text = next((f.name for f in table.schema if pa.types.is_string(f.type)), None)
        if text is None or "task_index" not in table.column_names:
            return {}
        return dict(zip(table["task_index"].to_pylist(), table[text].to_pylist(), strict=True))
    return {}


def read_v3_episodes(src):
    """episode_index -> its row of meta/episodes/*/*.parquet (v3.0), without the stats."""
    rows = {}
    for path in sorted((src / "meta" / "episodes").glob("*/*.parquet")):
        table = pq.read_table(path)
        keep = [c for c in table.column_names if not c.startswith("stats/")]
        for row in table.select(keep).to_pylist():
            rows[int(row["episode_index"])] = row
    return rows


def read_v2_episodes(src):
    """episode_index -> its line of meta/episodes.jsonl (v2.x), when there is one."""
    path = src / "meta" / "episodes.jsonl"
    if not path.is_file():
        return {}
    rows = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    return {int(r["episode_index"]): r for r in rows}


def read_rows(src, state, where):
    """The needed columns of every data parquet, as episode_index -> [parts, one per file]."""
    files = sorted((src / "data").glob("**/*.parquet"))
    if not files:
        raise ConvertError(f"{src / 'data'}: no parquet files (empty dataset)")
    episodes = {}
    for path in files:
        names = pq.read_schema(path).names
        if state not in names:
            raise ConvertError(f"{path}: no column {state!r} (columns: {', '.join(names)})")
        if "episode_index" not in names:
            raise ConvertError(f"{path}: no column 'episode_index' (columns: {', '.join(names)})")
        cols = [c for c in (state, "episode_index", "frame_index", "task_index") if c in names]
        table = pq.read_table(path, columns=cols)
        ep = table["episode_index"].to_numpy()
        matrix = column_matrix(table[state], f"{path}")
        frame = table["frame_index"].to_numpy() if "frame_index" in names else np.arange(len(ep))
        task = table["task_index"].to_numpy() if "task_index" in names else np.full(len(ep), -1)
        for e in np.unique(ep):
            mask = ep == e
            order = np.argsort(frame[mask], kind="stable")
            episodes.setdefault(int(e), []).append(
                {
                    "state": matrix[mask][order],
                    "task": task[mask][order],
                    "file": path,
                    "rows": np.flatnonzero(mask)[order],
                }
            )
    return episodes


def image_frames(path, key, rows):
    """PNG/JPEG frames stored in the parquet (`dtype: image`)."""
    column = pq.read_table(path, columns=[key])[key].to_pylist()
    return [
        np.asarray(Image.open(io.BytesIO(column[int(r)]["bytes"])).convert("RGB")) for r in rows
    ]


def video_span(src, info, meta, key, e):
    """The mp4 holding episode `e`'s frames of camera `key`, and their [start, end) seconds."""
    if not str(info["codebase_version"]).startswith("v3."):
        chunk = e // int(info.get("chunks_size") or 1000)
        path = info["video_path"].format(video_key=key, episode_chunk=chunk, episode_index=e)
        return src / path, 0.0, None
    where = src / "meta" / "episodes"
    m = meta.get(e)
    if m is None:
        raise ConvertError(f"{where}: no row for episode {e}")
    columns = [
        f"videos/{key}/{c}" for c in ("chunk_index", "file_index", "from_timestamp", "to_timestamp")
    ]
    if any(m.get(c) is None for c in columns):
        raise ConvertError(f"{where}: episode {e} lacks one of the columns {', '.join(columns)}")
    chunk, file, start, end = (m[c] for c in columns)
    path = info["video_path"].format(video_key=key, chunk_index=chunk, file_index=file)
    return src / path, float(start), float(end)


def convert(
    src, out, cameras=None, state="observation.state", stride=1, episodes=None, action=None
):
    src = Path(src)
    info = load_info(src)
    where = src / "meta" / "info.json"
    features = info["features"]
    version = str(info["codebase_version"])
    keys = pick_cameras(info, cameras, where)
    if state not in features:
        plain = [k for k, f in features.items() if f.get("dtype") not in ("video", "image")]
        raise ConvertError(f"{where}: no state feature {state!r} (features: {', '.join(plain)})")
    stride, chosen = check_stride(stride), parse_range(episodes)
    fps = info.get("fps") or 30
    short = [k[len(CAMERA_PREFIX) :] if k.startswith(CAMERA_PREFIX) else k for k in keys]
    tasks = read_tasks(src)
    meta = read_v3_episodes(src) if version.startswith("v3.") else read_v2_episodes(src)
    writer = DmbnWriter(out, short, f"lerobot:{src}")
    rows = read_rows(src, state, where)
    ids = sorted(rows)[chosen]
    width = None
    with writer:
        for e in progress(ids, "lerobot"):
            parts = rows[e]
            joints = np.concatenate([p["state"] for p in parts])
            width = joints.shape[1]
            frames = {}
            for key, name in zip(keys, short, strict=True):
                if features[key].get("dtype") == "image":
                    frames[name] = [
                        f for p in parts for f in image_frames(p["file"], key, p["rows"])
                    ]
                    continue
                path, start, end = video_span(src, info, meta, key, e)
                images = read_frames(path, start, end, fps)
                if len(images) != len(joints):
                    files = ", ".join(str(p["file"]) for p in parts)
                    raise ConvertError(
                        f"episode {e}: the video {path} has {len(images)} frames, "
                        f"the parquet ({files}) has {len(joints)} rows"
                    )
                frames[name] = images
            task = tasks.get(int(parts[0]["task"][0])) if len(parts[0]["task"]) else None
            if task is None and meta.get(e, {}).get("tasks"):
                task = meta[e]["tasks"][0]
            where_e = f"episode {e} ({parts[0]['file']})"
            writer.episode(
                e,
                safe_action(task, action),
                joints[::stride],
                {n: f[::stride] for n, f in frames.items()},
                where_e,
            )
        writer.finish(joint_names(features[state], width or 0), fps)
    return writer.count
