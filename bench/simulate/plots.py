#!/usr/bin/python3
"""The PNG plots of docs/simulation.md (run with Debian's python3, which has python3-matplotlib).

usage: /usr/bin/python3 bench/simulate/plots.py errors RESULTS.json OUT.png
       /usr/bin/python3 bench/simulate/plots.py residuals SPEC.json OUT.png
       /usr/bin/python3 bench/simulate/plots.py areas RUN.json OUT.png
errors: the Poisson study's L2 and H1 errors against DoFs, log-log, one panel per case, one colour per mesh
generator (RESULTS.json as poisson_table.py writes it). residuals: the heat runs' CG residual histories at t = 1 and
t = 10, one row per D (SPEC.json: {"D = 1": [[label, FILE.residuals.json], ...], ...}, the files as heat writes them).
areas: a mesh's cells coloured by their area over the mean (log 2 scale), the cells with the largest L2 errors starred
(RUN.json: poisson's JSON output for the mesh); whole mesh and a zoom on the worst cell. Needs python3-meshio too.
"""
import json
import math
import sys

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402

STYLE = {"polysquare": ("polysquare", "tab:blue"), "quad": ("Gmsh quads", "tab:orange"),
         "triangle": ("Gmsh triangles", "tab:green")}


def errors(results_path, out):
    results = json.load(open(results_path))
    cols = min(2, len(results))
    rows = math.ceil(len(results) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(5.5 * cols, 4.2 * rows), squeeze=False)
    for ax, (name, levels) in zip(axes.flat, results.items()):
        for kind, (label, colour) in STYLE.items():
            runs = [lv[kind] for lv in levels if lv[kind] is not None]
            dofs = [r["dofs"] for r in runs]
            ax.loglog(dofs, [r["l2"] for r in runs], "o-", color=colour, label=label + " L2")
            ax.loglog(dofs, [r["h1"] for r in runs], "s--", color=colour, label=label + " H1", alpha=0.8)
        ax.set_title(name)
        ax.set_xlabel("DoFs")
        ax.set_ylabel("error")
        ax.grid(True, which="both", alpha=0.3)
    for ax in list(axes.flat)[len(results):]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7)
    fig.suptitle("L2 (solid) and H1 seminorm (dashed) errors")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def residuals(spec_path, out):
    spec = json.load(open(spec_path))
    times = ["t1", "t10"]
    fig, axes = plt.subplots(len(spec), len(times), figsize=(11, 3.8 * len(spec)), squeeze=False)
    for row, (title, runs) in zip(axes, spec.items()):
        for label, path in runs:
            history = json.load(open(path))
            for ax, t in zip(row, times):
                ax.semilogy(range(len(history[t])), history[t], "o-", markersize=3, label=label)
        for ax, t in zip(row, times):
            ax.set_title("%s, t = %s" % (title, t[1:]))
            ax.set_xlabel("CG iteration")
            ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
            ax.set_ylabel("residual norm")
            ax.grid(True, which="both", alpha=0.3)
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def areas(run_path, out):
    import meshio
    import numpy as np
    from matplotlib.collections import PolyCollection

    run = json.load(open(run_path))
    mesh = meshio.read(run["mesh"])
    cells = [mesh.points[block.data][..., :2] for block in mesh.cells if block.type in ("quad", "triangle")]
    polygons = [p for block in cells for p in block]
    area = np.array([0.5 * abs(np.dot(p[:, 0], np.roll(p[:, 1], -1)) - np.dot(np.roll(p[:, 0], -1), p[:, 1]))
                     for p in polygons])
    colour = np.log2(area / area.mean())
    worst = [c["centre"] for c in run["worst_l2"]]
    fig, axes = plt.subplots(1, 2, figsize=(13, 6))
    for ax, width in zip(axes, (0.05, 0.3)):
        shown = PolyCollection(polygons, array=colour, cmap="coolwarm", edgecolor="k", linewidth=width)
        shown.set_clim(-2, 2)
        ax.add_collection(shown)
        ax.plot([c[0] for c in worst], [c[1] for c in worst], "*", color="lime", markersize=14, markeredgecolor="k")
        ax.set_aspect("equal")
    axes[0].autoscale()
    # The zoom: 40 mean cell sides around the worst cell.
    half = 20 * math.sqrt(area.mean())
    axes[1].set_xlim(worst[0][0] - half, worst[0][0] + half)
    axes[1].set_ylim(worst[0][1] - half, worst[0][1] + half)
    fig.colorbar(shown, ax=axes, label="log2(cell area / mean cell area)", shrink=0.8)
    fig.suptitle("%s: cell areas, the 3 cells with the largest L2 error starred" % run["mesh"].split("/")[-1])
    fig.savefig(out, dpi=90)


if __name__ == "__main__":
    {"errors": errors, "residuals": residuals, "areas": areas}[sys.argv[1]](sys.argv[2], sys.argv[3])
