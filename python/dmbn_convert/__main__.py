"""`python3 -m dmbn_convert {lerobot,robomimic,to-lerobot} ...`: see README.md.

Expected failures (bad input, an existing OUT) print `error: <message>` and exit 2, without a
traceback; the output folder is then absent (everything is written to `OUT.tmp-<pid>` first).
"""

import argparse
import sys

from . import ConvertError


def parser():
    p = argparse.ArgumentParser(prog="python3 -m dmbn_convert", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)

    def common(s):
        s.add_argument("--stride", type=int, default=1, help="keep every N-th frame/row")
        s.add_argument("--episodes", metavar="A:B", help="episode range, A inclusive, B exclusive")
        s.add_argument("--action", metavar="NAME", help="one action folder name for every episode")

    s = sub.add_parser("lerobot", help="a LeRobot dataset (v2.x, v3.0) -> the DMBN layout")
    s.add_argument("src")
    s.add_argument("out")
    s.add_argument(
        "--camera", action="append", help="camera key or short name (repeatable; first = default)"
    )
    s.add_argument(
        "--state", default="observation.state", help="state feature (default observation.state)"
    )
    common(s)

    s = sub.add_parser("robomimic", help="a robomimic-style HDF5 file -> the DMBN layout")
    s.add_argument("src", metavar="FILE.hdf5")
    s.add_argument("out")
    s.add_argument(
        "--camera", action="append", help="camera (agentview or agentview_image; repeatable)"
    )
    s.add_argument(
        "--state", action="append", help="obs key (repeatable, concatenated column-wise)"
    )
    common(s)

    s = sub.add_parser("to-lerobot", help="a DMBN-layout dataset -> a LeRobot v2.1 dataset")
    s.add_argument("src")
    s.add_argument("out")
    s.add_argument("--fps", type=int, help="frames per second (default dataset.json's, else 30)")
    s.add_argument("--camera", action="append", help="camera to write (repeatable; default all)")
    s.add_argument("--crf", type=int, default=18, help="libx264 quality, 0 = lossless (default 18)")
    return p


def main(argv=None):
    args = parser().parse_args(argv)
    try:
        if args.command == "lerobot":
            from .lerobot import convert

            n = convert(
                args.src, args.out, args.camera, args.state, args.stride, args.episodes, args.action
            )
        elif args.command == "robomimic":
            from .robomimic import convert

            n = convert(
                args.src, args.out, args.camera, args.state, args.stride, args.episodes, args.action
            )
        else:
            from .to_lerobot import convert

            n = convert(args.src, args.out, args.fps, args.camera, args.crf)
    except ConvertError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    print(f"wrote {n} episodes to {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
