#!/usr/bin/env python3
"""The paper's space/time trade-off on a "park": many clusters of objects at
very different scales, spread over a large ground.

Three ways to hold the same triangles (every cluster's meshes baked into
world space, so the flat structures see every triangle):
  grid-of-bvhs  a coarse grid over the clusters, one bvh per cluster
                (the meta-hierarchy of "Fair Play");
  grid          one uniform grid over every triangle;
  bvh           one flat bvh over every triangle;
and, for reference, the instanced form: a grid over clusters of transformed
instances of the one bunny (the memory a scene of instances needs).

For each it reports `rtk trace` figures on the scene's primary and incoherent
rays: Mrays/s, the root aggregate's build time, and the memory the build added.

    cargo build --release --workspace
    python3 host/benches/park.py [--clusters 64] [--rtk target/release/rtk] [--rounds 3]
"""

import argparse
import json
import math
import os
import random
import statistics
import subprocess
import tempfile

BUNNY = os.path.join(os.path.dirname(__file__), "..", "..", "scenes", "meshes", "bunny.ply")


def read_ply(path):
    """Vertices and faces of the scenes' binary PLY (float xyz, uchar-int faces)."""
    import struct
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + 11
    head = data[:end].decode()
    nv = int(next(l.split()[2] for l in head.splitlines() if l.startswith("element vertex")))
    nf = int(next(l.split()[2] for l in head.splitlines() if l.startswith("element face")))
    v = [struct.unpack_from("<3f", data, end + 12 * i) for i in range(nv)]
    o = end + 12 * nv
    f = []
    for _ in range(nf):
        f.append(struct.unpack_from("<3i", data, o + 1))
        o += 13
    return v, f


def clusters(n, seed=7):
    """Cluster centres over a 1000-wide park, each with a size from 0.2 to 20
    (a hundredfold range of scales) and a few bunnies."""
    r = random.Random(seed)
    out = []
    for _ in range(n):
        c = (r.uniform(-500, 500), 0.0, r.uniform(-500, 500))
        size = 10 ** r.uniform(math.log10(0.2), math.log10(20))
        members = []
        for _ in range(r.randint(2, 6)):
            members.append((
                c[0] + r.uniform(-3, 3) * size, 0.0, c[2] + r.uniform(-3, 3) * size,
                size * r.uniform(0.05, 0.15), r.uniform(0, 360)))
        out.append(members)
    return out


def baked_obj(verts, faces, tx, ty, tz, s, ry):
    a = math.radians(ry)
    cs, sn = math.cos(a), math.sin(a)
    lines = []
    for (x, y, z) in verts:
        x, y, z = x * s, y * s, z * s
        lines.append(f"v {cs * x + sn * z + tx:.6f} {y + ty:.6f} {-sn * x + cs * z + tz:.6f}")
    lines += [f"f {a + 1} {b + 1} {c + 1}" for (a, b, c) in faces]
    return "\n".join(lines) + "\n"


HEAD = '[render]\nroot = "park"\nintegrator = "normals"\n[cameras.c]\nclass = "pinhole"\n'


def write_scenes(d, cl, verts, faces):
    """The four scene files; returns their paths by name."""
    objs, cluster_defs, flat_children, top = [], [], [], []
    for k, members in enumerate(cl):
        names = []
        for j, m in enumerate(members):
            name = f"b{k}_{j}"
            with open(os.path.join(d, name + ".obj"), "w") as fh:
                fh.write(baked_obj(verts, faces, *m))
            objs.append(f'[objects.{name}]\nclass = "mesh"\nfile = "{name}.obj"\naccel = "none"\n')
            names.append(f'"{name}"')
        flat_children += names
        cluster_defs.append(f'[objects.c{k}]\nclass = "bvh"\nchildren = [{", ".join(names)}]\n')
        top.append(f'"c{k}"')
    common = HEAD + "".join(objs)
    scenes = {
        "grid-of-bvhs": common + "".join(cluster_defs)
        + f'[objects.park]\nclass = "grid"\nchildren = [{", ".join(top)}]\n',
        "grid": common + f'[objects.park]\nclass = "grid"\nchildren = [{", ".join(flat_children)}]\n',
        "bvh": common + f'[objects.park]\nclass = "bvh"\nchildren = [{", ".join(flat_children)}]\n',
    }
    inst = [HEAD, f'[objects.bunny]\nclass = "mesh"\nfile = "{os.path.abspath(BUNNY)}"\n']
    tops = []
    for k, members in enumerate(cl):
        kids = [f'{{ object = "bunny", transform = [{{ scale = {m[3]} }}, {{ rotate_y = {m[4]} }}, '
                f'{{ translate = [{m[0]}, {m[1]}, {m[2]}] }}] }}' for m in members]
        inst.append(f'[objects.c{k}]\nclass = "bvh"\nchildren = [{", ".join(kids)}]\n')
        tops.append(f'"c{k}"')
    inst.append(f'[objects.park]\nclass = "grid"\nchildren = [{", ".join(tops)}]\n')
    scenes["instanced grid-of-bvhs"] = "".join(inst)
    paths = {}
    for name, text in scenes.items():
        p = os.path.join(d, name.replace(" ", "-") + ".toml")
        with open(p, "w") as fh:
            fh.write(text)
        paths[name] = p
    return paths


def trace(rtk, scene, rayset):
    out = subprocess.run([rtk, "trace", scene, "--rayset", rayset, "--threads", "2",
                          "--iters", "3", "--json"], capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--clusters", type=int, default=64)
    ap.add_argument("--rtk", default="target/release/rtk")
    ap.add_argument("--rounds", type=int, default=3)
    a = ap.parse_args()
    verts, faces = read_ply(BUNNY)
    cl = clusters(a.clusters)
    tris = sum(len(m) for m in cl) * len(faces)
    with tempfile.TemporaryDirectory() as d:
        paths = write_scenes(d, cl, verts, faces)
        print(f"{a.clusters} clusters, {tris} triangles, sizes 0.2 to 20 in a 1000-wide park\n")
        print("| structure | primary Mrays/s | incoherent Mrays/s | build ms | memory MB | hits (primary) |")
        print("|---|---:|---:|---:|---:|---:|")
        for name, p in paths.items():
            runs = {s: [trace(a.rtk, p, s) for _ in range(a.rounds)] for s in ("primary", "incoherent")}
            med = lambda s, k: statistics.median(r[k] for r in runs[s])
            print(f"| {name} | {med('primary', 'mrays_per_s'):.2f} | {med('incoherent', 'mrays_per_s'):.2f} "
                  f"| {med('primary', 'build_seconds') * 1e3:.1f} | {med('primary', 'memory_bytes') / 1e6:.1f} "
                  f"| {runs['primary'][0]['hits']} |")


if __name__ == "__main__":
    main()
