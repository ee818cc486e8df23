"""What the package costs per frame over the core's own time (a benchmark,
not a test): `Tracker.step` timed from Python against the `total_ms` the
core measures inside it, on the frames of each sequence given.

    python python/bench_step.py samples/dynamic-pull /tmp/s1280 [--repeat 3]
"""

import argparse
import statistics
import time

import upetrack


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("sequences", nargs="+")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print("| sequence | size | frames x runs | median step() wall ms | median core total_ms | median overhead ms |")
    print("|---|---|---:|---:|---:|---:|")
    for path in args.sequences:
        seq = upetrack.open(path)
        frames = [seq[i] for i in range(len(seq))]
        walls, cores, overheads = [], [], []
        for _ in range(args.repeat):
            tracker = seq.tracker()
            for i, (color, depth) in enumerate(frames):
                occlusions = seq.occlusions_at(i)
                t0 = time.perf_counter()
                r = tracker.step(color, depth, occlusions=occlusions)
                wall = 1000.0 * (time.perf_counter() - t0)
                walls.append(wall)
                cores.append(r.total_ms)
                overheads.append(wall - r.total_ms)
        i = seq.intrinsics
        print(
            f"| {path} | {i.width}x{i.height} | {len(frames)} x {args.repeat} | "
            f"{statistics.median(walls):.3f} | {statistics.median(cores):.3f} | {statistics.median(overheads):.3f} |"
        )


if __name__ == "__main__":
    main()
