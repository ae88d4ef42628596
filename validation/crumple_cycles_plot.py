#!/usr/bin/env python3
"""Pictures of a crumple-and-open cycles run (docs/crumple.md, "Crumple-and-open cycles").

    build/validation/papersim_crumple_cycles --out DIR ...
    python3 validation/crumple_cycles_plot.py DIR --maps maps.png --heights heights.png --growth growth.png

--maps: for each cycle, the opened sheet in material coordinates, every face coloured by its
largest absolute principal plastic curvature (DIR/cycle_K_open.ply, or DIR/cycle_K_pressed.ply
when the run pressed each cycle). --heights: the opened (or pressed) sheets seen from above, every face coloured by its height above the ground. --growth: the plastic
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


def panels(run, cycles, path, panel, cmap, clim, label, last="open"):
    """One map per cycle, side by side, with a shared colour bar. panel(ply) gives the 2D
    polygons [mm], their values and the (x, y) extent [mm]."""
    fig, axes = plt.subplots(1, len(cycles), figsize=(2.0 * len(cycles) + 1.2, 3.4), squeeze=False,
                             constrained_layout=True)
    for ax, k in zip(axes[0], cycles):
        polygons, values, lo, hi = panel(os.path.join(run, f"cycle_{k}_{last}.ply"))
        pc = PolyCollection(polygons, array=values, cmap=cmap, edgecolors="face", linewidths=0.2)
        pc.set_clim(*(clim if clim else (0, max(1.0, float(np.percentile(values, 99.5))))))
        clim = clim or pc.get_clim()  # the first panel's scale for all
        ax.add_collection(pc)
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_aspect("equal")
        ax.set_title(f"after cycle {k}", fontsize=9)
        ax.set_xlabel("x [mm]", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[0][0].set_ylabel("y [mm]", fontsize=8)
    cb = fig.colorbar(pc, ax=list(axes[0]), shrink=0.8)
    cb.set_label(label, fontsize=8)
    fig.savefig(path, dpi=120)


def plastic_panel(ply):
    """The sheet in material coordinates, faces valued by their plastic curvature [1/m]."""
    X, F, K = read_ply(ply)
    X = X * 1e3
    return X[F], principal(K), X.min(axis=0), X.max(axis=0)


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


def height_panel(ply):
    """The sheet seen from above, faces valued by their height [mm], lower faces drawn first."""
    _, F, _ = read_ply(ply)
    x = world_positions(ply) * 1e3
    z = x[F][:, :, 2].mean(axis=1)
    order = np.argsort(z)
    return x[F][order][:, :, :2], z[order], x[:, :2].min(axis=0), x[:, :2].max(axis=0)


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
    ax.set_ylabel("after the cycle [m]")
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
        all_rows = list(csv.DictReader(f))
    # A cycle ends with its opening, or with its pressing when the run pressed (--press).
    last = "press" if any(r["phase"] == "press" for r in all_rows) else "open"
    rows = [r for r in all_rows if r["phase"] == last]
    if not rows:
        sys.exit(f"{a.run}/cycles.csv: no finished cycle")
    cycles = [int(r["cycle"]) for r in rows]
    ply = {"open": "open", "press": "pressed"}[last]
    if a.maps:
        panels(a.run, cycles, a.maps, plastic_panel, "viridis", None, "plastic curvature [1/m]", ply)
    if a.heights:
        panels(a.run, cycles, a.heights, height_panel, "magma", (0, 30), "height [mm]", ply)
    if a.growth:
        growth(rows, a.growth)


if __name__ == "__main__":
    main()
