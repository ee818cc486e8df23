#!/usr/bin/env python3
"""Writes large recordings for the recording benchmarks (not committed):

    venv/bin/python scripts/bench_recordings.py OUT_DIR [--gigabytes 2]

- OUT_DIR/rs300.bag: 300 frames of 640x480 from librealsense 2.55's recorder
  (lz4, depth from a depth imager, aligned on reading), for `upetrack export`;
- OUT_DIR/big.bag: the same scene repeated until the file is about
  --gigabytes large (uncompressed chunks, as the RealSense Viewer's default),
  for the first frame on the page and `upetrack info`.

Same environment as scripts/make_recordings.py; then run
scripts/bench_recordings.sh OUT_DIR for the table.
"""

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image

sys.path.insert(0, str(Path(__file__).resolve().parent))
import make_recordings as mr  # noqa: E402


def scene(tmp, frames):
    exe = mr.ROOT / "target" / "release" / "upetrack"
    subprocess.run([str(exe), "synth", "dynamic-pull", str(tmp), "--frames", str(frames)], check=True)
    intr = json.loads((tmp / "camera_intrinsic.json").read_text())
    m = intr["intrinsic_matrix"]
    cam = dict(width=intr["width"], height=intr["height"], fx=m[0], fy=m[4], cx=m[6], cy=m[7])
    colors = [np.asarray(Image.open(tmp / "color" / f"{i:06d}.jpg").convert("RGB")) for i in range(frames)]
    depths = [np.asarray(Image.open(tmp / "depth" / f"{i:06d}.png"), dtype=np.uint16) for i in range(frames)]
    return cam, colors, depths


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--gigabytes", type=float, default=2.0)
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    # The depth imager of a D435i at 640x480.
    mr.DEPTH_FX, mr.DEPTH_PPX, mr.DEPTH_PPY = 384.0, 322.6, 238.8
    with tempfile.TemporaryDirectory() as tmp:
        cam, colors, depths = scene(Path(tmp) / "scene", 300)
    mr.write_librealsense(cam, colors, depths, path=out / "rs300.bag", compress=True)
    per_frame = cam["width"] * cam["height"] * 5
    n = int(a.gigabytes * 1e9 / per_frame)
    reps = [k % 300 for k in range(n)]
    mr.write_librealsense(cam, [colors[k] for k in reps], [depths[k] for k in reps],
                          path=out / "big.bag", compress=False)
    for f in sorted(out.glob("*.bag")):
        print(f"{f}: {f.stat().st_size / 1e9:.2f} GB")


if __name__ == "__main__":
    sys.exit(main())
