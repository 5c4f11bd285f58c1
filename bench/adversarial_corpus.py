#!/usr/bin/env python3
"""Time and peak memory of the CLI on every row of tests/data/adversarial/cases.tsv (issue 13, round two), against
the issue's bounds: a refusal (exit 2 or 3) within 5 s, a mesh within 60 s, no run above 2 GB. Each run goes
through /usr/bin/time -v (wall clock, maximum resident set size). The tests assert each row's outcome, never its
time; this program is where the time is measured.

With --big it also makes the 1.2M-vertex ring of class 11 (a circle of radius 50 km, 1.2M vertices, too large to
commit) in a scratch directory and meshes it at --size 200 with the default simplification.

Each run is killed after --timeout seconds (default 300; it then shows exit 137).
Usage: bench/adversarial_corpus.py [--cli build/polysquare] [--big] [--only SUBSTRING] [--jobs N] [--timeout S]
Prints one line per row and a summary; exits 1 when a run breaks its bound or its promised exit code."""
import argparse
import math
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
CORPUS = os.path.join(ROOT, "tests", "data", "adversarial")
REFUSAL_S, MESH_S, MEMORY_MB = 5.0, 60.0, 2048.0


def rows():
    with open(os.path.join(CORPUS, "cases.tsv")) as f:
        for line in f:
            line = line.rstrip("\n")
            if not line or line.startswith("#"):
                continue
            name, file, command, args, code, _ = line.split("\t")
            yield name, file, command, args, int(code)


def run(cli, timeout, name, file, command, args, code):
    work = tempfile.mkdtemp(prefix="polysquare_bench_")
    try:
        if file == "{dir}":
            inp = work
        elif "{copy}" in args:
            inp = os.path.join(work, os.path.basename(file))
            shutil.copy(os.path.join(CORPUS, file), inp)
        else:
            inp = file if os.path.isabs(file) else os.path.join(CORPUS, file)
        a = args.replace("{dir}", work).replace("{copy}", inp)
        if command == "mesh" and "-o " not in args:
            a += " -o " + os.path.join(work, "out.msh")
        if command == "mesh":
            a += " -q"
        cmd = ["/usr/bin/time", "-v", "timeout", "-s", "KILL", str(timeout), cli, command, inp] + a.split()
        p = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, errors="replace")
        wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", p.stderr).group(1)
        seconds = sum(float(x) * 60 ** i for i, x in enumerate(reversed(wall.split(":"))))
        rss_mb = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr).group(1)) / 1024.0
        status = re.search(r"Exit status: (\d+)", p.stderr)
        got = int(status.group(1)) if status else -1
        return name, code, got, seconds, rss_mb
    finally:
        shutil.rmtree(work, ignore_errors=True)


def big_ring(directory):
    n, r = 1_200_000, 50_000.0
    ring = [[round(r * math.cos(2 * math.pi * k / n), 3), round(r * math.sin(2 * math.pi * k / n), 3)] for k in range(n)]
    path = os.path.join(directory, "ring_1200000.geojson")
    with open(path, "w") as f:
        json.dump({"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {"role": "domain"},
                   "geometry": {"type": "Polygon", "coordinates": [ring + [ring[0]]]}}]}, f)
    return path


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cli", default=os.path.join(ROOT, "build", "polysquare"))
    ap.add_argument("--big", action="store_true", help="also mesh the generated 1.2M-vertex ring")
    ap.add_argument("--only", default="", help="rows whose name contains this")
    ap.add_argument("--jobs", type=int, default=1, help="rows run at once (1: figures undisturbed)")
    ap.add_argument("--timeout", type=float, default=300, help="seconds after which a run is killed")
    opt = ap.parse_args()
    todo = [r for r in rows() if opt.only in r[0]]
    scratch = tempfile.mkdtemp(prefix="polysquare_bench_big_")
    try:
        if opt.big:
            todo.append(("ring_1200000", big_ring(scratch), "mesh", "--size 200", 0))
        with ThreadPoolExecutor(max_workers=opt.jobs) as pool:
            results = list(pool.map(lambda r: run(opt.cli, opt.timeout, *r), todo))
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    bad = 0
    worst = {"refusal": (0.0, ""), "mesh": (0.0, ""), "memory": (0.0, "")}
    print("%-44s %4s %4s %9s %9s  %s" % ("row", "want", "got", "seconds", "peak MB", "verdict"))
    for name, want, got, seconds, mb in results:
        kind = "mesh" if got == 0 else "refusal"
        bound = MESH_S if kind == "mesh" else REFUSAL_S
        problems = []
        if got != want:
            problems.append("exit %d, promised %d" % (got, want))
        if seconds > bound:
            problems.append("over %g s" % bound)
        if mb > MEMORY_MB:
            problems.append("over %g MB" % MEMORY_MB)
        bad += bool(problems)
        worst[kind] = max(worst[kind], (seconds, name))
        worst["memory"] = max(worst["memory"], (mb, name))
        print("%-44s %4d %4d %9.2f %9.1f  %s" % (name, want, got, seconds, mb, "; ".join(problems) or "ok"))
    print("\n%d rows; slowest refusal %.2f s (%s, bound %g s); slowest mesh %.2f s (%s, bound %g s); "
          "largest peak memory %.1f MB (%s, bound %g MB); %d over a bound or off their promise"
          % (len(results), worst["refusal"][0], worst["refusal"][1], REFUSAL_S, worst["mesh"][0], worst["mesh"][1],
             MESH_S, worst["memory"][0], worst["memory"][1], MEMORY_MB, bad))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
