#!/usr/bin/env python3
"""Hostile-input probe of papersim and scenegen (issue 17).

Runs the two programs as a careless, hostile or unlucky user would - broken scene files, broken
meshes, bad options, file names and values that are not UTF-8, inputs beyond any sane size,
interruptions at 25 / 50 / 90 % of a run, a full disk, re-runs into a used folder - and counts
what went wrong:

  crash       ended by a signal it was not sent, or an uncaught exception / sanitizer report
  hang        still running after the timeout (60 s)
  silent      an input that must be refused was accepted (exit 0)
  partial     files left after a failure or an interruption, a staging folder left, POV-Ray
              outliving scenegen, or a published folder mixing two runs
  fulldisk0   exit status 0 on a full disk
  badstatus   an exit status outside the documented table (0-6, 130, 143)
  badmessage  a message that misleads: "stoi", a number of more than 30 digits, "(0 triangle
              pairs)", a log path in a deleted folder, "internal error" for the user's input

Usage: validation/hostile_input_probe.py --papersim BIN --scenegen BIN [--quick]
The full disk is a filled 256 KiB tmpfs when this process may mount one (root), else a file
size limit of 0 bytes (RLIMIT_FSIZE); the table says which. Prints one table; exits 1 when any
count is not 0.
"""
import argparse
import copy
import json
import os
import re
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time

DOCUMENTED = {0, 1, 2, 3, 4, 5, 6, 130, 143}
CATEGORIES = ["crash", "hang", "silent", "partial", "fulldisk0", "badstatus", "badmessage"]
TIMEOUT = 60.0


class Probe:
    def __init__(self, papersim, scenegen, work):
        self.papersim = papersim
        self.scenegen = scenegen
        self.work = work
        self.counts = {}  # family -> {category: n, "inputs": n}
        self.examples = {}
        self.n = 0

    # --- bookkeeping -------------------------------------------------------------------------
    def count(self, family, category, what):
        row = self.counts.setdefault(family, {c: 0 for c in CATEGORIES + ["inputs"]})
        row[category] += 1
        self.examples.setdefault((family, category), what)

    def seen(self, family):
        row = self.counts.setdefault(family, {c: 0 for c in CATEGORIES + ["inputs"]})
        row["inputs"] += 1

    def fresh(self, tag):
        self.n += 1
        d = os.path.join(self.work, "%s-%d" % (tag, self.n))
        os.makedirs(d)
        return d

    # --- running -------------------------------------------------------------------------------
    def run(self, argv, fsize=None, timeout=TIMEOUT):
        def limit():
            if fsize is not None:
                resource.setrlimit(resource.RLIMIT_FSIZE, (fsize, fsize))
        t0 = time.time()
        proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                preexec_fn=limit, errors="replace")
        try:
            out, err = proc.communicate(timeout=timeout)
            return {"status": proc.returncode, "out": out, "err": err,
                    "seconds": time.time() - t0, "hang": False}
        except subprocess.TimeoutExpired:
            kill_tree(proc.pid)
            proc.kill()
            proc.communicate()
            return {"status": None, "out": "", "err": "", "seconds": timeout, "hang": True}

    def judge(self, family, what, r, must_fail, out=None, existed_before=None, full_disk=False):
        """Count what is wrong with one finished run."""
        self.seen(family)
        if r["hang"]:
            self.count(family, "hang", what)
            return
        st = r["status"]
        err = r["err"]
        if st < 0 or "terminate called" in err or "Sanitizer" in err or st in (134, 136, 139):
            self.count(family, "crash", "%s (status %s)" % (what, st))
            return
        if st not in DOCUMENTED:
            self.count(family, "badstatus", "%s (status %d)" % (what, st))
        if must_fail and st == 0:
            self.count(family, "silent", what)
        if full_disk and st == 0:
            self.count(family, "fulldisk0", what)
        if st != 0 and misleading(err):
            self.count(family, "badmessage", "%s: %s" % (what, err.strip()[:160]))
        if out is not None and st != 0 and st != 3:
            left = leftovers(out, existed_before or [])
            if left:
                self.count(family, "partial", "%s left %s" % (what, left[:4]))
        if out is not None and st != 0 and hidden(out):
            self.count(family, "partial", "%s left %s" % (what, hidden(out)))

    # --- inputs --------------------------------------------------------------------------------
    def small_scene(self):
        d = self.fresh("drawn")
        r = self.run([self.papersim, "scenario", "pull", "--seed", "1", "--draw-only", "--out", d])
        with open(os.path.join(d, "scene.json")) as f:
            scene = json.load(f)
        scene["duration"] = 0.05
        scene["sheet"]["edge_length"] = 0.02
        return scene

    def example(self, kind="flat"):
        d = self.fresh("example")
        path = os.path.join(d, kind + ".obj")
        self.run([self.scenegen, "example", kind, "--out", path])
        with open(path) as f:
            return f.read()


def misleading(err):
    return ("stoi" in err or re.search(r"\d{31,}", err) is not None or "(0 triangle pairs)" in err
            or ".scenegen-job/" in err or "internal error" in err)


def leftovers(out, before):
    if not os.path.exists(out):
        return []
    names = []
    for root, dirs, files in os.walk(out):
        for n in files + dirs:
            rel = os.path.relpath(os.path.join(root, n), out)
            if rel not in before:
                names.append(rel)
    return sorted(names)


def hidden(out):
    if not os.path.isdir(out):
        return []
    return sorted(n for n in os.listdir(out) if n.startswith(".papersim") or n.startswith(".scenegen"))


def write(path, text):
    with open(path, "w") as f:
        f.write(text)
    return path


def leaves(node, path=()):
    if isinstance(node, dict):
        for k, v in node.items():
            yield from leaves(v, path + (k,))
    elif isinstance(node, list) and node and isinstance(node[0], (dict, list)):
        for i, v in enumerate(node):
            yield from leaves(v, path + (i,))
    else:
        yield path


def set_at(node, path, value):
    for k in path[:-1]:
        node = node[k]
    node[path[-1]] = value


def get_at(node, path):
    for k in path:
        node = node[k]
    return node


# --- families -----------------------------------------------------------------------------------

def scene_files(p, quick):
    base = p.small_scene()
    bad_values = [None, "text", {}, [], True] if not quick else [None, "text"]
    for path in leaves(base):
        original = get_at(base, path)
        for value in bad_values:
            if type(value) == type(original) or (isinstance(original, bool) and value is True):
                continue
            s = copy.deepcopy(base)
            set_at(s, path, value)
            d = p.fresh("scene")
            scene = write(os.path.join(d, "s.json"), json.dumps(s))
            out = os.path.join(d, "out")
            r = p.run([p.papersim, "run", scene, "--out", out, "--quiet"])
            p.judge("scene file", "%s = %r" % (".".join(map(str, path)), value), r, True, out)
    # Huge and tiny numbers: validity depends on the key; crashes, hangs and messages count.
    for path in leaves(base):
        if not isinstance(get_at(base, path), (int, float)) or isinstance(get_at(base, path), bool):
            continue
        for value in ([1e300, -1e300] if not quick else [1e300]):
            s = copy.deepcopy(base)
            set_at(s, path, value)
            d = p.fresh("scene")
            scene = write(os.path.join(d, "s.json"), json.dumps(s))
            out = os.path.join(d, "out")
            r = p.run([p.papersim, "run", scene, "--out", out, "--quiet"])
            p.judge("scene file", "%s = %g" % (".".join(map(str, path)), value), r, False, out)
    text = json.dumps(base, indent=2)
    for key in list(base.keys()):  # a key given twice
        dup = text.replace("{", '{\n  "%s": %s,' % (key, json.dumps(base[key])), 1)
        d = p.fresh("scene")
        r = p.run([p.papersim, "run", write(os.path.join(d, "s.json"), dup), "--out", os.path.join(d, "out"), "--quiet"])
        p.judge("scene file", "duplicate key %s" % key, r, True, os.path.join(d, "out"))
    for fraction in [0.1, 0.3, 0.5, 0.7, 0.9, 0.99]:  # a file cut short
        d = p.fresh("scene")
        cut = write(os.path.join(d, "s.json"), text[: int(len(text) * fraction)])
        r = p.run([p.papersim, "run", cut, "--out", os.path.join(d, "out"), "--quiet"])
        p.judge("scene file", "cut at %d%%" % (fraction * 100), r, True, os.path.join(d, "out"))
    # A sheet mesh and an obstacle mesh that cannot be read: the message must name scene and key.
    for key in ["sheet.mesh", "obstacles[0]"]:
        s = copy.deepcopy(base)
        d = p.fresh("scene")
        bad = write(os.path.join(d, "bad.obj"), "v 0 0 0\nf 1/1 x 3\n")
        if key == "sheet.mesh":
            s["sheet"]["mesh"] = bad
        else:
            s["obstacles"] = [{"kind": "mesh", "mesh": bad}]
        scene = write(os.path.join(d, "s.json"), json.dumps(s))
        r = p.run([p.papersim, "run", scene, "--out", os.path.join(d, "out"), "--quiet"])
        p.judge("scene file", key + " unreadable", r, True, os.path.join(d, "out"))
        if r["status"] not in (None, 0) and not (scene in r["err"] and key in r["err"]):
            p.count("scene file", "badmessage", "%s error names neither file nor key: %s" % (key, r["err"].strip()[:120]))
    s = copy.deepcopy(base)
    s["sheet"]["position"] = [1e300, 0, 0]
    s["self_contact"] = {"enabled": True}
    d = p.fresh("scene")
    r = p.run([p.papersim, "run", write(os.path.join(d, "s.json"), json.dumps(s)), "--out", os.path.join(d, "out"), "--quiet"])
    p.judge("scene file", "sheet at 1e300", r, True, os.path.join(d, "out"))


def mesh_files(p, quick):
    flat = p.example("flat")
    lines = flat.splitlines()
    v_lines = [i for i, l in enumerate(lines) if l.startswith("v ")]
    f_lines = [i for i, l in enumerate(lines) if l.startswith("f ")]
    variants = []
    for value in ["1e10", "1e150", "1e200", "1e300", "nan", "inf", "-inf"]:
        m = list(lines)
        m[v_lines[0]] = "v %s 0 0" % value
        variants.append(("coordinate %s" % value, "\n".join(m) + "\n"))
    for token in ["x", "0", "-99999", "99999999999", "1/", "//", "1.5", "2147483648"]:
        m = list(lines)
        parts = m[f_lines[-1]].split()
        parts[2] = token
        m[f_lines[-1]] = " ".join(parts)
        variants.append(("face token %s" % token, "\n".join(m) + "\n"))
    for fraction in [0.25, 0.5, 0.75]:
        keep = f_lines[0] + int(len(f_lines) * fraction)
        variants.append(("faces cut to %d%%" % (fraction * 100), "\n".join(lines[:keep]) + "\n"))
    text = "\n".join(lines) + "\n"
    variants.append(("cut mid-line", text[: len(text) - 7]))
    variants.append(("no vt", "\n".join(l for l in lines if not l.startswith("vt ")) + "\n"))
    variants.append(("empty", ""))
    variants.append(("binary junk", "\x00\xff\x10garbage\n" * 50))
    for what, content in variants:
        d = p.fresh("mesh")
        mesh = write(os.path.join(d, "m.obj"), content)
        r = p.run([p.papersim, "metrics", mesh])
        p.judge("mesh file", "metrics, " + what, r, True)
        r = p.run([p.scenegen, "prepare", mesh, "--out", os.path.join(d, "job"), "--size", "32x48"])
        p.judge("mesh file", "prepare, " + what, r, True, os.path.join(d, "job"))
        r = p.run([p.scenegen, "render", mesh, "--out", os.path.join(d, "render"), "--size", "32x48", "--quiet"])
        p.judge("mesh file", "render, " + what, r, True, os.path.join(d, "render"))
    for what, content in [("PLY vertex count -5", "ply\nformat ascii 1.0\nelement vertex -5\nend_header\n"),
                          ("PLY vertex count 1e11", "ply\nformat ascii 1.0\nelement vertex 99999999999\nend_header\n"),
                          ("PLY without end_header", "ply\nformat ascii 1.0\nelement vertex 3\n")]:
        d = p.fresh("mesh")
        r = p.run([p.papersim, "metrics", write(os.path.join(d, "m.ply"), content)])
        p.judge("mesh file", what, r, True)


def options(p, quick):
    d = p.fresh("options")
    mesh = write(os.path.join(d, "flat.obj"), p.example("flat"))
    scene = write(os.path.join(d, "s.json"), json.dumps(p.small_scene()))
    out = os.path.join(d, "out")
    cases = [
        [p.papersim], [p.papersim, "nope"], [p.papersim, "run"], [p.papersim, "run", scene],
        [p.papersim, "run", scene, "--out", ""], [p.papersim, "run", scene, "--out", out, "--frames", "-1"],
        [p.papersim, "run", scene, "--out", out, "--bogus"],
        [p.papersim, "run", scene, "--out", out, "--trace", "bogus"], [p.papersim, "run", scene, "--out", out, "--trace", ""],
        [p.papersim, "scenario", "pull", "--seed", "1", "--out", out, "--trace", "newton,"],
        [p.papersim, "scenario", "nope", "--seed", "1", "--out", out],
        [p.papersim, "scenario", "pull", "--seed", "-1", "--out", out],
        [p.papersim, "scenario", "pull", "--seed", "2147483648", "--draw-only", "--out", out],
        [p.papersim, "scenario", "pull", "--seed", "x", "--out", out],
        [p.papersim, "scenario", "pull", "--seed", "1", "--out", ""],
        [p.papersim, "metrics"], [p.papersim, "metrics", mesh, "--csv", ""],
        [p.papersim, "metrics", mesh, "--crease-angle", "400"], [p.papersim, "metrics", os.path.join(d, "missing.obj")],
        [p.scenegen], [p.scenegen, "nope"], [p.scenegen, "render", mesh],
        [p.scenegen, "example", "nope", "--out", os.path.join(d, "e.obj")],
        [p.scenegen, "example", "flat", "--out", ""],
        [p.papersim, "dataset-stats", mesh], [p.papersim, "dataset-stats", os.path.join(d, "missing")],
        [p.papersim, "dataset-stats", d, "--plots", mesh],
    ]
    for opt in [["--size", "128x180junk"], ["--size", "128"], ["--size", "0x0"], ["--size", "-128x180"],
                ["--size", "x"], ["--seed", "-1"], ["--seed", "1.5"], ["--seed", "abc"],
                ["--threads", "-1"], ["--dpi", "0"], ["--dpi", "-5"], ["--backward-grid", "3x3junk"],
                ["--passes", "nope"], ["--quality", "ultra"], ["--rig", "nope"], ["--out", ""]]:
        cases.append([p.scenegen, "prepare", mesh, "--out", os.path.join(d, "job")] + opt)
    cases.append([p.scenegen, "render", mesh, "--out", out, "--parallel", "-1"])
    batch = [p.papersim, "batch", "--out", out, "--scenarios", "pull", "--seeds", "0-1"]
    for opt in [["--jobs", "-2"], ["--jobs", "x"], ["--time-limit", "nan"], ["--time-limit", "-1"],
                ["--checkpoint-every", "-1"], ["--shard", "2/2"], ["--shard", "x"], ["--slurm", "0"],
                ["--slurm-cpus", "0"], ["--slurm-max-running", "-1"]]:
        cases.append(batch + opt)
    for scenarios, seeds in [("pull", "x"), ("pull", "5-1"), ("pull", ""), ("nope", "0-1"), ("", "0-1")]:
        cases.append(batch[:4] + ["--scenarios", scenarios, "--seeds", seeds])
    for opt in [["--views", "0"], ["--views", "-1"], ["--threads", "0"], ["--dpi", "-1"], ["--size", "0x0"],
                ["--jobs", "-1"], ["--quality", "ultra"], ["--passes", "nope"]]:
        cases.append([p.scenegen, "batch", d] + opt)
    ds = os.path.join(d, "ds")  # a dataset of one mesh, for the mesh lists
    os.makedirs(os.path.join(ds, "meshes", "pull", "0", "0"))
    write(os.path.join(ds, "meshes", "pull", "0", "0", "sheet.obj"), p.example("flat"))
    head = "# scenegen batch mesh list: %s meshes\n"
    for name, content in [("empty", ""), ("no head", "meshes/pull/0/0\n"), ("dots", head % 1 + "meshes/pull/../0\n"),
                          ("absolute", head % 1 + "/meshes/pull/0/0\n"), ("short", head % 2 + "meshes/pull/0/0\n"),
                          ("long seed", head % 1 + "meshes/pull/0/" + "9" * 20 + "\n"),
                          ("long count", head % ("9" * 20) + "meshes/pull/0/0\n"),
                          ("twice", head % 2 + "meshes/pull/0/0\nmeshes/pull/0/0\n"),
                          ("binary", head % 1 + "meshes/pull/0/\x00\n")]:
        f = write(os.path.join(d, name.replace(" ", "_") + ".meshes"), content)
        cases.append([p.scenegen, "batch", ds, "--mesh-list", f, "--shard", "0/2"])
        cases.append([p.scenegen, "batch", ds, "--mesh-list", f, "--slurm", "2"])
    for f in [os.path.join(d, "missing.meshes"), ds, mesh]:
        cases.append([p.scenegen, "batch", ds, "--mesh-list", f])
    # A dataset whose finished sample has no manifest row and a damaged meta.json: the batch must
    # stop naming the folder (status 2), not report an internal error.
    for name, meta in [("no meta", None), ("not json", "{"), ("no run", "{}"), ("run a list", '{"run": [], "quality": {}, "sheet": {}}'),
                       ("sheet a number", '{"run": {"steps": "x"}, "quality": {}, "sheet": 3}'),
                       ("bad metrics", '{"run": {}, "quality": {}, "sheet": {}}')]:
        damaged = os.path.join(d, "damaged-" + name.replace(" ", "_"))
        sample = os.path.join(damaged, "meshes", "pull", "0", "0")
        os.makedirs(sample)
        if meta is not None:
            write(os.path.join(sample, "meta.json"), meta)
        if name == "bad metrics":
            write(os.path.join(sample, "metrics.json"), '{"meshes": [{"metrics": {"creases": []}}]}')
        r = p.run([p.papersim, "batch", "--out", damaged, "--scenarios", "pull", "--seeds", "0", "--quiet"])
        p.judge("command line", "papersim batch on a dataset whose sample has %s" % name, r, True)
        if r["status"] not in (2, None) and not r["hang"]:
            p.count("command line", "badstatus", "damaged dataset (%s): status %s" % (name, r["status"]))
    for argv in cases:
        target = out if os.path.basename(argv[0]) == "papersim" else os.path.join(d, "job")
        shutil.rmtree(out, ignore_errors=True)
        shutil.rmtree(os.path.join(d, "job"), ignore_errors=True)
        r = p.run(argv)
        p.judge("command line", " ".join(os.path.basename(a) if a.startswith("/") else repr(a) if a == "" else a for a in argv), r, True, target)


def foreign_names(p, quick):
    """File names and --set values that are not UTF-8 (0xFF, here the surrogate escape \\udcff):
    names are written into the JSON outputs with U+FFFD in their place; values that would go
    into a scene, and dataset folders whose rows could not be written, are refused. Dataset
    folders a Slurm script cannot name are refused too."""
    d = p.fresh("names")
    ff = "\udcff"  # os.fsencode gives the byte 0xFF
    mesh = write(os.path.join(d, "sheet" + ff + ".obj"), p.example("flat"))
    out = os.path.join(d, "out")
    succeed = [
        ("prepare of a mesh named 0xFF", [p.scenegen, "prepare", mesh, "--out", os.path.join(d, "job"), "--size", "32x48"]),
        ("metrics --json of a mesh named 0xFF", [p.papersim, "metrics", mesh, "--json"]),
        ("metrics of the folder holding it", [p.papersim, "metrics", d]),
    ]
    for what, argv in succeed:
        shutil.rmtree(os.path.join(d, "job"), ignore_errors=True)
        p.judge("names", what, p.run(argv), False)
    ds = os.path.join(d, "ds")
    os.makedirs(os.path.join(ds, "meshes", "pu" + ff + "ll", "0", "0"))
    write(os.path.join(ds, "meshes", "pu" + ff + "ll", "0", "0", "sheet.obj"), p.example("flat"))
    with open(os.path.join(d, "list.meshes"), "wb") as f:
        f.write(b"# scenegen batch mesh list: 1 meshes\nmeshes/pu\xffll/0/0\n")
    listed = os.path.join(d, "list.meshes")
    fail = [
        ("batch --set name=0xFF", [p.papersim, "batch", "--out", out, "--scenarios", "pull", "--seeds", "0", "--set", "name=" + ff], out),
        ("batch --set 0xFF=1", [p.papersim, "batch", "--out", out, "--scenarios", "pull", "--seeds", "0", "--set", ff + "=1"], out),
        ("scenegen batch over a scenario folder named 0xFF", [p.scenegen, "batch", ds, "--size", "32x48"], os.path.join(ds, "renders")),
        ("scenegen batch --slurm over a scenario folder named 0xFF", [p.scenegen, "batch", ds, "--slurm", "2"], os.path.join(ds, "slurm")),
        ("scenegen batch --mesh-list with a line of 0xFF", [p.scenegen, "batch", ds, "--mesh-list", listed], os.path.join(ds, "renders")),
    ]
    for what, argv, target in fail:
        p.judge("names", what, p.run(argv), True, target)
    # Dataset folders a Slurm script must name: a space and '#' are quoted, a '%' (sbatch's log
    # name pattern) and a backslash (its escape) are refused before anything is written.
    spaced = os.path.join(d, "my data #2")
    p.judge("names", "batch --slurm into 'my data #2'",
            p.run([p.papersim, "batch", "--out", spaced, "--scenarios", "pull", "--seeds", "0-3", "--slurm", "2"]), False)
    for name in ["a%Ab", "a\\b"]:
        target = os.path.join(d, name)
        p.judge("names", "batch --slurm into '%s'" % name,
                p.run([p.papersim, "batch", "--out", target, "--scenarios", "pull", "--seeds", "0-3", "--slurm", "2"]),
                True, target)


def limits(p, quick):
    d = p.fresh("limits")
    mesh = write(os.path.join(d, "flat.obj"), p.example("flat"))
    r = p.run([p.scenegen, "render", mesh, "--out", os.path.join(d, "big"), "--size", "100000x100000", "--quiet"], timeout=TIMEOUT)
    p.judge("limits", "--size 100000x100000", r, True, os.path.join(d, "big"))
    big = os.path.join(d, "million.obj")
    with open(big, "w") as f:
        f.write("# papersim sheet 0.2 0.3\n")
        n = 1000
        for j in range(n):
            f.write("".join("v %g %g 0\n" % (0.2 * i / (n - 1), 0.3 * j / (n - 1)) for i in range(n)))
        for j in range(n):
            f.write("".join("vt %g %g\n" % (i / (n - 1), j / (n - 1)) for i in range(n)))
        for j in range(n - 1):
            f.write("".join("f %d/%d %d/%d %d/%d\n" % (a, a, a + 1, a + 1, a + n + 1, a + n + 1)
                            for a in (j * n + i + 1 for i in range(n - 1))))
    r = p.run([p.scenegen, "prepare", big, "--out", os.path.join(d, "job"), "--size", "32x48"], timeout=TIMEOUT)
    p.judge("limits", "1M-vertex mesh (scenegen)", r, True, os.path.join(d, "job"))
    r = p.run([p.papersim, "metrics", big], timeout=TIMEOUT)
    p.judge("limits", "1M-vertex mesh (metrics)", r, True)
    s = p.small_scene()
    s["sheet"]["edge_length"] = 1e-4
    r = p.run([p.papersim, "run", write(os.path.join(d, "s.json"), json.dumps(s)), "--out", os.path.join(d, "out")], timeout=TIMEOUT)
    p.judge("limits", "edge_length 1e-4 (4.4M vertices)", r, True, os.path.join(d, "out"))


def full_disk(p, quick):
    """Every writing command on a full disk."""
    mnt = os.path.join(p.work, "disk")
    os.makedirs(mnt)
    mounted = False
    if os.geteuid() == 0:
        mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs", mnt],
                                 capture_output=True).returncode == 0
    fsize = None if mounted else 0
    p.full_disk_method = "a filled 256 KiB tmpfs" if mounted else "a file size limit of 0 bytes"
    if mounted:
        fd = os.open(os.path.join(mnt, "filler"), os.O_WRONLY | os.O_CREAT)
        for size in (4096, 1):  # whole pages, then the last bytes
            try:
                while os.write(fd, b"x" * size) == size:
                    pass
            except OSError:
                pass
        os.close(fd)
    d = p.fresh("fullinputs")
    mesh = write(os.path.join(d, "c.obj"), p.example("cylinder"))
    scene = write(os.path.join(d, "s.json"), json.dumps(p.small_scene()))
    dataset = os.path.join(d, "dataset")  # a dataset's manifest, for dataset-stats --plots
    os.makedirs(dataset)
    write(os.path.join(dataset, "manifest.jsonl"),
          "".join(json.dumps({"key": "pull/%d" % i, "scenario": "pull", "wall_seconds": 1.0 + i}) + "\n" for i in range(5)))
    cases = [
        ("papersim run", [p.papersim, "run", scene, "--out", os.path.join(mnt, "run"), "--quiet"], os.path.join(mnt, "run")),
        ("papersim scenario --draw-only", [p.papersim, "scenario", "pull", "--seed", "1", "--draw-only", "--out", os.path.join(mnt, "drawn")], os.path.join(mnt, "drawn")),
        ("papersim metrics --csv", [p.papersim, "metrics", mesh, "--csv", os.path.join(mnt, "m.csv")], None),
        ("papersim metrics --plots", [p.papersim, "metrics", mesh, "--plots", os.path.join(mnt, "plots")], None),
        ("papersim dataset-stats --plots", [p.papersim, "dataset-stats", dataset, "--plots", os.path.join(mnt, "stats")], None),
        ("scenegen example", [p.scenegen, "example", "flat", "--out", os.path.join(mnt, "flat.obj")], None),
        ("scenegen render", [p.scenegen, "render", mesh, "--out", os.path.join(mnt, "sample"), "--size", "32x48", "--quality", "draft", "--quiet"], os.path.join(mnt, "sample")),
        ("papersim batch", [p.papersim, "batch", "--out", os.path.join(mnt, "ds"), "--scenarios", "pull", "--seeds", "0-3",
                            "--set", "duration=0.05", "--set", "sheet.edge_length=0.02", "--quiet"], None),
    ]
    for what, argv, out in cases:
        r = p.run(argv, fsize=fsize)
        p.judge("full disk", what, r, False, out, full_disk=True)
        ds = os.path.join(mnt, "ds")  # a batch: no sample folder, no row, no staging folder left
        if os.path.isdir(ds):
            left = [n for n in ("meshes", "manifest.jsonl", "failures.jsonl")
                    if os.path.exists(os.path.join(ds, n)) and (os.path.isdir(os.path.join(ds, n)) or os.path.getsize(os.path.join(ds, n)) > 0)]
            left += [os.path.join(".staging", n) for n in os.listdir(os.path.join(ds, ".staging"))] if os.path.isdir(os.path.join(ds, ".staging")) else []
            if left:
                p.count("full disk", "partial", "%s left %s" % (what, left[:3]))
        # A dataset's empty lock files are its bookkeeping, kept by every batch (docs/batch.md).
        files = [n for n in leftovers(mnt, ["filler"]) if not os.path.isdir(os.path.join(mnt, n))
                 and not n.startswith(os.path.join("ds", ".locks") + os.sep)]
        if files:
            p.count("full disk", "partial", "%s left %s" % (what, files[:3]))
        for n in os.listdir(mnt):
            if n != "filler":
                full = os.path.join(mnt, n)
                shutil.rmtree(full, ignore_errors=True) if os.path.isdir(full) else os.remove(full)
    if mounted:
        subprocess.run(["umount", mnt])


def mixed_outputs(p, quick):
    d = p.fresh("mixed")
    s = p.small_scene()
    out = os.path.join(d, "out")
    s["output"]["ply"] = True
    r = p.run([p.papersim, "run", write(os.path.join(d, "a.json"), json.dumps(s)), "--out", out, "--frames", "2", "--quiet"])
    s["output"]["ply"] = False
    r = p.run([p.papersim, "run", write(os.path.join(d, "b.json"), json.dumps(s)), "--out", out, "--quiet"])
    p.judge("re-run into a used folder", "papersim ply false after true", r, False)
    if sorted(os.listdir(out)) != ["meta.json", "sheet.obj"] or "sheet.ply" in r["out"]:
        p.count("re-run into a used folder", "partial", "papersim: %s after 'ply: false'; said %r" % (sorted(os.listdir(out)), r["out"][:60]))
    mesh = write(os.path.join(d, "flat.obj"), p.example("flat"))
    sample = os.path.join(d, "sample")
    p.run([p.scenegen, "render", mesh, "--out", sample, "--size", "32x48", "--quality", "draft", "--quiet"])
    r = p.run([p.scenegen, "render", mesh, "--out", sample, "--size", "32x48", "--quality", "draft", "--passes", "mask", "--quiet"])
    p.judge("re-run into a used folder", "scenegen fewer passes", r, False)
    expected = ["document.png", "mask.png", "meta.json"]
    if sorted(os.listdir(sample)) != expected:
        p.count("re-run into a used folder", "partial", "scenegen --passes mask after all: %s" % sorted(os.listdir(sample)))
    fold = os.path.join(d, "fold.obj")
    # a sheet folded flat on itself (fold 178 degrees): no camera sees it whole
    write(fold, folded_sheet())
    r = p.run([p.scenegen, "render", fold, "--out", sample, "--size", "32x48", "--quiet"])
    p.judge("re-run into a used folder", "scenegen no valid camera over a sample", r, False)
    if r["status"] == 3 and sorted(os.listdir(sample)) != ["meta.json"]:
        p.count("re-run into a used folder", "partial", "no valid camera left %s" % sorted(os.listdir(sample)))


def folded_sheet():
    """A 0.2 x 0.3 m sheet folded 180 degrees at x = 0.1 (the two halves 1 mm apart)."""
    nx, ny = 11, 16
    v, vt, f = [], [], []
    for j in range(ny):
        for i in range(nx):
            x, y = 0.2 * i / (nx - 1), 0.3 * j / (ny - 1)
            v.append((x, y, 0.0) if x <= 0.1 else (0.2 - x, y, 0.001))
            vt.append((i / (nx - 1), j / (ny - 1)))
    for j in range(ny - 1):
        for i in range(nx - 1):
            a = j * nx + i + 1
            f.append((a, a + 1, a + nx + 1))
            f.append((a, a + nx + 1, a + nx))
    return ("# papersim sheet 0.2 0.3\n" + "".join("v %g %g %g\n" % p for p in v) +
            "".join("vt %g %g\n" % t for t in vt) +
            "".join("f %d/%d %d/%d %d/%d\n" % (a, a, b, b, c, c) for a, b, c in f))


def interruptions(p, quick):
    s = p.small_scene()
    s["duration"] = 0.3
    d = p.fresh("interrupt")
    scene = write(os.path.join(d, "s.json"), json.dumps(s))
    t0 = time.time()
    p.run([p.papersim, "run", scene, "--out", os.path.join(d, "baseline"), "--quiet", "--frames", "1"])
    papersim_seconds = time.time() - t0
    mesh = write(os.path.join(d, "c.obj"), p.example("cylinder"))
    render = ["--size", "64x90", "--quiet"]
    t0 = time.time()
    p.run([p.scenegen, "render", mesh, "--out", os.path.join(d, "sample-baseline")] + render)
    scenegen_seconds = time.time() - t0
    for program, seconds in [("papersim", papersim_seconds), ("scenegen", scenegen_seconds)]:
        for fraction in [0.25, 0.5, 0.9]:
            for sig in [signal.SIGINT, signal.SIGTERM, signal.SIGKILL]:
                out = os.path.join(p.fresh("interrupt"), "out")
                if program == "papersim":
                    argv = [p.papersim, "run", scene, "--out", out, "--quiet", "--frames", "1"]
                else:
                    argv = [p.scenegen, "render", mesh, "--out", out] + render
                proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
                time.sleep(seconds * fraction)
                kids = children(proc.pid)
                sent = time.time()
                proc.send_signal(sig)
                try:
                    _, err = proc.communicate(timeout=TIMEOUT)
                    took = time.time() - sent
                except subprocess.TimeoutExpired:
                    proc.kill()
                    p.seen("interruption")
                    p.count("interruption", "hang", "%s %s at %d%%" % (program, sig.name, fraction * 100))
                    continue
                what = "%s %s at %d%%" % (program, signal.Signals(sig).name, fraction * 100)
                p.seen("interruption")
                if proc.returncode == 0:
                    continue  # finished before the signal
                time.sleep(0.5)
                alive = [k for k in kids if is_alive(k)]
                if alive:
                    p.count("interruption", "partial", "%s: POV-Ray %s still running" % (what, alive))
                    for k in alive:
                        os.kill(k, signal.SIGKILL)
                if sig != signal.SIGKILL:
                    if took > 1.0:
                        p.count("interruption", "hang", "%s: took %.1f s to stop" % (what, took))
                    if os.path.exists(out):
                        p.count("interruption", "partial", "%s left %s" % (what, leftovers(out, [])[:3] or [out]))
                    if proc.returncode > 0 and proc.returncode not in DOCUMENTED:
                        p.count("interruption", "badstatus", "%s: status %d" % (what, proc.returncode))
                else:
                    # The next run into the same output must remove what SIGKILL left.
                    if program == "papersim":
                        bad = dict(s)
                        bad["duration"] = -1
                        p.run([p.papersim, "run", write(os.path.join(os.path.dirname(out), "bad.json"), json.dumps(bad)), "--out", out])
                    else:
                        p.run([p.scenegen, "render", mesh, "--out", out, "--size", "32x48", "--povray", "/bin/false"])
                    if hidden(out):
                        p.count("interruption", "partial", "%s: the next run left %s" % (what, hidden(out)))


def kill_tree(pid):
    """SIGKILL the descendants of `pid` (a hung scenegen's POV-Ray would run on)."""
    for kid in children(pid):
        kill_tree(kid)
        try:
            os.kill(kid, signal.SIGKILL)
        except OSError:
            pass


def children(pid):
    kids = []
    try:
        for task in os.listdir("/proc/%d/task" % pid):
            with open("/proc/%d/task/%s/children" % (pid, task)) as f:
                kids += [int(k) for k in f.read().split()]
    except OSError:
        pass
    return kids


def is_alive(pid):
    try:
        with open("/proc/%d/stat" % pid) as f:
            stat = f.read()
        return stat[stat.rfind(")") + 2] != "Z"
    except OSError:
        return False


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--papersim", required=True)
    ap.add_argument("--scenegen", required=True)
    ap.add_argument("--quick", action="store_true", help="fewer scene mutations")
    ap.add_argument("--examples", action="store_true", help="print one example per non-zero count")
    args = ap.parse_args()
    work = tempfile.mkdtemp(prefix="papersim-probe-")
    p = Probe(os.path.abspath(args.papersim), os.path.abspath(args.scenegen), work)
    p.full_disk_method = "?"
    t0 = time.time()
    try:
        for family in [scene_files, mesh_files, options, foreign_names, limits, full_disk, mixed_outputs, interruptions]:
            family(p, args.quick)
    finally:
        subprocess.run(["umount", os.path.join(work, "disk")], capture_output=True)
        shutil.rmtree(work, ignore_errors=True)
    header = ["family", "inputs"] + CATEGORIES
    rows = [[f, str(c["inputs"])] + [str(c[k]) for k in CATEGORIES] for f, c in p.counts.items()]
    total = ["total", str(sum(c["inputs"] for c in p.counts.values()))] + \
            [str(sum(c[k] for c in p.counts.values())) for k in CATEGORIES]
    rows.append(total)
    widths = [max(len(r[i]) for r in rows + [header]) for i in range(len(header))]
    print("papersim %s, scenegen %s; full disk: %s; %.0f s" % (args.papersim, args.scenegen, p.full_disk_method, time.time() - t0))
    print("| " + " | ".join(h.ljust(w) for h, w in zip(header, widths)) + " |")
    print("|" + "|".join("-" * (w + 2) for w in widths) + "|")
    for r in rows:
        print("| " + " | ".join(x.ljust(w) for x, w in zip(r, widths)) + " |")
    if args.examples:
        for (family, category), what in sorted(p.examples.items()):
            print("  %s / %s: %s" % (family, category, what))
    return 1 if any(int(x) for x in total[2:]) else 0


if __name__ == "__main__":
    sys.exit(main())
