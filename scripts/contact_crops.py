#!/usr/bin/python3
"""Before / after crops of photos, enlarged 4 times (nearest neighbour), side by side.

usage: contact_crops.py OUT.png ROW [ROW ...]
  ROW = LABEL:BEFORE.png:AFTER.png:X:Y:W:H   (crop box in pixels of both photos; LABEL may
        hold colons, the paths may not)

One row per crop: the crop of BEFORE, a white gap, the crop of AFTER, with LABEL above.
Used for docs/images/scenegen_contact_line.png (docs/scenegen.md, "Contact shadow").
"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

SCALE, GAP, LABEL_H = 4, 8, 22


def crop(path, x, y, w, h):
    img = plt.imread(path)[..., :3]
    return np.kron(img[y : y + h, x : x + w], np.ones((SCALE, SCALE, 1)))


def main(out, rows):
    parsed = []
    for row in rows:
        label, before, after, *box = row.rsplit(":", 6)
        x, y, w, h = map(int, box)
        parsed.append((label, crop(before, x, y, w, h), crop(after, x, y, w, h)))
    width = max(b.shape[1] + GAP + a.shape[1] for _, b, a in parsed)
    height = sum(LABEL_H + b.shape[0] + GAP for _, b, _ in parsed)
    canvas = np.ones((height, width, 3))
    fig = plt.figure(figsize=(width / 100, height / 100), dpi=100)
    top = 0
    for label, b, a in parsed:
        fig.text(4 / width, 1 - (top + 16) / height, label, fontsize=10)
        top += LABEL_H
        canvas[top : top + b.shape[0], : b.shape[1]] = b
        canvas[top : top + a.shape[0], b.shape[1] + GAP : b.shape[1] + GAP + a.shape[1]] = a
        top += b.shape[0] + GAP
    fig.figimage(canvas, 0, 0, origin="upper")
    fig.savefig(out, dpi=100)


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2:])
