#!/usr/bin/env python3
"""Writes a synthetic dataset's manifest.jsonl and failures.jsonl for timing `papersim
dataset-stats` on millions of rows without simulating them.

    scripts/synthetic_dataset.py OUT --rows N [--failure-share 0.02] [--seed 1]

Each manifest row has the fields, key layout and size (about 470 bytes) of a `papersim batch`
row: key "meshes/<scenario>/<seed // 1000>/<seed>", seeds 0..N-1 spread over the six scenarios,
random figures. A share of the seeds also gets a failure row (failures.jsonl, written before its
manifest row, as a retried sample); half of those then fail for good (no manifest row), and one
manifest row in 1,000 is written twice, as a sample finished twice. Deterministic for a seed.
"""
import argparse
import os
import random
import sys

SCENARIOS = ["pull", "fold", "fall-cylinder", "fall-gable", "fall-sphere", "fall-spheres"]
REASONS = ["solver did not converge", "stretch beyond the limit", "timed out", "killed"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", help="folder to write (created; its two files are replaced)")
    ap.add_argument("--rows", type=int, required=True, help="samples (seeds)")
    ap.add_argument("--failure-share", type=float, default=0.02)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    if a.rows < 1 or not 0 <= a.failure_share <= 1:
        ap.error("--rows must be positive and --failure-share in [0, 1]")
    os.makedirs(a.out, exist_ok=True)
    rng = random.Random(a.seed)
    paths = [os.path.join(a.out, n) for n in ("manifest.jsonl", "failures.jsonl")]
    with open(paths[0] + ".partial", "w") as man, open(paths[1] + ".partial", "w") as fail:
        for seed in range(a.rows):
            sc = SCENARIOS[seed % len(SCENARIOS)]
            key = f"meshes/{sc}/{seed // 1000}/{seed}"
            failed = rng.random() < a.failure_share
            if failed:
                fail.write(f'{{"key":"{key}","reason":"{rng.choice(REASONS)}",'
                           f'"scenario":"{sc}","seed":{seed},"set":{{}}}}\n')
                if rng.random() < 0.5:
                    continue
            wall = rng.lognormvariate(3.0, 0.5)
            row = (f'{{"abs_curvature_integral":{rng.uniform(0, 0.05)!r},'
                   f'"closest_obstacle_distance":{rng.uniform(0, 1e-4)!r},'
                   f'"cpu_seconds":{wall * 1.01!r},"crease_length":{rng.uniform(0, 2)!r},'
                   f'"key":"{key}","max_stretch":{1 + rng.uniform(0, 0.005)!r},'
                   f'"newton_iterations":{rng.randint(100, 20000)},"path":"{key}",'
                   f'"scenario":"{sc}","seed":{seed},"self_intersections":0,"set":{{}},'
                   f'"sim_wall_seconds":{wall * 0.9!r},"steps":{rng.randint(50, 500)},'
                   f'"vertices":{rng.randint(100, 5000)},"wall_seconds":{wall!r}}}\n')
            man.write(row)
            if rng.random() < 0.001:
                man.write(row)
    for p in paths:
        os.replace(p + ".partial", p)
    print(f"{a.out}: {a.rows} samples, "
          + ", ".join(f"{os.path.basename(p)} {os.path.getsize(p) / 1e6:.0f} MB" for p in paths))


if __name__ == "__main__":
    sys.exit(main())
