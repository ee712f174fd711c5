#!/bin/bash
# The paper's sparse transforms (issue 10): one dense rotation over N
# scaled-and-translated spheres against the same spheres each under its own
# pre-concatenated dense transform. Instruction counts under callgrind,
# one thread (deterministic; BENCHMARKS.md "Sparse transforms", which also
# records why the transform plugin has no sparse shortcut).
#
#   host/benches/sparse_transforms.sh [RTK]     # default ./target/release/rtk
set -euo pipefail
rtk=${1:-./target/release/rtk}
dir=$(mktemp -d)
head() {
  cat <<H
[render]
width = 160
height = 120
root = "world"
background = [0.2, 0.3, 0.4]
integrator = { class = "whitted", max_depth = 4 }
[cameras.c]
class = "pinhole"
eye = [0.0, 6.0, 14.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 50.0
[lights.l]
class = "directional"
direction = [-0.3, -1.0, -0.5]
irradiance = [2.0, 2.0, 2.0]
[shaders.s]
class = "lambert"
[objects.ball]
class = "sphere"
H
}
children() { # $1: "dense" adds the rotation to every child
  for i in $(seq 0 19); do for j in $(seq 0 19); do
    x=$(echo "($i - 9.5) * 0.5" | bc -l); z=$(echo "($j - 9.5) * 0.5" | bc -l)
    s=$(echo "0.08 + 0.01 * (($i * 7 + $j * 3) % 10)" | bc -l)
    rot=""; [ "$1" = dense ] && rot=", { rotate_y = 30.0 }"
    printf '  { object = "ball", shader = "s", transform = [{ scale = %.3f }, { translate = [%.3f, 0.0, %.3f] }%s] },\n' "$s" "$x" "$z" "$rot"
  done; done
}
{ head; echo '[objects.group]'; echo 'class = "bvh"'; echo 'children = ['; children sparse; echo ']'
  echo '[objects.world]'; echo 'class = "list"'; echo 'children = [{ object = "group", transform = [{ rotate_y = 30.0 }] }]'; } > "$dir/sparse.toml"
{ head; echo '[objects.world]'; echo 'class = "bvh"'; echo 'children = ['; children dense; echo ']'; } > "$dir/dense.toml"
count() {
  valgrind --tool=callgrind --callgrind-out-file=/dev/null "$@" 2>&1 >/dev/null |
    grep -o "Collected : [0-9]*" | awk '{print $3}'
}
for s in sparse dense; do
  echo "$s $(count "$rtk" render "$dir/$s.toml" -o "$dir/$s.exr" -q --threads 1)"
done
"$rtk" diff "$dir/sparse.exr" "$dir/dense.exr" | sed -n 1p
