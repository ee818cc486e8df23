#!/usr/bin/env python3
"""Writes the recording fixtures of tests/recordings/ with the real writers.

    python3 -m venv venv && venv/bin/pip install pyrealsense2==2.55.1.6486 rosbags numpy pillow
    python3 -m venv venv259 && venv259/bin/pip install pyrealsense2==2.59.1.11053 rosbags numpy pillow
    apt-get install -y libusb-1.0-0            # pyrealsense2's runtime
    cargo build --release -p upetrack-cli
    venv/bin/python scripts/make_recordings.py      # from the repository root: the .bag files
    venv259/bin/python scripts/make_recordings.py   # librealsense 2.59's .db3 and its goldens

From one synthetic scene (`upetrack synth dynamic-pull`, 8 frames, halved to
320x240 so each file stays small) it writes:

- reference/: the scene as a sequence folder (the contract's layout), the
  original that recordings are compared with;
- librealsense.bag: pyrealsense2's own recorder (librealsense 2.55, lz4
  chunks) fed by a software device: colour rgb8 and depth z16 seen by a depth
  imager with its own intrinsics, 15 mm from the colour camera and turned by
  0.3 degrees, so the depth is not aligned to colour, as a real D435i's;
- golden/aligned_<n>.png: pyrealsense2's rs2::align (to colour) of each frame
  of librealsense.bag, played back;
- librealsense.db3 and golden_db3/ (run with pyrealsense2 2.59): the same
  from librealsense 2.59's recorder, which writes rosbag2 in SQLite with
  PNG colour and compressedDepth depth;
- ros2_png.db3 (8 frames, PNG-compressed colour and compressedDepth depth)
  and ros2_raw.db3 (3 frames, raw images): realsense-ros's ROS 2 layout
  (/camera/camera/...) written by `rosbags` in rosbag2's SQLite storage;
- ros2_png.mcap and ros2_raw.mcap: the same in rosbag2's MCAP storage;
- ros_bz2.bag, ros_lz4.bag, ros_none.bag: realsense-ros's layout
  (/camera/color/image_raw bgr8, /camera/aligned_depth_to_color/image_raw
  16UC1 in mm, their camera_info) written by `rosbags`, one per chunk
  compression (8, 4 and 3 frames);
- dlo.json: the colour range and occluder of the scene, for `--dlo`;
- fuzz/seeds/rosbag/: the same writers at 16x12 pixels, 2 frames, as seeds
  for the bag reader's fuzz target.
"""

import json
import math
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from PIL import Image

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "tests" / "recordings"
FRAMES = 8
FPS = 30
# The depth imager: wider field of view, its own principal point (as a D435i's).
DEPTH_FX, DEPTH_PPX, DEPTH_PPY = 192.0, 161.3, 119.4
# Depth to colour: 15 mm baseline and a small turn about y.
BASELINE = [0.0148, 0.0001, 0.0003]
TURN_DEG = 0.3


def rotation_y(deg):
    a = math.radians(deg)
    return np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])


def synth_scene(tmp):
    exe = ROOT / "target" / "release" / "upetrack"
    subprocess.run([str(exe), "synth", "dynamic-pull", str(tmp), "--frames", str(FRAMES)], check=True)
    intr = json.loads((tmp / "camera_intrinsic.json").read_text())
    m = intr["intrinsic_matrix"]
    # Halved: pixel centres map as (c + 0.5) / 2 - 0.5.
    cam = dict(width=intr["width"] // 2, height=intr["height"] // 2, fx=m[0] / 2, fy=m[4] / 2,
               cx=(m[6] + 0.5) / 2 - 0.5, cy=(m[7] + 0.5) / 2 - 0.5)
    colors, depths = [], []
    for i in range(FRAMES):
        c = np.asarray(Image.open(tmp / "color" / f"{i:06d}.jpg").convert("RGB"), dtype=np.float32)
        c = c.reshape(cam["height"], 2, cam["width"], 2, 3).mean(axis=(1, 3))
        colors.append(np.clip(np.round(c), 0, 255).astype(np.uint8))
        d = np.asarray(Image.open(tmp / "depth" / f"{i:06d}.png"), dtype=np.uint16)
        depths.append(d[::2, ::2].copy())
    return cam, colors, depths


def write_reference(tmp, cam, colors, depths):
    ref = OUT / "reference"
    if ref.exists():
        shutil.rmtree(ref)
    (ref / "color").mkdir(parents=True)
    (ref / "depth").mkdir()
    for i in range(FRAMES):
        Image.fromarray(colors[i]).save(ref / "color" / f"{i:06d}.png")
        Image.fromarray(depths[i]).save(ref / "depth" / f"{i:06d}.png")
    (ref / "camera_intrinsic.json").write_text(json.dumps({
        "width": cam["width"], "height": cam["height"],
        "intrinsic_matrix": [cam["fx"], 0, 0, 0, cam["fy"], 0, cam["cx"], cam["cy"], 1]}, indent=1))
    dlo = json.loads((tmp / "dlo.json").read_text())
    for o in dlo["occlusions"]:
        o["rect"] = [v // 2 for v in o["rect"]]
    (ref / "dlo.json").write_text(json.dumps(dlo, indent=1))
    shutil.copy(tmp / "groundtruth.json", ref / "groundtruth.json")
    config = dict(dlo)
    config.pop("groundtruth", None)
    (OUT / "dlo.json").write_text(json.dumps(config, indent=1))


def depth_imager_view(cam, depth):
    """Depth as the depth imager sees it: each colour pixel's point carried
    into the depth camera, nearest surface kept, 0 where nothing lands."""
    h, w = depth.shape
    v, u = np.mgrid[0:h, 0:w]
    z = depth.astype(np.float64) * 0.001
    ok = z > 0
    pc = np.stack([(u - cam["cx"]) / cam["fx"] * z, (v - cam["cy"]) / cam["fy"] * z, z], axis=-1)[ok]
    r, t = rotation_y(TURN_DEG), np.array(BASELINE)
    pd = (pc - t) @ r  # inverse of p_c = R p_d + t
    du = np.round(pd[:, 0] / pd[:, 2] * DEPTH_FX + DEPTH_PPX).astype(int)
    dv = np.round(pd[:, 1] / pd[:, 2] * DEPTH_FX + DEPTH_PPY).astype(int)
    units = np.round(pd[:, 2] / 0.001).astype(np.int64)
    inside = (du >= 0) & (du < w) & (dv >= 0) & (dv < h)
    out = np.full((h, w), np.iinfo(np.int64).max, dtype=np.int64)
    np.minimum.at(out, (dv[inside], du[inside]), units[inside])
    out[out == np.iinfo(np.int64).max] = 0
    return out.astype(np.uint16)


def write_librealsense(cam, colors, depths, path=None, compress=True):
    import pyrealsense2 as rs

    path = path or OUT / "librealsense.bag"
    w, h = cam["width"], cam["height"]
    dev = rs.software_device()
    depth_sensor = dev.add_sensor("Stereo Module")
    color_sensor = dev.add_sensor("RGB Camera")
    di = rs.intrinsics()
    di.width, di.height, di.fx, di.fy, di.ppx, di.ppy = w, h, DEPTH_FX, DEPTH_FX, DEPTH_PPX, DEPTH_PPY
    di.model, di.coeffs = rs.distortion.brown_conrady, [0.0] * 5
    ci = rs.intrinsics()
    ci.width, ci.height, ci.fx, ci.fy, ci.ppx, ci.ppy = w, h, cam["fx"], cam["fy"], cam["cx"], cam["cy"]
    ci.model, ci.coeffs = rs.distortion.inverse_brown_conrady, [0.0] * 5
    profiles = []
    for sensor, kind, uid, bpp, fmt, intr in [
        (depth_sensor, rs.stream.depth, 0, 2, rs.format.z16, di),
        (color_sensor, rs.stream.color, 1, 3, rs.format.rgb8, ci),
    ]:
        vs = rs.video_stream()
        vs.type, vs.index, vs.uid, vs.width, vs.height = kind, 0, uid, w, h
        vs.fps, vs.bpp, vs.fmt, vs.intrinsics = FPS, bpp, fmt, intr
        profiles.append(sensor.add_video_stream(vs))
    depth_sensor.add_read_only_option(rs.option.depth_units, 0.001)
    ex = rs.extrinsics()
    ex.rotation = [float(v) for v in rotation_y(TURN_DEG).T.flatten()]  # column-major
    ex.translation = BASELINE
    profiles[0].register_extrinsics_to(profiles[1], ex)
    recorder = rs.recorder(str(path), dev, compress)
    queue = rs.frame_queue(64)
    depth_sensor.open(profiles[0])
    color_sensor.open(profiles[1])
    depth_sensor.start(queue)
    color_sensor.start(queue)
    keep = []
    for i in range(len(colors)):
        d = np.ascontiguousarray(depth_imager_view(cam, depths[i]))
        c = np.ascontiguousarray(colors[i])
        keep += [d, c]
        for sensor, prof, buf, bpp in [(depth_sensor, profiles[0], d, 2), (color_sensor, profiles[1], c, 3)]:
            f = rs.software_video_frame()
            f.pixels, f.stride, f.bpp = buf, w * bpp, bpp
            f.timestamp, f.domain, f.frame_number = i * 1000.0 / FPS, rs.timestamp_domain.hardware_clock, i
            f.profile = prof.as_video_stream_profile()
            sensor.on_video_frame(f)
        time.sleep(1.0 / FPS)
    time.sleep(0.3)
    del recorder
    return path


def write_goldens(path, gold):
    import pyrealsense2 as rs

    if gold.exists():
        shutil.rmtree(gold)
    gold.mkdir()
    cfg = rs.config()
    cfg.enable_device_from_file(str(path), repeat_playback=False)
    pipe = rs.pipeline()
    prof = pipe.start(cfg)
    prof.get_device().as_playback().set_real_time(False)
    align = rs.align(rs.stream.color)
    n = 0
    while True:
        ok, fs = pipe.try_wait_for_frames(2000)
        if not ok:
            break
        fs = align.process(fs)
        d = np.asanyarray(fs.get_depth_frame().get_data()).copy()
        num = fs.get_color_frame().get_frame_number()
        Image.fromarray(d).save(gold / f"aligned_{num:06d}.png")
        n += 1
    pipe.stop()
    print(f"{n} aligned goldens")


def write_ros(cam, colors, depths, out=None, sizes=None):
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    Img, Info = ts.types["sensor_msgs/msg/Image"], ts.types["sensor_msgs/msg/CameraInfo"]
    Header, Time = ts.types["std_msgs/msg/Header"], ts.types["builtin_interfaces/msg/Time"]
    Roi = ts.types["sensor_msgs/msg/RegionOfInterest"]
    w, h = cam["width"], cam["height"]
    k = np.array([cam["fx"], 0, cam["cx"], 0, cam["fy"], cam["cy"], 0, 0, 1], dtype=np.float64)
    p = np.array([cam["fx"], 0, cam["cx"], 0, 0, cam["fy"], cam["cy"], 0, 0, 0, 1, 0], dtype=np.float64)
    # Frames per file: the uncompressed ones are cut short to stay under 2 MB.
    for name, comp, frames in [("bz2", Writer.CompressionFormat.BZ2, (sizes or [FRAMES])[0]),
                               ("lz4", Writer.CompressionFormat.LZ4, (sizes or [0, 4])[1]),
                               ("none", None, (sizes or [0, 0, 3])[2])]:
        path = (out or OUT) / f"ros_{name}.bag"
        path.unlink(missing_ok=True)
        wr = Writer(path)
        if comp is not None:
            wr.set_compression(comp)
        with wr:
            topics = {}
            for t, ty in [("/camera/color/image_raw", Img), ("/camera/color/camera_info", Info),
                          ("/camera/aligned_depth_to_color/image_raw", Img),
                          ("/camera/aligned_depth_to_color/camera_info", Info)]:
                topics[t] = wr.add_connection(t, ty.__msgtype__, typestore=ts)
            for i in range(frames):
                ns = 1_000_000_000 + i * 1_000_000_000 // FPS
                # Depth arrives 2 ms after colour, as two topics of one camera do.
                for topic, stamp in [("/camera/color", ns), ("/camera/aligned_depth_to_color", ns + 2_000_000)]:
                    hdr = Header(seq=i, stamp=Time(sec=stamp // 10**9, nanosec=stamp % 10**9),
                                 frame_id="camera_color_optical_frame")
                    info = Info(header=hdr, height=h, width=w, distortion_model="plumb_bob",
                                D=np.zeros(5), K=k, R=np.eye(3).flatten(), P=p, binning_x=0, binning_y=0,
                                roi=Roi(x_offset=0, y_offset=0, height=0, width=0, do_rectify=False))
                    if topic == "/camera/color":
                        bgr = np.ascontiguousarray(colors[i][:, :, ::-1])
                        img = Img(header=hdr, height=h, width=w, encoding="bgr8", is_bigendian=0,
                                  step=w * 3, data=bgr.flatten())
                    else:
                        img = Img(header=hdr, height=h, width=w, encoding="16UC1", is_bigendian=0,
                                  step=w * 2, data=depths[i].astype("<u2").view(np.uint8).flatten())
                    wr.write(topics[f"{topic}/image_raw"], stamp, ts.serialize_ros1(img, Img.__msgtype__))
                    wr.write(topics[f"{topic}/camera_info"], stamp, ts.serialize_ros1(info, Info.__msgtype__))


def write_ros2(cam, colors, depths, out=None, sizes=(FRAMES, 3), storage="db3"):
    import io
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    Img, Info = ts.types["sensor_msgs/msg/Image"], ts.types["sensor_msgs/msg/CameraInfo"]
    Comp = ts.types["sensor_msgs/msg/CompressedImage"]
    Header, Time = ts.types["std_msgs/msg/Header"], ts.types["builtin_interfaces/msg/Time"]
    Roi = ts.types["sensor_msgs/msg/RegionOfInterest"]
    w, h = cam["width"], cam["height"]
    k = np.array([cam["fx"], 0, cam["cx"], 0, cam["fy"], cam["cy"], 0, 0, 1], dtype=np.float64)
    p = np.array([cam["fx"], 0, cam["cx"], 0, 0, cam["fy"], cam["cy"], 0, 0, 0, 1, 0], dtype=np.float64)

    def png(array):
        b = io.BytesIO()
        Image.fromarray(array).save(b, format="PNG")
        return np.frombuffer(b.getvalue(), dtype=np.uint8)

    base = "/camera/camera"
    for name, compressed, frames in [("png", True, sizes[0]), ("raw", False, sizes[1])]:
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp) / "bag"
            topics = {}
            plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
            with Writer(folder, version=8, storage_plugin=plugin) as wr:
                for stream in ["color", "aligned_depth_to_color"]:
                    image = f"{base}/{stream}/image_raw"
                    if compressed:
                        image += "/compressed" if stream == "color" else "/compressedDepth"
                    topics[stream] = (wr.add_connection(image, (Comp if compressed else Img).__msgtype__, typestore=ts),
                                      wr.add_connection(f"{base}/{stream}/camera_info", Info.__msgtype__, typestore=ts))
                for i in range(frames):
                    ns = 1_000_000_000 + i * 1_000_000_000 // FPS
                    for stream, stamp in [("color", ns), ("aligned_depth_to_color", ns + 2_000_000)]:
                        hdr = Header(stamp=Time(sec=stamp // 10**9, nanosec=stamp % 10**9),
                                     frame_id="camera_color_optical_frame")
                        info = Info(header=hdr, height=h, width=w, distortion_model="plumb_bob",
                                    d=np.zeros(5), k=k, r=np.eye(3).flatten(), p=p, binning_x=0, binning_y=0,
                                    roi=Roi(x_offset=0, y_offset=0, height=0, width=0, do_rectify=False))
                        if stream == "color" and compressed:
                            msg = Comp(header=hdr, format="rgb8; png compressed bgr8", data=png(colors[i]))
                        elif compressed:
                            head = np.zeros(12, dtype=np.uint8)  # compressedDepth's format and parameters
                            msg = Comp(header=hdr, format="16UC1; compressedDepth png",
                                       data=np.concatenate([head, png(depths[i])]))
                        elif stream == "color":
                            msg = Img(header=hdr, height=h, width=w, encoding="rgb8", is_bigendian=0,
                                      step=w * 3, data=np.ascontiguousarray(colors[i]).flatten())
                        else:
                            msg = Img(header=hdr, height=h, width=w, encoding="16UC1", is_bigendian=0,
                                      step=w * 2, data=depths[i].astype("<u2").view(np.uint8).flatten())
                        image_conn, info_conn = topics[stream]
                        wr.write(image_conn, stamp, ts.serialize_cdr(msg, msg.__msgtype__))
                        wr.write(info_conn, stamp, ts.serialize_cdr(info, Info.__msgtype__))
            stored = next(folder.glob(f"*.{storage}"))
            shutil.copy(stored, (out or OUT) / f"ros2_{name}.{storage}")


def write_seeds(cam, colors, depths, v259):
    seeds = ROOT / "fuzz" / "seeds" / "rosbag"
    seeds.mkdir(parents=True, exist_ok=True)
    small = dict(width=16, height=12, fx=cam["fx"] / 20, fy=cam["fy"] / 20,
                 cx=(cam["cx"] + 0.5) / 20 - 0.5, cy=(cam["cy"] + 0.5) / 20 - 0.5)
    c = [x[::20, ::20].copy() for x in colors[:2]]
    d = [x[::20, ::20].copy() for x in depths[:2]]
    global DEPTH_FX, DEPTH_PPX, DEPTH_PPY
    saved = (DEPTH_FX, DEPTH_PPX, DEPTH_PPY)
    DEPTH_FX, DEPTH_PPX, DEPTH_PPY = 10.0, 8.1, 5.9
    if v259:
        write_librealsense(small, c, d, path=seeds / "librealsense.db3")
    else:
        write_ros(small, c, d, out=seeds, sizes=[2, 2, 2])
        write_ros2(small, c, d, out=seeds, sizes=(2, 2))
        write_ros2(small, c, d, out=seeds, sizes=(2, 2), storage="mcap")
        write_librealsense(small, c, d, path=seeds / "librealsense_lz4.bag", compress=True)
        write_librealsense(small, c, d, path=seeds / "librealsense_none.bag", compress=False)
    DEPTH_FX, DEPTH_PPX, DEPTH_PPY = saved


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        cam, colors, depths = synth_scene(tmp / "scene")
        write_reference(tmp / "scene", cam, colors, depths)
    import pyrealsense2 as rs

    # pyrealsense2 2.59 says its version (and writes .db3); 2.55 does not.
    v259 = getattr(rs, "__version__", "2.55") >= "2.59"
    if v259:
        rec = write_librealsense(cam, colors, depths, path=OUT / "librealsense.db3")
        write_goldens(rec, OUT / "golden_db3")
    else:
        rec = write_librealsense(cam, colors, depths)
        write_goldens(rec, OUT / "golden")
        write_ros(cam, colors, depths)
        write_ros2(cam, colors, depths)
        write_ros2(cam, colors, depths, sizes=(FRAMES, 3), storage="mcap")
    write_seeds(cam, colors, depths, v259)
    for f in sorted(OUT.rglob("*")):
        if f.is_file():
            print(f"{f.relative_to(ROOT)}: {f.stat().st_size} bytes")


if __name__ == "__main__":
    sys.exit(main())
