#!/usr/bin/env python3
"""Pictures of a fold run (docs/fold.md): side views of the sheet and the roller at chosen times,
seen along the roller's axis, and the residual rest curvature across the fold on the flat sheet.

    papersim scenario fold --seed 0 --out DIR --frames 10        # any run of a fold scene
    python3 validation/fold_plots.py DIR --times 4.0,4.3,4.8 --side side.png --plastic plastic.png

Reads DIR/scene.json (the roller's keyframes, the handle's point), DIR/frames/frame_N.obj (the
frame of step N is taken at t = N * time_step, which holds for runs without split steps between
frames; papersim numbers frames by accepted steps) and DIR/sheet.ply (the plastic curvature per
face). Needs numpy and matplotlib (Debian: python3-numpy, python3-matplotlib)."""
import argparse
import json
import os
import struct
import sys

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402


def read_obj(path):
    """World positions and faces of a frame."""
    V, F = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                V.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                F.append([int(x.split("/")[0]) - 1 for x in line.split()[1:4]])
    return np.array(V), np.array(F)


def read_ply(path):
    """Material coordinates, faces and plastic curvature (kxx, kyy, kxy) of papersim's sheet.ply."""
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().split("\n")
    if "format binary_little_endian 1.0" not in header:
        sys.exit(f"{path}: not a binary little-endian PLY")
    vprops = [l.split()[-1] for l in header if l.startswith("property double")]
    nv = int(next(l for l in header if l.startswith("element vertex")).split()[-1])
    nf = int(next(l for l in header if l.startswith("element face")).split()[-1])
    fprops = header[header.index(next(l for l in header if l.startswith("element face"))) + 2:]
    fprops = [l.split()[-1] for l in fprops if l.startswith("property double")]
    nvp = len(vprops) - len(fprops)
    if nvp <= 0 or fprops[:3] != ["kxx", "kyy", "kxy"]:
        sys.exit(f"{path}: no plastic curvature (kxx, kyy, kxy) per face")
    V = np.frombuffer(data, dtype="<f8", count=nv * nvp, offset=end).reshape(nv, nvp)
    X = V[:, [vprops.index("mx"), vprops.index("my")]]
    offset = end + nv * nvp * 8
    F = np.empty((nf, 3), dtype=int)
    K = np.empty((nf, len(fprops)))
    for i in range(nf):
        if data[offset] != 3:
            sys.exit(f"{path}: face {i} is not a triangle")
        F[i] = struct.unpack_from("<3i", data, offset + 1)
        K[i] = struct.unpack_from(f"<{len(fprops)}d", data, offset + 13)
        offset += 13 + 8 * len(fprops)
    return X, F, K[:, :3]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="output folder of a fold run (scene.json, frames/, sheet.ply)")
    ap.add_argument("--times", default="", help="side views at these times [s], comma separated")
    ap.add_argument("--side", help="write the side views to this PNG")
    ap.add_argument("--plastic", help="write the rest curvature across the fold to this PNG")
    a = ap.parse_args()
    scene = json.load(open(os.path.join(a.run, "scene.json")))
    roller = next(o for o in scene["obstacles"] if o["kind"] == "cylinder")
    keys = roller["keyframes"]
    T = np.array([k["time"] for k in keys])
    P = np.array([k["position"] for k in keys])
    width, height = scene["sheet"]["width"], scene["sheet"]["height"]
    point = np.array(scene["handles"][0]["point"])
    d2 = np.array([0.5 * width, 0.5 * height]) - point
    d2 /= np.linalg.norm(d2)
    if a.side:
        times = [float(t) for t in a.times.split(",") if t]
        if not times:
            sys.exit("--side needs --times")
        # The roller moves along its own keyframes; its direction of travel is the fold direction.
        travel = P[-1] - P[0]
        along = travel / np.linalg.norm(travel)
        axis = np.cross([0.0, 0.0, 1.0], along)
        fig, axes = plt.subplots(len(times), 1, figsize=(8, 2.4 * len(times)), squeeze=False)
        for ax, t in zip(axes[:, 0], times):
            step = int(round(t / scene["time_step"]))
            path = os.path.join(a.run, "frames", f"frame_{step:06d}.obj")
            if not os.path.exists(path):
                sys.exit(f"{path}: no frame at t = {t} s (run with --frames K dividing {step})")
            V, F = read_obj(path)
            c = np.array([np.interp(t, T, P[:, i]) for i in range(3)])
            s, z = (V - c) @ along, V[:, 2]
            for tri in F:
                loop = np.r_[tri, tri[0]]
                ax.plot(s[loop], z[loop], "k-", lw=0.15)
            th = np.linspace(0, 2 * np.pi, 200)
            r = roller["radius"]
            ax.plot(r * np.cos(th), c[2] + r * np.sin(th), "r-", lw=1)
            ax.set_aspect("equal")
            ax.set_xlim(-0.15, 0.15)
            ax.set_ylim(-0.002, 0.11)
            ax.set_title(f"t = {t:.2f} s ({len(V)} vertices); along the roller's travel [m]", fontsize=9)
        plt.tight_layout()
        plt.savefig(a.side, dpi=90)
        print(f"wrote {a.side}")
    if a.plastic:
        X, F, K = read_ply(os.path.join(a.run, "sheet.ply"))
        kn = K[:, 0] * d2[0] ** 2 + K[:, 1] * d2[1] ** 2 + 2 * K[:, 2] * d2[0] * d2[1]
        fig, ax = plt.subplots(figsize=(5, 6.5))
        pc = PolyCollection(X[F], array=kn, cmap="coolwarm", edgecolors="k", linewidths=0.1)
        pc.set_clim(-300, 300)
        ax.add_collection(pc)
        ax.set_aspect("equal")
        ax.autoscale()
        ax.set_title(f"rest curvature across the fold [1/m], {len(X)} vertices", fontsize=9)
        plt.colorbar(pc)
        plt.tight_layout()
        plt.savefig(a.plastic, dpi=80)
        print(f"wrote {a.plastic}")


if __name__ == "__main__":
    main()
