#!/usr/bin/python3
"""The PNG plots of docs/simulation.md (run with Debian's python3, which has python3-matplotlib).

usage: /usr/bin/python3 bench/simulate/plots.py errors RESULTS.json OUT.png
       /usr/bin/python3 bench/simulate/plots.py residuals SPEC.json OUT.png
errors: the Poisson study's L2 and H1 errors against DoFs, log-log, one panel per case, one colour per mesh
generator (RESULTS.json as poisson_table.py writes it). residuals: the heat runs' CG residual histories at t = 1 and
t = 10, one row per D (SPEC.json: {"D = 1": [[label, FILE.residuals.json], ...], ...}, the files as heat writes them).
"""
import json
import math
import sys

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt  # noqa: E402

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
            ax.set_ylabel("residual norm")
            ax.grid(True, which="both", alpha=0.3)
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    {"errors": errors, "residuals": residuals}[sys.argv[1]](sys.argv[2], sys.argv[3])
