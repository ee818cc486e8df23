#!/usr/bin/env python3
"""Upstream TrackDLO (RMDLO/trackdlo, MIT) against ours over whole sequences.

Builds sequence_driver.cpp (ours) against the upstream sources in
../shared/upstream/trackdlo, as make_goldens.py builds its driver, with
OpenCV (Debian: libopencv-dev) for the colour conversion, the mask and the
edge drawing the ROS node uses. For each sequence folder given it then

1. tracks it with our TrackDLO under `--params trackdlo-upstream` (the
   evaluation launch values, 5 mm voxels, the cloud on the rope's surface),
2. runs upstream's per-frame pipeline and tracking step over the same
   frames, initialised with the nodes ours initialised with (the node takes
   them from initialize.py, which needs ROS), with the same M,
3. scores both with `upetrack score` and prints one table.

    cargo build --release -p upetrack-cli
    python3 tests/data/trackdlo-upstream/compare_sequences.py target/compare-data/static-s-150f-seed1 ...

KEEP_DIR=<dir> keeps the built driver and both result files there.

UPSTREAM_INIT=<python> runs upstream's own initialiser instead
(upstream_init.py: initialize.py without ROS, with that interpreter, which
needs numpy, scipy, opencv-python-headless, scikit-image and pillow): then
the upstream row is upstream's whole pipeline, its initialiser included,
and the table adds UPETrack's own result on the same frames.

Single-colour mode with the sequence's own HSV range (the evaluation launch
file's multi-colour thresholds are fixed to blue, red and yellow ropes).
"""
import glob
import json
import os
import subprocess
import sys
import tempfile

from make_goldens import HERE, ROOT, PARAMS, build

# trackdlo_eval.launch, besides PARAMS.
D_VIS = 0.06
DLO_PIXEL_WIDTH = 30
LEAF = 0.005
UPETRACK = os.path.join(ROOT, "target", "release", "upetrack")
OPENCV = ["-I/usr/include/opencv4", "-lopencv_imgcodecs", "-lopencv_imgproc", "-lopencv_core"]


def frames_of(seq, folder_names, exts):
    for name in folder_names:
        d = os.path.join(seq, name)
        if os.path.isdir(d):
            return sorted(p for p in glob.glob(os.path.join(d, "*")) if p.lower().endswith(exts))
    raise SystemExit(f"{seq}: no {folder_names[0]} folder")


def job(seq, init):
    intr = json.load(open(os.path.join(seq, "camera_intrinsic.json")))
    k = intr["intrinsic_matrix"]
    dlo = json.load(open(os.path.join(seq, "dlo.json")))
    seg = dlo["segmentation"]
    colour = frames_of(seq, ["color", "rgb", "image"], (".jpg", ".jpeg", ".png"))
    depth = frames_of(seq, ["depth"], (".png",))
    assert len(colour) == len(depth), f"{seq}: {len(colour)} colour, {len(depth)} depth frames"
    p = PARAMS
    lines = [
        f"{k[0]} {k[4]} {k[6]} {k[7]} {intr['width']} {intr['height']} {dlo.get('depth_scale', 0.001)}",
        f"{p['visibility_threshold']} {p['beta']} {p['lambda_']} {p['alpha']} {p['k_vis']} {p['mu']} "
        f"{p['max_iter']} {p['tol']} {p['beta_pre_proc']} {p['lambda_pre_proc']} {p['lle_weight']}",
        f"{D_VIS} {DLO_PIXEL_WIDTH} {LEAF}",
        " ".join(str(v) for v in seg["hsv_lower"] + seg["hsv_upper"]),
        str(len(init)),
        *(" ".join(repr(c) for c in n) for n in init),
        str(len(colour)),
    ]
    for i, (c, d) in enumerate(zip(colour, depth)):
        rects = [o["rect"] for o in dlo.get("occlusions", []) if o["frames"][0] <= i <= o["frames"][1]]
        lines.append(f"{c} {d} {len(rects)} " + " ".join(" ".join(str(v) for v in r) for r in rects))
    return "\n".join(lines) + "\n"


def main():
    seqs = sys.argv[1:]
    if not seqs:
        raise SystemExit(__doc__)
    sys.stdout.reconfigure(line_buffering=True)
    keep = os.environ.get("KEEP_DIR")  # keeps the driver and both results there
    with tempfile.TemporaryDirectory() as scratch:
        tmp = keep or scratch
        os.makedirs(tmp, exist_ok=True)
        exe = build(tempfile.mkdtemp(dir=tmp), "sequence_driver.cpp", OPENCV)
        for seq in seqs:
            name = os.path.basename(os.path.normpath(seq))
            ours = os.path.join(tmp, f"{name}.ours.json")
            subprocess.run([UPETRACK, "track", seq, "--params", "trackdlo-upstream", "--out", ours],
                           check=True, stderr=subprocess.DEVNULL)
            init = json.load(open(ours))["frames"][0]["nodes"]
            python = os.environ.get("UPSTREAM_INIT")
            extra = []
            if python:
                r = subprocess.run([python, os.path.join(HERE, "upstream_init.py"), seq, str(len(init))],
                                   capture_output=True, text=True)
                if r.returncode != 0:
                    last = r.stderr.strip().splitlines()[-1:] or ["no message"]
                    print(f"{name}: upstream's initialiser failed: {last[0]}", file=sys.stderr)
                    continue
                init = json.loads(r.stdout)
                upe = os.path.join(tmp, f"{name}.upetrack.json")
                subprocess.run([UPETRACK, "track", seq, "--out", upe], check=True, stderr=subprocess.DEVNULL)
                extra = [upe]
            upstream = os.path.join(tmp, f"{name}.upstream.json")
            with open(upstream, "w") as out:
                r = subprocess.run([exe], input=job(seq, init), stdout=out, stderr=subprocess.PIPE, text=True)
            if r.stderr and r.returncode == 0:
                sys.stderr.write(r.stderr)
            if r.returncode != 0:
                print(f"{name}: upstream stopped: {r.stderr.strip()}", file=sys.stderr)
                continue
            table = subprocess.run([UPETRACK, "score", seq, upstream, ours, *extra], check=True,
                                   capture_output=True, text=True).stdout
            rows = [l for l in table.splitlines() if l.startswith("|")]
            if seq == seqs[0]:
                print("\n".join(rows[:2]))
            print("\n".join(rows[2:]))


if __name__ == "__main__":
    main()
