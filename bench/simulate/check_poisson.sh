#!/usr/bin/env bash
# The fast check of bench/simulate/poisson (CTest simulate.poisson_converges): mechanical_part's manufactured
# solution on polysquare meshes at sizes 5 and 2.5; the L2 error must fall at a rate in h ~ DoFs^-1/2 between 1.8
# and 2.6 (Q1: 2) and the H1 seminorm error at least at 0.9 (Q1: 1). Measured 2026-12-07: 559 and 2109 DoFs,
# L2 3.43 -> 0.777 (rate 2.24), H1 2.17 -> 1.06 (rate 1.08), 27 and 49 CG iterations. poisson itself exits 1 when
# CG fails.
set -euo pipefail
cli=$1 poisson=$2 region=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for size in 5 2.5; do
  "$cli" mesh "$region" --size "$size" -o "$work/$size.msh" > /dev/null
  "$poisson" "$work/$size.msh" --region "$region" --json "$work/$size.json" > /dev/null
done
python3 - "$work/5.json" "$work/2.5.json" <<'PY'
import json, math, sys
a, b = (json.load(open(p)) for p in sys.argv[1:])
rate = {e: 2 * math.log(a[e] / b[e]) / math.log(b["dofs"] / a["dofs"]) for e in ("l2", "h1")}
print("DoFs %d -> %d: L2 %.3g -> %.3g (rate %.2f), H1 %.3g -> %.3g (rate %.2f)" % (
    a["dofs"], b["dofs"], a["l2"], b["l2"], rate["l2"], a["h1"], b["h1"], rate["h1"]))
sys.exit(0 if 1.8 <= rate["l2"] <= 2.6 and rate["h1"] >= 0.9 else 1)
PY
