#!/usr/bin/python3
"""Independent check of "quads across every channel cross-section", plus two finite-volume figures of the whole mesh.

usage: bench/channel_sections.py MESH DOMAIN.geojson CENTERLINES.json [--spacing 50] [--skip 1.5] [--across 3]
                                 [--json OUT]

MESH is any mesh meshio reads (.msh, .vtu, ...; Gmsh's or polysquare's). CENTERLINES.json is the sidecar written by
scripts/make-channel-estuary: {"channels": [{"name", "points": [[x, y], ...], "widths": [...]}, ...],
"skip": [{"x", "y", "width", "kind"}, ...]}.

Cross-sections: along each centre line, every SPACING metres of arc length, the line through the centre-line point
normal to it (4 nominal widths each way) is clipped to the domain polygon and the piece holding the centre-line
point is kept: the section from bank to bank. Sections whose centre-line point lies within SKIP x the larger of
its width and the skip point's width of a skip point (a mouth into the bay, a junction with another channel, a
channel head) are not cross-sections and are left out; so are sections that do not end on the domain boundary
within 4 widths (reported as "open"). A section counts the quads whose interior it passes through: candidates
from a shapely STRtree over the quads (the section shifted by 1e-3 widths along the centre line either way, the
smaller count kept, so that a section lying exactly along mesh edges counts one side), kept when the section's interior meets the quad's interior (DE-9IM) and
their intersection is longer than 1e-6 x the section's length (so quads touching it at a corner or along an edge only do not count). Triangles are not
counted as quads across.

Whole mesh: edge ratio (longest / shortest edge of each quad) average and maximum; finite-volume orthogonality of
every interior edge (quads and any triangles): |cos| of the angle between the edge and the segment joining the
area centroids of its two cells (0 = orthogonal; D-Flow FM refuses a network with a value above 0.5), with the
fractions of interior edges above 0.5 and above 0.1.

Needs /usr/bin/python3 with Debian's python3-numpy, python3-meshio and python3-shapely (1.8)."""
import argparse, contextlib, io, json, math, sys

import warnings

import numpy as np
import meshio
warnings.filterwarnings("ignore", message=".*STRtree will be changed.*")
from shapely.geometry import LineString, Point, Polygon, shape
from shapely.affinity import translate
from shapely.ops import unary_union
from shapely.strtree import STRtree


def quiet_read(path):
    """meshio.read without the blank lines meshio 5.0's MSH reader prints on stdout."""
    with contextlib.redirect_stdout(io.StringIO()):
        return meshio.read(path)


def read_domain(path):
    fc = json.load(open(path))
    feats = fc["features"] if "features" in fc else [fc]
    polys = []
    for f in feats:
        role = f.get("properties", {}).get("role")
        g = shape(f["geometry"])
        if role == "domain" or (role is None and g.geom_type in ("Polygon", "MultiPolygon")):
            polys.append(g)
    if not polys:
        sys.exit("error: no domain polygon in %s" % path)
    return unary_union(polys)


def read_mesh(path):
    m = quiet_read(path)
    P = np.asarray(m.points, float)[:, :2]
    quads = [c.data for c in m.cells if c.type == "quad"]
    tris = [c.data for c in m.cells if c.type == "triangle"]
    Q = np.concatenate(quads).astype(np.int64) if quads else np.zeros((0, 4), np.int64)
    T = np.concatenate(tris).astype(np.int64) if tris else np.zeros((0, 3), np.int64)
    return P, Q, T


def polygon_area_centroid(X):
    """X: (n, k, 2) vertex coordinates of n polygons of k vertices -> signed areas (n,), centroids (n, 2)."""
    x, y = X[:, :, 0], X[:, :, 1]
    # shift to the first vertex for accuracy in projected coordinates (1e5-1e6 m)
    x0, y0 = x[:, :1], y[:, :1]
    x, y = x - x0, y - y0
    xn, yn = np.roll(x, -1, 1), np.roll(y, -1, 1)
    c = x * yn - xn * y
    a = c.sum(1) / 2
    with np.errstate(divide="ignore", invalid="ignore"):
        cx = ((x + xn) * c).sum(1) / (6 * a)
        cy = ((y + yn) * c).sum(1) / (6 * a)
    bad = ~np.isfinite(cx) | ~np.isfinite(cy)
    cx[bad] = x[bad].mean(1); cy[bad] = y[bad].mean(1)
    return a, np.stack([cx + x0[:, 0], cy + y0[:, 0]], 1)


def mesh_figures(P, Q, T):
    out = {"quads": int(len(Q)), "triangles": int(len(T))}
    if len(Q):
        X = P[Q]
        el = np.linalg.norm(np.roll(X, -1, 1) - X, axis=2)
        er = el.max(1) / np.maximum(el.min(1), 1e-300)
        out.update(edge_ratio_avg=round(float(er.mean()), 4), edge_ratio_max=round(float(er.max()), 4),
                   edge_ratio_p99=round(float(np.quantile(er, 0.99)), 4))
    # interior edges over all cells (quads, then triangles)
    cents, edges, owner = [], [], []
    base = 0
    for C in (Q, T):
        if not len(C):
            continue
        _, cen = polygon_area_centroid(P[C])
        cents.append(cen)
        k = C.shape[1]
        e = np.stack([C, np.roll(C, -1, 1)], 2).reshape(-1, 2)
        edges.append(np.sort(e, 1))
        owner.append(np.repeat(np.arange(len(C)) + base, k))
        base += len(C)
    if not edges:
        return out
    cen = np.concatenate(cents); E = np.concatenate(edges); own = np.concatenate(owner)
    key = E[:, 0] * (len(P) + 1) + E[:, 1]
    order = np.argsort(key, kind="stable")
    ks = key[order]
    same = np.nonzero(ks[1:] == ks[:-1])[0]
    a, b = order[same], order[same + 1]
    ev = P[E[a, 1]] - P[E[a, 0]]
    cv = cen[own[b]] - cen[own[a]]
    with np.errstate(divide="ignore", invalid="ignore"):
        cosv = np.abs((ev * cv).sum(1)) / (np.linalg.norm(ev, axis=1) * np.linalg.norm(cv, axis=1))
    cosv = np.nan_to_num(cosv, nan=1.0)
    n = len(cosv)
    worst = int(np.argmax(cosv)) if n else 0
    out.update(interior_edges=int(n),
               ortho_mean=round(float(cosv.mean()), 5) if n else 0.0,
               ortho_max=round(float(cosv.max()), 5) if n else 0.0,
               ortho_p99=round(float(np.quantile(cosv, 0.99)), 5) if n else 0.0,
               ortho_frac_above_0_5=round(float((cosv > 0.5).mean()), 6) if n else 0.0,
               ortho_edges_above_0_5=int((cosv > 0.5).sum()),
               ortho_frac_above_0_1=round(float((cosv > 0.1).mean()), 6) if n else 0.0,
               ortho_worst_at=[round(float(v), 2) for v in (P[E[a[worst], 0]] + P[E[a[worst], 1]]) / 2] if n else None)
    return out


def resample_line(pts, wid, spacing):
    """Stations every `spacing` m of arc length (starting spacing/2 in): point, unit tangent, width."""
    pts = np.asarray(pts, float); wid = np.asarray(wid, float)
    seg = np.hypot(*np.diff(pts, axis=0).T)
    s = np.r_[0.0, np.cumsum(seg)]
    L = s[-1]
    st = np.arange(spacing / 2, L, spacing)
    x = np.interp(st, s, pts[:, 0]); y = np.interp(st, s, pts[:, 1]); w = np.interp(st, s, wid)
    # tangent from the points one station-width either side (smooth, independent of the vertex spacing)
    d = np.maximum(np.interp(st, s, wid) * 0.5, 5.0)
    xa, ya = np.interp(np.clip(st - d, 0, L), s, pts[:, 0]), np.interp(np.clip(st - d, 0, L), s, pts[:, 1])
    xb, yb = np.interp(np.clip(st + d, 0, L), s, pts[:, 0]), np.interp(np.clip(st + d, 0, L), s, pts[:, 1])
    t = np.stack([xb - xa, yb - ya], 1)
    t /= np.linalg.norm(t, axis=1)[:, None]
    return np.stack([x, y], 1), t, w, st


def sections(domain, side, spacing, skip_factor):
    skips = [(j["x"], j["y"], j.get("width", 0.0), j.get("kind", "")) for j in side.get("skip", [])]
    out, skipped, opened, outside = [], 0, [], []
    for ch in side["channels"]:
        X, T, W, S = resample_line(ch["points"], ch["widths"], spacing)
        for p, t, w, s in zip(X, T, W, S):
            if any(math.hypot(p[0] - jx, p[1] - jy) < skip_factor * max(w, jw) for jx, jy, jw, _ in skips):
                skipped += 1
                continue
            n = np.array([-t[1], t[0]])
            reach = 4.0 * w
            a, b = p - reach * n, p + reach * n
            full = LineString([a, b])
            cut = full.intersection(domain)
            pieces = list(cut.geoms) if hasattr(cut, "geoms") else [cut]
            c = Point(p)
            mine = [g for g in pieces if g.geom_type == "LineString" and not g.is_empty and g.distance(c) < 1e-6 * w]
            rec = dict(channel=ch["name"], s=round(float(s), 1), x=round(float(p[0]), 2), y=round(float(p[1]), 2),
                       width=round(float(w), 2))
            if not mine:
                outside.append(rec)
                continue
            sec = max(mine, key=lambda g: g.length)
            ends = np.array(sec.coords)[[0, -1]]
            if min(np.hypot(*(ends[0] - a)), np.hypot(*(ends[0] - b)), np.hypot(*(ends[1] - a)),
                   np.hypot(*(ends[1] - b))) < 1e-6 * reach:
                opened.append(rec)
                continue
            rec["length"] = round(float(sec.length), 2)
            rec["geom"] = sec
            rec["t"] = (float(t[0]), float(t[1]))
            out.append(rec)
    return out, skipped, opened, outside


def count_across(P, Q, secs):
    """Quads each section passes through (interior), with a prefilter to the quads near any section."""
    if not secs or not len(Q):
        for r in secs:
            r["quads"] = 0
        return
    X = P[Q]
    lo, hi = X.min(1), X.max(1)
    # mark a grid of cells covered by the sections' boxes; keep quads whose box meets a marked cell
    boxes = np.array([r["geom"].bounds for r in secs])
    g = max(float(np.median(boxes[:, 2:] - boxes[:, :2])), 1.0) * 2
    o = np.minimum(boxes[:, :2].min(0), lo.min(0)) - g
    ext = np.maximum(boxes[:, 2:].max(0), hi.max(0)) + g
    nx, ny = int((ext[0] - o[0]) / g) + 2, int((ext[1] - o[1]) / g) + 2
    mark = np.zeros((ny, nx), np.int64)
    for b in boxes:
        i0, j0 = ((b[:2] - o) // g).astype(int); i1, j1 = ((b[2:] - o) // g).astype(int)
        mark[j0:j1 + 1, i0:i1 + 1] = 1
    sat = np.zeros((ny + 1, nx + 1), np.int64)
    sat[1:, 1:] = mark.cumsum(0).cumsum(1)
    i0, j0 = ((lo - o) // g).astype(int).T; i1, j1 = ((hi - o) // g).astype(int).T
    hits = sat[j1 + 1, i1 + 1] - sat[j0, i1 + 1] - sat[j1 + 1, i0] + sat[j0, i0]
    near = np.nonzero(hits > 0)[0]
    polys = [Polygon(X[k]) for k in near]
    tree = STRtree(polys)
    def through(sec):
        tol = 1e-6 * sec.length
        n = 0
        for pg in tree.query(sec):
            if not sec.relate_pattern(pg, "T********"):     # the section's interior meets the quad's interior
                continue
            if not pg.is_valid:
                pg = pg.buffer(0)
            if sec.intersection(pg).length > tol:
                n += 1
        return n

    for r in secs:
        # A section lying exactly along mesh edges (a structured mesh, a station on a grid line) would meet no
        # quad interior or, with rounding, zigzag across the edges: count it shifted by 1e-3 widths along the
        # centre line, both ways, and keep the smaller count.
        d = 1e-3 * r["width"]
        r["quads"] = min(through(translate(r["geom"], sg * d * r["t"][0], sg * d * r["t"][1])) for sg in (1, -1))


def summary(secs, across):
    c = np.array([r["quads"] for r in secs]) if secs else np.zeros(0)
    out = {"sections": int(len(c))}
    if len(c):
        out.update(min=int(c.min()), p05=float(np.quantile(c, 0.05)), median=float(np.median(c)),
                   mean=round(float(c.mean()), 3), below_across=int((c < across).sum()))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("mesh"); ap.add_argument("domain"); ap.add_argument("centerlines")
    ap.add_argument("--spacing", type=float, default=50.0, help="metres between sections along a centre line")
    ap.add_argument("--skip", type=float, default=1.5, help="leave out sections within this many widths of a skip point")
    ap.add_argument("--across", type=int, default=3, help="count the sections with fewer quads than this")
    ap.add_argument("--json", help="write every figure (and every section) here")
    ap.add_argument("--worst", type=int, default=5)
    a = ap.parse_args()

    domain = read_domain(a.domain)
    side = json.load(open(a.centerlines))
    P, Q, T = read_mesh(a.mesh)
    secs, skipped, opened, outside = sections(domain, side, a.spacing, a.skip)
    count_across(P, Q, secs)
    res = {"mesh": a.mesh, "spacing": a.spacing, "skip_widths": a.skip}
    res["across"] = summary(secs, a.across)
    res["across"].update(skipped_near_junctions=skipped, open=len(opened), centre_outside_domain=len(outside))
    ratio = np.array([r["length"] / r["width"] for r in secs]) if secs else np.zeros(1)
    res["across"]["section_over_width"] = [round(float(ratio.min()), 3), round(float(np.median(ratio)), 3),
                                           round(float(ratio.max()), 3)]
    # sections much longer than the channel is wide: still counted, but likely crossing into a junction or a bend
    long_ = [r for r in secs if r["length"] > 1.5 * r["width"]]
    res["across"]["longer_than_1_5_widths"] = len(long_)
    per = {}
    for r in secs:
        per.setdefault(r["channel"], []).append(r["quads"])
    res["per_channel"] = {k: {"sections": len(v), "min": int(min(v)), "median": float(np.median(v))} for k, v in per.items()}
    worst = sorted(secs, key=lambda r: (r["quads"], -r["length"]))[:a.worst]
    res["worst"] = [{k: v for k, v in r.items() if k not in ("geom", "t")} for r in worst]
    res["mesh_figures"] = mesh_figures(P, Q, T)

    A = res["across"]
    print("%s: %d quads, %d triangles" % (a.mesh, len(Q), len(T)))
    if A["sections"]:
        print("quads across channel sections (every %g m, %d left out near mouths/junctions/heads, %d open, %d centre "
              "outside): sections %d, min %d, p05 %g, median %g, mean %.2f, below %d: %d"
              % (a.spacing, skipped, len(opened), len(outside), A["sections"], A["min"], A["p05"], A["median"],
                 A["mean"], a.across, A["below_across"]))
    else:
        print("no cross-sections found")
    print("section length / nominal width: min %.2f median %.2f max %.2f; %d sections longer than 1.5 widths (counted)"
          % (*A["section_over_width"], len(long_)))
    for r in long_[:3]:
        print("  long section: %s s=%.1f (%.1f, %.1f) width %.1f m, section %.1f m: %d quads"
              % (r["channel"], r["s"], r["x"], r["y"], r["width"], r["length"], r["quads"]))
    for k, v in res["per_channel"].items():
        print("  %-14s sections %4d  min %3d  median %5.1f" % (k, v["sections"], v["min"], v["median"]))
    print("worst sections:")
    for r in res["worst"]:
        print("  %-14s s=%7.1f m  (%.1f, %.1f)  width %.1f m, section %.1f m: %d quads"
              % (r["channel"], r["s"], r["x"], r["y"], r["width"], r["length"], r["quads"]))
    for r in opened[:3] + outside[:3]:
        print("  not checked: %s s=%.1f (%.1f, %.1f)" % (r["channel"], r["s"], r["x"], r["y"]))
    M = res["mesh_figures"]
    if "edge_ratio_avg" in M:
        print("edge ratio (longest/shortest per quad): avg %.3f, p99 %.3f, max %.3f"
              % (M["edge_ratio_avg"], M["edge_ratio_p99"], M["edge_ratio_max"]))
    if "interior_edges" in M:
        print("orthogonality |cos| (edge vs centroid link) over %d interior edges: mean %.4f, p99 %.4f, max %.4f; "
              "above 0.5: %d (%.4f %%), above 0.1: %.2f %%"
              % (M["interior_edges"], M["ortho_mean"], M["ortho_p99"], M["ortho_max"], M["ortho_edges_above_0_5"],
                 100 * M["ortho_frac_above_0_5"], 100 * M["ortho_frac_above_0_1"]))
    if a.json:
        res["sections_list"] = [{k: v for k, v in r.items() if k not in ("geom", "t")} for r in secs]
        res["open_list"] = opened; res["outside_list"] = outside
        with open(a.json, "w") as f:
            json.dump(res, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
