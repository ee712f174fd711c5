#!/usr/bin/env python3
"""Mitsuba 3's render tests through rtk: one line per scene.

Every `test_*.xml` of ../shared/data/mitsuba-tests/tests/scenes is imported
(`rtk import`, the integrator its name ends in) and, if rtk translates it,
rendered at Mitsuba's budget (2,000,000 samples an image, seed 0) and
judged by Mitsuba's z-test (`rtk diff --ztest`, 99.75 % of the
pixel-channels above the Sidak-corrected level). A refused scene shows
the first reason the importer gave. tests/tests/mitsuba.rs asserts the
same run.

    cargo build --release --workspace
    python3 host/benches/mitsuba_tests.py [--rtk target/release/rtk] [--scenes DIR]
"""

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def collect(scenes):
    for d in sorted(os.listdir(scenes)):
        folder = os.path.join(scenes, d)
        if not os.path.isdir(folder):
            continue
        for f in sorted(os.listdir(folder)):
            if f.startswith("test_") and f.endswith(".xml"):
                base, integrator = f[:-4].rsplit("_", 1)
                refs = os.path.join(folder, "refs")
                yield (f"{d}/{f[:-4]}", os.path.join(folder, f), integrator,
                       os.path.join(refs, base + "_ref_rgb.exr"),
                       os.path.join(refs, base + "_ref_rgb_var.exr"))


def exr_size(path, rtk):
    # `rtk diff X X` prints nothing about size; read the EXR header's
    # dataWindow instead (box2i: xmin, ymin, xmax, ymax).
    data = open(path, "rb").read(4096)
    i = data.find(b"dataWindow\x00box2i\x00")
    xmin, ymin, xmax, ymax = (int.from_bytes(data[i + 21 + 4 * k:i + 25 + 4 * k], "little", signed=True)
                              for k in range(4))
    return xmax - xmin + 1, ymax - ymin + 1


def one(rtk, name, xml, integrator, ref, var, tmp):
    define = ["-D", f"integrator={integrator}"]
    imp = subprocess.run([rtk, "import", xml] + define, capture_output=True, text=True)
    if imp.returncode != 0:
        reason = imp.stderr.strip().splitlines()[-1] if imp.stderr.strip() else "?"
        reason = reason.replace(os.path.dirname(xml) + "/", "")
        return "refused", "", "", reason
    w, h = exr_size(ref, rtk)
    spp = 2_000_000 // (w * h)
    out = os.path.join(tmp, "img.exr")
    t0 = time.time()
    r = subprocess.run([rtk, "render", xml, "-q", "--spp", str(spp), "--set", "render.seed=0", "-o", out] + define,
                       capture_output=True, text=True)
    secs = time.time() - t0
    if r.returncode != 0:
        return "error", f"{secs:.2f}", "", r.stderr.strip().splitlines()[-1]
    d = subprocess.run([rtk, "diff", out, ref, "--ztest", var, "--spp", str(spp)], capture_output=True, text=True)
    m = re.search(r"failing (\d+) of (\d+)", d.stdout)
    failing = f"{m.group(1)}/{m.group(2)}" if m else "?"
    verdict = "pass" if d.returncode == 0 else "FAIL"
    return verdict, f"{secs:.2f}", failing, f"{spp} spp"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rtk", default=os.path.join(ROOT, "target/release/rtk"))
    ap.add_argument("--scenes", default=os.path.join(ROOT, "../shared/data/mitsuba-tests/tests/scenes"))
    a = ap.parse_args()
    if not os.path.isdir(a.scenes):
        sys.exit(f"{a.scenes}: not found (Mitsuba's tests live in ../shared/data/mitsuba-tests)")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for t in collect(a.scenes):
            rows.append((t[0],) + one(a.rtk, *t, tmp))
    print("| scene | result | rtk render (s) | failing pixel-channels | spp, or why refused |")
    print("|---|---|---|---|---|")
    for r in rows:
        print("| " + " | ".join(r) + " |")
    passed = sum(r[1] == "pass" for r in rows)
    refused = sum(r[1] == "refused" for r in rows)
    print(f"\n{passed} pass, {refused} refused, {len(rows) - passed - refused} fail, of {len(rows)}")


if __name__ == "__main__":
    main()
