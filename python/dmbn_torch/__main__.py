"""`python -m dmbn_torch check MODEL.safetensors PREDICTION.safetensors [--tolerance 1e-4]
[--out F]`: compares the twin with `dmbn predict --arrays` (the inputs are in the prediction
file) and exits 1 when any value differs by more than the tolerance. Training has its own
command line: `python -m dmbn_torch.train --help`."""
import argparse
import json
import sys

from .model import load


def check(model_path, prediction_path, tolerance, out_path=None):
    """The largest difference between this twin and `dmbn predict --arrays`, per output;
    returns whether all are within `tolerance`. With `out_path`, saves the twin's prediction
    there (same names and shapes)."""
    from safetensors.torch import load_file, save_file

    arrays = load_file(prediction_path)
    model = load(model_path)
    out = model.predict(arrays["observed_frames"], arrays["observed_joints"],
                        arrays["observed_times"], arrays["target_times"],
                        float(arrays["blend"][0]))
    if out_path:
        save_file({k: v.contiguous() for k, v in out.items()}, out_path)
    worst = {k: float((out[k] - arrays[k]).abs().max()) for k in out}
    ok = all(v <= tolerance for v in worst.values())
    print(json.dumps({"model": model.config["kind"], "max_abs_diff": worst,
                      "tolerance": tolerance, "ok": ok}))
    return ok


def main():
    parser = argparse.ArgumentParser(prog="python -m dmbn_torch",
                                     description="The PyTorch twin of dmbn's models.")
    sub = parser.add_subparsers(dest="command", required=True)
    c = sub.add_parser("check", help="compare with `dmbn predict --arrays`")
    c.add_argument("model")
    c.add_argument("prediction")
    c.add_argument("--tolerance", type=float, default=1e-4)
    c.add_argument("--out", help="also save the twin's prediction (safetensors)")
    args = parser.parse_args()
    sys.exit(0 if check(args.model, args.prediction, args.tolerance, args.out) else 1)


if __name__ == "__main__":
    main()
