"""The Python module against its anchors, side by side in one run
(BENCHMARKS.md, "Python module (issue 24)").

    python host/python/benches/bench_python.py trace    # dragon-200k: rtk trace, rtk.Scene.trace, embreex
    python host/python/benches/bench_python.py render   # Cornell: rtk render, rtk.render, Mitsuba 3

Run from the checkout's root with ../shared beside it, in a virtual
environment holding this module (pip install ./host/python), embreex and
mitsuba==3.9.1 (llvm_ad_rgb needs libllvm19). Nothing else may run on the
machine meanwhile. Each figure is the median of --iters timed calls after
one untimed warm-up call; Python figures include the conversion into and
out of NumPy (the call's arguments are NumPy arrays, its results NumPy
arrays).
"""

import os

# NumPy's OpenBLAS threads spin after a BLAS call and would take the cores
# from whichever tracer runs next: one thread, for every tracer alike.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
RTK = ROOT / "target" / "release" / "rtk"
DRAGON = ROOT.parent / "shared" / "data" / "meshes" / "dragon-200k.ply"
MITSUBA_ANCHOR = ROOT.parent / "shared" / "anchors" / "mitsuba"


def median_seconds(f, iters):
    f()
    times = []
    for _ in range(iters):
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def resident_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def read_rays(path):
    rec = np.fromfile(path, dtype="<f4").reshape(-1, 8)
    return np.ascontiguousarray(rec[:, 0:3]), np.ascontiguousarray(rec[:, 3:6])


def cli_trace_seconds(rayset, threads, iters):
    out = subprocess.check_output(
        [str(RTK), "trace", str(DRAGON), "--rayset", rayset, "--threads", str(threads),
         "--iters", str(iters), "--json"]
    )
    return json.loads(out)["trace_seconds"]


def bench_trace(iters):
    import rtk
    from embreex import rtcore_scene as rtcs
    from embreex.mesh_construction import TriangleMesh

    scene = rtk.load_file(DRAGON)  # bvh, as rtk trace's default
    import trimesh  # embreex's usual loader; reads the same PLY

    mesh = trimesh.load(DRAGON, process=False)
    ev = np.ascontiguousarray(mesh.vertices, dtype=np.float32)
    ef = np.ascontiguousarray(mesh.faces, dtype=np.int32)
    escene = rtcs.EmbreeScene()
    TriangleMesh(escene, ev, ef)

    print(f"# dragon-200k ({len(ef)} triangles), median of {iters}; Mrays/s")
    print("set,threads,rtk_trace,rtk_py_hits,rtk_py_surface,embreex_primid,embreex_full,py_vs_cli,py_vs_embreex")
    for rayset in ["primary", "incoherent"]:
        rays = Path(f"/tmp/bench_py_{rayset}.rays")
        subprocess.check_call(
            [str(RTK), "trace", str(DRAGON), "--rayset", rayset, "--save-rays", str(rays), "--threads", "1"],
            stdout=subprocess.DEVNULL,
        )
        o, d = read_rays(rays)
        n = len(o)
        # Agreement with Embree on the hits (the same rays, two tracers).
        ours = scene.trace(o, d, surface=False)
        theirs = escene.run(o, d, output=1)
        both = ours["hit"] & (theirs["primID"] >= 0)
        agree = np.mean(ours["hit"] == (theirs["primID"] >= 0))
        same_prim = np.mean(ours["prim"][both] == theirs["primID"][both])
        e_prim = median_seconds(lambda: escene.run(o, d), iters)
        e_full = median_seconds(lambda: escene.run(o, d, output=1), iters)
        for threads in (1, 2):
            cli = cli_trace_seconds(rayset, threads, iters)
            py = median_seconds(lambda: scene.trace(o, d, surface=False, threads=threads), iters)
            pys = median_seconds(lambda: scene.trace(o, d, surface=True, threads=threads), iters)
            m = lambda s: n / s / 1e6  # noqa: E731
            print(
                f"{rayset},{threads},{m(cli):.2f},{m(py):.2f},{m(pys):.2f},{m(e_prim):.2f},{m(e_full):.2f},"
                f"{cli / py:.3f},{e_prim / py:.2f}"
            )
        rss0 = resident_bytes()
        kept = scene.trace(o, d, surface=False)
        grown = resident_bytes() - rss0
        outputs = sum(v.nbytes for v in kept.values())
        del kept
        print(f"# {rayset}: {n} rays: resident memory grew {grown / 2**20:.1f} MiB for {outputs / 2**20:.1f} MiB of outputs")
        print(f"# {rayset}: hit/miss agree with embreex on {agree:.5%}, same prim on {same_prim:.5%} of common hits")


def mitsuba_seconds(variant, spp, iters):
    """End to end in a fresh process: import, load the anchor's scene dict,
    render, to NumPy; the first (compiling) run untimed for llvm_ad_rgb."""
    code = f"""
import sys, time, json, statistics
sys.path.insert(0, {str(MITSUBA_ANCHOR)!r})
t0 = time.perf_counter()
import mitsuba as mi, drjit as dr, numpy as np
mi.set_variant({variant!r})
dr.set_thread_count(2)
import scenes
t_import = time.perf_counter() - t0
def once():
    s = mi.load_dict(scenes.mitsuba_dict("cornell", spp={spp}))
    img = np.array(mi.render(s, spp={spp}, seed=1))
    return img
once()
times = []
for _ in range({iters}):
    t = time.perf_counter(); img = once(); times.append(time.perf_counter() - t)
ref = np.load({str(MITSUBA_ANCHOR / "ref_cornell.npy")!r})
print(json.dumps({{"seconds": statistics.median(times), "import": t_import,
                  "rmse": float(np.sqrt(np.mean((img[..., :3] - ref) ** 2)))}}))
"""
    return json.loads(subprocess.check_output([sys.executable, "-c", code]).decode().strip().splitlines()[-1])


def bench_render(spp, iters):
    import rtk

    scene_path = ROOT / "scenes" / "cornell.toml"
    ref = rtk.read(MITSUBA_ANCHOR / "ref_cornell.exr")

    def cli():
        subprocess.check_call(
            [str(RTK), "render", str(scene_path), "--spp", str(spp), "--threads", "2", "-q", "-o", "/tmp/bench_py.exr"]
        )

    def py_render_only(scene=rtk.load_file(scene_path)):
        return scene.render(spp=spp, threads=2)

    def py_end_to_end():
        return rtk.load_file(scene_path).render(spp=spp, threads=2)

    t_cli = median_seconds(cli, iters)
    t_py = median_seconds(py_render_only, iters)
    t_e2e = median_seconds(py_end_to_end, iters)
    rmse = rtk.diff(py_end_to_end(), ref)["rmse"]
    print(f"# Cornell 256x256, {spp} spp, 2 threads, median of {iters}; seconds")
    print("renderer,seconds,rmse")
    print(f"rtk render (process: start, load, render, write EXR),{t_cli:.3f},{rmse:.5f}")
    print(f"rtk.Scene.render (render to NumPy),{t_py:.3f},{rmse:.5f}")
    print(f"rtk.load_file + render (end to end),{t_e2e:.3f},{rmse:.5f}")
    for variant in ["scalar_rgb", "llvm_ad_rgb"]:
        m = mitsuba_seconds(variant, spp, iters)
        print(f"mitsuba {variant} (mi.load_dict + mi.render + NumPy),{m['seconds']:.3f},{m['rmse']:.5f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("what", choices=["trace", "render"])
    ap.add_argument("--iters", type=int, default=5)
    ap.add_argument("--spp", type=int, default=64)
    a = ap.parse_args()
    if a.what == "trace":
        bench_trace(a.iters)
    else:
        bench_render(a.spp, a.iters)


if __name__ == "__main__":
    main()
