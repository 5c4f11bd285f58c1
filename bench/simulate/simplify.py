#!/usr/bin/python3
"""Writes a copy of a GeoJSON region whose domain rings are simplified to a mesh size, for Gmsh. polysquare simplifies
curves finer than its size before meshing (--simplify: every dropped vertex within the size of the result); Gmsh
meshes every input vertex it is given (make-gmsh-geo splits rings at every vertex turning by more than 30 degrees,
and a raw coastline turns at most of its thousands of vertices), so on a coastline Gmsh's DoFs cannot come down to
polysquare's at a coarse size unless it gets the rings simplified the same way.

usage: /usr/bin/python3 bench/simulate/simplify.py REGION.geojson SIZE OUT.geojson
Each polygon part: Douglas-Peucker with tolerance SIZE, topology kept (shapely); holes and parts of area below SIZE^2
dropped; then points every SIZE / 4 along each segment, so that make-gmsh-geo's splines through the few remaining
vertices stay on the straight segments (a spline through them alone bulges across narrow channels, and Gmsh then
fails to recover its edges). Feature curves are copied as they are. Needs Debian's python3-shapely.
"""
import json
import math
import sys

from shapely.geometry import MultiPolygon, Polygon, mapping, shape


def densify(ring, step):
    """The closed ring's points with extra points at most step apart along every segment."""
    out = []
    for (x0, y0), (x1, y1) in zip(ring[:-1], ring[1:]):
        n = max(1, math.ceil(math.hypot(x1 - x0, y1 - y0) / step))
        out += [(x0 + (x1 - x0) * i / n, y0 + (y1 - y0) * i / n) for i in range(n)]
    return out + [out[0]]


def main():
    src, size, out = sys.argv[1], float(sys.argv[2]), sys.argv[3]
    doc = json.load(open(src))
    for f in doc["features"]:
        if f.get("properties", {}).get("role") != "domain":
            continue
        geom = shape(f["geometry"])
        kept = []
        for part in (geom.geoms if isinstance(geom, MultiPolygon) else [geom]):
            s = part.simplify(size, preserve_topology=True)
            if s.is_empty or s.area < size * size:
                continue
            holes = [h for h in s.interiors if Polygon(h).area >= size * size]
            kept.append(Polygon(densify(s.exterior.coords, size / 4), [densify(h.coords, size / 4) for h in holes]))
        f["geometry"] = mapping(MultiPolygon(kept) if len(kept) > 1 else kept[0])
    with open(out, "w") as fh:
        json.dump(doc, fh)


if __name__ == "__main__":
    main()
