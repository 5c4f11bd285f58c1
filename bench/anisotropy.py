#!/usr/bin/python3
"""Where a graded mesh's quads are stretched, and which way: aspect by distance from the shore, long axis across
or along it.

usage: bench/anisotropy.py MESH DOMAIN.geojson [--bands 0,30,100,300,1e9] [--sample 5] [--json OUT]

MESH is any quad mesh meshio reads. Each quad's aspect is the mean of one pair of opposite sides over the mean of
the other (>= 1), its long axis the direction of the longer pair; its distance is from its centroid to the domain's
rings (sampled every SAMPLE metres), and the distance's gradient (central differences of 2 m) is the direction
away from the shore. A stretched quad (aspect > 1.5) is "radial" when its long axis is within 45 degrees of that
gradient (|cos| > 0.7), "along" the shore when within 17 degrees of the shore (|cos| < 0.3). A graded mesh whose
counts cannot change across the size gradient (a map has no singular node inside) shows quads stretched along
the shore near it (too few along the fine side) and radially offshore (too many along the coarse side).

Needs /usr/bin/python3 with Debian's python3-numpy and python3-meshio (no scipy: distances by brute force in
chunks, a few seconds for 20k quads and 20k boundary samples)."""
import argparse, json, sys

import numpy as np
import meshio


def ring_samples(domain_path, spacing):
    with open(domain_path) as f:
        d = json.load(f)
    out = []

    def add(ring):
        r = np.asarray(ring, dtype=float)[:, :2]
        for a, b in zip(r[:-1], r[1:]):
            n = int(np.ceil(np.linalg.norm(b - a) / spacing)) + 1
            out.extend(a + (b - a) * t for t in np.linspace(0.0, 1.0, n, endpoint=False))

    for feat in d["features"]:
        role = (feat.get("properties") or {}).get("role", "domain")
        g = feat["geometry"]
        if role != "domain" or g is None:
            continue
        polys = [g["coordinates"]] if g["type"] == "Polygon" else g["coordinates"] if g["type"] == "MultiPolygon" else []
        for poly in polys:
            for ring in poly:
                add(ring)
    return np.asarray(out)


def distance(points, samples, chunk=400):
    out = np.empty(len(points))
    for i in range(0, len(points), chunk):
        p = points[i:i + chunk]
        out[i:i + chunk] = np.sqrt(((p[:, None, :] - samples[None]) ** 2).sum(-1)).min(1)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("mesh")
    ap.add_argument("domain")
    ap.add_argument("--bands", default="0,30,100,300,1e9", help="distance band edges in metres")
    ap.add_argument("--sample", type=float, default=5.0, help="ring sample spacing in metres")
    ap.add_argument("--json", help="write the figures here too")
    a = ap.parse_args()
    m = meshio.read(a.mesh)
    quads = [c.data for c in m.cells if c.type == "quad"]
    if not quads:
        sys.exit(f"error: {a.mesh}: no quads")
    Q = np.vstack(quads)
    P = m.points[:, :2]
    E = np.array([np.linalg.norm(P[Q[:, (i + 1) % 4]] - P[Q[:, i]], axis=1) for i in range(4)])
    first, second = (E[0] + E[2]) / 2, (E[1] + E[3]) / 2
    aspect = np.maximum(first / second, second / first)
    long_axis = np.where((first > second)[:, None], P[Q[:, 1]] - P[Q[:, 0]], P[Q[:, 2]] - P[Q[:, 1]])
    long_axis /= np.linalg.norm(long_axis, axis=1)[:, None]
    samples = ring_samples(a.domain, a.sample)
    c = P[Q].mean(1)
    h = 2.0
    dist = distance(c, samples)
    grad = np.stack([(distance(c + [h, 0], samples) - distance(c - [h, 0], samples)) / (2 * h),
                     (distance(c + [0, h], samples) - distance(c - [0, h], samples)) / (2 * h)], 1)
    grad /= np.maximum(np.linalg.norm(grad, axis=1), 1e-12)[:, None]
    cos = np.abs((long_axis * grad).sum(1))
    stretched = aspect > 1.5
    edges = [float(x) for x in a.bands.split(",")]
    rows = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        k = (dist >= lo) & (dist < hi)
        s = k & stretched
        rows.append({"from_m": lo, "to_m": hi, "quads": int(k.sum()),
                     "aspect_avg": float(aspect[k].mean()) if k.any() else None,
                     "stretched": int(s.sum()), "radial": int((cos[s] > 0.7).sum()), "along": int((cos[s] < 0.3).sum())})
    result = {"mesh": a.mesh, "quads": int(len(Q)), "aspect_avg": float(aspect.mean()),
              "edge_ratio_avg": float((E.max(0) / E.min(0)).mean()), "stretched": int(stretched.sum()), "bands": rows}
    print(f"{a.mesh}: {len(Q)} quads, aspect avg {aspect.mean():.3f}, edge ratio avg {result['edge_ratio_avg']:.3f}, "
          f"{stretched.sum()} with aspect > 1.5")
    print("| distance from the rings (m) | quads | aspect avg | aspect > 1.5 | long axis radial | along the shore |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        avg = "-" if r["aspect_avg"] is None else f"{r['aspect_avg']:.2f}"
        print(f"| {r['from_m']:g}-{r['to_m']:g} | {r['quads']} | {avg} | {r['stretched']} | {r['radial']} | {r['along']} |")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(result, f, indent=1)


if __name__ == "__main__":
    main()
