#!/usr/bin/env python3
"""How firm is a ratio of medians over a few draws? A paired bootstrap over the draws.

Reads a run table of papersim_runtime_error's studies (docs/data/remesh_pull_*.csv: one row per
seed and setting, with `rms_mm` and `cpu_s`) and compares one setting with a baseline over the
given seeds. Prints the ratio of the medians (setting / baseline) of the error and of the CPU
time, their 95% intervals from resampling the draws with replacement (each draw keeps its pair
of runs), and the share of resamples that meet each form of the accuracy-per-cost target: the
baseline's error in at most a third of its time, or a third of its error in at most its time.

    scripts/median_ratio_interval.py docs/data/remesh_pull_3dec.csv --seeds 0-4,6,14 \
        --baseline off,,7.0,10.0 --setting 3:20:0.1@10,0.7,5.25,10.0

A run is named by remesh,aspect_min,start_edge_mm,step_ms as written in the table.
"""
import argparse
import csv
import random
import statistics
import sys


def parse_seeds(text):
    seeds = []
    for part in text.split(","):
        lo, _, hi = part.partition("-")
        seeds.extend(range(int(lo), int(hi or lo) + 1))
    return seeds


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("table")
    ap.add_argument("--seeds", required=True, help="e.g. 0-4,6,14")
    ap.add_argument("--baseline", required=True, help="remesh,aspect_min,start_edge_mm,step_ms")
    ap.add_argument("--setting", required=True, help="remesh,aspect_min,start_edge_mm,step_ms")
    ap.add_argument("--resamples", type=int, default=20000)
    ap.add_argument("--rng-seed", type=int, default=1)
    args = ap.parse_args()

    keys = ("remesh", "aspect_min", "start_edge_mm", "step_ms")
    runs = {}
    try:
        with open(args.table, newline="") as f:
            for row in csv.DictReader(f):
                runs[(int(row["seed"]),) + tuple(row[k] for k in keys)] = (
                    float(row["rms_mm"]), float(row["cpu_s"]))
    except (OSError, KeyError, ValueError) as e:
        sys.exit(f"median_ratio_interval: {args.table}: {e}")
    baseline, setting = (tuple(s.split(",")) for s in (args.baseline, args.setting))
    for name, key in (("--baseline", baseline), ("--setting", setting)):
        if len(key) != 4:
            sys.exit(f"median_ratio_interval: {name}: want 4 comma-separated fields, got {len(key)}")
    seeds = parse_seeds(args.seeds)
    missing = [s for s in seeds if (s,) + baseline not in runs or (s,) + setting not in runs]
    if missing:
        sys.exit(f"median_ratio_interval: no pair of runs for seeds {missing} in {args.table}")

    def ratios(draws):
        return tuple(statistics.median(runs[(s,) + setting][i] for s in draws) /
                     statistics.median(runs[(s,) + baseline][i] for s in draws) for i in (0, 1))

    rng = random.Random(args.rng_seed)
    boot = [ratios([rng.choice(seeds) for _ in seeds]) for _ in range(args.resamples)]
    err, cpu = ratios(seeds)
    print(f"{len(seeds)} draws, {args.resamples} resamples")
    for i, (name, value) in enumerate((("error", err), ("cpu", cpu))):
        v = sorted(b[i] for b in boot)
        lo, hi = v[int(0.025 * len(v))], v[int(0.975 * len(v)) - 1]
        print(f"{name} ratio {value:.3f}, 95% interval {lo:.3f} to {hi:.3f}")
    first = sum(e <= 1 and c <= 1 / 3 for e, c in boot) / len(boot)
    second = sum(e <= 1 / 3 and c <= 1 for e, c in boot) / len(boot)
    print(f"resamples meeting the target: same error in a third of the time {first:.4f}, "
          f"a third of the error in the same time {second:.4f}")


if __name__ == "__main__":
    main()
