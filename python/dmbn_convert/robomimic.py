"""robomimic-style HDF5 (robomimic, LIBERO, MimicGen) into the DMBN layout.

`data/demo_N/obs/<camera>_image` uint8 [T, H, W, 3] and state keys such as
`robot0_joint_pos` [T, 7] and `robot0_gripper_qpos` [T, 2]; several state keys are
concatenated column-wise. Demos in numeric order (demo_2 before demo_10); each demo's id is
its position in that order. The task name: LIBERO's `problem_info` language instruction, else
`env_args` env_name. Frames are written as stored (robosuite renders them upside down; no flip).
"""

import json
import re
from pathlib import Path

import h5py
import numpy as np

from . import ConvertError
from .writer import DmbnWriter, check_stride, parse_range, progress, safe_action

DEFAULT_STATE = ("robot0_joint_pos", "robot0_gripper_qpos")


def demo_number(name):
    m = re.fullmatch(r"demo_(\d+)", name)
    return int(m.group(1)) if m else None


def attr_json(group, name):
    value = group.attrs.get(name)
    if value is None:
        return {}
    try:
        return json.loads(value.decode() if isinstance(value, bytes) else str(value))
    except ValueError:
        return {}


def task_and_fps(data):
    problem, env = attr_json(data, "problem_info"), attr_json(data, "env_args")
    task = problem.get("language_instruction") or env.get("env_name")
    fps = (env.get("env_kwargs") or {}).get("control_freq")
    return task, fps


def obs_key(demo, obs, key, path, name):
    if key not in obs:
        raise ConvertError(
            f"{path}: demo {name!r} has no obs key {key!r} (keys: {', '.join(sorted(obs))})"
        )
    return obs[key]


def convert(file, out, cameras=None, states=None, stride=1, episodes=None, action=None):
    path = Path(file)
    if not path.is_file():
        raise ConvertError(f"{path}: missing (expected a robomimic-style HDF5 file)")
    stride, chosen = check_stride(stride), parse_range(episodes)
    try:
        h5 = h5py.File(path, "r")
    except OSError as e:
        raise ConvertError(f"{path}: not an HDF5 file ({e})") from None
    with h5:
        if "data" not in h5:
            raise ConvertError(
                f"{path}: no 'data' group (expected data/demo_N/obs/...; has: {', '.join(h5)})"
            )
        data = h5["data"]
        demos = sorted((n for n in data if demo_number(n) is not None), key=demo_number)
        if not demos:
            raise ConvertError(
                f"{path}: no demos under data/ (expected data/demo_0, data/demo_1, ...)"
            )
        first = data[demos[0]]
        if "obs" not in first:
            raise ConvertError(f"{path}: demo {demos[0]!r} has no 'obs' group")
        have = sorted(k for k in first["obs"] if k.endswith("_image"))
        if cameras:
            keys = [c if c.endswith("_image") else c + "_image" for c in cameras]
            for key in keys:
                if key not in have:
                    short = ", ".join(k[: -len("_image")] for k in have) or "none"
                    raise ConvertError(
                        f"{path}: no camera {key[:-6]!r} in demo {demos[0]!r} (it has: {short})"
                    )
        else:
            if not have:
                raise ConvertError(
                    f"{path}: demo {demos[0]!r} has no *_image observation "
                    f"(keys: {', '.join(sorted(first['obs']))})"
                )
            keys = have[:1]
        if not states:
            states = [k for k in DEFAULT_STATE if k in first["obs"]] or [DEFAULT_STATE[0]]
        task, fps = task_and_fps(data)
        short = [k[: -len("_image")] for k in keys]
        names = []
        chosen_ids = list(range(len(demos)))[chosen]
        with DmbnWriter(out, short, f"robomimic:{path}") as writer:
            for i in progress(chosen_ids, "robomimic"):
                name = demos[i]
                demo = data[name]
                if "obs" not in demo:
                    raise ConvertError(
                        f"{path}: demo {name!r} has no 'obs' group (keys: {', '.join(demo)})"
                    )
                obs = demo["obs"]
                columns, names = [], []
                for key in states:
                    values = np.asarray(obs_key(demo, obs, key, path, name)[()])
                    values = values.reshape(len(values), -1)
                    columns.append(values)
                    names += [f"{key}_{j}" for j in range(values.shape[1])]
                lengths = {len(c) for c in columns}
                if len(lengths) != 1:
                    raise ConvertError(
                        f"{path}: demo {name!r}: state keys of different lengths "
                        f"({sorted(lengths)})"
                    )
                dtype = np.result_type(*columns)
                joints = np.concatenate(columns, axis=1).astype(
                    dtype if dtype.kind == "f" else np.float64
                )
                frames = {}
                for key, cam in zip(keys, short, strict=True):
                    images = obs_key(demo, obs, key, path, name)
                    if images.dtype != np.uint8 or images.ndim != 4 or images.shape[-1] != 3:
                        raise ConvertError(
                            f"{path}: demo {name!r} obs {key!r}: expected uint8 [T, H, W, 3], "
                            f"got {images.dtype} {list(images.shape)}"
                        )
                    if len(images) != len(joints):
                        raise ConvertError(
                            f"{path}: demo {name!r}: {key!r} has {len(images)} frames, "
                            f"the state {len(joints)} rows"
                        )
                    frames[cam] = images[::stride]
                writer.episode(
                    i, safe_action(task, action), joints[::stride], frames, f"{path}: demo {name!r}"
                )
            writer.finish(names, fps)
    return writer.count
