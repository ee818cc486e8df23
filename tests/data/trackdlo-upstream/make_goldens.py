#!/usr/bin/env python3
"""Golden outputs of the upstream TrackDLO tracking step (RMDLO/trackdlo,
MIT), for core/tests/trackdlo_golden.rs.

Builds driver.cpp (ours) against the upstream sources in
../shared/upstream/trackdlo (read from there, never copied here): the
sources are compiled from a temporary folder where the header keeps only
its Eigen and standard includes, ROS's logging macros do nothing, and
utils.cpp loses its RViz marker functions (the tracking step uses none of
them). Needs g++ and Eigen (Debian: libeigen3-dev) and numpy.

Each case is one call of trackdlo::tracking_step on fixed inputs (previous
nodes, rest coordinates, sigma^2, a cloud, the visible and the extended
visible node lists) with the parameters of upstream's evaluation launch
file; goldens.json holds inputs and outputs (or that upstream aborted).

    python3 tests/data/trackdlo-upstream/make_goldens.py [path/to/upstream/trackdlo]
"""
import json
import os
import re
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", "..", ".."))
UPSTREAM = os.environ.get("TRACKDLO_UPSTREAM") or os.path.join(ROOT, "..", "shared", "upstream", "trackdlo")

# trackdlo_eval.launch
PARAMS = dict(visibility_threshold=0.005, beta=0.5, lambda_=50000.0, alpha=3.0, k_vis=500.0, mu=0.1,
              max_iter=50, tol=0.0002, beta_pre_proc=3.0, lambda_pre_proc=1.0, lle_weight=10.0)


def build(tmp, driver="driver.cpp", extra=()):
    src = os.path.join(UPSTREAM, "trackdlo")
    header = open(os.path.join(src, "include", "trackdlo.h")).read()
    keep = []
    for line in header.splitlines():
        inc = re.match(r"\s*#include\s*[<\"]([^>\"]+)[>\"]", line)
        if inc and not (inc.group(1).startswith("Eigen/") or "/" not in inc.group(1)):
            continue  # ROS, PCL, OpenCV and message headers
        if inc and inc.group(1) in ("unistd.h",):
            keep.append(line)
            continue
        if line.strip() == "using cv::Mat;":
            continue
        keep.append(line)
    shim = "".join(f"#include <{h}>\n" for h in ("iostream", "map", "vector", "string", "algorithm", "cmath", "numeric", "chrono", "utility")) + "#define ROS_INFO(...) ((void)0)\n#define ROS_INFO_STREAM(...) ((void)0)\n#define ROS_ERROR(...) ((void)0)\n"
    header = "\n".join(keep).replace("#pragma once", "#pragma once\n" + shim, 1)
    os.makedirs(os.path.join(tmp, "include"))
    os.makedirs(os.path.join(tmp, "src"))
    open(os.path.join(tmp, "include", "trackdlo.h"), "w").write(header)
    utils_h = open(os.path.join(src, "include", "utils.h")).read()
    utils_h = re.sub(r"visualization_msgs::MarkerArray MatrixXd2MarkerArray \([^;]*\);", "", utils_h, flags=re.S)
    utils_h = utils_h.replace("using cv::Mat;", "")
    open(os.path.join(tmp, "include", "utils.h"), "w").write(utils_h)
    utils = open(os.path.join(src, "src", "utils.cpp")).read()
    # Drop the two RViz marker functions (from their signature to the next top-level function).
    utils = re.sub(r"visualization_msgs::MarkerArray MatrixXd2MarkerArray \(.*?\n}\n", "", utils, flags=re.S)
    utils = utils.replace("using cv::Mat;", "")
    open(os.path.join(tmp, "src", "utils.cpp"), "w").write(utils)
    track = open(os.path.join(src, "src", "trackdlo.cpp")).read().replace("using cv::Mat;", "")
    open(os.path.join(tmp, "src", "trackdlo.cpp"), "w").write(track)
    exe = os.path.join(tmp, "driver")
    # Assertions on (no NDEBUG): Eigen's bounds checks are what abort upstream.
    cmd = ["g++", "-O2", "-std=c++17", "-I/usr/include/eigen3", "-I" + os.path.join(tmp, "include"),
           os.path.join(HERE, driver), os.path.join(tmp, "src", "trackdlo.cpp"),
           os.path.join(tmp, "src", "utils.cpp"), "-o", exe, *extra]
    subprocess.run(cmd, check=True)
    return exe


def rope(m, spacing, phase=0.0):
    """An S-shaped rope in front of the camera, m nodes `spacing` apart."""
    t = np.linspace(0, 1, 400)
    curve = np.stack([-0.35 + 0.7 * t, 0.09 * np.sin(2 * np.pi * t + phase), 0.6 + 0.02 * t], axis=1)
    seg = np.linalg.norm(np.diff(curve, axis=0), axis=1)
    s = np.concatenate([[0], np.cumsum(seg)])
    target = np.arange(m) * spacing
    return np.stack([np.interp(target, s, curve[:, k]) for k in range(3)], axis=1)


def cloud_of(nodes, keep, rng, step=0.004, noise=0.0015):
    """Points along the polyline through `nodes` where `keep(i)` holds for the segment's first node."""
    pts = []
    for i in range(len(nodes) - 1):
        if not keep(i):
            continue
        a, b = nodes[i], nodes[i + 1]
        k = max(1, int(np.linalg.norm(b - a) / step))
        for j in range(k):
            pts.append(a + (b - a) * j / k + rng.normal(0, noise, 3))
    return np.array(pts)


def cases():
    rng = np.random.default_rng(7)
    m = 24
    spacing = 0.8 / (m - 1)
    prev = rope(m, spacing)
    geo = [float(i * spacing) for i in range(m)]
    out = []

    def case(name, now, hidden, extended=None, sigma2=0.0, points=None):
        visible = [i for i in range(m) if i not in hidden]
        ext = visible if extended is None else extended
        x = points if points is not None else cloud_of(now, lambda i: i not in hidden and i + 1 not in hidden, rng)
        out.append(dict(name=name, prev=prev.tolist(), geodesic=geo, sigma2=sigma2, cloud=x.tolist(),
                        visible=visible, extended=ext))

    moved = rope(m, spacing, phase=0.05) + np.array([0.004, 0.003, 0.0])
    case("no-occlusion", moved, [])
    case("hidden-middle", moved, list(range(9, 15)))
    case("hidden-tail", moved, list(range(17, 24)))
    case("hidden-head", moved, list(range(0, 6)))
    case("both-ends-hidden", moved, list(range(0, 4)) + list(range(20, 24)))
    big = rope(m, spacing, phase=0.25) + np.array([0.03, -0.02, 0.0])
    case("large-step", big, [])
    # A short gap taken as visible by the extension (d_vis).
    gap = [11]
    case("short-gap-extended", moved, gap, extended=list(range(m)))
    # Only three guide nodes left: upstream's issue #81.
    case("three-guide-nodes", moved, [i for i in range(m) if i not in (10, 11, 12)])
    return out


def run(exe, c):
    p = PARAMS
    lines = [f"{len(c['prev'])} {len(c['cloud'])}",
             f"{p['visibility_threshold']} {p['beta']} {p['lambda_']} {p['alpha']} {p['k_vis']} {p['mu']} "
             f"{p['max_iter']} {p['tol']} {p['beta_pre_proc']} {p['lambda_pre_proc']} {p['lle_weight']}",
             repr(c["sigma2"]), " ".join(repr(g) for g in c["geodesic"])]
    lines += [" ".join(repr(v) for v in row) for row in c["prev"]]
    lines += [" ".join(repr(v) for v in row) for row in c["cloud"]]
    lines.append(f"{len(c['visible'])} " + " ".join(map(str, c["visible"])))
    lines.append(f"{len(c['extended'])} " + " ".join(map(str, c["extended"])))
    r = subprocess.run([exe], input="\n".join(lines) + "\n", capture_output=True, text=True)
    if r.returncode != 0:
        return dict(aborted=True, stderr=r.stderr.strip().splitlines()[-1:] if r.stderr else [])
    tok = r.stdout.split()
    i = 0

    def take(n):
        nonlocal i
        vals = [float(t) for t in tok[i:i + n]]
        i += n
        return vals
    assert tok[i] == "sigma2"; i += 1
    sigma2 = take(1)[0]
    assert tok[i] == "guide"; i += 1
    g = int(tok[i]); i += 1
    guide = [take(3) for _ in range(g)]
    assert tok[i] == "priors"; i += 1
    k = int(tok[i]); i += 1
    priors = [take(4) for _ in range(k)]
    assert tok[i] == "nodes"; i += 1
    n = int(tok[i]); i += 1
    nodes = [take(3) for _ in range(n)]
    return dict(aborted=False, sigma2=sigma2, guide=guide, priors=priors, nodes=nodes)


def main():
    global UPSTREAM
    if len(sys.argv) > 1:
        UPSTREAM = sys.argv[1]
    with tempfile.TemporaryDirectory() as tmp:
        exe = build(tmp)
        result = []
        for c in cases():
            c["upstream"] = run(exe, c)
            print(c["name"], "aborted" if c["upstream"]["aborted"] else "ok", file=sys.stderr)
            result.append(c)
    with open(os.path.join(HERE, "goldens.json"), "w") as f:
        json.dump(dict(params=PARAMS, source="RMDLO/trackdlo c05921e, trackdlo_eval.launch", cases=result), f)


if __name__ == "__main__":
    main()
