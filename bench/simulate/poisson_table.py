#!/usr/bin/env python3
"""The manufactured-solution Poisson study of issue 54: L2 and H1-seminorm errors and their convergence rates on
polysquare, Gmsh quad and Gmsh triangle meshes of several cases at equal DoFs; the Poisson part of
docs/simulation.md (simulation.py writes the page; running this file is `simulation.py --heat-part keep`).

Steps (every command is logged and listed on the page), for each case of --poisson-cases (NAME:SIZE, SIZE the
coarsest polysquare size) and each of --levels sizes, halving:
  1. polysquare meshes the case at the size; bench/simulate/poisson solves -laplace(u) = f for
     u = sin(k x') sin(k y') on it (x', y' over the case's bounding box) and measures the errors;
  2. Gmsh 4.8 meshes it as quads (scripts/make-gmsh-geo: Frontal-Delaunay + Blossom, features embedded) and as
     triangles (Delaunay, P1), each at a size searched so its DoFs are within --match of polysquare's (a size where
     Blossom finds no matching is skipped); cases in SIMPLIFIED are given to Gmsh with their rings simplified at
     polysquare's size (simplify.py), as polysquare simplifies them, else Gmsh's DoFs cannot come near;
  3. poisson on the Gmsh meshes; rates between sizes and fitted over all, in h ~ DoFs^-1/2;
  4. plots.py draws the error against DoFs (docs/img/poisson_errors.png).
"""
import datetime
import json
import math
import os
import sys

import common
from common import ROOT, SYSTEM_PYTHON, fmt, gmsh_mesh, last_json, run, scan

# Coastlines whose raw rings Gmsh would follow vertex by vertex: Gmsh gets them simplified at polysquare's size.
SIMPLIFIED = {"delta_water"}
GENERATORS = [("polysquare", "polysquare (Q1)"), ("quad", "Gmsh quads (Frontal-Delaunay + Blossom, Q1)"),
              ("triangle", "Gmsh triangles (Delaunay, P1)")]


def add_arguments(ap):
    ap.add_argument("--poisson-cases", default="letter_R:4,mechanical_part:5,smile:4,delta_water:1600",
                    help="Poisson: NAME:SIZE, the coarsest polysquare size of each case (data/cases or "
                         "/work/shared/data/cases)")
    ap.add_argument("--levels", type=int, default=4, help="Poisson: sizes per case, halving")
    ap.add_argument("--k", type=float, default=6 * math.pi,
                    help="Poisson: wavenumber over the bounding box's larger side (6 pi: three wavelengths)")
    ap.add_argument("--match", type=float, default=0.05, help="Poisson: largest relative DoF difference to Gmsh")


def case_path(name):
    for folder in (os.path.join(ROOT, "data", "cases"), "/work/shared/data/cases"):
        path = os.path.join(folder, name + ".geojson")
        if os.path.exists(path):
            return path
    sys.exit("no case %s.geojson in data/cases or /work/shared/data/cases" % name)


def poisson(args, case, mesh, *extra):
    return last_json(run([args.poisson, mesh, "--region", case, "--k", repr(args.k)] + list(extra)))


def match_size(count, h0, target, tol):
    """(size, count) with count within tol of target: Newton steps on count ~ size^-2 from h0 (a size Gmsh refuses
    is nudged by 1 %), then common.scan's grid around the best size if they do not get there. (None, None) when
    nothing was counted."""
    h, best = h0, (None, None)
    for _ in range(8):
        n = count(h)
        if n is None:
            h = round(h * 1.01, 4)
            continue
        if best[1] is None or abs(n - target) < abs(best[1] - target):
            best = (h, n)
        if abs(n - target) <= tol * target / 2:  # aim well inside the tolerance, where the counts allow
            return best
        h = round(h * math.sqrt(n / target), 4)
    if best[1] is not None and abs(best[1] - target) <= tol * target:
        return best
    found = scan(count, best[0] or h0, target, spread=0.05, step=0.01)
    if best[1] is not None:
        found[best[0]] = best[1]
    return common.nearest(found, target)


def level(args, name, case, work, size):
    """One size of one case, nudged by up to 4 % where Gmsh cannot match polysquare's DoFs there: Gmsh's counts
    jump (a curve gains a segment) and Blossom fails at whole runs of sizes, so some DoF counts have no Gmsh
    mesh within --match. The first size with both Gmsh meshes matched, else the one with the most."""
    best = None
    for nudge in (0, 0.02, -0.02, 0.04, -0.04):
        row = matched_level(args, name, case, work, round(size * (1 + nudge), 4))
        matched = sum(row[kind] is not None for kind in ("quad", "triangle"))
        if best is None or matched > best[0]:
            best = (matched, row)
        if matched == 2:
            break
    return best[1]


def matched_level(args, name, case, work, size):
    """polysquare's run at the size, and Gmsh's quad and triangle runs at DoFs matching it (None where no Gmsh size
    gets within --match)."""
    ps_mesh = common.polysquare_mesh(args.polysquare, case, os.path.join(work, "polysquare_%g.msh" % size),
                                     ["--size", "%g" % size])
    row = {"size": size, "polysquare": dict(poisson(args, case, ps_mesh), size=size)}
    target = row["polysquare"]["dofs"]
    geometry, prefix = case, "gmsh"
    if name in SIMPLIFIED:
        geometry = os.path.join(work, "simplified_%g.geojson" % size)
        if not os.path.exists(geometry):
            run([SYSTEM_PYTHON, os.path.join(ROOT, "bench", "simulate", "simplify.py"), case, "%g" % size, geometry])
        prefix = "gmsh_s%g" % size
    for kind in ("quad", "triangle"):
        def count(h, kind=kind):
            mesh = gmsh_mesh(geometry, work, h, kind, prefix)
            if mesh is None:
                return None
            r = last_json(run([args.poisson, mesh, "--count"]))
            return None if kind == "quad" and r["quads"] == 0 else r["dofs"]
        h, n = match_size(count, 1.1 * size, target, args.match)
        row[kind] = None
        if n is not None and abs(n - target) <= args.match * target:
            row[kind] = dict(poisson(args, case, gmsh_mesh(geometry, work, h, kind, prefix)), size=h)
    return row


def rate(a, b, key):
    """Convergence rate in h ~ DoFs^-1/2 between two runs."""
    return 2 * math.log(a[key] / b[key]) / math.log(b["dofs"] / a["dofs"])


def fitted_rate(runs, key):
    """Least-squares slope of log(error) against log(DoFs^-1/2) over the runs."""
    xs = [-0.5 * math.log(r["dofs"]) for r in runs]
    ys = [math.log(r[key]) for r in runs]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)


def runs_of(levels, kind):
    return [lv[kind] for lv in levels if lv[kind] is not None]


def shapes(r):
    """Min SJ and max edge ratio, the quads' and (where there are any) the triangles'."""
    out = []
    for kind in ("quads", "triangles"):
        if "sj_min_" + kind in r:
            out.append(("%.2f" % r["sj_min_" + kind], "%.2f" % r["edge_ratio_max_" + kind], kind))
    if len(out) == 1:
        return out[0][:2]
    return tuple("%s (triangles %s)" % (out[0][i], out[1][i]) for i in range(2))


def worst_line(r, label):
    """The cells holding the most of a run's L2 and H1 errors: where, how much, their shapes."""
    def cell(c):
        return ("(%.4g, %.4g) %.1f %%, %s, SJ %.2f, edge ratio %.2f, area %.2f times the mean, %d irregular "
                "corner%s%s" % (c["centre"][0], c["centre"][1], 100 * c["share"],
                                "quad" if c["vertices"] == 4 else "triangle", c["sj"], c["edge_ratio"],
                                c["area_ratio"], c["irregular_corners"], "" if c["irregular_corners"] == 1 else "s",
                                ", on the boundary" if c["at_boundary"] else ""))
    return ("%s: largest L2 errors in %s; largest H1 error in %s. Whole mesh: min SJ %s, max edge ratio %s, "
            "%d irregular interior vertices, cell areas over the mean %.2f / %.2f / %.2f (5th percentile / 95th / "
            "largest); the cells over twice the mean area (%.1f %% of them) hold %.1f %% of the L2 error squared." % (
                (label, "; ".join(cell(c) for c in r["worst_l2"]), cell(r["worst_h1"][0])) + shapes(r) +
                (r["irregular_vertices"], r["area_ratio_p05"], r["area_ratio_p95"], r["area_ratio_max"],
                 100 * r["large_cells_fraction"], 100 * r["large_cells_l2_share"])))


def case_section(name, levels):
    ps0 = levels[0]["polysquare"]
    L = ["### %s\n" % name]
    L.append("Box corner (%.6g, %.6g), side %.6g, k = %.4g (%.1f wavelengths across); ||u||_L2 = %.4g, |u|_H1 = %.4g "
             "on polysquare's finest mesh.\n" % (ps0["box"][0], ps0["box"][1], ps0["box"][2], ps0["k"],
                                                  ps0["k"] / (2 * math.pi), levels[-1]["polysquare"]["u_l2"],
                                                  levels[-1]["polysquare"]["u_h1"]))
    L.append("| polysquare size | mesh | mesh size | cells | DoFs | L2 error | H1 error | L2 rate | H1 rate | "
             "CG iterations | min SJ | max edge ratio | irregular interior vertices |")
    L.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    previous = {}
    for lv in levels:
        for kind, label in GENERATORS:
            r = lv[kind]
            if r is None:
                L.append("| %g | %s | - | no Gmsh size within the DoF tolerance | | | | | | | | | |" % (lv["size"], label))
                continue
            rates = ("%.2f" % rate(previous[kind], r, "l2"), "%.2f" % rate(previous[kind], r, "h1")) \
                if kind in previous else ("-", "-")
            cells = "%d" % r["cells"] + (" (%d triangles)" % r["triangles"] if r["quads"] and r["triangles"] else "")
            L.append("| %g | %s | %g | %s | %d | %s | %s | %s | %s | %d | %s | %s | %d |" % ((
                lv["size"], label, r["size"], cells, r["dofs"], fmt(r["l2"]), fmt(r["h1"]), rates[0], rates[1],
                r["cg_iterations"]) + shapes(r) + (r["irregular_vertices"],)))
            previous[kind] = r
    L.append("")
    fits = []
    for kind, label in GENERATORS:
        runs = runs_of(levels, kind)
        if len(runs) >= 2:
            fits.append("%s L2 %.2f, H1 %.2f" % (kind, fitted_rate(runs, "l2"), fitted_rate(runs, "h1")))
    L.append("Rates fitted over all sizes (log-log slope in h ~ DoFs^-1/2): " + "; ".join(fits) + ".\n")
    fine = levels[-1]
    ps = fine["polysquare"]
    ratios = []
    for kind in ("quad", "triangle"):
        if fine[kind] is not None:
            ratios.append("against Gmsh %ss (%d DoFs to polysquare's %d): L2 %.2f, H1 %.2f" % (
                kind, fine[kind]["dofs"], ps["dofs"], ps["l2"] / fine[kind]["l2"], ps["h1"] / fine[kind]["h1"]))
    L.append("At the finest size, polysquare's errors over Gmsh's (below 1: polysquare better): " +
             ("; ".join(ratios) if ratios else "no Gmsh mesh matched") + ".\n")
    loses = fine["quad"] is not None and ps["l2"] > fine["quad"]["l2"]
    L.append(("polysquare loses on L2 here. " if loses else "") + worst_line(ps, "polysquare at the finest size") +
             (" " + worst_line(fine["quad"], "Gmsh quads") if fine["quad"] is not None else "") + "\n")
    return L


def summary(results):
    L = ["| case | finest DoFs: polysquare / Gmsh quad / Gmsh triangle | L2: polysquare | Gmsh quad | Gmsh triangle | "
         "L2 ratio polysquare / Gmsh quad | polysquare rates at the finest pair, L2 / H1 | fitted L2 rates: "
         "polysquare / Gmsh quad / Gmsh triangle |", "|---|---|---|---|---|---|---|---|"]
    for name, levels in results.items():
        fine = levels[-1]
        ps, q, t = fine["polysquare"], fine["quad"], fine["triangle"]
        pair = levels[-2]["polysquare"], ps

        def fit(kind):
            runs = runs_of(levels, kind)
            return "%.2f" % fitted_rate(runs, "l2") if len(runs) >= 2 else "-"
        L.append("| %s | %d / %s / %s | %s | %s | %s | %s | %.2f / %.2f | %s / %s / %s |" % (
            name, ps["dofs"], q["dofs"] if q else "-", t["dofs"] if t else "-", fmt(ps["l2"]),
            fmt(q["l2"]) if q else "-", fmt(t["l2"]) if t else "-", "%.2f" % (ps["l2"] / q["l2"]) if q else "-",
            rate(*pair, "l2"), rate(*pair, "h1"), fit("polysquare"), fit("quad"), fit("triangle")))
    L.append("")
    return L


def reading(results, pictures):
    """What the tables say against the issue's asks (polysquare's L2 <= Gmsh quads' at the finest size; rates >= 1.9
    in L2 and >= 0.95 in H1), and where polysquare loses, where its error sits (pictures: {case: its cell-area
    picture's path on the page})."""
    wins, losses, slow = [], [], []
    for name, levels in results.items():
        ps, q = levels[-1]["polysquare"], levels[-1]["quad"]
        if q is not None:
            (wins if ps["l2"] <= q["l2"] else losses).append((name, ps["l2"] / q["l2"]))
        before = levels[-2]["polysquare"]
        l2, h1 = rate(before, ps, "l2"), rate(before, ps, "h1")
        if l2 < 1.9 or h1 < 0.95:
            slow.append("%s (%.2f / %.2f; from %d to %d DoFs its irregular interior vertices go from %d to %d and its "
                        "cells over twice the mean area from %.1f %% to %.1f %%)" % (
                            name, l2, h1, before["dofs"], ps["dofs"], before["irregular_vertices"],
                            ps["irregular_vertices"], 100 * before["large_cells_fraction"],
                            100 * ps["large_cells_fraction"]))
    L = ["### Reading the numbers\n"]
    L.append("At the finest size polysquare's L2 error is below Gmsh quads' on %s%s. polysquare's rates at the finest "
             "pair of sizes are at least 1.9 (L2) and 0.95 (H1) %s.\n" % (
                 ", ".join("%s (ratio %.2f)" % w for w in wins) or "no case",
                 "; above on " + ", ".join("%s (ratio %.2f)" % w for w in losses) if losses else "",
                 "on every case" if not slow else "except on " + "; ".join(slow)))
    for name, _ in losses:
        ps, q = results[name][-1]["polysquare"], results[name][-1]["quad"]
        worst = ps["worst_l2"]
        L.append("Where polysquare loses (%s): its error sits in its largest cells, not in badly shaped ones. The %.1f %% "
                 "of its cells over twice the mean area hold %.1f %% of the L2 error squared (Gmsh quads: %.1f %% of "
                 "cells, %.1f %%); its largest cell is %.1f times the mean (Gmsh's %.1f), and the %d cells with the "
                 "largest error are %.1f to %.1f times the mean with SJ %.2f or more and %d irregular corners between "
                 "them. The picture shows the cell sizes changing in patches and bands, whole stretches of quads at 2 to 4 "
                 "times the mean area beside stretches at a quarter of it; Gmsh's sizes vary less (95th percentile "
                 "%.2f times the mean to polysquare's %.2f). Which stage sets those spacings (each subregion's map, "
                 "the side counts subregions share) is not measured here; quads held nearer the requested size "
                 "wherever the open water is wide is what would close the gap.\n\n![%s: polysquare's cell areas, "
                 "the cells with the largest L2 error starred](%s)\n" % (
                     name, 100 * ps["large_cells_fraction"], 100 * ps["large_cells_l2_share"],
                     100 * q["large_cells_fraction"], 100 * q["large_cells_l2_share"], ps["area_ratio_max"],
                     q["area_ratio_max"], len(worst), min(c["area_ratio"] for c in worst),
                     max(c["area_ratio"] for c in worst), min(c["sj"] for c in worst),
                     sum(c["irregular_corners"] for c in worst), q["area_ratio_p95"], ps["area_ratio_p95"], name,
                     pictures[name]))
    return L


def part(args):
    """Runs the study and returns the Poisson part of the page (markdown lines)."""
    started = datetime.datetime.now(datetime.timezone.utc)
    load = os.getloadavg()
    results = {}
    for spec in args.poisson_cases.split(","):
        name, coarsest = spec.split(":")
        case = case_path(name)
        work = os.path.join(args.work, "poisson", name)
        os.makedirs(work, exist_ok=True)
        results[name] = [level(args, name, case, work, float(coarsest) / 2 ** i) for i in range(args.levels)]
        print("poisson: %s done" % name, flush=True)
    data = os.path.join(args.work, "poisson", "results.json")
    with open(data, "w") as f:
        json.dump(results, f, indent=1)
    png = os.path.join(args.img, "poisson_errors.png")
    run([SYSTEM_PYTHON, os.path.join(ROOT, "bench", "simulate", "plots.py"), "errors", data, png])

    L = ["## Manufactured-solution Poisson study\n"]
    L.append("This part generated %s UTC (%.0f s; load average %.1f at the start). Results as JSON: `%s`.\n" % (
        started.strftime("%Y-%m-%d %H:%M"), (datetime.datetime.now(datetime.timezone.utc) - started).total_seconds(),
        load[0], os.path.relpath(data, ROOT)))
    L.append("### Problem\n")
    L.append("-laplace(u) = f with u = sin(k x') sin(k y'), x' = (x - x0) / L, y' = (y - y0) / L: (x0, y0) the lower "
             "left corner of the case's bounding box (of the GeoJSON, so every mesh of a case has the same u whatever "
             "it does to the boundary), L its larger side; k = %.4g puts %.1f wavelengths across. u exact on the whole "
             "boundary (Dirichlet, interpolated at the boundary nodes). Feature curves (mechanical_part's circle, "
             "smile's eyes and mouth) need no condition: u is smooth across them, so they act only as interior mesh "
             "edges every generator must follow, which is how they shape the meshes measured here. Q1 on quads "
             "(FE_Q), P1 on triangles (FE_SimplexP), both through hp collections on Gmsh's quad meshes, whose Blossom "
             "recombination leaves a few triangles; CG with SSOR (omega 1.2) to a residual of 1e-12 times the "
             "right-hand side's norm. Errors against u over each mesh, Gauss quadrature above the element's order "
             "(QGauss(4) on quads, QGaussSimplex(3) on triangles): L2 and the H1 seminorm, absolute. deal.II 9.4.\n" % (
                 args.k, args.k / (2 * math.pi)))
    L.append("Sizes: polysquare at %d sizes halving from each case's coarsest (`--poisson-cases %s`); Gmsh quad and "
             "triangle sizes searched so their DoFs are within %.0f %% of polysquare's at each size (a size where "
             "Blossom finds no perfect matching is skipped). delta_water is a coastline of 3,541 points: polysquare "
             "simplifies it to the size, and Gmsh (which would put a mesh node at nearly every point and so cannot "
             "come down to polysquare's DoFs) gets its rings simplified at polysquare's size (`simplify.py`: "
             "Douglas-Peucker with the size as tolerance, as polysquare's --simplify bound, parts and holes below "
             "size^2 left out); the domains therefore differ a little between generators and sizes, which u, defined "
             "everywhere, allows (errors are over each mesh's own domain). Rates: between consecutive sizes "
             "and fitted over all, in h ~ DoFs^-1/2 (Q1 / P1: 2 in L2, 1 in H1). Min SJ: the smallest corner sine "
             "of any quad (and, in brackets, of any triangle: a triangle's best is 0.87; Gmsh's quad meshes keep a "
             "few triangles, some of them slivers); irregular interior vertices: interior vertices not shared by "
             "exactly 4 quads (a vertex of a triangle counts).\n" % (args.levels, args.poisson_cases,
                                                                      100 * args.match))
    L.append("### Summary\n")
    L += summary(results)
    L.append("![Poisson errors against DoFs](%s)\n" % os.path.relpath(png, os.path.dirname(args.out)))
    pictures = {}
    for name, levels in results.items():  # where polysquare loses: its finest mesh's cell areas
        fine = levels[-1]
        if fine["quad"] is not None and fine["polysquare"]["l2"] > fine["quad"]["l2"]:
            run_json = os.path.join(args.work, "poisson", name, "finest_polysquare.json")
            with open(run_json, "w") as f:
                json.dump(fine["polysquare"], f)
            picture = os.path.join(args.img, "poisson_%s_areas.png" % name)
            run([SYSTEM_PYTHON, os.path.join(ROOT, "bench", "simulate", "plots.py"), "areas", run_json, picture])
            pictures[name] = os.path.relpath(picture, os.path.dirname(args.out))
    L += reading(results, pictures)
    for name, levels in results.items():
        L += case_section(name, levels)
    return L


if __name__ == "__main__":
    import simulation
    simulation.main(["--heat-part", "keep"] + sys.argv[1:])
