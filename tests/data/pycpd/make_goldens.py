"""Golden outputs of pycpd's DeformableRegistration for the CPD tests.

Run once with `python3 make_goldens.py` (pip install pycpd==2.0.0 numpy);
it rewrites goldens.json next to it. The point sets are made here from a
fixed seed and stored in the file, so the Rust test needs no Python.
"""
import json
import os

import numpy as np
import pycpd
from pycpd import DeformableRegistration

rng = np.random.default_rng(20261122)


def curve_2d(n):
    t = np.linspace(0.0, 1.0, n)
    return np.stack([t, 0.2 * np.sin(2 * np.pi * t)], axis=1)


def helix_3d(n):
    t = np.linspace(0.0, 1.0, n)
    return np.stack([t, 0.1 * np.cos(3 * t), 0.1 * np.sin(3 * t)], axis=1)


cases = []

# 2D: a sine curve bent and shifted, target denser than source, no outliers.
y = curve_2d(20)
t = np.linspace(0.0, 1.0, 60)
x = np.stack([t + 0.05, 0.25 * np.sin(2 * np.pi * t + 0.3) + 0.02], axis=1)
x += rng.normal(0.0, 0.005, x.shape)
cases.append(dict(name="2d-bent-sine", X=x, Y=y, alpha=2.0, beta=2.0, w=0.0,
                  max_iterations=100, tolerance=1e-3))

# 2D: same source, target with 20 % uniform outliers, w = 0.2, narrow kernel.
outliers = rng.uniform(-0.5, 1.5, (15, 2))
cases.append(dict(name="2d-outliers", X=np.vstack([x, outliers]), Y=y, alpha=1.0,
                  beta=0.3, w=0.2, max_iterations=100, tolerance=1e-6))

# 3D: a helix-like rope deformed at one end, rope scale in metres.
y3 = helix_3d(24)
t = np.linspace(0.0, 1.0, 80)
x3 = np.stack([t, 0.1 * np.cos(3 * t) + 0.05 * t ** 2, 0.1 * np.sin(3 * t) - 0.03 * t], axis=1)
x3 += rng.normal(0.0, 0.003, x3.shape)
cases.append(dict(name="3d-rope", X=x3, Y=y3, alpha=2.0, beta=0.3, w=0.1,
                  max_iterations=150, tolerance=1e-9))

# 3D: stiff regularisation (large lambda), few iterations: the cap ends it.
cases.append(dict(name="3d-stiff-capped", X=x3, Y=y3, alpha=50.0, beta=1.0, w=0.05,
                  max_iterations=7, tolerance=0.0))

out = {"generator": "pycpd " + getattr(pycpd, "__version__", "2.0.0") + ", numpy " + np.__version__,
       "cases": []}
for c in cases:
    reg = DeformableRegistration(X=c["X"], Y=c["Y"], alpha=c["alpha"], beta=c["beta"], w=c["w"],
                                 max_iterations=c["max_iterations"], tolerance=c["tolerance"])
    ty, _ = reg.register()
    out["cases"].append(dict(
        name=c["name"], X=c["X"].tolist(), Y=c["Y"].tolist(), lambda_=c["alpha"], beta=c["beta"],
        w=c["w"], max_iterations=c["max_iterations"], tolerance=c["tolerance"],
        TY=ty.tolist(), sigma2=float(reg.sigma2), iterations=int(reg.iteration)))
    print(c["name"], "iterations", reg.iteration, "sigma2", reg.sigma2)

with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "goldens.json"), "w") as f:
    json.dump(out, f)
