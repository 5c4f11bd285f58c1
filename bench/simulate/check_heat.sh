#!/usr/bin/env bash
# The fast check of bench/simulate/heat (CTest simulate.heat_converges): mechanical_part at D = 100, a coarse
# polysquare mesh (size 5) against a Q2 reference on a finer one (size 2.5). heat exits 1 when CG needs more than 20
# iterations a step or eps is above 0.05 (measured 2026-12-07: eps(1) 0.023, eps(10) 0.003, at most 6 iterations).
set -euo pipefail
cli=$1 heat=$2 region=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$cli" mesh "$region" --size 2.5 -o "$work/ref.msh" > /dev/null
"$heat" "$work/ref.msh" --region "$region" --degree 2 --dt 0.05 --diffusivity 100 --save "$work/ref" > /dev/null
"$cli" mesh "$region" --size 5 -o "$work/coarse.msh" > /dev/null
"$heat" "$work/coarse.msh" --region "$region" --dt 0.05 --diffusivity 100 --reference "$work/ref.msh" "$work/ref" \
  --max-cg 20 --max-eps 0.05
