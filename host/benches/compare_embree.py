#!/usr/bin/env python3
"""rtk's hits against Embree's, ray by ray, with every disagreement explained.

What: for each mesh and each ray set of ../shared/anchors/embree/RAYS.md
(primary and incoherent nearest hits, incoherent occlusion), run Embree's
harness (`embree_bench --dump`) and `rtk trace --out --save-rays`, check that
both traced the same rays (rtk's JSON rays_hash against Embree's), read both
per-ray answers and compare them. A ray matches when both miss, both hit the
same primitive (t may differ in the last bits: the largest relative
difference is reported, with both programs' errors against f64), or, for
occlusion, both agree.

Each mismatching ray is re-intersected in f64 (Python floats; Moller-Trumbore
without rejection, so the barycentrics say how far inside or outside a
triangle the ray passes) and classified:

  dup           two triangles with the same three vertex positions (the
                dragon has 1,405 such groups), hit in f64 at equal t;
  tie           both triangles hit in f64 at equal t, they share a vertex
                (same index, or same position: the teapot's patches duplicate
                their seam vertices), and on either triangle the crossing
                lies near the shared edge or vertex;
  graze         one program hits, the other misses, and in f64 the hit
                triangle is hit near one of its edges (shared or not: a ray
                grazing the mesh's outline). For occlusion, where neither
                program names a triangle, every triangle is tested in f64
                (brute force): some triangle must be hit within tolerance,
                and all of those near an edge;
  graze_behind  both hit, at clearly different t: the nearer triangle is hit
                near an edge in f64 and the farther one within tolerance (one
                program slipped past a silhouette edge onto a surface behind);
  diff          different triangles sharing no vertex, both hit in f64 at
                equal t (surfaces crossing or touching);
  fold          the same between triangles that share a vertex, with the
                crossing away from it (a folded or self-intersecting mesh);
  unexpl        anything else: printed in full; the exit status is then 1.

"Near an edge" means within --bary-eps (barycentric, default 1e-5) or,
scale-aware, within --ulps (default 2) f32 ulps of the largest coordinate
involved divided by |cos(ray, normal)|, in world units; "equal t" means within
--t-eps (relative, default 1e-6) or that same world distance. The
scale-aware test matters on the dragon (coordinates ~100 for edges ~0.4: one
f32 ulp of a coordinate is ~2e-5 barycentric); each ray it is needed for is
printed and counted ("of which via --ulps"). The "f64 sides with" column says
whose answer the f64 test supports (a hit triangle beats a miss or a triangle
missed in f64; of two hit triangles the nearer wins, "undecided" on equal t,
on duplicates, or when both triangles are missed in f64; for occlusion, whether any triangle
is hit), whatever the category: on a tie it names the triangle that
contains the crossing.

Why: hit counts and checksums agreeing within tolerance can hide
compensating errors; this accounts for every single ray.

How to run (from /work/main; the anchor is built by its build.sh):
    python3 host/benches/compare_embree.py \\
        --embree /tmp/anchors/embree/embree_bench \\
        --meshes ../shared/data/meshes/{bunny,teapot,dragon-200k}.ply
Other options: --rtk (default target/release/rtk), --aggregate (rtk's,
default bvh), --threads (2), --show N (also print the first N rays of every
category), --keep DIR (keep the ray and hit files there instead of a
temporary folder).

Expected runtime: ~4 s per small mesh and ~15 s for the dragon (202,520
triangles) on 2 cores, the Python comparison of 3 x 2^20 rays dominating;
only mismatches get f64 geometry, and an occlusion mismatch costs one
brute-force pass over the triangles (~0.4 s on the dragon). Standard library
only; needs ~200 MB of memory and ~200 MB of temporary files per mesh.
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
from collections import namedtuple

# (name in the table, rtk --rayset, rtk extra flags, Embree dump/JSON set name)
SETS = [
    ("primary", "primary", [], "primary_intersect1"),
    ("incoherent", "incoherent", [], "incoherent_intersect1"),
    ("occluded", "incoherent", ["--occluded"], "incoherent_occluded1"),
]
LABELS = {  # category -> column title
    "dup": "duplicate triangles",
    "tie": "tie on shared edge/vertex",
    "graze": "graze/silhouette (other misses)",
    "graze_behind": "graze (other hits behind)",
    "diff": "different surfaces, equal t",
    "fold": "adjacent overlapping triangles, equal t",
    "unexpl": "unexplained",
}
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


Hit = namedtuple("Hit", "t bary dist scale")
Hit.__doc__ = """The ray's crossing with a triangle's plane, in f64: t, the
barycentrics (b0, b1, b2), the signed distances (world units, positive
inside) to the edges opposite corners 0, 1, 2, and `scale`, one f32 ulp of
the coordinates involved divided by |cos(ray, normal)|: how far an f32
computation can misplace the crossing (see Tol)."""


def f64_hit(o, d, tri):
    """Hit of the ray on the triangle (with no rejection), None if parallel."""
    isect = intersect(o, d, tri)
    if isect is None:
        return None
    t, bary = isect
    n = cross(sub(tri[1], tri[0]), sub(tri[2], tri[0]))
    area2 = math.sqrt(dot(n, n))
    cos = abs(dot(d, n)) / (area2 * math.sqrt(dot(d, d)))
    point = tuple(o[k] + t * d[k] for k in range(3))
    size = max(abs(x) for v in (o, point) + tuple(tri) for x in v)
    dist = tuple(bary[k] * area2 / math.dist(tri[(k + 1) % 3], tri[(k + 2) % 3]) for k in range(3))
    return Hit(t, bary, dist, size * 2.0 ** -23 / max(cos, 1e-12))


class Tol:
    """Tolerances: `bary` (barycentric) and `t` (relative) as given; with
    `ulps` > 0 a crossing also counts as near an edge when its world distance
    to it is within ulps * hit.scale, and two t as equal when they differ by
    at most that. The second, scale-aware test is needed on meshes whose
    coordinates are large next to their triangles (the dragon: coordinates
    ~100, edges ~0.4, so one f32 ulp of a coordinate is ~2e-5 barycentric)."""

    def __init__(self, bary, t, ulps):
        self.bary, self.t, self.ulps = bary, t, ulps

    def near(self, hit, k):
        """The crossing is within tolerance of the edge opposite corner k."""
        return abs(hit.bary[k]) <= self.bary or abs(hit.dist[k]) <= self.ulps * hit.scale

    def inside(self, hit):
        """Hit within tolerance: in front, every negative barycentric near 0."""
        return hit is not None and hit.t > 0.0 and all(
            hit.bary[k] >= 0.0 or self.near(hit, k) for k in range(3))

    def grazes(self, hit):
        """Hit within tolerance, and near an edge."""
        return self.inside(hit) and any(self.near(hit, k) for k in range(3))

    def close_t(self, h1, h2):
        dt = abs(h1.t - h2.t)
        return dt <= self.t * max(abs(h1.t), abs(h2.t)) or dt <= self.ulps * max(h1.scale, h2.scale)


def strict(hit):
    """Hit in exact-ish f64 terms: in front, no negative barycentric."""
    return hit is not None and hit.t > 0.0 and min(hit.bary) >= 0.0


def shared_corners(mesh, pa, pb):
    """Local corners (0..2) of triangle pa that are also corners of pb, by
    index or by position."""
    verts, tris = mesh
    ib = set(tris[pb])
    pos_b = {verts[i] for i in ib}
    return [k for k, i in enumerate(tris[pa]) if i in ib or verts[i] in pos_b]


def near_shared(tol, hit, corners):
    """The crossing is near the edge/vertex spanned by `corners`: near every
    edge opposite a corner that is not shared."""
    return all(tol.near(hit, k) for k in range(3) if k not in corners)


def triangle(mesh, prim):
    verts, tris = mesh
    return tuple(verts[i] for i in tris[prim])


# ---------------------------------------------------------------- classification

def category_nearest(mesh, tol, pr, pe, hr, he):
    """Category of a nearest-hit mismatch: rtk prim pr / Embree prim pe
    (-1 for a miss) and their f64 hits hr / he (None for a miss)."""
    if pr == MISS or pe == MISS:  # one hits, the other misses
        return "graze" if tol.grazes(hr or he) else "unexpl"
    if hr is None or he is None:  # a triangle parallel to the ray
        return "unexpl"
    if tol.close_t(hr, he):
        if not (tol.inside(hr) and tol.inside(he)):
            return "unexpl"
        ca, cb = shared_corners(mesh, pr, pe), shared_corners(mesh, pe, pr)
        if not ca:
            return "diff"
        if len(ca) == 3:
            return "dup"
        if near_shared(tol, hr, ca) or near_shared(tol, he, cb):
            return "tie"
        return "fold"
    near, far = (hr, he) if hr.t < he.t else (he, hr)
    return "graze_behind" if tol.grazes(near) and tol.inside(far) else "unexpl"


def verdict_nearest(hr, he):
    """Whose answer the f64 test supports: a strictly hit triangle beats a
    miss or a triangle missed in f64; of two hit ones the nearer wins."""
    vr, ve = strict(hr), strict(he)
    if vr and ve:
        return "rtk" if hr.t < he.t else "embree" if he.t < hr.t else "undecided"
    if vr or ve:
        return "rtk" if vr else "embree"
    return "rtk" if hr is None else "embree" if he is None else "undecided"


def classify_nearest(mesh, o, d, pr, pe, tol, tol0):
    """(category, f64 verdict, needed the scale-aware tolerance, details)."""
    hr = f64_hit(o, d, triangle(mesh, pr)) if pr != MISS else None
    he = f64_hit(o, d, triangle(mesh, pe)) if pe != MISS else None
    info = {"rtk": (pr, hr), "embree": (pe, he)}
    if pr != MISS and pe != MISS:
        info["shared corners"] = len(shared_corners(mesh, pr, pe))
    cat = category_nearest(mesh, tol0, pr, pe, hr, he)
    scaled = cat == "unexpl" and tol.ulps > 0
    if scaled:
        cat = category_nearest(mesh, tol, pr, pe, hr, he)
    verdict = "undecided" if cat == "dup" else verdict_nearest(hr, he)
    return cat, verdict, scaled and cat != "unexpl", info


def brute_force(mesh, o, d):
    """The triangles whose plane the ray crosses in front of it within 1 %
    (barycentric) of the triangle: [(prim, Hit)]. A cheap filter first."""
    verts, tris = mesh
    found = []
    for p, (i, j, k) in enumerate(tris):
        isect = intersect(o, d, (verts[i], verts[j], verts[k]))
        if isect is not None and isect[0] > 0.0 and min(isect[1]) >= -0.01:
            found.append((p, f64_hit(o, d, triangle(mesh, p))))
    return found


def category_occluded(tol, found):
    """A graze when some triangle is hit within tolerance and none clearly."""
    hit = [h for _, h in found if tol.inside(h)]
    return "graze" if hit and all(tol.grazes(h) for h in hit) else "unexpl"


def classify_occluded(mesh, o, d, occ_rtk, tol, tol0):
    """Occlusion mismatch: neither program names a triangle, so every
    triangle is tested in f64."""
    found = brute_force(mesh, o, d)
    cat = category_occluded(tol0, found)
    scaled = cat == "unexpl" and tol.ulps > 0
    if scaled:
        cat = category_occluded(tol, found)
    occluded = any(strict(h) for _, h in found)
    verdict = "rtk" if occluded == occ_rtk else "embree"
    return cat, verdict, scaled and cat != "unexpl", {"f64 candidates": found}


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


def fmt_hit(label, prim, hit):
    if hit is None:
        return f"    f64 {label} prim {prim}: ray parallel to its plane"
    k = min(range(3), key=lambda j: abs(hit.dist[j]))
    b = hit.bary
    return (f"    f64 {label} prim {prim}: t {hit.t!r} bary ({b[0]:.3e}, {b[1]:.3e}, {b[2]:.3e}), "
            f"nearest edge at {hit.dist[k]:+.2e} (world; + inside) = {hit.dist[k] / hit.scale:+.2f} "
            f"f32 ulps/|cos|")


def describe(i, o, d, rtk_ans, emb_ans, cat, verdict, info):
    lines = [f"  ray {i} [{LABELS[cat]}; f64 sides with {verdict}]",
             f"    org ({o[0]!r}, {o[1]!r}, {o[2]!r}) dir ({d[0]!r}, {d[1]!r}, {d[2]!r})",
             f"    rtk: {rtk_ans}   Embree: {emb_ans}"]
    for key, val in info.items():
        if key in ("rtk", "embree") and val[0] != MISS:
            lines.append(fmt_hit(key, *val))
        elif key == "f64 candidates":
            lines.append(f"    f64 brute force: {len(val)} triangle(s) crossed within 1 % (barycentric)")
            lines += [fmt_hit("", p, h) for p, h in val[:8]]
        elif key not in ("rtk", "embree"):
            lines.append(f"    {key}: {val}")
    return "\n".join(lines)


def answer(prim, t, occluded):
    if occluded:
        return "occluded" if prim != MISS else "free"
    return f"prim {prim} t {t!r}" if prim != MISS else "miss"


def compare_set(mesh, name, rtk_out, emb_out, rays, tol, show):
    """One table row for a set. Prints the unexplained rays, those explained
    only by the scale-aware tolerance, and the first `show` of each category."""
    occluded = name == "occluded"
    tol0 = Tol(tol.bary, tol.t, 0)
    (rp, rt, ru, rv), (ep, et) = rtk_out, emb_out
    bad, worst, wi = compare(rp, rt, ep, et)
    note = None if occluded or wi is None else worst_t_note(mesh, rays, wi, rp[wi], rt[wi], et[wi])
    counts = dict.fromkeys(list(LABELS) + ["scaled", "rtk", "embree", "undecided"], 0)
    for i in bad:
        o, d = ray_at(rays, i)
        if occluded:
            cat, verdict, scaled, info = classify_occluded(mesh, o, d, rp[i] != MISS, tol, tol0)
        else:
            cat, verdict, scaled, info = classify_nearest(mesh, o, d, rp[i], ep[i], tol, tol0)
            if rp[i] != MISS:
                info["rtk f32 (u, v)"] = (ru[i], rv[i])
        counts[cat] += 1
        counts[verdict] += 1
        counts["scaled"] += scaled
        if cat == "unexpl" or scaled or counts[cat] <= show:
            if scaled:
                info["note"] = "explained only with the scale-aware tolerance (--ulps)"
            print(describe(i, o, d, answer(rp[i], rt[i], occluded), answer(ep[i], et[i], occluded),
                           cat, verdict, info), flush=True)
    hits = (sum(1 for p in rp if p != MISS), sum(1 for p in ep if p != MISS))
    return {"set": name, "rays": len(rp), "hits": hits, "mismatches": len(bad),
            "counts": counts, "worst_t": None if occluded else worst, "worst_note": note}


def run_mesh(a, path, workdir, tol):
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
                          read_embree(f"{prefix}.embree.{key}.bin", n), read_rays(rays_path, n), tol, a.show)
        if row["hits"] != (r["hits"], emb["sets"][key]["hits"]):
            sys.exit(f"{name} {set_name}: hit files disagree with the reported hit counts")
        rows.append(dict(row, mesh=name))
    return rows


def table(rows):
    cats = list(LABELS)
    out = ["| mesh | set | rays | hits rtk | hits Embree | mismatches | "
           + " | ".join(LABELS[c] for c in cats)
           + " | of which via --ulps | f64 sides with rtk / Embree / undecided | max rel. t diff, same prim |",
           "|---|---|" + "---:|" * (len(cats) + 7)]
    for r in rows:
        c = r["counts"]
        w = "-" if r["worst_t"] is None else f"{r['worst_t']:.2e}"
        out.append(f"| {r['mesh']} | {r['set']} | {r['rays']:,} | {r['hits'][0]:,} | {r['hits'][1]:,} "
                   f"| {r['mismatches']} | " + " | ".join(str(c[k]) for k in cats)
                   + f" | {c['scaled']} | {c['rtk']} / {c['embree']} / {c['undecided']} | {w} |")
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
    ap.add_argument("--ulps", type=float, default=2.0,
                    help="scale-aware tolerance in f32 ulps of the coordinates / |cos| (0: off)")
    ap.add_argument("--show", type=int, default=0, help="print the first N rays of every category")
    ap.add_argument("--keep", help="folder for the ray and hit files (default: a temporary one)")
    a = ap.parse_args()
    tol = Tol(a.bary_eps, a.t_eps, a.ulps)
    t0 = time.monotonic()
    rows = []
    for path in a.meshes:
        if a.keep:
            os.makedirs(a.keep, exist_ok=True)
            rows += run_mesh(a, path, a.keep, tol)
        else:
            with tempfile.TemporaryDirectory() as tmp:
                rows += run_mesh(a, path, tmp, tol)
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
