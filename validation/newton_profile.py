#!/usr/bin/env python3
"""Where the Newton iterations of a run go, by phase, from the per-iteration trace that
papersim prints on stderr with --trace newton (docs/performance.md).

    papersim run SCENE.json --out DIR --quiet --trace newton 2> newton.log
    python3 validation/newton_profile.py newton.log [--impact-ms 20] [--bin-ms 20]

Phases are read from the trace itself: flight = the steps before the first one that needs more
than 2 iterations (a free fall takes 2: the step and the check); impact = the next --impact-ms;
rest = the steps after the last one that needs more than 3; draping = between impact and rest.
Per phase: steps, iterations, iterations per step, the iterations a looser stopping test (1e-3 and
1e-2 m/s instead of the default 1e-4) would have stopped at on the same trajectory, iterations
whose residual grew, and steps the line search shortened (and which term limited them)."""
import argparse
import collections
import re
import sys


def read_trace(path):
    """{step start time [s]: [[residual, step length or None, limiting term or None], ...]}"""
    steps = collections.OrderedDict()
    with open(path) as f:
        for line in f:
            m = re.match(r"t (\S+) it (\d+) E (\S+) residual (\S+) decrement (\S+)", line)
            if m:
                steps.setdefault(float(m.group(1)), []).append([float(m.group(4)), None, None])
                continue
            m = re.match(r"\s+step (\S+) \(feasible (\S+), limited by (\S+)\)", line)
            if m and steps:
                last = steps[next(reversed(steps))][-1]
                last[1], last[2] = float(m.group(1)), m.group(3)
    return steps


def phases(steps, impact_s):
    times = list(steps)
    busy = [t for t in times if len(steps[t]) > 2]
    if not busy:
        return {t: "flight" for t in times}
    first, last = busy[0], max(t for t in times if len(steps[t]) > 3) if any(len(steps[t]) > 3 for t in times) else busy[-1]
    out = {}
    for t in times:
        if t < first:
            out[t] = "flight"
        elif t < first + impact_s - 1e-12:
            out[t] = "impact"
        elif t > last:
            out[t] = "rest"
        else:
            out[t] = "draping"
    return out


def stop_at(its, tol):
    """Iterations the run would have taken with stopping tolerance tol [m/s] on this trajectory."""
    return next((i + 1 for i, it in enumerate(its) if it[0] < tol), len(its))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("log")
    p.add_argument("--impact-ms", type=float, default=20)
    p.add_argument("--bin-ms", type=float, default=20)
    a = p.parse_args()
    steps = read_trace(a.log)
    if not steps:
        sys.exit(f"{a.log}: no 't ... it ... residual' lines (run papersim with --trace newton)")
    ph = phases(steps, 1e-3 * a.impact_ms)
    total = sum(len(v) for v in steps.values())
    print(f"{'phase':8s} {'from_ms':>7s} {'steps':>6s} {'newton':>7s} {'share':>6s} {'per_step':>8s} "
          f"{'at_1e-3':>8s} {'at_1e-2':>8s} {'grows':>6s} {'short':>6s}")
    for name in ["flight", "impact", "draping", "rest"]:
        ts = [t for t in steps if ph[t] == name]
        if not ts:
            continue
        its = [steps[t] for t in ts]
        n = sum(len(i) for i in its)
        grows = sum(1 for i in its for k in range(1, len(i)) if i[k][0] > i[k - 1][0])
        short = sum(1 for i in its for it in i if it[1] is not None and it[1] < 1)
        print(f"{name:8s} {1e3 * ts[0]:7.1f} {len(ts):6d} {n:7d} {n / total:6.1%} {n / len(ts):8.2f} "
              f"{sum(stop_at(i, 1e-3) for i in its) / len(ts):8.2f} {sum(stop_at(i, 1e-2) for i in its) / len(ts):8.2f} "
              f"{grows:6d} {short:6d}")
    lim = collections.Counter(it[2] for v in steps.values() for it in v if it[1] is not None and it[1] < 1)
    print("shortened steps limited by:", ", ".join(f"{k} {v}" for k, v in lim.most_common()))
    print(f"iterations per step in {a.bin_ms:g} ms bins:")
    bins = collections.defaultdict(list)
    for t, v in steps.items():
        bins[int(t / (1e-3 * a.bin_ms) + 1e-9)].append(len(v))
    for b in sorted(bins):
        v = bins[b]
        print(f"  {b * a.bin_ms:6.0f}-{(b + 1) * a.bin_ms:4.0f} ms: {sum(v) / len(v):6.2f} per step, max {max(v):3d}")


if __name__ == "__main__":
    main()
