"""What bench/simulate's scripts (heat_table.py, poisson_table.py, simulation.py) share: running and logging commands,
making polysquare and Gmsh meshes of a case once, and searching the size that gives a count."""
import json
import math
import os
import shlex
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
JUDGE = "/work/shared/tools/judge.py"
# The interpreter of the helpers that need Debian's numpy, meshio, shapely or matplotlib (a `python3` earlier on
# PATH, e.g. pyenv's, may lack them).
SYSTEM_PYTHON = "/usr/bin/python3"
COMMANDS = []  # every command run, for the page


def run(cmd, log=None, check=True):
    """Runs cmd under nice (the machine is shared); on failure stops the script with the command and its output,
    or with check=False returns None."""
    full = ["nice", "-n", "10"] + cmd
    COMMANDS.append(" ".join(shlex.quote(c) for c in full))
    p = subprocess.run(full, capture_output=True, text=True)
    if log:
        with open(log, "w") as f:
            f.write(p.stdout + p.stderr)
    if p.returncode != 0 and not check:
        return None
    if p.returncode != 0:
        sys.exit("failed (%d): %s\n%s%s" % (p.returncode, COMMANDS[-1], p.stdout[-3000:], p.stderr[-3000:]))
    return p.stdout


def last_json(text):
    return json.loads(text.strip().splitlines()[-1])


def polysquare_mesh(cli, case, out, options):
    """polysquare's mesh of case with the given CLI options, written to out once (an existing out is reused)."""
    if not os.path.exists(out):
        run([cli, "mesh", case] + options + ["-o", out], log=out + ".log")
    return out


def gmsh_mesh(case, work, size, kind, prefix="gmsh"):
    """Gmsh mesh of the case: kind 'quad' (the project's baseline .geo) or 'triangle' (Delaunay, no recombination).
    Only the surfaces are a physical group, so embedded feature curves' line elements (which deal.II refuses as
    interior boundary lines) are not written; the curves stay as mesh edges. None when Gmsh fails (Blossom finds
    no perfect matching at some sizes: it then writes triangles and exits 1)."""
    geo = os.path.join(work, "%s_%s_%g.geo" % (prefix, kind, size))
    msh = geo[:-4] + ".msh"
    failed = msh + ".failed"
    if os.path.exists(failed):
        return None
    if not os.path.exists(msh):
        run([os.path.join(ROOT, "scripts", "make-gmsh-geo"), case, "%g" % size, geo])
        extra = ["Physical Surface(1) = Surface{:};"]  # every part of a multi-part domain
        if kind == "triangle":
            extra += ["Mesh.Algorithm = 5;", "Mesh.RecombineAll = 0;"]
        with open(geo, "a") as f:
            f.write("\n".join(extra) + "\n")
        if run(["gmsh", geo, "-2", "-format", "msh41", "-o", msh], log=msh + ".log", check=False) is None:
            os.replace(msh, failed) if os.path.exists(msh) else open(failed, "w").close()
            return None
    return msh


def judge(mesh):
    COMMANDS.append("%s %s %s" % (SYSTEM_PYTHON, JUDGE, mesh))
    p = subprocess.run(["nice", "-n", "10", SYSTEM_PYTHON, JUDGE, mesh], capture_output=True, text=True)
    return json.loads(p.stdout.strip().splitlines()[-1]) if p.returncode == 0 else None


def scan(count, h0, target, spread=0.15, step=0.01):
    """{size: count} over sizes spread around the one expected to give target (counts go as 1/size^2, estimated
    from count(h0)); sizes where count is None (refused, e.g. Blossom found no matching) are left out. A grid rather
    than a root search: Gmsh's Blossom fails at whole runs of sizes and polysquare's counts move in steps."""
    n0, h = None, h0
    while n0 is None and h < 2 * h0:
        n0, h = count(h), h * 1.03
    if n0 is None:
        return {}
    centre = (h / 1.03) * math.sqrt(n0 / target)
    k = int(round(spread / step))
    found = {}
    for i in range(-k, k + 1):
        size = round(centre * (1 + i * step), 3)
        n = count(size)
        if n is not None:
            found[size] = n
    return found


def nearest(found, target):
    return min(found.items(), key=lambda kv: abs(kv[1] - target)) if found else (None, None)


def fmt(x, digits=2):
    return "%.*e" % (digits, x) if isinstance(x, float) else str(x)
