#!/bin/sh
# What the paper's bounding-volume types cost and save (issue 12): the same
# scene under `bvh` with bound = "box", "sphere" and "slabs" (a second
# volume tested on the box test's survivors), same rays, same hits.
#   sh host/benches/bounds.sh [SCENE_OR_MESH ...]      (after cargo build --release)
# Defaults: the dragon's primary and incoherent rays (triangles: volumes from
# their vertices) and scenes/volumes.toml (rotated tori and rods: each child
# answers inq_bounds with its own sphere and slabs).
set -eu
rtk=${RTK:-target/release/rtk}
inputs=${*:-"../shared/data/meshes/dragon-200k.ply scenes/volumes.toml"}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for input in $inputs; do
  case "$input" in
    *.ply|*.obj)
      abs=$(cd "$(dirname "$input")" && pwd)/$(basename "$input")
      for b in box sphere slabs; do
        printf '[render]\nroot = "world"\nintegrator = "normals"\n[cameras.none]\nclass = "pinhole"\n[objects.m]\nclass = "mesh"\nfile = "%s"\naccel = "none"\n[objects.world]\nclass = "bvh"\nbound = "%s"\nchildren = ["m"]\n' "$abs" "$b" > "$tmp/$b.toml"
      done ;;
    *)
      for b in box sphere slabs; do
        grep -v '^bound = ' "$input" | sed "s/^class = \"bvh\"$/class = \"bvh\"\nbound = \"$b\"/" > "$tmp/$b.toml"
        # Relative mesh paths resolve against the scene's folder.
        cp -r "$(dirname "$input")/meshes" "$tmp/" 2>/dev/null || true
      done ;;
  esac
  for set in primary incoherent; do
    for b in box sphere slabs; do
      "$rtk" trace "$tmp/$b.toml" --rayset $set --threads 2 --iters 3 --json |
        python3 -c "import json,sys; j=json.load(sys.stdin); print('| $(basename "$input") | $set | $b | %.2f | %.1f | %.2f | %.2f | %d |' % (j['mrays_per_s'], j['build_seconds']*1e3, j['node_tests_per_ray'], j['prim_tests_per_ray'], j['hits']))"
    done
  done
done
