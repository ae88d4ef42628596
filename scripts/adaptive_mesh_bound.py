#!/usr/bin/env python3
"""How many vertices would an ideal adapted mesh need to resolve a sheet as well as a uniform one?

Reads sheets written by papersim (sheet.obj: positions, material coordinates as `vt` in units
of the sheet's width and height from the `# papersim sheet W H` header) and, from the shape of
each, estimates the RMS interpolation error of a uniform mesh of edge --uniform and the fewest
vertices an adapted mesh needs for the same RMS error, isotropic and anisotropic.

Model. A linear triangle on a surface whose principal curvatures are a >= b >= 0 (absolute
values), with extents h1 across the principal direction of a and h2 along it, deviates from the
surface by e = (a h1^2 + b h2^2) / 8; it covers about h1 h2 of the sheet, so the vertex density is
1 / (h1 h2) (the uniform mesh: h1 = h2 = h, e = (a + b) h^2 / 8). An element's aspect
rho = h1 / h2 is bounded below by aspect_min. For a given local error, the density is least at
rho = sqrt(b / a) clamped to [aspect_min, 1], giving density = (rho a + b / rho) / (8 e); the RMS
error over the sheet at the fewest vertices is then met with e proportional to k^(1/3), where
k = rho a + b / rho (a Lagrange multiplier argument). Without size limits the ratio of vertex
counts at equal RMS error is closed:

    N_adapted / N_uniform = <k^(2/3)>^(3/2) / <(a + b)^2>^(1/2)      (<> : mean over material area)

a lower bound for any mesh that obeys the aspect limit, under this model: size limits only add
vertices. With --size-min / --size-max the same allocation is clamped (h1 >= size_min,
h1, h2 <= size_max) and the error level found again by bisection; that is a mesh that exists, so
its count is one the ideal stays below.

Curvature per face: the gradient, in material coordinates, of the area-weighted vertex normals
interpolated linearly over the face, with the face's metric (the sheet is nearly isometric).

    scripts/adaptive_mesh_bound.py --uniform 7 --size-min 3 --size-max 20 DIR/seed_0/reference/sheet.obj ...
"""
import argparse
import math
import statistics
import sys


def fail(message):
    """Bad input: say what and where, exit 2 (as papersim does)."""
    print(f"adaptive_mesh_bound: {message}", file=sys.stderr)
    sys.exit(2)


def read_sheet(path):
    """Positions, material coordinates (m) and faces of a papersim sheet.obj."""
    pos, tex, faces = [], [], []
    width = height = None
    try:
        with open(path) as f:
            for n, line in enumerate(f, 1):
                parts = line.split()
                if not parts:
                    continue
                if parts[0] == "#" and parts[1:3] == ["papersim", "sheet"]:
                    width, height = float(parts[3]), float(parts[4])
                elif parts[0] == "v":
                    pos.append(tuple(float(x) for x in parts[1:4]))
                elif parts[0] == "vt":
                    tex.append((float(parts[1]), float(parts[2])))
                elif parts[0] == "f":
                    corners = [p.split("/") for p in parts[1:]]
                    if len(corners) != 3 or any(len(c) < 2 for c in corners):
                        fail(f"{path}:{n}: want a triangle with v/vt indices")
                    if any(c[0] != c[1] for c in corners):
                        fail(f"{path}:{n}: v and vt indices differ")
                    faces.append(tuple(int(c[0]) - 1 for c in corners))
    except (OSError, ValueError, IndexError) as e:
        fail(f"{path}: {e}")
    if width is None:
        fail(f"{path}: no '# papersim sheet W H' header")
    if len(tex) != len(pos) or not faces:
        fail(f"{path}: {len(pos)} positions, {len(tex)} material points, "
                 f"{len(faces)} faces")
    mat = [(u * width, v * height) for u, v in tex]
    return pos, mat, faces, width * height


def sub(p, q):
    return (p[0] - q[0], p[1] - q[1], p[2] - q[2])


def cross(p, q):
    return (p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0])


def dot(p, q):
    return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]


def face_curvatures(pos, mat, faces):
    """(material area, |k1|, |k2|) per face, |k1| >= |k2|."""
    normals = [[0.0, 0.0, 0.0] for _ in pos]
    for i, j, k in faces:
        n = cross(sub(pos[j], pos[i]), sub(pos[k], pos[i]))  # length: twice the area
        for v in (i, j, k):
            for c in range(3):
                normals[v][c] += n[c]
    for n in normals:
        length = math.sqrt(dot(n, n)) or 1.0  # a vertex of no face keeps a zero normal
        for c in range(3):
            n[c] /= length
    out = []
    for i, j, k in faces:
        # Material edge matrix D = [X1-X0, X2-X0] (2x2) and its inverse.
        d00, d10 = mat[j][0] - mat[i][0], mat[j][1] - mat[i][1]
        d01, d11 = mat[k][0] - mat[i][0], mat[k][1] - mat[i][1]
        det = d00 * d11 - d01 * d10
        area = abs(det) / 2
        if det == 0:
            continue  # no material area: it weighs nothing in the means
        inv = ((d11 / det, -d01 / det), (-d10 / det, d00 / det))
        e1, e2 = sub(pos[j], pos[i]), sub(pos[k], pos[i])
        m1, m2 = sub(normals[j], normals[i]), sub(normals[k], normals[i])
        # Columns of x_,X (world tangents) and n_,X in material directions.
        t = [tuple(e1[c] * inv[0][a] + e2[c] * inv[1][a] for c in range(3)) for a in (0, 1)]
        dn = [tuple(m1[c] * inv[0][a] + m2[c] * inv[1][a] for c in range(3)) for a in (0, 1)]
        g = [[dot(t[a], t[b]) for b in (0, 1)] for a in (0, 1)]
        s = [[-(dot(t[a], dn[b]) + dot(t[b], dn[a])) / 2 for b in (0, 1)] for a in (0, 1)]
        # Principal curvatures: eigenvalues of g^-1 s.
        gdet = g[0][0] * g[1][1] - g[0][1] * g[1][0]
        if gdet <= 0:
            continue  # collapsed in space: no tangent plane to measure on
        w = [[(g[1][1] * s[0][b] - g[0][1] * s[1][b]) / gdet for b in (0, 1)],
             [(-g[1][0] * s[0][b] + g[0][0] * s[1][b]) / gdet for b in (0, 1)]]
        tr, dt = w[0][0] + w[1][1], w[0][0] * w[1][1] - w[0][1] * w[1][0]
        disc = math.sqrt(max(tr * tr / 4 - dt, 0.0))
        k1, k2 = abs(tr / 2 + disc), abs(tr / 2 - disc)
        out.append((area, max(k1, k2), min(k1, k2)))
    return out


def rho_for(a, b, aspect_min):
    return min(1.0, max(aspect_min, math.sqrt(b / a))) if a > 0 else 1.0


def effective_curvature(a, b, rho):
    """k = rho a + b / rho: the density an element of aspect rho needs per unit error is k / (8 e)."""
    return rho * a + b / rho


def uniform_error(curv, h):
    """RMS deviation of a uniform mesh of edge h: e = (a + b) h^2 / 8 per face."""
    total = sum(A for A, _, _ in curv)
    return h * h / 8 * math.sqrt(sum(A * (a + b) ** 2 for A, a, b in curv) / total)


def closed_ratio(curv, aspect_min):
    total = sum(A for A, _, _ in curv)
    mean_k23 = sum(A * effective_curvature(a, b, rho_for(a, b, aspect_min)) ** (2 / 3)
                   for A, a, b in curv) / total
    mean_iso2 = sum(A * (a + b) ** 2 for A, a, b in curv) / total
    return mean_k23 ** 1.5 / math.sqrt(mean_iso2)


def clamped_mesh(curv, aspect_min, size_min, size_max, scale):
    """Vertices (per unit area, integrated) and RMS error of the clamped allocation e = scale k^(1/3)."""
    total = verts = err2 = 0.0
    for A, a, b in curv:
        rho = rho_for(a, b, aspect_min)
        k = effective_curvature(a, b, rho)
        if k > 0:
            e = scale * k ** (1 / 3)
            h1 = math.sqrt(8 * e / (a + b / rho ** 2))
        else:
            h1 = size_max
        h1 = min(max(h1, size_min), size_max)
        h2 = min(h1 / rho, size_max)
        total += A
        verts += A / (h1 * h2)
        err2 += A * ((a * h1 * h1 + b * h2 * h2) / 8) ** 2
    return verts, math.sqrt(err2 / total)


def clamped_ratio(curv, aspect_min, size_min, size_max, target_err, uniform_verts):
    lo, hi = 1e-12, 1.0
    for _ in range(100):
        mid = math.sqrt(lo * hi)
        _, err = clamped_mesh(curv, aspect_min, size_min, size_max, mid)
        if err > target_err:
            hi = mid
        else:
            lo = mid
    verts, err = clamped_mesh(curv, aspect_min, size_min, size_max, lo)
    return verts / uniform_verts, err


def synthetic_sheet(radius, flat_share, edge=0.0035, width=0.21, height=0.297):
    """A grid sheet flat on x < flat_share * width and rolled on a cylinder of `radius` beyond."""
    nx, ny = round(width / edge) + 1, round(height / edge) + 1
    x0 = flat_share * width
    pos, mat, faces = [], [], []
    for j in range(ny):
        for i in range(nx):
            X, Y = width * i / (nx - 1), height * j / (ny - 1)
            s = max(X - x0, 0.0)
            pos.append((min(X, x0) + radius * math.sin(s / radius), Y, radius * (1 - math.cos(s / radius))))
            mat.append((X, Y))
    for j in range(ny - 1):
        for i in range(nx - 1):
            a = j * nx + i
            faces += [(a, a + 1, a + nx + 1), (a, a + nx + 1, a + nx)]
    return pos, mat, faces


def self_test():
    """Known answers: a sheet rolled on a cylinder, and one half flat and half rolled."""
    h, smax, radius = 0.007, 0.020, 0.05
    failures = []

    def check(name, got, want, rel):
        ok = abs(got - want) <= rel * abs(want)
        print(f"{'ok  ' if ok else 'FAIL'} {name}: {got:.4f} (want {want:.4f} within {rel:.0%})")
        if not ok:
            failures.append(name)

    # Rolled sheet: a = 1 / R, b = 0. The uniform mesh's error is h^2 / (8 R); an element may be
    # 1 / aspect_min times longer along the axis at the same error, so the ideal count is
    # aspect_min of the uniform one, and with size_max the longer extent stops at size_max.
    curv = face_curvatures(*synthetic_sheet(radius, 0.0))
    total = sum(A for A, _, _ in curv)
    err = uniform_error(curv, h)
    check("cylinder: uniform error, mm", err * 1000, h * h / (8 * radius) * 1000, 0.02)
    for x in (1.0, 0.7, 0.5, 0.2):
        check(f"cylinder: ideal ratio at aspect {x:g}", closed_ratio(curv, x), x, 0.01)
        got, _ = clamped_ratio(curv, x, 0.003, smax, err, total / (h * h))
        check(f"cylinder: clamped ratio at aspect {x:g}", got, max(x, h / smax), 0.01)
    # Half flat, half rolled: the ideal isotropic mesh puts no vertex on the flat half and the
    # uniform mesh's size on the rolled one (half the count); with size_max the flat half costs
    # (h / size_max)^2 of its uniform count.
    curv = face_curvatures(*synthetic_sheet(radius, 0.5))
    total = sum(A for A, _, _ in curv)
    err = uniform_error(curv, h)
    check("half rolled: ideal isotropic ratio", closed_ratio(curv, 1.0), 0.5, 0.03)
    got, _ = clamped_ratio(curv, 1.0, 0.003, smax, err, total / (h * h))
    check("half rolled: clamped isotropic ratio", got, 0.5 + 0.5 * (h / smax) ** 2, 0.03)
    return 1 if failures else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("sheets", nargs="*", help="sheet.obj files written by papersim")
    ap.add_argument("--uniform", type=float, default=7.0, help="uniform mesh's edge, mm (default 7)")
    ap.add_argument("--size-min", type=float, default=3.0, help="adapted mesh's size_min, mm (default 3)")
    ap.add_argument("--size-max", type=float, default=20.0, help="adapted mesh's size_max, mm (default 20)")
    ap.add_argument("--aspects", default="1,0.7,0.5,0.2", help="aspect_min values (default 1,0.7,0.5,0.2)")
    ap.add_argument("--self-test", action="store_true",
                    help="check the estimates against known answers on synthetic sheets and exit")
    args = ap.parse_args()
    if args.self_test:
        return self_test()
    if not args.sheets:
        ap.error("want at least one sheet.obj (or --self-test)")
    try:
        aspects = [float(x) for x in args.aspects.split(",")]
    except ValueError:
        fail(f"--aspects: want numbers in (0, 1], got {args.aspects!r}")
    if any(not 0 < x <= 1 for x in aspects):
        fail(f"--aspects: want numbers in (0, 1], got {args.aspects!r}")
    if not 0 < args.size_min <= args.size_max:
        fail("want 0 < --size-min <= --size-max")
    h = args.uniform / 1000
    smin, smax = args.size_min / 1000, args.size_max / 1000

    sheets = [(path, read_sheet(path)) for path in args.sheets]  # every file read before output
    head = ["sheet", "uniform_err_mm"] + [f"ideal_a{x:g}" for x in aspects] + \
        [f"clamped_a{x:g}" for x in aspects]
    print(",".join(head))
    columns = {name: [] for name in head[1:]}
    for path, (pos, mat, faces, _) in sheets:
        curv = face_curvatures(pos, mat, faces)
        total = sum(A for A, _, _ in curv)
        uniform_err = uniform_error(curv, h)
        uniform_verts = total / (h * h)
        row = {"uniform_err_mm": uniform_err * 1000}
        for x in aspects:
            row[f"ideal_a{x:g}"] = closed_ratio(curv, x)
            row[f"clamped_a{x:g}"], _ = clamped_ratio(curv, x, smin, smax, uniform_err, uniform_verts)
        print(",".join([path] + [f"{row[n]:.4f}" for n in head[1:]]), flush=True)
        for n in head[1:]:
            columns[n].append(row[n])
    if len(args.sheets) > 1:
        print(",".join(["median"] + [f"{statistics.median(columns[n]):.4f}" for n in head[1:]]))


if __name__ == "__main__":
    sys.exit(main())
