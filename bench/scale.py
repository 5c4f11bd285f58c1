#!/usr/bin/env python3
"""How polysquare scales with the quad count: one case at several sizes, each with several thread and process
counts, in one run. Printed per run: quads, wall seconds, quads per second, microseconds per quad and its ratio
to the first size's (the issue's target: within 1.5 x from 1M to 17M quads), peak memory of the run (the largest
process's resident set, from wait4), structured fraction, SJ min, interior singular nodes per 1000 quads, the
part's stage seconds from the report, core-seconds against the paper's 17M-quad run, and whether the mesh is
byte-identical to the first configuration's at that size.

usage: bench/scale.py [--bin build/polysquare] [--case delta_box] [--sizes 40,20,10] [--configs t1,t2,np2]
                      [--out out/bench_scale] [--time-limit SECONDS] [-- extra mesh options]
Configurations: tN = one process with N threads; npN = mpirun -np N (the driver divides the cores among them).
delta_box at 40, 20 and 10 m gives about 1M, 4M and 17M quads; the 10 m run takes hours on two cores.
"""
import argparse
import json
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# FPPM paper, Sec. 6.3: 17,382,945 quads, 113 s partitioning + 439 s meshing on 50 cores.
PAPER_QUADS, PAPER_CORE_SECONDS = 17_382_945, (113 + 439) * 50


def command(binary, config, args):
    if config.startswith("np"):
        ranks = int(config[2:])
        mpi = ["mpirun", "-np", str(ranks)]
        if os.geteuid() == 0:
            mpi.append("--allow-run-as-root")
        if ranks > (os.cpu_count() or 1):
            mpi.append("--oversubscribe")
        return mpi + [binary] + args, ranks
    threads = int(config[1:])
    return [binary] + args + ["--threads", str(threads)], threads


def run(cmd):
    """Wall seconds and peak resident set (MB) of the largest process of the run."""
    t0 = time.monotonic()
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(p.pid, 0)
    seconds = time.monotonic() - t0
    err = p.stderr.read().decode(errors="replace")
    code = os.waitstatus_to_exitcode(status)
    return seconds, usage.ru_maxrss / 1024.0, code, err


def stage_seconds(report):
    """The chosen candidates' stage seconds, summed over parts (map split into its parts)."""
    out = {}
    for part in report.get("candidates", []):
        for c in part:
            if not c.get("chosen"):
                continue
            stages = c.get("stage_seconds", {})
            for k, v in stages.items():
                if isinstance(v, (int, float)):
                    out[k] = out.get(k, 0.0) + v
            for k, v in stages.get("map_of", {}).items():
                if k.endswith("seconds") or k in ("partition", "split_rounds"):
                    out[k] = out.get(k, 0.0) + v
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "polysquare"))
    ap.add_argument("--case", default="delta_box")
    ap.add_argument("--sizes", default="40,20,10")
    ap.add_argument("--configs", default="t1,t2,np2")
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "bench_scale"))
    ap.add_argument("--time-limit", type=float, default=0.0, help="passed to mesh --time-limit (0 = none)")
    ap.add_argument("extra", nargs="*", help="extra mesh options (after --)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    case = a.case if a.case.endswith(".geojson") else os.path.join(ROOT, "data", "cases", a.case + ".geojson")
    name = os.path.splitext(os.path.basename(case))[0]
    configs = [c.strip() for c in a.configs.split(",") if c.strip()]
    print("%-8s %-5s %10s %9s %9s %8s %6s %8s %6s %6s %7s %9s %s" % (
        "size", "run", "quads", "wall s", "quads/s", "us/quad", "ratio", "peak MB", "str", "SJmin", "sing/kq",
        "core-s/q", "stages (s) / identical"))
    first_us = None
    for size in [s.strip() for s in a.sizes.split(",") if s.strip()]:
        first_mesh = None
        for config in configs:
            mesh = os.path.join(a.out, "%s_%s_%s.msh" % (name, size, config))
            report_path = os.path.join(a.out, "%s_%s_%s.json" % (name, size, config))
            args = ["mesh", case, "--size", size, "-o", mesh, "--report", report_path, "--quiet", "--binary"]
            if a.time_limit > 0:
                args += ["--time-limit", str(a.time_limit)]
            cmd, cores = command(a.bin, config, args + a.extra)
            seconds, peak_mb, code, err = run(cmd)
            if code != 0:
                print("%-8s %-5s failed (exit %d): %s" % (size, config, code, err.strip().splitlines()[-1:] or ""))
                continue
            with open(report_path) as f:
                report = json.load(f)
            s = report["summary"]
            quads = s["quads"]
            us = seconds * 1e6 / quads
            if first_us is None:
                first_us = us
            with open(mesh, "rb") as f:
                data = f.read()
            if first_mesh is None:
                first_mesh, same = data, "first"
            else:
                same = "identical" if data == first_mesh else "DIFFERS"
            # Core-seconds per quad against the paper's (50 cores): below 1 means less work per quad.
            core_ratio = (seconds * min(cores, os.cpu_count() or 1) / quads) / (PAPER_CORE_SECONDS / PAPER_QUADS)
            stages = " ".join("%s %.0f" % (k, v) for k, v in sorted(stage_seconds(report).items()) if v >= 1.0)
            print("%-8s %-5s %10d %9.1f %9.0f %8.1f %6.2f %8.0f %6.3f %6.3f %7.2f %9.3f %s / %s" % (
                size, config, quads, seconds, quads / seconds, us, us / first_us, peak_mb, s["structured_fraction"],
                s["sj_min"], 1000.0 * s["interior_singularities"] / quads, core_ratio, stages, same), flush=True)
    print("ratio: microseconds per quad over the first run's; core-s/q: wall x cores per quad over the paper's "
          "(%d quads, %d core-seconds)" % (PAPER_QUADS, PAPER_CORE_SECONDS))


if __name__ == "__main__":
    main()
