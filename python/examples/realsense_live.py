"""Track a rope live from a RealSense camera, or from a recording, with upetrack.

    python realsense_live.py                          # the connected camera
    python realsense_live.py --bag recording.bag      # a recording, as fast as it plays
    python realsense_live.py --bag recording.bag --headless --frames 30

The colour range defaults to a blue rope (OpenCV's HSV: (90, 90, 30) to
(130, 255, 255)); give another with --hsv H S V H S V. Each frame prints the
number of visible nodes and the step's time; with OpenCV installed and
without --headless, the nodes are drawn over the colour image.
"""

import argparse
import sys

import numpy as np
import pyrealsense2 as rs

import upetrack


def project(nodes, intr):
    """Pixel coordinates of camera-frame points (metres)."""
    z = np.maximum(nodes[:, 2], 1e-6)
    return np.stack([intr.fx * nodes[:, 0] / z + intr.cx, intr.fy * nodes[:, 1] / z + intr.cy], axis=1)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bag", help="play a recording (.bag or .db3) instead of the camera")
    ap.add_argument("--frames", type=int, help="stop after this many frames")
    ap.add_argument("--headless", action="store_true", help="print only, draw nothing")
    ap.add_argument("--hsv", type=int, nargs=6, metavar="N", help="colour range: H S V low, then high")
    ap.add_argument("--algorithm", default="upetrack", choices=upetrack.algorithms())
    args = ap.parse_args(argv)

    pipeline, config = rs.pipeline(), rs.config()
    if args.bag:
        config.enable_device_from_file(args.bag, repeat_playback=False)
    else:
        config.enable_stream(rs.stream.color, 640, 480, rs.format.rgb8, 30)
        config.enable_stream(rs.stream.depth, 640, 480, rs.format.z16, 30)
    profile = pipeline.start(config)
    if args.bag:
        profile.get_device().as_playback().set_real_time(False)
    align = rs.align(rs.stream.color)
    color_profile = profile.get_stream(rs.stream.color).as_video_stream_profile()
    intrinsics = upetrack.Intrinsics.from_realsense(color_profile.get_intrinsics())
    depth_scale = profile.get_device().first_depth_sensor().get_depth_scale()
    hsv = (tuple(args.hsv[:3]), tuple(args.hsv[3:])) if args.hsv else None
    tracker = upetrack.Tracker(intrinsics, algorithm=args.algorithm, depth_scale=depth_scale, hsv=hsv)

    cv2 = None
    if not args.headless:
        try:
            import cv2  # noqa: F811 (optional)
        except ImportError:
            print("OpenCV is not installed: printing only", file=sys.stderr)

    tracked = 0
    try:
        while args.frames is None or tracked < args.frames:
            try:
                frames = pipeline.wait_for_frames(5000)
            except RuntimeError:
                break  # the recording has ended
            frames = align.process(frames)
            color_frame, depth_frame = frames.get_color_frame(), frames.get_depth_frame()
            if not color_frame or not depth_frame:
                continue
            color = np.asanyarray(color_frame.get_data())
            if color_frame.get_profile().format() == rs.format.bgr8:
                color = np.ascontiguousarray(color[:, :, ::-1])
            depth = np.asanyarray(depth_frame.get_data())
            result = tracker.step(color, depth)
            tracked += 1
            state = f"lost ({result.reason})" if result.lost else f"{int(result.visible.sum())} visible nodes"
            print(f"frame {tracked}: {state}, step {result.track_ms:.2f} ms, frame {result.total_ms:.2f} ms")
            if cv2 is not None:
                image = np.ascontiguousarray(color[:, :, ::-1])
                for (u, v), seen in zip(project(result.nodes, intrinsics), result.visible):
                    cv2.circle(image, (int(u), int(v)), 4, (0, 0, 230) if seen else (0, 210, 255), -1)
                cv2.imshow("upetrack", image)
                if cv2.waitKey(1) == 27:
                    break
    finally:
        pipeline.stop()
    return tracked


if __name__ == "__main__":
    main()
