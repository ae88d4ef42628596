#!/usr/bin/env python3
"""Pictures of a crumple-and-open cycles run (docs/crumple.md, "Crumple-and-open cycles").

    build/validation/papersim_crumple_cycles --out DIR ...
    python3 validation/crumple_cycles_plot.py DIR --maps maps.png --heights heights.png --growth growth.png

--maps: for each cycle, the opened sheet in material coordinates, every face coloured by its
largest absolute principal plastic curvature (DIR/cycle_K_open.ply). --heights: the opened sheets
seen from above, every face coloured by its height above the ground. --growth: the plastic
curvature integral and the plastic network length after each cycle against ln(cycle), with the
least-squares line a + b ln k (DIR/cycles.csv). Needs numpy and matplotlib (Debian: python3-numpy,
python3-matplotlib)."""
import argparse
import csv
import os
import sys

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fold_plots import read_ply  # noqa: E402


def principal(K):
    """Largest absolute principal value of each (kxx, kyy, kxy) [1/m]."""
    mean = 0.5 * (K[:, 0] + K[:, 1])
    r = np.hypot(0.5 * (K[:, 0] - K[:, 1]), K[:, 2])
    return np.maximum(np.abs(mean + r), np.abs(mean - r))


def maps(run, cycles, path):
    fig, axes = plt.subplots(1, len(cycles), figsize=(2.0 * len(cycles) + 1.2, 3.4), squeeze=False,
                             constrained_layout=True)
    top = None
    for ax, k in zip(axes[0], cycles):
        X, F, K = read_ply(os.path.join(run, f"cycle_{k}_open.ply"))
        kp = principal(K)
        top = top or max(1.0, float(np.percentile(kp, 99.5)))
        pc = PolyCollection(X[F] * 1e3, array=kp, cmap="viridis", edgecolors="face", linewidths=0.2)
        pc.set_clim(0, top)
        ax.add_collection(pc)
        ax.set_xlim(X[:, 0].min() * 1e3, X[:, 0].max() * 1e3)
        ax.set_ylim(X[:, 1].min() * 1e3, X[:, 1].max() * 1e3)
        ax.set_aspect("equal")
        ax.set_title(f"after cycle {k}", fontsize=9)
        ax.set_xlabel("x [mm]", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[0][0].set_ylabel("y [mm]", fontsize=8)
    cb = fig.colorbar(pc, ax=list(axes[0]), shrink=0.8)
    cb.set_label("plastic curvature [1/m]", fontsize=8)
    fig.savefig(path, dpi=120)


def world_positions(path):
    """World positions (#V x 3) of a binary sheet PLY of papersim."""
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().split("\n")
    nv = int(next(l for l in header if l.startswith("element vertex")).split()[-1])
    start = header.index(next(l for l in header if l.startswith("element vertex"))) + 1
    props = []
    for l in header[start:]:
        if not l.startswith("property double"):
            break
        props.append(l.split()[-1])
    V = np.frombuffer(data, dtype="<f8", count=nv * len(props), offset=end).reshape(nv, len(props))
    return V[:, [props.index("x"), props.index("y"), props.index("z")]]


def heights(run, cycles, path):
    fig, axes = plt.subplots(1, len(cycles), figsize=(2.0 * len(cycles) + 1.2, 3.4), squeeze=False,
                             constrained_layout=True)
    for ax, k in zip(axes[0], cycles):
        ply = os.path.join(run, f"cycle_{k}_open.ply")
        _, F, _ = read_ply(ply)
        x = world_positions(ply) * 1e3
        order = np.argsort(x[F][:, :, 2].mean(axis=1))  # lower faces first, so the top layer shows
        pc = PolyCollection(x[F][order][:, :, :2], array=x[F][order][:, :, 2].mean(axis=1), cmap="magma",
                            edgecolors="face", linewidths=0.2)
        pc.set_clim(0, 30)
        ax.add_collection(pc)
        ax.set_xlim(x[:, 0].min(), x[:, 0].max())
        ax.set_ylim(x[:, 1].min(), x[:, 1].max())
        ax.set_aspect("equal")
        ax.set_title(f"after cycle {k}", fontsize=9)
        ax.set_xlabel("x [mm]", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[0][0].set_ylabel("y [mm]", fontsize=8)
    cb = fig.colorbar(pc, ax=list(axes[0]), shrink=0.8)
    cb.set_label("height [mm]", fontsize=8)
    fig.savefig(path, dpi=120)


def growth(rows, path):
    k = np.array([int(r["cycle"]) for r in rows])
    fig, ax = plt.subplots(figsize=(5, 3.4))
    for key, label, marker in (("plastic_curvature_integral_m", "plastic curvature integral [m]", "o"),
                               ("plastic_length_m", "plastic network length [m]", "s")):
        y = np.array([float(r[key]) for r in rows])
        b, a = np.polyfit(np.log(k), y, 1)
        ax.plot(np.log(k), y, marker, label=f"{label}: {a:.3f} + {b:.3f} ln k")
        ax.plot(np.log(k), a + b * np.log(k), "-", color=ax.lines[-1].get_color(), lw=0.8)
    ax.set_xlabel("ln(cycle)")
    ax.set_ylabel("after opening [m]")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="--out folder of papersim_crumple_cycles")
    ap.add_argument("--maps", help="write the plastic curvature maps to this PNG")
    ap.add_argument("--heights", help="write the opened sheets' heights, seen from above, to this PNG")
    ap.add_argument("--growth", help="write the growth against ln(cycle) to this PNG")
    a = ap.parse_args()
    with open(os.path.join(a.run, "cycles.csv")) as f:
        rows = [r for r in csv.DictReader(f) if r["phase"] == "open"]
    if not rows:
        sys.exit(f"{a.run}/cycles.csv: no finished cycle")
    if a.maps:
        maps(a.run, [int(r["cycle"]) for r in rows], a.maps)
    if a.heights:
        heights(a.run, [int(r["cycle"]) for r in rows], a.heights)
    if a.growth:
        growth(rows, a.growth)


if __name__ == "__main__":
    main()
