#!/bin/bash
# What the robust numerics cost (issue 8, BENCHMARKS.md "Numerics"): builds
# rtk once with naive-kernels.patch applied in a scratch worktree. The patch
# adds a run-time switch, RTK_NAIVE=name[,name...], that swaps each robust
# measure (docs/numerics.md, the rule in brackets) for its naive form:
#   mt        Möller–Trumbore instead of the watertight test [3]
#   recheck   reject a hit within its t bound instead of rechecking t [4]
#   sphere    textbook b²-4ac quadratic in f32 [5]
#   sphere32  the reformulated quadratic in f32 instead of f64 [5]
#   offset    no origin offset for spawned rays [7]
#   inset     no edge inset of triangle hit points [6]
#   between   shadow rays offset at their origin only [7]
#   side      no side guard on reflected/refracted directions [13]
#   xform     no way-back term in the transform's error bound [8]
#   slab      f32 min/max slabs, no far-plane widening [10]
#   tie       no tie margin when bvh/kdtree cull by the best hit [11]
#   origin    render about the world's origin, not the camera [14]
#   all       every one of them
# The same binary runs robust (RTK_NAIVE unset) and naive, so both pay the
# switch's check (one cached load and a branch).
#
# Prints callgrind instruction counts per workload and mode (deterministic,
# unlike wall time on a shared machine), then which `rtk stress --quick`
# measurements fail with each measure swapped out.
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
for mode in none mt sphere32 sphere slab tie all; do
  echo "$mode trace-bunny-primary $(RTK_NAIVE=$mode count "$rtk" trace scenes/meshes/bunny.ply --rayset primary --threads 1)"
  echo "$mode trace-bunny-incoherent $(RTK_NAIVE=$mode count "$rtk" trace scenes/meshes/bunny.ply --rayset incoherent --threads 1)"
  echo "$mode render-default-256 $(RTK_NAIVE=$mode count "$rtk" render scenes/default.toml -o /tmp/nc.png -q --threads 1 --set render.width=256 --set render.height=192)"
  echo "$mode render-mirrors-240 $(RTK_NAIVE=$mode count "$rtk" render scenes/mirrors.toml -o /tmp/nc.png -q --threads 1 --set render.width=240 --set render.height=180)"
  echo "$mode render-quadrics-256 $(RTK_NAIVE=$mode count "$rtk" render scenes/quadrics.toml -o /tmp/nc.png -q --threads 1 --set render.width=256 --set render.height=192)"
done
for mode in mt recheck sphere sphere32 offset inset between side xform slab tie origin; do
  echo "== RTK_NAIVE=$mode: failing measurements"
  RTK_NAIVE=$mode "$rtk" stress --quick 2>&1 | grep -E "FAIL|measurements" || true
done
