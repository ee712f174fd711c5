#!/usr/bin/env python3
"""rtk's hits against Embree's, ray by ray, with every disagreement explained.

What: for each mesh and each ray set of ../shared/anchors/embree/RAYS.md
(primary and incoherent nearest hits, incoherent occlusion), run Embree's
harness (`embree_bench --dump`) and `rtk trace --out`, read both per-ray
answers and compare them. A ray matches when both miss, both hit the same
primitive (t may differ in the last bits: the largest relative difference is
reported), or, for occlusion, both agree. Each mismatching ray is then
re-intersected in f64 (Python floats; Moller-Trumbore without rejection, so
the barycentrics say how far inside or outside a triangle the ray passes)
and classified:

  tie     tie on a shared edge/vertex: both triangles hit in f64 at t equal
          within --t-eps (relative), they share a vertex (same index or the
          same position: the teapot's patches duplicate their seam vertices),
          and on either triangle the hit point lies within --bary-eps
          (barycentric) of the shared edge or vertex;
  graze   graze/silhouette: one program hits, the other misses, and in f64
          the hit triangle is hit with a barycentric within --bary-eps of an
          edge (shared or not: a ray grazing the mesh's outline). For
          occlusion, where neither program names a triangle, every triangle
          is tested in f64 (brute force): the ray must hit nothing clearly
          (all f64 hits within --bary-eps of an edge) and graze something;
  diff    different surfaces at nearly equal t: both hit different triangles
          sharing no vertex, both hit in f64, t equal within --t-eps;
  unexpl  anything else; printed in full, and the exit status is 1.

Why: hit counts and checksums agreeing within tolerance can hide
compensating errors; this accounts for every single ray.

How to run (from /work/main; the anchor is built by its build.sh):
    python3 host/benches/compare_embree.py \\
        --embree /tmp/anchors/embree/embree_bench \\
        --meshes ../shared/data/meshes/{bunny,teapot,dragon-200k}.ply
Options: --rtk (default target/release/rtk), --aggregate (rtk's, default
bvh), --threads (2), --bary-eps (1e-5), --t-eps (1e-6), --show N (print the
first N rays of every category, not only the unexplained ones), --keep DIR
(keep the ray and hit files there instead of a temporary folder).

Expected runtime: about 10 s per small mesh and under a minute for the
dragon (202,520 triangles) on 2 cores: the comparison of 3 x 2^20 rays in
pure Python dominates; only mismatches get f64 geometry, and an occlusion
mismatch costs one brute-force pass over the triangles (~0.3 s on the
dragon). Standard library only.
"""

import argparse
import json
import math
import os
import struct
import subprocess
import sys
import tempfile
import time
from array import array

# (name in the table, rtk --rayset, rtk extra flags, Embree dump/JSON set name)
SETS = [
    ("primary", "primary", [], "primary_intersect1"),
    ("incoherent", "incoherent", [], "incoherent_intersect1"),
    ("occluded", "incoherent", ["--occluded"], "incoherent_occluded1"),
]
CATEGORIES = ["tie", "graze", "diff", "unexpl"]
MISS = -1


# ---------------------------------------------------------------- input files

def read_ply(path):
    """Vertices as (x, y, z) float tuples (f32 values, exact in f64) and
    triangles as (i, j, k) index tuples, from a binary little-endian PLY."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").split("\n")
    if "format binary_little_endian 1.0" not in header:
        sys.exit(f"{path}: not a binary little-endian PLY")
    nv = nf = None
    for line in header:
        w = line.split()
        if w[:2] == ["element", "vertex"]:
            nv = int(w[2])
        elif w[:2] == ["element", "face"]:
            nf = int(w[2])
    vf = array("f", data[end:end + 12 * nv])
    verts = [(vf[3 * i], vf[3 * i + 1], vf[3 * i + 2]) for i in range(nv)]
    tris = []
    for n, a, b, c in struct.iter_unpack("<B3i", data[end + 12 * nv:end + 12 * nv + 13 * nf]):
        if n != 3:
            sys.exit(f"{path}: face with {n} vertices (only triangles supported)")
        tris.append((a, b, c))
    return verts, tris


def native(arr, path, size, stride):
    """Checks a binary file's length; arrays are native-endian, files LE."""
    if sys.byteorder != "little":
        arr.byteswap()
    if len(arr) * arr.itemsize != size * stride:
        sys.exit(f"{path}: {len(arr) * arr.itemsize} bytes, expected {size * stride}")
    return arr


def read_embree(path, nrays):
    """Embree dump: i32 prim (-1 miss), f32 t (+inf miss) per ray."""
    with open(path, "rb") as f:
        data = f.read()
    prims = native(array("i", data), path, nrays, 8)[0::2]
    ts = native(array("f", data), path, nrays, 8)[1::2]
    return prims, ts


def read_rtk_hits(path, nrays):
    """rtk hit file: f32 t, u32 prim (0xFFFFFFFF miss), f32 u, f32 v."""
    with open(path, "rb") as f:
        data = f.read()
    fl = native(array("f", data), path, nrays, 16)
    prims = native(array("i", data), path, nrays, 16)[1::4]  # 0xFFFFFFFF reads as -1
    return prims, fl[0::4], fl[2::4], fl[3::4]


def read_rays(path, nrays):
    """rtk ray file: f32 ox oy oz dx dy dz t_min t_max; checks the interval
    is (0, +inf) for every ray, as in RAYS.md."""
    with open(path, "rb") as f:
        rays = native(array("f", f.read()), path, nrays, 32)
    if set(rays[6::8]) != {0.0} or set(rays[7::8]) != {math.inf}:
        sys.exit(f"{path}: rays with an interval other than (0, +inf)")
    return rays


# ---------------------------------------------------------------- running

def run_embree(exe, mesh, threads, prefix):
    cmd = [exe, mesh, "--threads", str(threads), "--no-packets", "--iters", "1",
           "--builds", "1", "--dump", prefix]
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    return json.loads(next(l for l in out.splitlines() if l.startswith("JSON "))[5:])


def run_rtk(exe, mesh, rayset, extra, aggregate, threads, hits, rays):
    cmd = [exe, "trace", mesh, "--rayset", rayset, "--aggregate", aggregate,
           "--threads", str(threads), "--out", hits, "--save-rays", rays, "--json"] + extra
    return json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)


# ---------------------------------------------------------------- f64 geometry

def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def intersect(o, d, tri):
    """Moller-Trumbore in f64 without rejection: (t, (b0, b1, b2)) of the
    ray's crossing with the triangle's plane, b1/b2 the weights of vertices
    1/2; None when the ray is parallel to the plane."""
    v0, v1, v2 = tri
    e1, e2 = sub(v1, v0), sub(v2, v0)
    p = cross(d, e2)
    det = dot(e1, p)
    if det == 0.0:
        return None
    s = sub(o, v0)
    q = cross(s, e1)
    b1, b2 = dot(s, p) / det, dot(d, q) / det
    return dot(e2, q) / det, (1.0 - b1 - b2, b1, b2)


def hit_in_f64(isect, eps):
    """Hit with tolerance: in front of the origin, no barycentric below -eps."""
    return isect is not None and isect[0] > 0.0 and min(isect[1]) >= -eps


def grazes(isect, eps):
    """Hit within eps of an edge: the smallest barycentric is within eps of 0."""
    return isect is not None and isect[0] > 0.0 and abs(min(isect[1])) <= eps


def close_t(a, b, eps):
    return abs(a - b) <= eps * max(abs(a), abs(b))


def shared_corners(mesh, pa, pb):
    """Local corners (0..2) of triangle pa that are also corners of pb, by
    index or by position."""
    verts, tris = mesh
    ib = set(tris[pb])
    pos_b = {verts[i] for i in ib}
    return [k for k, i in enumerate(tris[pa]) if i in ib or verts[i] in pos_b]


def near_shared(bary, corners, eps):
    """The point lies within eps of the edge/vertex spanned by `corners`:
    every other corner's barycentric is within eps of 0."""
    return all(abs(bary[k]) <= eps for k in range(3) if k not in corners)


def triangle(mesh, prim):
    verts, tris = mesh
    return tuple(verts[i] for i in tris[prim])


# ---------------------------------------------------------------- classification

def classify_nearest(mesh, o, d, pr, pe, eps):
    """Category and f64 details of a nearest-hit mismatch (rtk prim pr,
    Embree prim pe, -1 for a miss)."""
    info = {}
    for who, p in (("rtk", pr), ("embree", pe)):
        if p != MISS:
            info[who] = (p, intersect(o, d, triangle(mesh, p)))
    if pr == MISS or pe == MISS:  # one hits, the other misses
        _, isect = info["rtk" if pr != MISS else "embree"]
        return ("graze" if grazes(isect, eps.bary) else "unexpl"), info
    ir, ie = info["rtk"][1], info["embree"][1]
    if not (hit_in_f64(ir, eps.bary) and hit_in_f64(ie, eps.bary)) or not close_t(ir[0], ie[0], eps.t):
        return "unexpl", info
    ca, cb = shared_corners(mesh, pr, pe), shared_corners(mesh, pe, pr)
    info["shared"] = len(ca)
    if not ca:
        return "diff", info
    if near_shared(ir[1], ca, eps.bary) or near_shared(ie[1], cb, eps.bary):
        return "tie", info
    return "unexpl", info


def brute_force(mesh, o, d, eps):
    """Every triangle the ray hits in f64 within tolerance: [(prim, t, bary)]."""
    verts, tris = mesh
    found = []
    for p, tri in enumerate(tris):
        isect = intersect(o, d, (verts[tri[0]], verts[tri[1]], verts[tri[2]]))
        if hit_in_f64(isect, eps):
            found.append((p, isect[0], isect[1]))
    return found


def classify_occluded(mesh, o, d, eps):
    """An occlusion mismatch is a graze when the ray hits no triangle clearly
    in f64 (all hits within eps of an edge) and grazes at least one."""
    found = brute_force(mesh, o, d, eps.bary)
    info = {"f64 hits": found}
    if found and all(min(b) <= eps.bary for _, _, b in found):
        return "graze", info
    return "unexpl", info


# ---------------------------------------------------------------- comparison

def compare(rtk_prims, rtk_ts, emb_prims, emb_ts):
    """Indices of mismatching rays, and the largest relative t difference
    among rays where both hit the same primitive."""
    bad = [i for i, (a, b) in enumerate(zip(rtk_prims, emb_prims)) if a != b]
    worst, worst_i = 0.0, None
    for i, (a, b, ta, tb) in enumerate(zip(rtk_prims, emb_prims, rtk_ts, emb_ts)):
        if a == b and a != MISS and ta != tb:
            rel = abs(ta - tb) / max(abs(ta), abs(tb))
            if rel > worst:
                worst, worst_i = rel, i
    return bad, worst, worst_i


def worst_t_note(mesh, rays, i, prim, t_rtk, t_emb):
    """Where the largest t difference comes from: each program's relative
    error against the f64 t, and how obliquely the ray meets the triangle."""
    o, d = ray_at(rays, i)
    tri = triangle(mesh, prim)
    t, _ = intersect(o, d, tri)
    n = cross(sub(tri[1], tri[0]), sub(tri[2], tri[0]))
    cos = abs(dot(d, n)) / math.sqrt(dot(n, n) * dot(d, d))
    return (f"ray {i} prim {prim}: f64 t {t:.9g}, rtk error {(t_rtk - t) / t:+.2e}, "
            f"Embree error {(t_emb - t) / t:+.2e}, |cos(ray, normal)| {cos:.2e}")


def ray_at(rays, i):
    return tuple(rays[8 * i:8 * i + 3]), tuple(rays[8 * i + 3:8 * i + 6])


def describe(i, o, d, rtk_ans, emb_ans, cat, info):
    lines = [f"  ray {i} [{cat}] org ({o[0]!r}, {o[1]!r}, {o[2]!r}) dir ({d[0]!r}, {d[1]!r}, {d[2]!r})",
             f"    rtk: {rtk_ans}   embree: {emb_ans}"]
    for key, val in info.items():
        if key in ("rtk", "embree"):
            p, isect = val
            if isect is None:
                lines.append(f"    f64 {key} prim {p}: ray parallel to its plane")
            else:
                t, b = isect
                lines.append(f"    f64 {key} prim {p}: t {t!r} bary ({b[0]:.3e}, {b[1]:.3e}, {b[2]:.3e})")
        elif key == "f64 hits":
            lines.append(f"    f64 brute force: {len(val)} triangle(s) hit within tolerance")
            for p, t, b in val[:8]:
                lines.append(f"      prim {p}: t {t!r} bary ({b[0]:.3e}, {b[1]:.3e}, {b[2]:.3e})")
        else:
            lines.append(f"    {key}: {val}")
    return "\n".join(lines)


def answer(prim, t, occluded):
    if occluded:
        return "occluded" if prim != MISS else "free"
    return f"prim {prim} t {t!r}" if prim != MISS else "miss"


def compare_set(mesh, name, rtk_out, emb_out, rays, eps, show):
    """One table row for a set; prints the unexplained (and --show) rays."""
    occluded = name == "occluded"
    (rp, rt, ru, rv), (ep, et) = rtk_out, emb_out
    bad, worst, wi = compare(rp, rt, ep, et)
    note = None if occluded or wi is None else worst_t_note(mesh, rays, wi, rp[wi], rt[wi], et[wi])
    counts = dict.fromkeys(CATEGORIES, 0)
    for i in bad:
        o, d = ray_at(rays, i)
        if occluded:
            cat, info = classify_occluded(mesh, o, d, eps)
        else:
            cat, info = classify_nearest(mesh, o, d, rp[i], ep[i], eps)
            if rp[i] != MISS:
                info["rtk f32 (u, v)"] = (ru[i], rv[i])
        counts[cat] += 1
        if cat == "unexpl" or counts[cat] <= show:
            print(describe(i, o, d, answer(rp[i], rt[i], occluded), answer(ep[i], et[i], occluded),
                           cat, info), flush=True)
    hits = (sum(1 for p in rp if p != MISS), sum(1 for p in ep if p != MISS))
    return {"set": name, "rays": len(rp), "hits": hits, "mismatches": len(bad),
            "counts": counts, "worst_t": None if occluded else worst, "worst_note": note}


def run_mesh(a, path, workdir, eps):
    name = os.path.basename(path).removesuffix(".ply")
    mesh = read_ply(path)
    prefix = os.path.join(workdir, name)
    emb = run_embree(a.embree, path, a.threads, prefix + ".embree")
    rows = []
    for set_name, rayset, extra, key in SETS:
        hits, rays_path = f"{prefix}.{set_name}.hits", f"{prefix}.{rayset}.rays"
        r = run_rtk(a.rtk, path, rayset, extra, a.aggregate, a.threads, hits, rays_path)
        if r["rays_hash"] != emb["rays_hash"][rayset]:
            sys.exit(f"{name} {set_name}: rays hash {r['rays_hash']} (rtk) != "
                     f"{emb['rays_hash'][rayset]} (Embree): not the same rays")
        n = r["rays"]
        print(f"{name} {set_name}: comparing {n} rays (hash {r['rays_hash']})", flush=True)
        row = compare_set(mesh, set_name, read_rtk_hits(hits, n),
                          read_embree(f"{prefix}.embree.{key}.bin", n), read_rays(rays_path, n), eps, a.show)
        if row["hits"] != (r["hits"], emb["sets"][key]["hits"]):
            sys.exit(f"{name} {set_name}: hit files disagree with the reported hit counts")
        rows.append(dict(row, mesh=name))
    return rows


def table(rows):
    out = ["| mesh | set | rays | hits rtk | hits Embree | mismatches | tie (shared edge/vertex) "
           "| graze/silhouette | different surfaces, equal t | unexplained | max rel. t diff (matching hits) |",
           "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        c = r["counts"]
        w = "-" if r["worst_t"] is None else f"{r['worst_t']:.2e}"
        out.append(f"| {r['mesh']} | {r['set']} | {r['rays']:,} | {r['hits'][0]:,} | {r['hits'][1]:,} "
                   f"| {r['mismatches']} | {c['tie']} | {c['graze']} | {c['diff']} | {c['unexpl']} | {w} |")
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--embree", required=True, help="embree_bench binary")
    ap.add_argument("--rtk", default="target/release/rtk")
    ap.add_argument("--meshes", nargs="+", required=True)
    ap.add_argument("--aggregate", default="bvh")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--bary-eps", type=float, default=1e-5)
    ap.add_argument("--t-eps", type=float, default=1e-6)
    ap.add_argument("--show", type=int, default=0, help="print the first N rays of every category")
    ap.add_argument("--keep", help="folder for the ray and hit files (default: a temporary one)")
    a = ap.parse_args()
    eps = argparse.Namespace(bary=a.bary_eps, t=a.t_eps)
    t0 = time.monotonic()
    rows = []
    for path in a.meshes:
        if a.keep:
            os.makedirs(a.keep, exist_ok=True)
            rows += run_mesh(a, path, a.keep, eps)
        else:
            with tempfile.TemporaryDirectory() as tmp:
                rows += run_mesh(a, path, tmp, eps)
    print()
    print(table(rows))
    print("\nLargest t difference among matching hits, against f64:")
    for r in rows:
        if r["worst_note"]:
            print(f"- {r['mesh']} {r['set']}: {r['worst_note']}")
    print(f"\n{time.monotonic() - t0:.1f} s")
    return 1 if any(r["counts"]["unexpl"] for r in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
