"""The DMBN layout's writer, and the helpers every converter shares.

Layout: `<root>/<id>/<action>/<k>.png` (default camera), `<root>/<id>/<action>/<camera>/<k>.png`
(further cameras), `<root>/<id>/<action>/joint_<id>.txt` (T rows of D numbers) and
`<root>/dataset.json` (joint names, cameras, fps, source). The writer checks what the Rust
reader would otherwise trip over later (finite values, one D for the whole dataset, one image
size per sequence, T frames per camera) and names the source in each message.
"""

import json
import os
import re
import shutil
import sys
from pathlib import Path

import numpy as np
from PIL import Image
from tqdm import tqdm

from . import ConvertError


def safe_action(task, forced=None):
    """A folder name for an episode's task: lowercase, runs of non-alnum -> '_', max 40 chars."""
    if forced:
        name = forced
    else:
        name = re.sub(r"[^a-z0-9]+", "_", str(task or "").lower()).strip("_")[:40].strip("_")
    if not name:
        return "episode"
    if "/" in name or name.startswith(".") or name in (".", ".."):
        raise ConvertError(f"--action {name!r}: expected a plain folder name (no '/', not hidden)")
    return name


def parse_range(text):
    """`A:B` (either may be empty) as a slice over the episodes, in their source order."""
    if text is None:
        return slice(None)
    parts = text.split(":")
    try:
        if len(parts) != 2:
            raise ValueError
        a, b = (int(p) if p.strip() else None for p in parts)
    except ValueError:
        raise ConvertError(f"--episodes {text!r}: expected A:B (e.g. 0:10, 5:, :3)") from None
    return slice(a, b)


def check_stride(stride):
    if stride < 1:
        raise ConvertError(f"--stride {stride}: expected a positive integer")
    return stride


def format_row(row):
    """Shortest text that reads back as the same value at the row's own precision."""
    if row.dtype == np.float32:
        return " ".join(str(v) for v in row)  # numpy's shortest float32 repr
    return " ".join(repr(float(v)) for v in row)


def progress(items, desc):
    """A progress bar over episodes on stderr, closed (ending its line) however the loop ends."""
    with tqdm(total=len(items), desc=desc, unit="episode", file=sys.stderr) as bar:
        for item in items:
            yield item
            bar.update()


class DmbnWriter:
    """Writes episodes into `OUT.tmp-<pid>`; `finish` renames it to OUT, `abort` removes it.

    Use as a context manager: an exception inside the block removes the temporary folder.
    """

    def __init__(self, out, cameras, source):
        self.out = Path(out)
        if self.out.exists() and (not self.out.is_dir() or any(self.out.iterdir())):
            raise ConvertError(f"{self.out}: exists and is not empty (refusing to overwrite it)")
        self.cameras = list(cameras)
        self.source = source
        self.tmp = self.out.parent / f"{self.out.name}.tmp-{os.getpid()}"
        self.width = None  # D, from the first episode
        self.count = 0

    def __enter__(self):
        self.out.parent.mkdir(parents=True, exist_ok=True)
        shutil.rmtree(self.tmp, ignore_errors=True)
        self.tmp.mkdir()
        return self

    def __exit__(self, kind, value, tb):
        if kind is not None:
            shutil.rmtree(self.tmp, ignore_errors=True)
        return False

    def episode(self, ident, action, joints, frames, where):
        """One episode: `joints` [T, D]; `frames[camera]` T RGB arrays [H, W, 3] (uint8).

        `where` names the source (a file, an episode) in the error messages.
        """
        joints = np.asarray(joints)
        if joints.ndim == 1:
            joints = joints[:, None]
        if joints.ndim != 2 or len(joints) == 0 or joints.shape[1] == 0:
            raise ConvertError(
                f"{where}: expected a non-empty [T, D] state, got shape {joints.shape}"
            )
        if not np.issubdtype(joints.dtype, np.floating):
            joints = joints.astype(np.float64)
        if not np.isfinite(joints).all():
            row = int(np.argwhere(~np.isfinite(joints))[0][0])
            raise ConvertError(f"{where}: state row {row} holds a non-finite value")
        if self.width is None:
            self.width = joints.shape[1]
        elif joints.shape[1] != self.width:
            raise ConvertError(
                f"{where}: state has {joints.shape[1]} values per row, "
                f"earlier episodes have {self.width}"
            )
        folder = self.tmp / str(ident) / action
        if folder.exists():
            raise ConvertError(f"{where}: episode {ident}/{action} written twice")
        folder.mkdir(parents=True)
        for n, camera in enumerate(self.cameras):
            images = frames[camera]
            if len(images) != len(joints):
                raise ConvertError(
                    f"{where}: camera {camera!r} has {len(images)} frames, "
                    f"the state {len(joints)} rows"
                )
            target = folder if n == 0 else folder / camera
            target.mkdir(exist_ok=True)
            for k, image in enumerate(images):
                image = np.asarray(image)
                if image.dtype != np.uint8 or image.ndim != 3 or image.shape[2] != 3:
                    raise ConvertError(
                        f"{where}: camera {camera!r} frame {k}: expected RGB uint8 [H, W, 3], "
                        f"got {image.dtype} {list(image.shape)}"
                    )
                if image.shape != np.shape(images[0]):
                    h, w = np.shape(images[0])[:2]
                    raise ConvertError(
                        f"{where}: camera {camera!r} frame {k} is "
                        f"{image.shape[1]}x{image.shape[0]}, frame 0 is {w}x{h} "
                        "(expected one size per sequence)"
                    )
                Image.fromarray(image).save(target / f"{k}.png", compress_level=1)
        text = "\n".join(format_row(row) for row in joints) + "\n"
        (folder / f"joint_{ident}.txt").write_text(text)
        self.count += 1

    def finish(self, joint_names, fps):
        """Writes dataset.json and renames the temporary folder to OUT."""
        if self.count == 0:
            raise ConvertError(f"{self.source}: no episodes to write (empty dataset or range)")
        names = list(joint_names or [])
        if len(names) != self.width:
            names = [f"j{i}" for i in range(self.width)]
        meta = {"joint_names": names, "cameras": self.cameras}
        if fps:
            meta["fps"] = fps
        meta["source"] = self.source
        (self.tmp / "dataset.json").write_text(json.dumps(meta, indent=2) + "\n")
        if self.out.exists():
            self.out.rmdir()  # empty, checked at the start
        os.rename(self.tmp, self.out)
