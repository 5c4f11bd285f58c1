#!/usr/bin/python3
"""Graded meshes side by side: Gmsh 4.8 on a distance-graded size field against polysquare's graded mode.

usage: bench/graded.py [--case data/cases/channel_estuary.geojson] [--size-min HMIN] [--size-max 500] [--grade 0.15]
                       [--across N] [--threads 2] [--out out/graded] [--timeout 1200] [--skip-gmsh]
                       [--skip-polysquare] [--cli build/polysquare] [--polysquare-args "..."]

The size field both tools are asked for: h(x) = min(HMAX, HMIN + G d(x)), d the distance to the domain boundary
(and to feature curves). HMIN defaults to the narrowest channel width / 3 when the case has a centre-line sidecar
(CASE.centerlines.json, from scripts/make-channel-estuary), else 15 m.

Gmsh 4.8.4 (/usr/bin/gmsh): the geometry from scripts/make-gmsh-geo (rings split at turns above 30 degrees, splines),
then Field[1] = Distance over every curve (NumPointsPerCurve: 4.8's name for later versions' Sampling), Field[2] =
Threshold (SizeMin HMIN, SizeMax HMAX, DistMin 0, DistMax (HMAX - HMIN) / G: linear in between, so h = HMIN + G d),
Background Field = 2, sizes from points, curvature and boundary extension off, Mesh.Algorithm 6 (Frontal-Delaunay)
+ RecombinationAlgorithm 1 (Blossom), Recombine Surface{:}. polysquare: `mesh CASE --size-min HMIN --size-max HMAX
--grade G [--across N]`; when its --help does not list --size-min the run is reported as not available.

Each mesh is judged independently: /work/shared/tools/judge.py (regular quad fraction, interior singular nodes per
1000 quads, SJ min), size conformity computed here (sqrt(quad area) / h(centroid), h as above with shapely
distances to the boundary: median, p05, p95), the neighbour size ratio (sqrt of the larger over the smaller area of
two quads sharing an edge: p99, max), and bench/channel_sections.py (fewest quads across a channel section, edge
ratio, orthogonality) when the sidecar exists. Wall time and peak memory are those of the mesher's process.
Needs /usr/bin/python3 with Debian's python3-numpy, python3-meshio and python3-shapely (1.8)."""
import argparse, contextlib, io, json, math, os, re, shlex, signal, subprocess, sys, time

import warnings

import numpy as np
import meshio
warnings.filterwarnings("ignore", message=".*STRtree will be changed.*")
from shapely.geometry import LineString, Point, shape
from shapely.ops import unary_union
from shapely.strtree import STRtree


def quiet_read(path):
    """meshio.read without the blank lines meshio 5.0's MSH reader prints on stdout."""
    with contextlib.redirect_stdout(io.StringIO()):
        return meshio.read(path)

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
JUDGE = "/work/shared/tools/judge.py"
PY = "/usr/bin/python3"


def run_timed(cmd, log, timeout, cwd=None):
    """Runs cmd with stdout+stderr to log; returns (exit code or None on timeout, wall s, peak RSS GB)."""
    t0 = time.time()
    with open(log, "w") as f:
        p = subprocess.Popen(cmd, stdout=f, stderr=subprocess.STDOUT, cwd=cwd, start_new_session=True)
        while True:
            pid, status, ru = os.wait4(p.pid, os.WNOHANG)
            if pid == p.pid:
                p.returncode = os.waitstatus_to_exitcode(status)
                return p.returncode, time.time() - t0, ru.ru_maxrss / 1024.0 / 1024.0
            if time.time() - t0 > timeout:
                os.killpg(p.pid, signal.SIGKILL)      # the process group this function started
                pid, status, ru = os.wait4(p.pid, 0)
                return None, time.time() - t0, ru.ru_maxrss / 1024.0 / 1024.0
            time.sleep(0.1)


def read_case(path):
    fc = json.load(open(path))
    feats = fc["features"] if "features" in fc else [fc]
    dom, lines = [], []
    for f in feats:
        role = f.get("properties", {}).get("role")
        g = shape(f["geometry"])
        if role == "domain" or (role is None and g.geom_type in ("Polygon", "MultiPolygon")):
            dom.append(g)
        elif role == "feature" or (role is None and "Line" in g.geom_type):
            lines.append(g.boundary if g.geom_type.endswith("Polygon") else g)
    return unary_union(dom), lines


def boundary_segments(domain, features):
    segs = []
    polys = list(domain.geoms) if hasattr(domain, "geoms") else [domain]
    rings = [r for p in polys for r in [p.exterior] + list(p.interiors)]
    curves = [np.asarray(r.coords) for r in rings]
    for f in features:
        for g in (f.geoms if hasattr(f, "geoms") else [f]):
            if g.geom_type == "LineString":
                curves.append(np.asarray(g.coords))
    for c in curves:
        # chunks of up to 8 segments: few tree items, short exact distances
        for i in range(0, len(c) - 1, 8):
            segs.append(LineString(c[i:min(i + 9, len(c))]))
    return segs


def distance_to(points, segs):
    tree = STRtree(segs)
    out = np.empty(len(points))
    for k, (x, y) in enumerate(points):
        p = Point(x, y)
        out[k] = tree.nearest(p).distance(p)
    return out


def size_figures(mesh, domain, features, hmin, hmax, grade):
    m = quiet_read(mesh)
    P = np.asarray(m.points, float)[:, :2]
    qs = [c.data for c in m.cells if c.type == "quad"]
    if not qs:
        return {}
    Q = np.concatenate(qs).astype(np.int64)
    X = P[Q]
    x0 = X[:, :1, :]
    Y = X - x0
    xs, ys = Y[:, :, 0], Y[:, :, 1]
    c = xs * np.roll(ys, -1, 1) - np.roll(xs, -1, 1) * ys
    area = np.abs(c.sum(1) / 2)
    cen = X.mean(1)
    t0 = time.time()
    # shapely distances cost ~80 us a quad: above 400k quads the size ratio is taken on a fixed sample of 400k
    pick = np.arange(len(Q)) if len(Q) <= 400000 else np.sort(np.random.default_rng(0).choice(len(Q), 400000, replace=False))
    d = distance_to(cen[pick], boundary_segments(domain, features))
    h = np.minimum(hmax, hmin + grade * d)
    r = np.sqrt(area[pick]) / h
    # neighbour size ratio over quads sharing an edge
    E = np.sort(np.stack([Q, np.roll(Q, -1, 1)], 2).reshape(-1, 2), 1)
    own = np.repeat(np.arange(len(Q)), 4)
    key = E[:, 0] * (len(P) + 1) + E[:, 1]
    o = np.argsort(key, kind="stable")
    same = np.nonzero(key[o][1:] == key[o][:-1])[0]
    a1, a2 = area[own[o[same]]], area[own[o[same + 1]]]
    nr = np.sqrt(np.maximum(a1, a2) / np.maximum(np.minimum(a1, a2), 1e-300))
    worst = own[o[same[int(np.argmax(nr))]]] if len(nr) else 0
    return dict(size_ratio_median=round(float(np.median(r)), 4), size_ratio_p05=round(float(np.quantile(r, 0.05)), 4),
                size_ratio_p95=round(float(np.quantile(r, 0.95)), 4), size_ratio_min=round(float(r.min()), 4),
                size_ratio_max=round(float(r.max()), 4),
                nbr_ratio_p99=round(float(np.quantile(nr, 0.99)), 4) if len(nr) else None,
                nbr_ratio_max=round(float(nr.max()), 4) if len(nr) else None,
                nbr_ratio_worst_at=[round(float(v), 1) for v in cen[worst]] if len(nr) else None,
                size_ratio_quads=int(len(pick)), distance_seconds=round(time.time() - t0, 1))


def judge(mesh, case):
    p = subprocess.run([PY, JUDGE, mesh, case], capture_output=True, text=True)
    if p.returncode != 0:
        return {"judge_error": p.stderr.strip().splitlines()[-1] if p.stderr.strip() else "exit %d" % p.returncode}
    return json.loads(p.stdout.strip().splitlines()[-1])


def sections(mesh, case, side, out_json):
    if not side:
        return {}
    p = subprocess.run([PY, os.path.join(HERE, "channel_sections.py"), mesh, case, side, "--json", out_json],
                       capture_output=True, text=True)
    if p.returncode != 0:
        return {"sections_error": (p.stderr.strip().splitlines() or ["exit %d" % p.returncode])[-1]}
    r = json.load(open(out_json))
    A, M = r["across"], r["mesh_figures"]
    return dict(sections=A.get("sections"), sections_min=A.get("min"), sections_p05=A.get("p05"),
                sections_median=A.get("median"), sections_below_3=A.get("below_across"),
                worst_section=r["worst"][0] if r["worst"] else None,
                edge_ratio_avg=M.get("edge_ratio_avg"), edge_ratio_max=M.get("edge_ratio_max"),
                ortho_frac_above_0_5=M.get("ortho_frac_above_0_5"), ortho_frac_above_0_1=M.get("ortho_frac_above_0_1"),
                ortho_max=M.get("ortho_max"))


def gmsh_geo(case, hmin, hmax, grade, out_dir):
    base = os.path.join(out_dir, "gmsh_base.geo")
    subprocess.run([PY, os.path.join(ROOT, "scripts", "make-gmsh-geo"), case, repr(hmax), base], check=True)
    text = open(base).read()
    pts = {int(m.group(1)): (float(m.group(2)), float(m.group(3)))
           for m in re.finditer(r"^Point\((\d+)\) = \{([^,]+), ([^,]+),", text, re.M)}
    curves = {int(m.group(2)): [int(v) for v in m.group(3).split(",")]
              for m in re.finditer(r"^(Line|Spline)\((\d+)\) = \{([^}]*)\};", text, re.M)}
    if not curves:
        raise RuntimeError("make-gmsh-geo wrote no curves")
    # Distance samples: NumPointsPerCurve points on every curve (uniform in the curve's parameter, which for a
    # spline through our points is about uniform per input segment): enough for HMIN / 4 on the longest curve and
    # 4 per input segment on the curve with the most points.
    longest = max(sum(math.dist(pts[a], pts[b]) for a, b in zip(c[:-1], c[1:])) for c in curves.values())
    most = max(len(c) for c in curves.values())
    sampling = int(min(max(longest / (hmin / 4.0), 4 * most, 20), 200000))
    ids = sorted(curves)
    lines = [text.rstrip("\n"),
             "// bench/graded.py: size field h = min(HMAX, HMIN + G d), d = distance to every curve",
             "Mesh.CharacteristicLengthMin = %r;" % hmin, "Mesh.CharacteristicLengthMax = %r;" % hmax,
             "Field[1] = Distance;",
             "Field[1].CurvesList = {%s};" % ", ".join(map(str, ids)),
             "Field[1].NumPointsPerCurve = %d;" % sampling,
             "Field[2] = Threshold;", "Field[2].InField = 1;",
             "Field[2].SizeMin = %r;" % hmin, "Field[2].SizeMax = %r;" % hmax,
             "Field[2].DistMin = 0;", "Field[2].DistMax = %r;" % ((hmax - hmin) / grade),
             "Background Field = 2;",
             "Mesh.MeshSizeExtendFromBoundary = 0;", "Mesh.MeshSizeFromPoints = 0;", "Mesh.MeshSizeFromCurvature = 0;",
             "Mesh.Algorithm = 6;", "Mesh.RecombinationAlgorithm = 1;", "Recombine Surface{:};", ""]
    geo = os.path.join(out_dir, "gmsh_graded.geo")
    open(geo, "w").write("\n".join(lines))
    return geo, len(ids), sampling


def count_cells(mesh):
    m = quiet_read(mesh)
    q = sum(len(c.data) for c in m.cells if c.type == "quad")
    t = sum(len(c.data) for c in m.cells if c.type == "triangle")
    return q, t


def run_gmsh(a, case, side, domain, feats):
    res = {"tool": "gmsh 4.8"}
    geo, ncurves, sampling = gmsh_geo(case, a.size_min, a.size_max, a.grade, a.out)
    msh = os.path.join(a.out, "gmsh_graded.msh")
    if os.path.exists(msh):
        os.remove(msh)
    log = os.path.join(a.out, "gmsh_graded.log")
    cmd = ["/usr/bin/gmsh", geo, "-2", "-format", "msh22", "-nt", str(a.threads), "-o", msh]
    print("gmsh: %s  (%d curves, %d distance samples per curve)" % (" ".join(cmd), ncurves, sampling), flush=True)
    rc, wall, mem = run_timed(cmd, log, a.timeout)
    res.update(seconds=round(wall, 1), peak_gb=round(mem, 2), exit=rc)
    errors = [l.strip() for l in open(log, errors="replace") if l.startswith("Error")]
    if rc is None:
        res["failure"] = "timed out after %.0f s" % a.timeout
    elif errors:
        res["failure"] = errors[0] + (" (+%d more errors)" % (len(errors) - 1) if len(errors) > 1 else "")
    elif rc != 0:
        res["failure"] = "exit %d (%s)" % (rc, open(log, errors="replace").read().strip().splitlines()[-1:])
    if not os.path.exists(msh):
        res.setdefault("failure", "no mesh written")
        return res
    q, t = count_cells(msh)
    res.update(quads=q, triangles=t, mesh=msh)
    if q == 0:
        res.setdefault("failure", "no quads in the mesh")
        return res
    evaluate(res, msh, a, case, side, domain, feats, "gmsh")
    return res


def run_polysquare(a, case, side, domain, feats):
    res = {"tool": "polysquare"}
    cli = a.cli
    if not (os.path.isfile(cli) and os.access(cli, os.X_OK)):
        res["failure"] = "no polysquare binary at %s" % cli
        return res
    h = subprocess.run([cli, "mesh", "--help"], capture_output=True, text=True)
    if "--size-min" not in h.stdout + h.stderr:
        res["failure"] = "polysquare: grading flags not available"
        return res
    msh = os.path.join(a.out, "polysquare_graded.msh")
    rep = os.path.join(a.out, "polysquare_graded.json")
    for f in (msh, rep):
        if os.path.exists(f):
            os.remove(f)
    cmd = [cli, "mesh", case, "--size-min", repr(a.size_min), "--size-max", repr(a.size_max), "--grade", repr(a.grade)]
    if a.across:
        cmd += ["--across", str(a.across)]
    cmd += ["--threads", str(a.threads), "-o", msh, "--report", rep] + shlex.split(a.polysquare_args or "")
    print("polysquare: %s" % " ".join(cmd), flush=True)
    log = os.path.join(a.out, "polysquare_graded.log")
    rc, wall, mem = run_timed(cmd, log, a.timeout)
    res.update(seconds=round(wall, 1), peak_gb=round(mem, 2), exit=rc)
    if rc != 0 or not os.path.exists(msh):
        tail = open(log, errors="replace").read().strip().splitlines()[-1:]
        res["failure"] = ("timed out after %.0f s" % a.timeout) if rc is None else "exit %s: %s" % (rc, tail)
        return res
    q, t = count_cells(msh)
    res.update(quads=q, triangles=t, mesh=msh)
    evaluate(res, msh, a, case, side, domain, feats, "polysquare")
    return res


def evaluate(res, msh, a, case, side, domain, feats, tag):
    j = judge(msh, case)
    res.update({k: j.get(k) for k in ("regular_quad_frac", "sing_per_kquad", "sing_interior", "sj_min", "sj_p001",
                                      "inverted", "frac_sj_below_03", "er_avg", "er_max", "area_rel_err",
                                      "bnd_dist_max", "judge_error") if k in j})
    res.update(size_figures(msh, domain, feats, a.size_min, a.size_max, a.grade))
    res.update(sections(msh, case, side, os.path.join(a.out, tag + "_sections.json")))


def fmt(v, nd=2):
    if v is None:
        return "-"
    if isinstance(v, float):
        return ("%." + str(nd) + "f") % v
    return str(v)


def table(rows):
    cols = [("tool", "tool", 0), ("quads", "quads", 0), ("triangles", "tris", 0), ("seconds", "seconds", 1),
            ("peak_gb", "GB", 2), ("regular_quad_frac", "regular", 3), ("sing_per_kquad", "sing/1000", 1),
            ("sj_min", "SJ min", 3), ("size_ratio_median", "size med", 2), ("size_ratio_p05", "p05", 2),
            ("size_ratio_p95", "p95", 2), ("nbr_ratio_p99", "nbr p99", 2), ("nbr_ratio_max", "nbr max", 2),
            ("sections_min", "across min", 0), ("edge_ratio_avg", "ER avg", 2), ("ortho_frac_above_0_5", "orth>0.5", 4)]
    body = [[fmt(r.get(k), nd) for k, _, nd in cols] for r in rows]
    widths = [max(len(h), *(len(b[i]) for b in body)) for i, (_, h, _) in enumerate(cols)]
    lines = ["  ".join(h.rjust(w) for (_, h, _), w in zip(cols, widths))]
    lines += ["  ".join(c.rjust(w) for c, w in zip(b, widths)) for b in body]
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description="Gmsh 4.8 vs polysquare on a graded size field")
    ap.add_argument("--case", default=os.path.join(ROOT, "data", "cases", "channel_estuary.geojson"))
    ap.add_argument("--centerlines", help="centre-line sidecar (default: CASE with .centerlines.json, when it exists)")
    ap.add_argument("--size-min", type=float, help="HMIN (default: narrowest channel width / 3, else 15)")
    ap.add_argument("--size-max", type=float, default=500.0)
    ap.add_argument("--grade", type=float, default=0.15)
    ap.add_argument("--across", type=int, help="polysquare --across N (not passed when absent)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "graded"))
    ap.add_argument("--timeout", type=float, default=1200.0, help="seconds per mesher run")
    ap.add_argument("--skip-gmsh", action="store_true")
    ap.add_argument("--skip-polysquare", action="store_true")
    ap.add_argument("--cli", default=os.path.join(ROOT, "build", "polysquare"))
    ap.add_argument("--polysquare-args", help="more arguments for polysquare mesh, one shell-quoted string")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    case = os.path.abspath(a.case)
    side = a.centerlines or re.sub(r"\.geojson$", "", case) + ".centerlines.json"
    side = side if os.path.exists(side) else None
    if a.size_min is None:
        if side:
            a.size_min = round(min(c["width_min"] for c in json.load(open(side))["channels"]) / 3.0, 2)
        else:
            a.size_min = 15.0
    if not (0 < a.size_min <= a.size_max) or a.grade <= 0:
        sys.exit("error: need 0 < --size-min <= --size-max and --grade > 0")
    domain, feats = read_case(case)
    print("case %s: %.2f km^2; HMIN %g m, HMAX %g m, G %g%s; uniform mesh at HMIN ~ %.0f quads; centre lines: %s"
          % (os.path.basename(case), domain.area / 1e6, a.size_min, a.size_max, a.grade,
             ", --across %d" % a.across if a.across else "", domain.area / a.size_min ** 2, side or "none"), flush=True)
    rows = []
    if not a.skip_gmsh:
        rows.append(run_gmsh(a, case, side, domain, feats))
    if not a.skip_polysquare:
        rows.append(run_polysquare(a, case, side, domain, feats))
    for r in rows:
        if r.get("failure") == "polysquare: grading flags not available":
            print(r["failure"] + " (%s mesh --help lists no --size-min)" % a.cli)
        elif r.get("failure"):
            print("%s: FAILED: %s" % (r["tool"], r["failure"]))
    ok = {r["tool"]: r for r in rows if r.get("quads") and not r.get("failure")}
    shown = [r for r in rows if r.get("quads")]
    if "gmsh 4.8" in ok and "polysquare" in ok:
        g, p = ok["gmsh 4.8"], ok["polysquare"]
        ratio = {"tool": "poly/gmsh"}
        for k in ("quads", "seconds", "peak_gb", "regular_quad_frac", "sing_per_kquad", "sj_min"):
            if isinstance(g.get(k), (int, float)) and isinstance(p.get(k), (int, float)) and g[k]:
                ratio[k] = round(p[k] / g[k], 3)
        shown.append(ratio)
    if shown:
        print(table(shown))
    for r in rows:
        if r.get("worst_section"):
            w = r["worst_section"]
            print("%s: fewest quads across: %d at %s s=%.0f m (%.1f, %.1f), width %.1f m; sections below 3: %s"
                  % (r["tool"], w["quads"], w["channel"], w["s"], w["x"], w["y"], w["width"], r.get("sections_below_3")))
        if r.get("nbr_ratio_worst_at"):
            print("%s: largest neighbour size ratio %.2f at (%.1f, %.1f)" % (r["tool"], r["nbr_ratio_max"],
                                                                           *r["nbr_ratio_worst_at"]))
    summary = {"case": case, "size_min": a.size_min, "size_max": a.size_max, "grade": a.grade, "across": a.across,
               "threads": a.threads, "area_km2": round(domain.area / 1e6, 3),
               "uniform_quads_at_hmin": round(domain.area / a.size_min ** 2), "runs": rows}
    with open(os.path.join(a.out, "graded.json"), "w") as f:
        json.dump(summary, f, indent=1)
    print("figures: %s" % os.path.join(a.out, "graded.json"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
