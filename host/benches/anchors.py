#!/usr/bin/env python3
"""rtk's aggregates against Embree and tinybvh, side by side, on the exact
ray sets of ../shared/anchors/embree/RAYS.md.

Each round runs, back to back: embree_bench, tinybvh_bench (BVH8_CPU) and
`rtk trace` for each aggregate and ray set; the table reports the median over
rounds of Mrays/s and of build time, and each figure's ratio to Embree's from
the same rounds. Hit counts of every run are checked against Embree's.

Build the anchors first (they are not part of the project):
    sh ../shared/anchors/embree/build.sh     # needs libembree-dev (apt)
    sh ../shared/anchors/tinybvh/build.sh
then
    cargo build --release --workspace
    python3 host/benches/anchors.py --embree PATH/embree_bench --tinybvh PATH/tinybvh_bench \\
        --meshes ../shared/data/meshes/{bunny,teapot,dragon-200k}.ply --rounds 3

--aggregates takes any of bvh, kdtree, octree, grid, slabs, raycls (default:
the first four), each with parameters of its own after `+`, set on the
generated scene's root: `bvh+simd=avx2,bvh+simd=avx512` times the bvh's two
AVX walks side by side. raycls builds its cells while it traces: its build time
(its `prepare`) leaves them out, and they are built in the first of the
three passes `rtk trace --iters 3` times (the median pass is reported).
"""

import argparse
import json
import statistics
import subprocess
import sys

SETS = [
    ("primary", "primary_intersect1", []),
    ("incoherent", "incoherent_intersect1", []),
    ("occluded", "incoherent_occluded1", ["--occluded"]),
]


def anchor(cmd):
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    line = next(l for l in out.splitlines() if l.startswith("JSON "))
    return json.loads(line[5:])


def rtk(exe, mesh, agg, rayset, extra, threads):
    cls, *params = agg.split("+")
    # `+stream` is not a parameter: it traces through the stream entries.
    sets = [x for p in params if p != "stream" for x in ("--set", f"objects.world.{p}")]
    sets += ["--stream"] if "stream" in params else []
    cmd = [exe, "trace", mesh, "--rayset", rayset, "--aggregate", cls,
           "--threads", str(threads), "--iters", "3", "--json"] + sets + extra
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    return json.loads(out)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--embree", required=True)
    ap.add_argument("--tinybvh")
    ap.add_argument("--rtk", default="target/release/rtk")
    ap.add_argument("--meshes", nargs="+", required=True)
    ap.add_argument("--aggregates", default="bvh,kdtree,octree,grid")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    aggs = a.aggregates.split(",")
    rows = []
    for mesh in a.meshes:
        name = mesh.rsplit("/", 1)[-1].removesuffix(".ply")
        fig = {}  # (who, set) -> [mrays], (who, "build") -> [ms]
        hits = {}
        for _ in range(a.rounds):
            e = anchor([a.embree, mesh, "--threads", str(a.threads), "--no-packets"])
            fig.setdefault(("embree", "build"), []).append(e["build_ms"])
            for s, key, _ in SETS:
                fig.setdefault(("embree", s), []).append(e["sets"][key]["mrays_s"])
                hits[s] = e["sets"][key]["hits"]
            if a.tinybvh:
                t = anchor([a.tinybvh, mesh, "--threads", str(a.threads), "--layouts", "bvh8"])
                lay = t["layouts"]["bvh8"]
                fig.setdefault(("tinybvh bvh8", "build"), []).append(lay["build_ms"])
                for s, key, _ in SETS:
                    fig.setdefault(("tinybvh bvh8", s), []).append(lay["sets"][key]["mrays_s"])
            for agg in aggs:
                for s, _, extra in SETS:
                    rayset = "primary" if s == "primary" else "incoherent"
                    r = rtk(a.rtk, mesh, agg, rayset, extra, a.threads)
                    if r["hits"] != hits[s]:
                        print(f"warning: {name} {agg} {s}: {r['hits']} hits, Embree {hits[s]}",
                              file=sys.stderr)
                    fig.setdefault((f"rtk {agg}", s), []).append(r["mrays_per_s"])
                    if s == "primary":
                        fig.setdefault((f"rtk {agg}", "build"), []).append(r["build_seconds"] * 1e3)
        who_all = ["embree"] + (["tinybvh bvh8"] if a.tinybvh else []) + [f"rtk {x}" for x in aggs]
        for who in who_all:
            med = {k: statistics.median(fig[(who, k)]) for k in ["build"] + [s for s, _, _ in SETS]}
            emb = {k: statistics.median(fig[("embree", k)]) for k in med}
            cells = []
            for s, _, _ in SETS:
                cells.append(f"{med[s]:.2f} ({med[s] / emb[s]:.2f})")
            cells.append(f"{med['build']:.1f} ({med['build'] / emb['build']:.2f})")
            rows.append(f"| {name} | {who} | " + " | ".join(cells) + " |")
    print("| mesh | tracer | primary Mrays/s (x Embree) | incoherent | occluded | build ms (x Embree) |")
    print("|---|---|---:|---:|---:|---:|")
    print("\n".join(rows))


if __name__ == "__main__":
    main()
