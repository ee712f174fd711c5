"""The rtk Python module against the `rtk` binary (bit for bit), analytic
answers, and the bad inputs a user will give it."""

import _thread
import os
import struct
import subprocess
import threading

import numpy as np
import pytest

import rtk

SMALL = {"render.width": 48, "render.height": 36}


def cli_render(rtk_bin, root, scene, out, sets):
    args = [str(rtk_bin), "render", str(root / scene), "-o", str(out), "-q"]
    for k, v in sets.items():
        args += ["--set", f"{k}={v}"]
    subprocess.check_call(args)


# -- plugins -----------------------------------------------------------------


def test_the_package_loads_its_bundled_plugins_without_the_binary():
    found = rtk.plugins()
    kinds = {p["kind"] for p in found}
    assert {"object", "shader", "integrator", "camera", "light"} <= kinds, kinds
    bundled = os.path.join(os.path.dirname(rtk.__file__), "plugins")
    by_class = {p["class"]: p for p in found}
    for c in ["bvh", "mesh", "sphere", "path", "lambert", "pinhole"]:
        assert by_class[c]["file"].startswith(bundled), by_class[c]


def test_plugin_path_is_searched_first(tmp_path):
    # An empty extra folder changes nothing; a broken library in it is reported.
    (tmp_path / "librtk_sphere.so").write_bytes(b"not a library")
    found = {p["class"]: p for p in rtk.plugins(plugin_path=tmp_path)}
    assert found["sphere"]["kind"] == "refused"
    assert found["sphere"]["file"] == str(tmp_path / "librtk_sphere.so")


# -- render ------------------------------------------------------------------


@pytest.mark.parametrize("scene", ["scenes/cornell.toml", "scenes/default.toml"])
def test_render_is_bit_identical_to_rtk_render(rtk_bin, root, tmp_path, scene):
    sets = dict(SMALL, **{"render.spp": 4})
    cli_render(rtk_bin, root, scene, tmp_path / "cli.exr", sets)
    img = rtk.load_file(root / scene, **sets).render(threads=2)
    assert img.shape == (36, 48, 3) and img.dtype == np.float32
    ref = rtk.read(tmp_path / "cli.exr")
    assert np.array_equal(img, ref)


def test_render_spp_and_seed_are_the_overrides_and_threads_do_not_matter(rtk_bin, root, tmp_path):
    cli_render(
        rtk_bin, root, "scenes/cornell.toml", tmp_path / "cli.exr",
        dict(SMALL, **{"render.spp": 3, "render.seed": 7}),
    )
    scene = rtk.load_file(root / "scenes/cornell.toml", **SMALL)
    a = scene.render(spp=3, seed=7, threads=1)
    b = scene.render(spp=3, seed=7, threads=2)
    assert np.array_equal(a, rtk.read(tmp_path / "cli.exr"))
    assert np.array_equal(a, b)
    # The scene's own settings come back after an override.
    assert scene.spp == rtk.load_file(root / "scenes/cornell.toml").spp


def test_progress_bar_and_bad_render_arguments(root):
    scene = rtk.load_file(root / "scenes/cornell.toml", **SMALL)
    img = scene.render(spp=2, progress=True)
    assert np.isfinite(img).all()
    with pytest.raises(ValueError, match="spp"):
        scene.render(spp=-1)
    with pytest.raises(ValueError, match="spp"):
        scene.render(spp=1.5)


def test_ctrl_c_raises_keyboard_interrupt_and_the_scene_still_renders(root):
    scene = rtk.load_file(root / "scenes/cornell.toml")
    threading.Timer(0.5, _thread.interrupt_main).start()
    with pytest.raises(KeyboardInterrupt):
        scene.render(spp=1 << 20)
    assert scene.render(spp=1, threads=1).shape[2] == 3


# -- loading and its errors --------------------------------------------------


def test_a_missing_scene_file_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.toml"):
        rtk.load_file(tmp_path / "nope.toml")


def test_an_unknown_override_key_names_the_key(root):
    with pytest.raises(ValueError, match="no_such_key"):
        rtk.load_file(root / "scenes/cornell.toml", **{"render.no_such_key": 3})


def test_scene_text_errors_name_line_and_key(root):
    lines = (root / "scenes/cornell.toml").read_text().splitlines()
    at = next(i for i, l in enumerate(lines) if l.startswith("width"))
    lines[at] = 'width = "wide"'
    with pytest.raises(ValueError) as e:
        rtk.load_string("\n".join(lines), base_dir=root / "scenes")
    msg = str(e.value)
    assert f"<string>.toml:{at + 1}:" in msg, msg
    assert "width" in msg, msg


def test_load_string_resolves_files_against_base_dir(root):
    text = (root / "scenes/bunny.toml").read_text()
    scene = rtk.load_string(text, base_dir=root / "scenes", **SMALL)
    assert scene.size == (48, 36)
    with pytest.raises(ValueError, match="bunny.ply"):
        rtk.load_string(text, base_dir=root, **SMALL)


def test_stats_and_objects(root):
    scene = rtk.load_file(root / "scenes/cornell.toml")
    s = scene.stats()
    assert (s["width"], s["height"]) == scene.size
    assert any(p["class"] == "mesh" or p["kind"] == "object" for p in s["plugins"])
    assert s["objects_created"] >= 1
    names = scene.objects()
    assert len(names) == s["instances"] and "render.root" in names


# -- trace -------------------------------------------------------------------


def random_rays(n, lo, hi, seed=1):
    rng = np.random.default_rng(seed)
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    c = (lo + hi) / 2
    r = np.linalg.norm(hi - lo)
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    o = c - d * r + rng.uniform(-0.3, 0.3, size=(n, 3)) * (hi - lo)
    return o.astype(np.float32), d.astype(np.float32)


def write_ray_file(path, o, d):
    n = len(o)
    rec = np.zeros((n, 8), np.float32)
    rec[:, 0:3], rec[:, 3:6], rec[:, 6], rec[:, 7] = o, d, 0.0, np.inf
    path.write_bytes(rec.astype("<f4").tobytes())


def read_hit_file(path):
    raw = np.frombuffer(path.read_bytes(), dtype=np.dtype([("t", "<f4"), ("prim", "<u4"), ("u", "<f4"), ("v", "<f4")]))
    return raw


@pytest.mark.parametrize("accel", ["bvh", "kdtree", "grid"])
def test_trace_equals_rtk_trace_hit_file_bit_for_bit(rtk_bin, root, tmp_path, accel):
    mesh = root / "scenes/meshes/bunny.ply"
    scene = rtk.load_file(mesh, accel=accel)
    lo, hi = scene.stats()["bounds"]
    o, d = random_rays(20000, lo, hi)
    write_ray_file(tmp_path / "rays.bin", o, d)
    subprocess.check_call(
        [str(rtk_bin), "trace", str(mesh), "--aggregate", accel, "--rays", str(tmp_path / "rays.bin"),
         "--out", str(tmp_path / "hits.bin"), "--threads", "2"],
        stdout=subprocess.DEVNULL,
    )
    ref = read_hit_file(tmp_path / "hits.bin")
    for threads in (1, 2):
        h = scene.trace(o, d, threads=threads)
        assert np.array_equal(h["t"].view(np.uint32), ref["t"].view(np.uint32))
        prim = np.where(ref["prim"] == 0xFFFFFFFF, -1, ref["prim"].astype(np.int64))
        assert np.array_equal(h["prim"], prim)
        assert np.array_equal(h["bary"][:, 0].view(np.uint32), ref["u"].view(np.uint32))
        assert np.array_equal(h["bary"][:, 1].view(np.uint32), ref["v"].view(np.uint32))
        assert np.array_equal(h["hit"], np.isfinite(ref["t"]))
    assert 1000 < h["hit"].sum() < 20000


def test_occluded_agrees_with_nearest_hits(root):
    scene = rtk.load_file(root / "scenes/meshes/bunny.ply")
    lo, hi = scene.stats()["bounds"]
    o, d = random_rays(5000, lo, hi, seed=3)
    near = scene.trace(o, d, surface=False)
    # A segment ending before the nearest hit is unblocked; past it, blocked.
    t = np.where(near["hit"], near["t"], 1e3).astype(np.float32)
    short = scene.trace(o, d, t_max=t * 0.999, occluded=True)
    long = scene.trace(o, d, t_max=t * 1.001 + 1e-4, occluded=True)
    assert not short["hit"][near["hit"]].any()
    assert np.array_equal(long["hit"], near["hit"])


def test_trace_float64_and_non_contiguous_inputs_give_the_same_hits(root):
    scene = rtk.load_file(root / "scenes/meshes/bunny.ply")
    lo, hi = scene.stats()["bounds"]
    o, d = random_rays(3000, lo, hi, seed=5)
    base = scene.trace(o, d)
    f64 = scene.trace(o.astype(np.float64), d.astype(np.float64))
    fortran = scene.trace(np.asfortranarray(o), np.asfortranarray(d))
    strided = scene.trace(np.repeat(o, 2, axis=0)[::2], np.repeat(d, 2, axis=0)[::2])
    for other in (f64, fortran, strided):
        for k in base:
            assert np.array_equal(base[k], other[k]), k


def test_trace_surface_fields_are_unit_normals_facing_the_ray_side(root):
    scene = rtk.load_file(root / "scenes/cornell.toml")
    lo, hi = scene.stats()["bounds"]
    o, d = random_rays(4000, lo, hi, seed=7)
    h = scene.trace(o, d)
    hit = h["hit"]
    assert hit.any()
    n = h["normal"][hit]
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-5)
    names = scene.objects()
    assert (h["object"][hit] >= 0).all() and (h["object"][hit] < len(names)).all()
    assert (h["object"][~hit] == -1).all()
    assert np.isfinite(h["uv"][hit]).all()


def test_trace_bad_inputs_raise_clear_errors(root):
    scene = rtk.load_file(root / "scenes/meshes/bunny.ply")
    o = np.zeros((4, 3), np.float32)
    d = np.tile(np.float32([0, 0, 1]), (4, 1))
    with pytest.raises(ValueError, match="N x 3"):
        scene.trace(np.zeros((4, 2)), d)
    with pytest.raises(ValueError, match="N x 3"):
        scene.trace(np.zeros(12), d)
    with pytest.raises(ValueError, match="differ in length"):
        scene.trace(o[:3], d)
    with pytest.raises(ValueError, match="numbers"):
        scene.trace(o.astype(str), d)
    bad = o.copy()
    bad[2, 1] = np.nan
    with pytest.raises(ValueError, match="ray 2"):
        scene.trace(bad, d)
    with pytest.raises(ValueError, match="t_min"):
        scene.trace(o, d, t_min=np.zeros(3))
    with pytest.raises(ValueError, match="ray 0"):
        scene.trace(o, d, t_min=-1.0)
    empty = scene.trace(np.zeros((0, 3)), np.zeros((0, 3)))
    assert all(len(v) == 0 for v in empty.values())


def test_a_million_ray_trace_allocates_only_its_outputs(root):
    scene = rtk.load_file(root / "scenes/meshes/bunny.ply")
    lo, hi = scene.stats()["bounds"]
    o, d = random_rays(1 << 20, lo, hi, seed=9)
    scene.trace(o[:4096], d[:4096], surface=False)  # pools and mailboxes made

    def rss():
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")

    before = rss()
    h = scene.trace(o, d, surface=False)
    grown = rss() - before
    outputs = sum(v.nbytes for v in h.values())
    # No per-ray Python objects (tens of bytes each); a little slack for
    # the allocator's pages.
    assert grown < outputs + (8 << 20), (grown, outputs)


# -- meshes from arrays ------------------------------------------------------


def quad_scene(vertices, indices, **mesh):
    return {
        "render": {"width": 8, "height": 8, "root": "world", "camera": "cam", "origin": "world"},
        "cameras": {"cam": {"class": "pinhole", "eye": [0.0, 0.0, 5.0], "look_at": [0.0, 0.0, 0.0]}},
        "objects": {
            "quad": {"class": "mesh", "vertices": vertices, "indices": indices, **mesh},
            "world": {"class": "list", "children": ["quad"]},
        },
    }


QUAD_V = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float64)
QUAD_F = np.array([[0, 1, 2], [0, 2, 3]], np.int64)


def test_a_mesh_from_arrays_is_hit_where_the_plane_is(tmp_path):
    scene = rtk.load_dict(quad_scene(QUAD_V, QUAD_F))
    o = np.array([[0.25, -0.5, 3.0], [-0.5, 0.5, -2.0], [3.0, 0.0, 1.0]], np.float32)
    d = np.array([[0, 0, -1], [0, 0, 1], [0, 0, -1]], np.float32)
    h = scene.trace(o, d)
    assert h["hit"].tolist() == [True, True, False]
    assert h["t"][:2].tolist() == [3.0, 2.0]
    assert h["prim"].tolist() == [0, 1, -1]
    assert np.allclose(np.abs(h["normal"][:2, 2]), 1.0)
    assert scene.objects()[h["object"][0]] == "objects.world.children[0]"


def test_mesh_arrays_equal_the_same_mesh_from_a_file(tmp_path, root):
    rng = np.random.default_rng(4)
    v = rng.uniform(-1, 1, size=(300, 3))
    f = rng.integers(0, 300, size=(400, 3))
    obj = tmp_path / "m.obj"
    v32 = v.astype(np.float32)
    obj.write_text(
        "".join(f"v {a!r} {b!r} {c!r}\n" for a, b, c in v32.astype(float).tolist())
        + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in f.tolist())
    )
    from_file = rtk.load_file(obj)
    from_arrays = rtk.load_dict(quad_scene(v32, f.astype(np.int32)))
    o, d = random_rays(5000, [-1] * 3, [1] * 3, seed=2)
    a = from_file.trace(o, d, surface=False)
    b = from_arrays.trace(o, d, surface=False)
    for k in a:
        assert np.array_equal(a[k], b[k]), k
    assert a["hit"].sum() > 100


def test_float64_vertices_are_placed_in_f64_before_rounding():
    # Far from the world origin a float32 copy of the vertices would move
    # them by its spacing (1/64 at 6e5); the plugin subtracts the render
    # origin in f64 first, so the quad sits exactly where it is given.
    far = 600000.0
    v = QUAD_V * 0.01 + [far, 0.0, 0.0]
    scene_dict = quad_scene(v, QUAD_F)
    scene_dict["render"]["origin"] = [far, 0.0, 0.0]
    scene_dict["cameras"]["cam"] = {"class": "pinhole", "eye": [far, 0.0, 5.0], "look_at": [far, 0.0, 0.0]}
    img = rtk.load_dict(scene_dict, **{"render.background": [0.0, 0.0, 0.0]}).render(spp=1)
    assert img.shape == (8, 8, 3)
    # The centre pixel sees the quad (0.02 wide at distance 5 fills a few
    # pixels only with a narrow field of view; here it must at least not be NaN).
    assert np.isfinite(img).all()


def test_bad_mesh_arrays_name_the_array():
    with pytest.raises(ValueError, match="indices"):
        rtk.load_dict(quad_scene(QUAD_V, QUAD_F + 10))
    with pytest.raises(ValueError, match="indices"):
        rtk.load_dict(quad_scene(QUAD_V, QUAD_F.astype(np.float32)))
    with pytest.raises(ValueError, match="vertices"):
        rtk.load_dict(quad_scene(QUAD_V[:, :2], QUAD_F))
    bad = QUAD_V.copy()
    bad[1, 1] = np.inf
    with pytest.raises(ValueError, match="vertices"):
        rtk.load_dict(quad_scene(bad, QUAD_F))
    with pytest.raises(ValueError, match="colors"):
        rtk.load_dict(quad_scene(QUAD_V, QUAD_F, colors=np.zeros((4, 3))))
    d = quad_scene(QUAD_V, QUAD_F)
    d["objects"]["quad"]["file"] = "x.ply"
    with pytest.raises(ValueError, match="not both"):
        rtk.load_dict(d)


# -- images ------------------------------------------------------------------


def test_write_read_and_diff(tmp_path):
    img = np.random.default_rng(0).uniform(0, 2, size=(5, 7, 3)).astype(np.float32)
    rtk.write(tmp_path / "a.exr", img)
    assert np.array_equal(rtk.read(tmp_path / "a.exr"), img)
    assert rtk.diff(img, tmp_path / "a.exr") == {"rmse": 0.0, "relmse": 0.0}
    e = rtk.diff(img + 0.5, img)
    assert abs(e["rmse"] - 0.5) < 1e-6
    with pytest.raises(ValueError):
        rtk.write(tmp_path / "a.bmp", img)
    assert not any(p.name.startswith(".a.") or p.suffix == ".bmp" for p in tmp_path.iterdir())
    with pytest.raises(ValueError, match="H x W x 3"):
        rtk.write(tmp_path / "b.png", img[:, :, :2])


def test_converge_returns_its_table(root, tmp_path):
    scene = root / "scenes/cornell.toml"
    ref = tmp_path / "ref.exr"
    rtk.write(ref, rtk.load_file(scene, **SMALL).render(spp=16))
    table = rtk.converge(
        scene, tmp_path / "out", reference=ref, spp=[1, 4], seeds=1, threads=2,
        args=["--set", "render.width=48", "--set", "render.height=36", "--quiet"],
    )
    spp = np.asarray(table["spp"]).tolist()
    assert spp == [1, 4]
    rmse = np.asarray(table["rmse"], dtype=float)
    assert rmse[1] < rmse[0]


def test_arrays_outside_a_mesh_are_values_and_occluded_has_no_surface_fields():
    d = quad_scene(QUAD_V, QUAD_F)
    d["cameras"]["cam"]["eye"] = np.array([[0.0, 0.0, 40.0]])  # a 2-D array: a list of lists
    with pytest.raises(ValueError, match="eye"):
        rtk.load_dict(d)
    with pytest.raises(ValueError, match="2-D"):
        rtk.load_dict(quad_scene(QUAD_V.ravel(), QUAD_F))
    scene = rtk.load_dict(quad_scene(QUAD_V, QUAD_F))
    h = scene.trace(np.array([[0.5, -0.5, 2.0]]), np.array([[0.0, 0.0, 1.0]]), occluded=True)
    assert set(h) == {"t", "prim", "bary", "hit"} and not h["hit"][0]


def test_empty_images_and_bad_render_counts_are_refused(tmp_path, root):
    with pytest.raises(ValueError, match="empty"):
        rtk.write(tmp_path / "e.exr", np.zeros((0, 5, 3), np.float32))
    assert not list(tmp_path.iterdir())
    scene = rtk.load_file(root / "scenes/cornell.toml", **SMALL)
    for kw in ({"spp": 0}, {"threads": 0}, {"seed": -1}, {"spp": 2**32}):
        with pytest.raises(ValueError, match=next(iter(kw))):
            scene.render(**kw)
