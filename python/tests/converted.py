"""Writes one converted dataset of each format into OUT (for tests outside pytest).

    python python/tests/converted.py OUT

OUT/lerobot (a LeRobot v2.1 dataset: 8 state values, two cameras, 48 x 32 frames) and
OUT/lift.hdf5 (a robomimic file: 7 joint positions + 2 gripper values), written by the suite's
fixtures, are converted into OUT/from-lerobot and OUT/from-robomimic (DMBN layout). Used by
tests/convert.rs (train and score on them) and tests/browser/folder.test.mjs (the page opens
them). Exit code: the converters'.
"""

import json
import sys
from pathlib import Path

import h5py

sys.path.insert(0, str(Path(__file__).resolve().parent))
import test_convert as t  # noqa: E402


def write(out):
    t.write_v21(out / "lerobot")
    with h5py.File(out / "lift.hdf5", "w") as f:
        data = f.create_group("data")
        data.attrs["env_args"] = json.dumps({"env_name": "Lift"})
        for name, n in {"demo_0": 9, "demo_1": 8, "demo_2": 10}.items():
            obs = data.create_group(f"{name}/obs")
            for key, value in t.robomimic_arrays(name, n).items():
                obs.create_dataset(key, data=value)
    code = t.main(["lerobot", str(out / "lerobot"), str(out / "from-lerobot"), "--action", "pick"])
    code |= t.main(
        ["robomimic", str(out / "lift.hdf5"), str(out / "from-robomimic"), "--action", "lift"]
    )
    return code


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    sys.exit(write(Path(sys.argv[1])))
