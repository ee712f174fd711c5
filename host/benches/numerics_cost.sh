#!/bin/bash
# What the robust numerics cost (issue 8, BENCHMARKS.md "Numerics"): builds
# rtk once with naive-kernels.patch applied in a scratch worktree. The patch
# adds a run-time switch, RTK_NAIVE=name[,name...], that swaps each robust
# measure for its naive form (mt: Möller–Trumbore for the watertight test;
# recheck: reject instead of the f64 recheck; slab: f32::min/max and no
# widening; sphere: textbook quadratic; offset: no origin offset; inset: no
# edge inset; side: no direction-side guard; between: shadow rays offset at
# the origin only; origin: no camera-relative shift; all). The same binary
# runs robust (RTK_NAIVE unset) and naive, so both pay the switch's check.
#
# Prints callgrind instruction counts per workload and mode, then which
# `rtk stress --quick` measurements fail with each measure swapped out.
#
#   host/benches/numerics_cost.sh [WORKTREE]    # default /tmp/rtk-naive
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
wt=${1:-/tmp/rtk-naive}
if [ ! -d "$wt" ]; then
  git -C "$here" worktree add -f "$wt" HEAD >/dev/null
  git -C "$wt" apply "$here/host/benches/naive-kernels.patch"
fi
(cd "$wt" && CARGO_TARGET_DIR="$wt/target" cargo build --release --workspace -q)
rtk="$wt/target/release/rtk"
cd "$here"
count() {
  valgrind --tool=callgrind --callgrind-out-file=/dev/null "$@" 2>&1 >/dev/null |
    grep -o "Collected : [0-9]*" | awk '{print $3}'
}
for mode in none mt sphere slab all; do
  echo "$mode trace-bunny-primary $(RTK_NAIVE=$mode count "$rtk" trace scenes/meshes/bunny.ply --rayset primary --threads 1)"
  echo "$mode trace-bunny-incoherent $(RTK_NAIVE=$mode count "$rtk" trace scenes/meshes/bunny.ply --rayset incoherent --threads 1)"
  echo "$mode trace-nested-incoherent $(RTK_NAIVE=$mode count "$rtk" trace scenes/nested.toml --rayset incoherent --threads 1)"
  echo "$mode render-default-256 $(RTK_NAIVE=$mode count "$rtk" render scenes/default.toml -o /tmp/nc.png -q --threads 1 --set render.width=256 --set render.height=192)"
  echo "$mode render-mirrors-240 $(RTK_NAIVE=$mode count "$rtk" render scenes/mirrors.toml -o /tmp/nc.png -q --threads 1 --set render.width=240 --set render.height=180)"
  echo "$mode render-nested-256 $(RTK_NAIVE=$mode count "$rtk" render scenes/nested.toml -o /tmp/nc.png -q --threads 1 --set render.width=256 --set render.height=160)"
done
for mode in mt recheck slab sphere offset inset side between origin; do
  echo "== RTK_NAIVE=$mode: failing measurements"
  RTK_NAIVE=$mode "$rtk" stress --quick 2>&1 | grep -E "FAIL|measurements" || true
done
