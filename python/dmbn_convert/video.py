"""Video frames in and out with PyAV (the same FFmpeg LeRobot's own pyav backend uses)."""

import av
import numpy as np

from . import ConvertError


def read_frames(path, start=0.0, end=None, fps=30):
    """RGB frames [H, W, 3] of the mp4 at `path` shown in [start, end) seconds.

    LeRobot v3.0 packs several episodes into one mp4 and gives each a time range; v2.x has one
    file per episode (start 0, no end). Half a frame of slack absorbs rounded timestamps.
    """
    if not path.is_file():
        raise ConvertError(f"{path}: missing video file")
    slack = 0.5 / fps
    frames = []
    try:
        with av.open(str(path)) as container:
            if not container.streams.video:
                raise ConvertError(f"{path}: no video stream")
            stream = container.streams.video[0]
            base = float(stream.time_base)
            if start > slack:
                container.seek(int((start - slack) / base), stream=stream, backward=True)
            for frame in container.decode(stream):
                t = frame.time if frame.time is not None else (frame.pts or 0) * base
                if t < start - slack:
                    continue
                if end is not None and t >= end - slack:
                    break
                frames.append(frame.to_ndarray(format="rgb24"))
    except av.error.FFmpegError as e:
        raise ConvertError(f"{path}: cannot decode the video ({e})") from None
    return frames


def encoder():
    """The first H.264-or-fallback encoder these PyAV wheels have, with its info.json name."""
    for name, codec in (("libx264", "h264"), ("libopenh264", "h264"), ("mpeg4", "mpeg4")):
        try:
            av.codec.Codec(name, "w")
            return name, codec
        except Exception:  # noqa: BLE001 - PyAV raises several kinds for a missing codec
            continue
    raise ConvertError("PyAV has no H.264 or MPEG-4 encoder")


def write_frames(path, frames, fps, crf=18, gop=2):
    """Encodes RGB frames as an mp4 (yuv420p; GOP 2, as LeRobot does, for cheap seeking).

    yuv420p needs an even width and height: odd ones are encoded yuv444p instead.
    """
    name, _ = encoder()
    h, w = frames[0].shape[:2]
    pix_fmt = "yuv420p" if h % 2 == 0 and w % 2 == 0 else "yuv444p"
    with av.open(str(path), "w") as container:
        stream = container.add_stream(name, rate=int(fps))
        stream.width, stream.height, stream.pix_fmt = w, h, pix_fmt
        if name == "libx264":
            stream.options = {"crf": str(crf), "g": str(gop)}
        for image in frames:
            frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(image), format="rgb24")
            container.mux(stream.encode(frame))
        container.mux(stream.encode())
    return pix_fmt
