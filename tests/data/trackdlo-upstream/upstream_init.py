#!/usr/bin/env python3
"""Upstream TrackDLO's own initialiser (initialize.py) on a sequence's
first frame, without ROS: its rospy, ros_numpy and message imports are
stubbed, its globals set as its main block would from the launch file, and
its `callback()` called with the first colour and depth images. Prints the
initial nodes (metres, camera frame) as JSON.

    /path/to/venv/bin/python upstream_init.py <sequence> <num_of_nodes>

Needs numpy, scipy, opencv-python-headless, scikit-image and pillow (a venv
from the registry). The upstream sources are read, never copied: set
TRACKDLO_UPSTREAM, else ../shared/upstream/trackdlo beside the repository.
"""
import contextlib
import json
import os
import sys
import traceback
import types

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", "..", ".."))
UPSTREAM = os.environ.get("TRACKDLO_UPSTREAM") or os.path.join(ROOT, "..", "shared", "upstream", "trackdlo")


def stub_ros(captured):
    """Modules initialize.py and utils.py import, doing nothing but what
    the callback needs: numpify returns the array, create_cloud records
    the nodes it is given."""
    def module(name, **attrs):
        m = types.ModuleType(name)
        m.__dict__.update(attrs)
        sys.modules[name] = m
        return m

    class Anything:
        def __init__(self, *a, **k):
            pass

        def __getattr__(self, _):
            return lambda *a, **k: None

    errors = []
    # logerr is called in initialize.py's bare `except:`: keep the traceback.
    module("rospy", Time=types.SimpleNamespace(now=lambda: 0), set_param=lambda *a: None,
           logerr=lambda m: errors.append(f"{m}\n{traceback.format_exc()}"), signal_shutdown=lambda *a: None, Publisher=Anything, Subscriber=Anything)
    module("ros_numpy", numpify=lambda x: x)
    module("sensor_msgs")
    module("sensor_msgs.msg", PointCloud2=Anything, PointField=Anything, Image=Anything, CameraInfo=Anything)

    def create_cloud(header, fields, points):
        captured.append([[float(p[0]), float(p[1]), float(p[2])] for p in points])
    module("sensor_msgs.point_cloud2", create_cloud=create_cloud)
    module("std_msgs")
    module("std_msgs.msg", Header=Anything)
    module("message_filters", Subscriber=Anything, TimeSynchronizer=Anything)
    module("visualization_msgs")
    module("visualization_msgs.msg", Marker=Anything, MarkerArray=Anything)
    return errors


def main():
    if len(sys.argv) != 3:
        raise SystemExit(__doc__)
    seq, nodes = sys.argv[1], int(sys.argv[2])
    captured = []
    errors = stub_ros(captured)
    from compare_sequences import frames_of
    sys.path.insert(0, os.path.join(UPSTREAM, "trackdlo", "src"))
    import cv2
    import numpy as np
    import skimage.morphology as morphology
    # utils.py calls skeletonize(mask, method='zha') on a 3-channel mask.
    # The scikit-image of its day (0.16-0.19) sent any 3-dimensional image to
    # Lee's method whatever the name, and returned 0 / 255 bytes; today's
    # refuses the name and returns booleans. The shim takes the branch the
    # old release took and returns what it returned.
    skeletonize = morphology.skeletonize

    def old_skeletonize(image, method=None):
        if method == "zha" and image.ndim == 3:
            method = "lee"
        return skeletonize(image, method=method).astype(np.uint8) * 255
    morphology.skeletonize = old_skeletonize
    import initialize as up

    intr = json.load(open(os.path.join(seq, "camera_intrinsic.json")))
    k = intr["intrinsic_matrix"]
    dlo = json.load(open(os.path.join(seq, "dlo.json")))
    seg = dlo["segmentation"]
    scale = dlo.get("depth_scale", 0.001)
    colour = frames_of(seq, ["color", "rgb", "image"], (".jpg", ".jpeg", ".png"))[0]
    depth = frames_of(seq, ["depth"], (".png",))[0]
    rgb = cv2.cvtColor(cv2.imread(colour, cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)
    # initialize.py divides depth by 1000: millimetres.
    d = cv2.imread(depth, cv2.IMREAD_UNCHANGED).astype(np.float64) * scale * 1000.0
    # As its main block sets them from the launch file.
    up.proj_matrix = np.array([[k[0], 0, k[6], 0], [0, k[4], k[7], 0], [0, 0, 1, 0]], dtype=float)
    up.lower, up.upper = tuple(seg["hsv_lower"]), tuple(seg["hsv_upper"])
    up.num_of_nodes = nodes
    up.multi_color_dlo = False
    up.visualize_initialization_process = False
    up.result_frame_id = "camera_color_optical_frame"
    up.header = types.SimpleNamespace(stamp=0, frame_id="")
    up.fields = []
    up.pc_pub = up.results_pub = types.SimpleNamespace(publish=lambda *a: None)
    up.ndarray2MarkerArray = lambda *a, **k: None  # RViz markers only
    # Its progress messages go to stderr: stdout is the nodes' JSON.
    with contextlib.redirect_stdout(sys.stderr):
        up.callback(rgb, d.astype(np.uint16))
    if not captured:
        raise SystemExit(f"{seq}: upstream's initialiser failed: {''.join(errors)}")
    json.dump(captured[-1], sys.stdout)


if __name__ == "__main__":
    main()
