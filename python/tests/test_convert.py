"""Tests of python/dmbn_convert: fixtures written with each format's own libraries.

LeRobot v2.1 and v3.0 datasets are written by their documented layout with pyarrow and PyAV
(the `lerobot` package needs torch and much more), robomimic files with h5py, DMBN-layout
data with numpy and PIL. Joints are compared exactly (at float32 precision where the source
is float32), video frames approximately (H.264 yuv420p at qp 0 still subsamples chroma).
"""

import contextlib
import io
import json
import os
import sys
from pathlib import Path

import av
import h5py
import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from PIL import Image

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from dmbn_convert.__main__ import main  # noqa: E402

W, H = 48, 32  # non-square fixture frames
LENGTHS = [6, 9, 12]
TASKS = ["Pick up the red cube!", "stack blocks"]
MOTORS = ["shoulder_pan", "shoulder_lift", "elbow", "wrist_flex", "wrist_roll", "gripper", "x", "y"]
CAMERAS = ["top", "wrist"]
FPS = 10


def run(*args):
    """main(args) in-process: (exit code, stderr)."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = main([str(a) for a in args])
    return code, err.getvalue()


def frame(e, t, cam, w=W, h=H):
    """A smooth colour pattern (video-friendly) that differs by episode, step and camera."""
    y, x = np.mgrid[0:h, 0:w]
    r = 40 + 2 * x + 4 * t + 10 * e
    g = 60 + 3 * y + 2 * t + 30 * cam
    b = 100 + x + y + 20 * cam
    return np.stack([r, g, b], -1).clip(0, 255).astype(np.uint8)


def state(e, length, width=8):
    rng = np.random.default_rng(e)
    return rng.normal(size=(length, width)).astype(np.float32)


def encode(path, frames, fps=FPS):
    path.parent.mkdir(parents=True, exist_ok=True)
    with av.open(str(path), "w") as c:
        s = c.add_stream("libx264", rate=fps)
        s.width, s.height, s.pix_fmt = frames[0].shape[1], frames[0].shape[0], "yuv420p"
        s.options = {"qp": "0", "g": "2"}
        for f in frames:
            c.mux(s.encode(av.VideoFrame.from_ndarray(f, format="rgb24")))
        c.mux(s.encode())


def frames_table(e, length, start, width=8):
    st = state(e, length, width)
    return pa.table(
        {
            "observation.state": pa.FixedSizeListArray.from_arrays(pa.array(st.ravel()), width),
            "action": pa.FixedSizeListArray.from_arrays(pa.array(st.ravel()), width),
            "timestamp": pa.array(np.arange(length, dtype=np.float32) / FPS),
            "frame_index": pa.array(np.arange(length, dtype=np.int64)),
            "episode_index": pa.array(np.full(length, e, dtype=np.int64)),
            "index": pa.array(np.arange(start, start + length, dtype=np.int64)),
            "task_index": pa.array(np.full(length, e % 2, dtype=np.int64)),
        }
    )


def features(names):
    video = {"dtype": "video", "shape": [H, W, 3], "names": ["height", "width", "channels"]}
    f = {f"observation.images.{c}": dict(video) for c in CAMERAS}
    f["observation.state"] = {"dtype": "float32", "shape": [8], "names": names}
    f["action"] = {"dtype": "float32", "shape": [8], "names": names}
    for k in ("timestamp", "frame_index", "episode_index", "index", "task_index"):
        f[k] = {"dtype": "float32" if k == "timestamp" else "int64", "shape": [1], "names": None}
    return f


def write_v21(root):
    """A LeRobot v2.1 dataset: one parquet and one mp4 per camera per episode."""
    (root / "meta").mkdir(parents=True)
    info = {
        "codebase_version": "v2.1",
        "robot_type": "so100",
        "fps": FPS,
        "chunks_size": 1000,
        "total_episodes": 3,
        "total_frames": sum(LENGTHS),
        "total_tasks": 2,
        "data_path": "data/chunk-{episode_chunk:03d}/episode_{episode_index:06d}.parquet",
        "video_path": (
            "videos/chunk-{episode_chunk:03d}/{video_key}/episode_{episode_index:06d}.mp4"
        ),
        "features": features(MOTORS),
    }
    (root / "meta/info.json").write_text(json.dumps(info))
    (root / "meta/tasks.jsonl").write_text(
        "".join(json.dumps({"task_index": i, "task": t}) + "\n" for i, t in enumerate(TASKS))
    )
    eps = [
        {"episode_index": e, "tasks": [TASKS[e % 2]], "length": n} for e, n in enumerate(LENGTHS)
    ]
    (root / "meta/episodes.jsonl").write_text("".join(json.dumps(r) + "\n" for r in eps))
    start = 0
    for e, n in enumerate(LENGTHS):
        path = root / f"data/chunk-000/episode_{e:06d}.parquet"
        path.parent.mkdir(parents=True, exist_ok=True)
        pq.write_table(frames_table(e, n, start), path)
        for c, cam in enumerate(CAMERAS):
            encode(
                root / f"videos/chunk-000/observation.images.{cam}/episode_{e:06d}.mp4",
                [frame(e, t, c) for t in range(n)],
            )
        start += n
    return root


def write_v30(root):
    """A LeRobot v3.0 dataset: every episode in one parquet and one mp4 per camera."""
    (root / "meta/episodes/chunk-000").mkdir(parents=True)
    info = {
        "codebase_version": "v3.0",
        "robot_type": "so100",
        "fps": FPS,
        "chunks_size": 1000,
        "total_episodes": 3,
        "total_frames": sum(LENGTHS),
        "total_tasks": 2,
        "data_path": "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet",
        "video_path": "videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4",
        "features": features({"motors": MOTORS}),
    }
    (root / "meta/info.json").write_text(json.dumps(info))
    pq.write_table(pa.table({"task": TASKS, "task_index": [0, 1]}), root / "meta/tasks.parquet")
    starts = np.concatenate([[0], np.cumsum(LENGTHS)])
    (root / "data/chunk-000").mkdir(parents=True)
    pq.write_table(
        pa.concat_tables([frames_table(e, n, starts[e]) for e, n in enumerate(LENGTHS)]),
        root / "data/chunk-000/file-000.parquet",
    )
    meta = {
        "episode_index": [0, 1, 2],
        "tasks": [[TASKS[e % 2]] for e in range(3)],
        "length": LENGTHS,
        "data/chunk_index": [0] * 3,
        "data/file_index": [0] * 3,
        "dataset_from_index": starts[:-1].tolist(),
        "dataset_to_index": starts[1:].tolist(),
    }
    for c, cam in enumerate(CAMERAS):
        key = f"observation.images.{cam}"
        encode(
            root / f"videos/{key}/chunk-000/file-000.mp4",
            [frame(e, t, c) for e, n in enumerate(LENGTHS) for t in range(n)],
        )
        meta[f"videos/{key}/chunk_index"] = [0] * 3
        meta[f"videos/{key}/file_index"] = [0] * 3
        meta[f"videos/{key}/from_timestamp"] = (starts[:-1] / FPS).tolist()
        meta[f"videos/{key}/to_timestamp"] = (starts[1:] / FPS).tolist()
    pq.write_table(pa.table(meta), root / "meta/episodes/chunk-000/file-000.parquet")
    return root


@pytest.fixture(scope="module")
def v21(tmp_path_factory):
    return write_v21(tmp_path_factory.mktemp("v21") / "ds")


@pytest.fixture(scope="module")
def v30(tmp_path_factory):
    return write_v30(tmp_path_factory.mktemp("v30") / "ds")


def read_png(path):
    return np.asarray(Image.open(path).convert("RGB")).astype(np.float64)


def assert_close(path, expected, tol=6):
    got = read_png(path)
    assert got.shape == expected.shape, path
    mad = np.abs(got - expected).mean()
    assert mad < tol, f"{path}: mean absolute difference {mad:.2f}"


def check_episode(out, e, action, length, cameras, stride=1):
    folder = out / str(e) / action
    joints = np.loadtxt(folder / f"joint_{e}.txt", dtype=np.float32, ndmin=2)
    np.testing.assert_array_equal(joints, state(e, length)[::stride])
    for c, cam in enumerate(cameras):
        sub = folder if c == 0 else folder / cam
        kept = list(range(length))[::stride]
        assert sorted(int(p.stem) for p in sub.glob("*.png")) == list(range(len(kept)))
        for k, t in enumerate(kept):
            assert_close(sub / f"{k}.png", frame(e, t, CAMERAS.index(cam)))


@pytest.mark.parametrize("version", ["v21", "v30"])
def test_lerobot_two_cameras(version, request, tmp_path):
    src = request.getfixturevalue(version)
    out = tmp_path / "out"
    code, err = run("lerobot", src, out, "--camera", "observation.images.top", "--camera", "wrist")
    assert code == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["0", "1", "2", "dataset.json"]
    actions = ["pick_up_the_red_cube", "stack_blocks", "pick_up_the_red_cube"]
    for e, n in enumerate(LENGTHS):
        assert [p.name for p in (out / str(e)).iterdir()] == [actions[e]]
        check_episode(out, e, actions[e], n, CAMERAS)
    meta = json.loads((out / "dataset.json").read_text())
    assert meta == {
        "joint_names": MOTORS,
        "cameras": CAMERAS,
        "fps": FPS,
        "source": f"lerobot:{src}",
    }
    assert not list(tmp_path.glob("*.tmp-*"))


def test_lerobot_default_camera_stride_range_action(v21, tmp_path):
    out = tmp_path / "out"
    code, err = run("lerobot", v21, out, "--stride", "2", "--episodes", "1:", "--action", "grasp")
    assert code == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["1", "2", "dataset.json"]
    for e in (1, 2):
        check_episode(out, e, "grasp", LENGTHS[e], ["top"], stride=2)
        assert not (out / str(e) / "grasp" / "wrist").exists()
    assert json.loads((out / "dataset.json").read_text())["cameras"] == ["top"]
    code, err = run("lerobot", v21, tmp_path / "out2", "--episodes", ":1")
    assert code == 0, err
    assert sorted(p.name for p in (tmp_path / "out2").iterdir()) == ["0", "dataset.json"]


def test_lerobot_image_feature(v21, tmp_path):
    """`dtype: image` cameras: PNG bytes in the parquet (struct<bytes, path>), read exactly."""
    src = copy_tree(v21, tmp_path / "images")
    info = json.loads((src / "meta/info.json").read_text())
    info["features"]["observation.images.front"] = {
        "dtype": "image",
        "shape": [H, W, 3],
        "names": None,
    }
    (src / "meta/info.json").write_text(json.dumps(info))
    for e, n in enumerate(LENGTHS):
        path = src / f"data/chunk-000/episode_{e:06d}.parquet"
        pngs = []
        for t in range(n):
            buf = io.BytesIO()
            Image.fromarray(frame(e, t, 2)).save(buf, format="PNG")
            pngs.append({"bytes": buf.getvalue(), "path": f"frame_{t:06d}.png"})
        table = pq.read_table(path)
        column = pa.array(pngs, type=pa.struct([("bytes", pa.binary()), ("path", pa.string())]))
        pq.write_table(table.append_column("observation.images.front", column), path)
    out = tmp_path / "out"
    code, err = run("lerobot", src, out, "--camera", "front", "--camera", "top", "--episodes", "2:")
    assert code == 0, err
    folder = out / "2" / "pick_up_the_red_cube"
    for t in range(LENGTHS[2]):
        np.testing.assert_array_equal(read_png(folder / f"{t}.png"), frame(2, t, 2))
        assert_close(folder / f"top/{t}.png", frame(2, t, 0))


def test_refuses_an_existing_out(v21, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    code, err = run("lerobot", v21, out)
    assert code == 2 and str(out) in err and "not empty" in err
    assert [p.name for p in out.iterdir()] == ["keep.txt"]
    assert not list(tmp_path.glob("*.tmp-*"))
    empty = tmp_path / "empty"
    empty.mkdir()
    assert run("lerobot", v21, empty, "--episodes", "0:1")[0] == 0  # an empty OUT is fine


def copy_tree(src, dst):
    import shutil

    shutil.copytree(src, dst)
    return dst


def assert_fails(args, *needles, out):
    code, err = run(*args, out)
    assert code == 2, err
    assert err.splitlines()[-1].startswith("error: "), err
    assert "Traceback" not in err
    for needle in needles:
        assert str(needle) in err, f"{needle!r} not in {err!r}"
    assert not out.exists()
    assert not list(out.parent.glob(f"{out.name}.tmp-*"))


def test_lerobot_bad_inputs(v21, v30, tmp_path):
    out = tmp_path / "out"
    info = v21 / "meta" / "info.json"
    assert_fails(
        ["lerobot", v21, "--camera", "side"], info, "no camera 'side'", "top, wrist", out=out
    )
    assert_fails(
        ["lerobot", v21, "--state", "observation.joints"],
        info,
        "observation.joints",
        "observation.state",
        "action",
        out=out,
    )
    assert_fails(
        ["lerobot", tmp_path / "nowhere"], tmp_path / "nowhere/meta/info.json", "missing", out=out
    )
    # a video one frame short of its episode's parquet rows
    short = copy_tree(v21, tmp_path / "short")
    mp4 = short / "videos/chunk-000/observation.images.top/episode_000001.mp4"
    encode(mp4, [frame(1, t, 0) for t in range(LENGTHS[1] - 1)])
    assert_fails(
        ["lerobot", short],
        "episode 1",
        mp4,
        f"{LENGTHS[1] - 1} frames",
        f"{LENGTHS[1]} rows",
        out=out,
    )
    # state columns of another width in one episode
    wide = copy_tree(v21, tmp_path / "wide")
    path = wide / "data/chunk-000/episode_000002.parquet"
    pq.write_table(frames_table(2, LENGTHS[2], 15, width=7), path)
    assert_fails(
        ["lerobot", wide], "episode 2", path, "7 values per row", "earlier episodes have 8", out=out
    )
    # no episodes at all
    empty = copy_tree(v21, tmp_path / "empty")
    for p in (empty / "data").glob("**/*.parquet"):
        p.unlink()
    assert_fails(["lerobot", empty], empty / "data", "empty dataset", out=out)
    assert_fails(["lerobot", v30, "--episodes", "5:"], "no episodes", out=out)


# robomimic-style HDF5

DEMOS = {"demo_1": 5, "demo_2": 7, "demo_10": 6}  # numeric order: 1, 2, 10


def robomimic_arrays(name, n):
    rng = np.random.default_rng(int(name.split("_")[1]))
    return {
        "robot0_joint_pos": rng.normal(size=(n, 7)),
        "robot0_gripper_qpos": rng.normal(size=(n, 2)),
        "robot0_eef_pos": rng.normal(size=(n, 3)),
        "agentview_image": rng.integers(0, 256, size=(n, H, W, 3), dtype=np.uint8),
        "robot0_eye_in_hand_image": rng.integers(0, 256, size=(n, H, W, 3), dtype=np.uint8),
    }


@pytest.fixture(scope="module")
def hdf5(tmp_path_factory):
    path = tmp_path_factory.mktemp("robomimic") / "lift.hdf5"
    with h5py.File(path, "w") as f:
        data = f.create_group("data")
        data.attrs["env_args"] = json.dumps(
            {"env_name": "Lift", "env_kwargs": {"control_freq": 20}}
        )
        for name, n in DEMOS.items():
            obs = data.create_group(f"{name}/obs")
            for key, value in robomimic_arrays(name, n).items():
                obs.create_dataset(key, data=value)
            data[name].create_dataset("actions", data=np.zeros((n, 7)))
    return path


def test_robomimic(hdf5, tmp_path):
    out = tmp_path / "out"
    code, err = run("robomimic", hdf5, out)
    assert code == 0, err
    meta = json.loads((out / "dataset.json").read_text())
    names = [f"robot0_joint_pos_{i}" for i in range(7)] + [
        "robot0_gripper_qpos_0",
        "robot0_gripper_qpos_1",
    ]
    assert meta == {
        "joint_names": names,
        "cameras": ["agentview"],
        "fps": 20,
        "source": f"robomimic:{hdf5}",
    }
    for i, (name, n) in enumerate(DEMOS.items()):
        a = robomimic_arrays(name, n)
        folder = out / str(i) / "lift"
        joints = np.loadtxt(folder / f"joint_{i}.txt", ndmin=2)
        np.testing.assert_array_equal(
            joints, np.concatenate([a["robot0_joint_pos"], a["robot0_gripper_qpos"]], 1)
        )
        for k in range(n):
            np.testing.assert_array_equal(read_png(folder / f"{k}.png"), a["agentview_image"][k])
        assert not (folder / "robot0_eye_in_hand").exists()


def test_robomimic_options(hdf5, tmp_path):
    out = tmp_path / "out"
    code, err = run(
        "robomimic",
        hdf5,
        out,
        "--camera",
        "robot0_eye_in_hand",
        "--camera",
        "agentview_image",
        "--state",
        "robot0_eef_pos",
        "--state",
        "robot0_gripper_qpos",
        "--stride",
        "3",
        "--episodes",
        "1:3",
        "--action",
        "lift_cube",
    )
    assert code == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["1", "2", "dataset.json"]
    meta = json.loads((out / "dataset.json").read_text())
    assert meta["cameras"] == ["robot0_eye_in_hand", "agentview"]
    assert meta["joint_names"][:3] == ["robot0_eef_pos_0", "robot0_eef_pos_1", "robot0_eef_pos_2"]
    for i, (name, n) in list(enumerate(DEMOS.items()))[1:]:
        a = robomimic_arrays(name, n)
        folder = out / str(i) / "lift_cube"
        joints = np.loadtxt(folder / f"joint_{i}.txt", ndmin=2)
        np.testing.assert_array_equal(
            joints, np.concatenate([a["robot0_eef_pos"], a["robot0_gripper_qpos"]], 1)[::3]
        )
        for k, t in enumerate(range(0, n, 3)):
            np.testing.assert_array_equal(
                read_png(folder / f"{k}.png"), a["robot0_eye_in_hand_image"][t]
            )
            np.testing.assert_array_equal(
                read_png(folder / f"agentview/{k}.png"), a["agentview_image"][t]
            )


def test_robomimic_bad_inputs(hdf5, tmp_path):
    out = tmp_path / "out"
    assert_fails(
        ["robomimic", hdf5, "--camera", "frontview"],
        hdf5,
        "'frontview'",
        "agentview, robot0_eye_in_hand",
        out=out,
    )
    broken = tmp_path / "broken.hdf5"
    import shutil

    shutil.copy(hdf5, broken)
    with h5py.File(broken, "a") as f:
        del f["data/demo_10/obs/robot0_gripper_qpos"]
    assert_fails(
        ["robomimic", broken],
        broken,
        "'demo_10'",
        "'robot0_gripper_qpos'",
        "robot0_joint_pos",
        out=out,
    )
    empty = tmp_path / "empty.hdf5"
    with h5py.File(empty, "w") as f:
        f.create_group("data")
    assert_fails(["robomimic", empty], empty, "no demos", out=out)


# DMBN -> LeRobot -> DMBN


def write_sim(root):
    """Simulator-like DMBN data: 2 ids x grasp/move, 64x64 frames, 7 joints, object/endpoint."""
    truth = {}
    for i in range(2):
        for a, action in enumerate(["grasp", "move"]):
            folder = root / str(i) / action
            folder.mkdir(parents=True)
            n = 8 + 2 * i + a
            joints = (
                np.random.default_rng(10 * i + a).uniform(-1, 1, size=(n, 7)).astype(np.float32)
            )
            (folder / f"joint_{i}.txt").write_text(
                "".join(" ".join(str(v) for v in row) + "\n" for row in joints)
            )
            (folder / f"object_{i}.txt").write_text("0.1 0.2\n" * n)
            (folder / f"endpoint_{i}.txt").write_text("0.3 0.4 0.5\n" * n)
            images = []
            for t in range(n):
                y, x = np.mgrid[0:64, 0:64]
                img = np.stack([90 + x, 80 + y, np.full_like(x, 120 + 40 * a)], -1)
                img[20 + t : 32 + t, 10 + 3 * i : 22 + 3 * i] = [200, 60, 40]  # a moving block
                images.append(img.astype(np.uint8))
                Image.fromarray(images[-1]).save(folder / f"{t}.png")
            truth[(i, action)] = (joints, images)
    return truth


def test_round_trip(tmp_path):
    sim = tmp_path / "sim"
    truth = write_sim(sim)
    lr, back = tmp_path / "lerobot", tmp_path / "back"
    code, err = run("to-lerobot", sim, lr, "--fps", "15")
    assert code == 0, err
    info = json.loads((lr / "meta/info.json").read_text())
    assert info["codebase_version"] == "v2.1" and info["total_episodes"] == 4 and info["fps"] == 15
    assert info["features"]["observation.images.image"]["shape"] == [64, 64, 3]
    tasks = [
        json.loads(line)["task"] for line in (lr / "meta/tasks.jsonl").read_text().splitlines()
    ]
    assert tasks == ["grasp", "move"]
    table = pq.read_table(lr / "data/chunk-000/episode_000000.parquet")
    assert pa.types.is_fixed_size_list(table.schema.field("observation.state").type)
    state0, action0 = (
        np.array(table[c].to_pylist(), dtype=np.float32) for c in ("observation.state", "action")
    )
    np.testing.assert_array_equal(action0[:-1], state0[1:])
    code, err = run("lerobot", lr, back)
    assert code == 0, err
    for e, ((_, action), (joints, images)) in enumerate(sorted(truth.items())):
        folder = back / str(e) / action
        np.testing.assert_array_equal(
            np.loadtxt(folder / f"joint_{e}.txt", dtype=np.float32, ndmin=2), joints
        )
        for t, image in enumerate(images):
            assert_close(folder / f"{t}.png", image.astype(np.float64))
    meta = json.loads((back / "dataset.json").read_text())
    assert meta["cameras"] == ["image"] and meta["fps"] == 15 and len(meta["joint_names"]) == 7


def test_to_lerobot_bad_inputs(tmp_path):
    sim = tmp_path / "sim"
    write_sim(sim)
    out = tmp_path / "out"
    odd = sim / "1/move/3.png"
    Image.new("RGB", (32, 64)).save(odd)
    assert_fails(["to-lerobot", sim], odd, "32x64", "64x64", "one size per sequence", out=out)
    Image.new("RGB", (64, 64)).save(odd)
    with open(sim / "1/grasp/joint_1.txt", "w") as f:
        f.write("0 1 2\n" * 10)
    assert_fails(
        ["to-lerobot", sim],
        sim / "1/grasp/joint_1.txt",
        "3 values per row",
        "earlier episodes have 7",
        out=out,
    )
    assert_fails(["to-lerobot", tmp_path / "nothing"], tmp_path / "nothing", out=out)
    (tmp_path / "bare").mkdir()
    assert_fails(["to-lerobot", tmp_path / "bare"], "no episodes", out=out)


def test_cli_exit_code_without_traceback(tmp_path):
    """The real entry point: `python3 -m dmbn_convert` prints one error line and exits 2."""
    import subprocess

    env = dict(
        os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1]), PYTHONDONTWRITEBYTECODE="1"
    )
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "dmbn_convert",
            "lerobot",
            str(tmp_path / "none"),
            str(tmp_path / "out"),
        ],
        capture_output=True,
        text=True,
        env=env,
    )
    assert r.returncode == 2 and r.stderr.startswith("error: ") and "Traceback" not in r.stderr, (
        r.stderr
    )
