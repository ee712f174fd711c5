#!/usr/bin/env python3
"""The paper's space/time trade-off for ray classification (issue 12):
`raycls` over individual primitives against `raycls` over coarser
aggregates, with `bvh` and `slabs` alongside, on one mesh's Embree ray sets.

Arvo and Kirk fed ray classification coarser aggregates when its memory
grew: fewer, larger candidates make shorter candidate lists and fewer
cells, and each candidate costs a small traversal instead of one test. To
build "coarser aggregates" from one mesh, the script cuts it into clusters
of N triangles (consecutive in Morton order of their centroids, so each is
compact), writes each as an OBJ in a temporary folder (the dragon's licence
forbids copying it into the project; the clusters never leave /tmp), and
makes a scene whose root `raycls` has the clusters as children, each a
`mesh` under its own `bvh` object (an opaque child: a flattening parent
takes a mesh's triangles whatever its `accel` says). N = 0 is the
flat case: the whole mesh, its triangles flattened into raycls's own table.

Every configuration traces the same rays: every k-th ray of the Embree
anchor's set (`--limit` of them) (`rtk trace --rayset ... --save-rays`, over the mesh's box),
with `--iters 3`; the median pass is reported, and for raycls also the
first (the one that builds its cells). A configuration slower than
`--timeout` seconds is reported as such (raycls on scattered rays over
200k triangles, once its memory budget is spent, tests long lists). Memory is raycls's
own count (`stats = true`: peak bytes of cells, lists and tables) or the
process's growth during the build for the others (`rtk trace`).

    cargo build --release --workspace
    python3 host/benches/raycls_tradeoff.py --mesh ../shared/data/meshes/dragon-200k.ply \\
        --clusters 0,64,1024 --sets primary,incoherent
"""

import argparse
import json
import os
import re
import struct
import subprocess
import sys
import tempfile


def read_ply(path):
    """Vertices and triangles of a binary little-endian PLY (x y z floats,
    uchar-int face lists), as the shared meshes are written."""
    with open(path, "rb") as f:
        header = b""
        while not header.endswith(b"end_header\n"):
            header += f.readline()
        text = header.decode()
        nv = int(re.search(r"element vertex (\d+)", text).group(1))
        nf = int(re.search(r"element face (\d+)", text).group(1))
        if "binary_little_endian" not in text or "property list uchar int" not in text:
            sys.exit(f"{path}: only binary little-endian PLY with uchar/int faces")
        nprops = len(re.findall(r"property float", text.split("element face")[0]))
        vdata = f.read(4 * nprops * nv)
        verts = [struct.unpack_from("<3f", vdata, 4 * nprops * i) for i in range(nv)]
        faces = []
        for _ in range(nf):
            (n,) = struct.unpack("<B", f.read(1))
            idx = struct.unpack(f"<{n}i", f.read(4 * n))
            for k in range(1, n - 1):
                faces.append((idx[0], idx[k], idx[k + 1]))
    return verts, faces


def morton_key(c, lo, ext):
    """30-bit Morton code of a point in the box."""
    key = 0
    q = [min(1023, max(0, int((c[a] - lo[a]) / ext[a] * 1024))) if ext[a] > 0 else 0
         for a in range(3)]
    for bit in range(10):
        for a in range(3):
            key |= ((q[a] >> bit) & 1) << (3 * bit + a)
    return key


def write_clusters(verts, faces, n, folder):
    lo = [min(v[a] for v in verts) for a in range(3)]
    hi = [max(v[a] for v in verts) for a in range(3)]
    ext = [hi[a] - lo[a] for a in range(3)]

    def centroid(f):
        return [sum(verts[i][a] for i in f) / 3 for a in range(3)]

    order = sorted(range(len(faces)), key=lambda i: morton_key(centroid(faces[i]), lo, ext))
    names = []
    for c, start in enumerate(range(0, len(order), n)):
        chunk = [faces[i] for i in order[start:start + n]]
        used = sorted({i for f in chunk for i in f})
        remap = {old: k + 1 for k, old in enumerate(used)}
        path = os.path.join(folder, f"c{c}.obj")
        with open(path, "w") as out:
            out.writelines("v %r %r %r\n" % verts[i] for i in used)
            out.writelines("f %d %d %d\n" % tuple(remap[i] for i in f) for f in chunk)
        names.append(path)
    return names


def scene(folder, mesh, clusters, root, extra):
    head = '[render]\nroot = "world"\nintegrator = "normals"\n[cameras.none]\nclass = "pinhole"\n'
    if not clusters:
        objs = f'[objects.m]\nclass = "mesh"\nfile = {json.dumps(os.path.abspath(mesh))}\naccel = "none"\n'
        kids = ['"m"']
    else:
        # Each cluster's mesh under an explicit `bvh` object: an opaque
        # child (a flattening parent would take a mesh's triangles whatever
        # its `accel` says).
        objs = "".join(
            f'[objects.c{i}]\nclass = "mesh"\nfile = {json.dumps(p)}\naccel = "none"\n'
            f'[objects.b{i}]\nclass = "bvh"\nchildren = ["c{i}"]\n'
            for i, p in enumerate(clusters))
        kids = [f'"b{i}"' for i in range(len(clusters))]
    text = head + objs + f'[objects.world]\nclass = "{root}"\n{extra}children = [{", ".join(kids)}]\n'
    path = os.path.join(folder, f"{root}-{len(clusters)}.toml")
    with open(path, "w") as f:
        f.write(text)
    return path


def trace(rtk, path, rays, threads, timeout):
    try:
        r = subprocess.run([rtk, "trace", path, "--rays", rays, "--threads", str(threads),
                            "--iters", "3", "--json"], capture_output=True, text=True,
                           timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, None
    if r.returncode != 0:
        sys.exit(f"rtk trace {path} failed:\n{r.stderr}")
    out = json.loads(r.stdout)
    peak = re.search(r"peak_bytes=(\d+)", r.stderr)
    return out, (int(peak.group(1)) if peak else None)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rtk", default="target/release/rtk")
    ap.add_argument("--mesh", required=True)
    ap.add_argument("--clusters", default="0,64,1024",
                    help="triangles per cluster; 0: the mesh flattened")
    ap.add_argument("--sets", default="primary,incoherent")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--limit", type=int, default=1 << 18, help="rays per set (every k-th of the set)")
    ap.add_argument("--timeout", type=float, default=300)
    a = ap.parse_args()
    verts, faces = read_ply(a.mesh)
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        ray_files = {}
        flat = scene(folder, a.mesh, [], "bvh", "")
        for rayset in a.sets.split(","):
            full = os.path.join(folder, f"{rayset}-all.bin")
            subprocess.run([a.rtk, "trace", flat, "--rayset", rayset, "--save-rays", full],
                           capture_output=True, check=True)
            with open(full, "rb") as f:
                data = f.read()
            # Every k-th ray: the whole image (the primary set is in scanline
            # order), at `--limit` rays.
            k = max(1, len(data) // 32 // a.limit)
            data = b"".join(data[32 * i:32 * i + 32] for i in range(0, len(data) // 32, k))
            ray_files[rayset] = os.path.join(folder, f"{rayset}.bin")
            with open(ray_files[rayset], "wb") as f:
                f.write(data)
        configs = [("bvh", 0, ""), ("slabs", 0, "")]
        for n in [int(x) for x in a.clusters.split(",")]:
            configs.append(("raycls", n, "stats = true\n"))
        for root, n, extra in configs:
            clusters = write_clusters(verts, faces, n, folder) if n else []
            path = scene(folder, a.mesh, clusters, root, extra)
            for rayset in a.sets.split(","):
                out, peak = trace(a.rtk, path, ray_files[rayset], a.threads, a.timeout)
                rows.append((root, n, rayset, out, peak))
                if out is None:
                    print(json.dumps({"root": root, "cluster": n, "set": rayset,
                                      "timeout": a.timeout}), flush=True)
                    continue
                print(json.dumps({"root": root, "cluster": n, "set": rayset,
                                  "mrays": out["mrays_per_s"],
                                  "passes": out["pass_seconds"], "peak": peak,
                                  "memory": out.get("memory_bytes"), "hits": out.get("hits"),
                                  "build_ms": 1e3 * out.get("build_seconds", 0)}), flush=True)
    print("\n| root | candidates | set | Mrays/s (median pass) | first pass | build ms | memory MB | hits |")
    print("|---|---|---|---:|---:|---:|---:|---:|")
    for root, n, rayset, out, peak in rows:
        cand = "triangles" if n == 0 else f"bvhs of {n}"
        if out is None:
            print(f"| {root} | {cand} | {rayset} | over {a.timeout:.0f} s | | | | |")
            continue
        first = f"{out['rays'] / out['pass_seconds'][0] / 1e6:.2f}"
        mem = (peak if peak is not None else out.get("memory_bytes", 0)) / 1e6
        print(f"| {root} | {cand} | {rayset} | {out['mrays_per_s']:.2f} | {first} | "
              f"{1e3 * out.get('build_seconds', 0):.1f} | {mem:.1f} | {out.get('hits')} |")


if __name__ == "__main__":
    main()
