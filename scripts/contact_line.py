#!/usr/bin/python3
"""The dark line beside a sheet's resting edge in scenegen photos.

usage: contact_line.py EDGE SAMPLE [SAMPLE ...]
  EDGE   bottom | left: the middle 60% of the sheet's bottom or left edge in the image
  SAMPLE a `scenegen render` folder with image.png and mask.png

For each sample, the photo's channel mean (0-255) on table pixels at 1, 2, ..., 13 pixels from
the sheet's own mask (bins of one pixel, distances from a Euclidean distance transform), minus
the open table 14-20 pixels out, over the table pixels whose nearest sheet pixel lies on that
edge; and where the darkening stops: the first distance from which every bin is above -3.
Used for docs/scenegen.md ("Wider curl" under "Edge curl").
"""
import sys

import numpy as np
from PIL import Image
from scipy import ndimage


def profile(sample, edge):
    image = np.asarray(Image.open(sample + "/image.png").convert("RGB"), float).mean(axis=2)
    mask = np.asarray(Image.open(sample + "/mask.png").convert("L")) > 127
    if not mask.any():
        sys.exit(f"contact_line.py: {sample}/mask.png has no sheet pixel")
    dist, (near_r, near_c) = ndimage.distance_transform_edt(~mask, return_indices=True)
    rows, cols = np.nonzero(mask)
    r0, r1, c0, c1 = rows.min(), rows.max(), cols.min(), cols.max()
    h, w = r1 - r0, c1 - c0
    if edge == "bottom":
        on_edge = (near_r > r1 - 0.12 * h) & (near_c > c0 + 0.2 * w) & (near_c < c1 - 0.2 * w)
    else:
        on_edge = (near_c < c0 + 0.12 * w) & (near_r > r0 + 0.2 * h) & (near_r < r1 - 0.2 * h)
    table = image[on_edge & (dist >= 14) & (dist <= 20)].mean()
    return np.array([image[on_edge & (np.abs(dist - a) <= 0.5)].mean() - table for a in range(1, 14)])


def main(edge, samples):
    if edge not in ("bottom", "left"):
        sys.exit(f"contact_line.py: EDGE must be bottom or left, not '{edge}'")
    print("distance [px]      " + " ".join(f"{a:6d}" for a in range(1, 14)) + "  ends [px]")
    for s in samples:
        p = profile(s, edge)
        ends = next((i + 1 for i in range(len(p)) if (p[i:] > -3).all()), None)
        print(f"{s:18s} " + " ".join(f"{x:6.1f}" for x in p) + f"  {ends}")


if __name__ == "__main__":
    if len(sys.argv) < 3 or sys.argv[1] in ("-h", "--help"):
        print(__doc__)
        sys.exit(0 if len(sys.argv) > 1 and sys.argv[1] in ("-h", "--help") else 2)
    main(sys.argv[1], sys.argv[2:])
