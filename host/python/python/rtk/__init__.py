"""rtk in Python: render scenes to NumPy, cast arrays of rays, build scenes
from arrays.

    import rtk
    scene = rtk.load_file("scenes/cornell.toml", **{"render.spp": 16})
    image = scene.render()                  # H x W x 3 float32, linear
    rtk.write("cornell.exr", image)
    hits = scene.trace(origins, directions) # dict of arrays

Everything runs through the code the ``rtk`` binary runs: a scene loads with
the same ``--set`` semantics, renders to the same pixels as ``rtk render``'s
EXR, and ``trace`` gives ``rtk trace``'s hits bit for bit. The plugins ship
in the package (``rtk/plugins``); ``plugin_path=`` and ``RTK_PLUGIN_PATH``
are searched first. See docs/python.md.
"""

import json
import math
import os
from pathlib import Path

import numpy as np

from . import _rtk

__all__ = [
    "Scene",
    "load_file",
    "load_string",
    "load_dict",
    "plugins",
    "write",
    "read",
    "diff",
    "converge",
]

_BUNDLED = str(Path(__file__).resolve().parent / "plugins")


def _bundled():
    return _BUNDLED if os.path.isdir(_BUNDLED) else None


def _paths(plugin_path):
    if plugin_path is None:
        return []
    if isinstance(plugin_path, (str, os.PathLike)):
        return [str(plugin_path)]
    return [str(p) for p in plugin_path]


def _toml_value(v, key):
    """A Python value as the TOML text ``--set KEY=VALUE`` takes."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        f = float(v)
        if math.isnan(f):
            return "nan"
        if math.isinf(f):
            return "inf" if f > 0 else "-inf"
        return repr(f)
    if isinstance(v, (str, os.PathLike)):
        return json.dumps(str(v))
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x, key) for x in v) + "]"
    if isinstance(v, dict):
        inner = ", ".join(f"{_toml_key(k)} = {_toml_value(x, key)}" for k, x in v.items())
        return "{ " + inner + " }"
    raise TypeError(f"{key}: cannot write a {type(v).__name__} into a scene")


def _toml_key(k):
    k = str(k)
    bare = k and all(c.isalnum() or c in "_-" for c in k)
    return k if bare else json.dumps(k)


def _sets(overrides):
    return [f"{k}={_toml_value(v, k)}" for k, v in overrides.items()]


class Scene:
    """A built scene. Make one with :func:`load_file`, :func:`load_string`
    or :func:`load_dict`."""

    def __init__(self, native):
        self._native = native

    @property
    def size(self):
        """(width, height) of the image."""
        return self._native.size

    @property
    def spp(self):
        """Samples per pixel the scene asks for."""
        return self._native.spp

    def objects(self):
        """Each instance's path (``objects.world.children[2]``), indexed by
        the ``object`` ids :meth:`trace` reports."""
        return self._native.objects()

    def stats(self):
        """What the build did: plugins loaded, objects created, timings, bounds."""
        return json.loads(self._native.stats_json())

    def render(self, spp=None, seed=None, threads=None, progress=False):
        """Render the scene: an H x W x 3 float32 array of linear radiance,
        bit-identical to ``rtk render``'s EXR of the same scene and settings.

        The GIL is released while rendering. Ctrl-C stops the render at the
        next sample and raises KeyboardInterrupt. ``progress=True`` shows a
        tqdm bar (in a terminal or in Jupyter; needs tqdm).
        """
        for name, v, lo, hi in (
            ("spp", spp, 1, 2**32 - 1),
            ("seed", seed, 0, 2**63 - 1),
            ("threads", threads, 1, 1024),
        ):
            if v is not None and (
                not isinstance(v, (int, np.integer)) or isinstance(v, (bool, np.bool_)) or not lo <= v <= hi
            ):
                raise ValueError(f"{name} must be an integer in [{lo}, {hi}], got {v!r}")
        callback = None
        bar = None
        if progress:
            try:
                from tqdm.auto import tqdm
            except ImportError as e:
                raise ImportError("progress=True needs tqdm (pip install tqdm)") from e
            total = spp if spp is not None else self.spp
            bar = tqdm(total=total, unit="spp", desc="rendering")

            def callback(done, total):
                bar.n = done
                bar.refresh()

        try:
            return self._native.render(spp, seed, threads, callback)
        finally:
            if bar is not None:
                bar.close()

    def trace(
        self,
        origins,
        directions,
        t_min=0.0,
        t_max=math.inf,
        occluded=False,
        threads=None,
        surface=True,
    ):
        """Cast N rays (``origins``, ``directions``: N x 3, float32 or
        float64, read in place when C-contiguous; ``t_min``/``t_max``: one
        number or one per ray) as ``rtk trace`` does.

        Returns a dict of arrays: ``t`` (inf on a miss), ``prim`` (-1 on a
        miss), ``bary`` (N x 2), ``hit`` (bool), and unless ``surface=False``
        ``object`` (index into :meth:`objects`, -1 none), ``normal`` (N x 3
        unit geometric normal) and ``uv`` (N x 2). With ``occluded=True``
        ``hit`` says whether each ray is blocked (``t`` 0 and ``prim`` 1 if
        so) and there are no surface fields.
        """
        o = np.asarray(origins)
        d = np.asarray(directions)
        for name, a in (("origins", o), ("directions", d)):
            if a.ndim != 2 or a.shape[1] != 3:
                raise ValueError(f"{name} must be an N x 3 array, got shape {a.shape}")
            if a.dtype.kind not in "fiu":
                raise ValueError(f"{name} must hold numbers, got dtype {a.dtype}")
        if o.shape[0] != d.shape[0]:
            raise ValueError(
                f"origins ({o.shape[0]} rays) and directions ({d.shape[0]} rays) differ in length"
            )
        dtype = np.float64 if np.float64 in (o.dtype, d.dtype) else np.float32
        o = np.ascontiguousarray(o, dtype=dtype)
        d = np.ascontiguousarray(d, dtype=dtype)
        tmin = np.ascontiguousarray(np.atleast_1d(np.asarray(t_min, dtype=np.float32)).ravel())
        tmax = np.ascontiguousarray(np.atleast_1d(np.asarray(t_max, dtype=np.float32)).ravel())
        # An occlusion query finds no surface: no surface fields.
        surface = bool(surface) and not occluded
        return self._native.trace(o, d, tmin, tmax, bool(occluded), threads, surface)


def load_file(path, *, accel=None, plugin_path=None, **overrides):
    """Load a scene file (TOML; or a .ply/.obj mesh traced under ``accel``).

    ``overrides`` are ``rtk render --set`` keys with Python values:
    ``rtk.load_file("scenes/cornell.toml", **{"render.spp": 16})``.
    ``accel`` replaces the root's aggregate class, as ``rtk trace
    --aggregate`` does. Errors raise ValueError with rtk's message (file,
    line, column, object, key).
    """
    if not os.path.exists(path):
        raise FileNotFoundError(f"{path}: no such scene file")
    native = _rtk.load_file(
        str(path), _sets(overrides), accel, _paths(plugin_path), _bundled()
    )
    return Scene(native)


def load_string(text, base_dir=".", *, plugin_path=None, _arrays=(), _name="<string>.toml", **overrides):
    """Load a scene from TOML text; relative file parameters resolve
    against ``base_dir``."""
    native = _rtk.load_string(
        text,
        str(base_dir),
        _name,
        _sets(overrides),
        list(_arrays),
        _paths(plugin_path),
        _bundled(),
    )
    return Scene(native)


def _emit_table(path, table, lines, arrays):
    """Append ``[path]`` with its plain keys, then its sub-tables."""
    plain, subs = [], []
    # Only a mesh takes arrays by pointer; elsewhere an array is a list
    # (so a misplaced one is checked, and refused, as any value is).
    is_mesh = len(path) == 2 and path[0] == "objects" and table.get("class") == "mesh"
    for k, v in table.items():
        if isinstance(v, dict):
            subs.append((k, v))
        elif is_mesh and isinstance(v, np.ndarray):
            if v.ndim != 2:
                raise ValueError(
                    f"{'.'.join(path)}.{k}: expected a 2-D array (rows x columns), got shape {v.shape}"
                )
            arrays.append((".".join(path), str(k), v))
        else:
            plain.append((k, v))
    if path and (plain or not subs):
        lines.append("[" + ".".join(_toml_key(p) for p in path) + "]")
    for k, v in plain:
        lines.append(f"{_toml_key(k)} = {_toml_value(v, '.'.join(path + [str(k)]))}")
    for k, v in subs:
        _emit_table(path + [str(k)], v, lines, arrays)




def _bulk(def_path, name, a):
    """A mesh array as the kernel takes it: C-contiguous, floats as float32
    or float64 (kept), indices as int64 or their own integer type."""
    if name == "indices":
        if a.dtype.kind not in "iu":
            raise ValueError(f"{def_path}.indices: expected integers, got dtype {a.dtype}")
        if a.dtype not in (np.int32, np.uint32, np.int64):
            a = a.astype(np.int64)
    elif a.dtype not in (np.float32, np.float64):
        if a.dtype.kind not in "fiu":
            raise ValueError(f"{def_path}.{name}: expected numbers, got dtype {a.dtype}")
        a = a.astype(np.float64)
    return np.ascontiguousarray(a)


def load_dict(d, base_dir=".", *, plugin_path=None, **overrides):
    """Load a scene from a dictionary shaped as the TOML file is
    (``{"render": {...}, "objects": {"ball": {"class": "sphere", ...}}}``).

    A ``mesh`` definition's NumPy arrays are passed by pointer, not as text
    (elsewhere an array is written as a list): a ``mesh`` takes ``vertices`` (V x 3, float32 or float64; float64 stays
    float64 until the plugin places it), ``indices`` (F x 3 integers) and
    optionally ``normals`` (V x 3) and ``uvs`` (V x 2) instead of ``file``.
    """
    if not isinstance(d, dict):
        raise TypeError(f"load_dict takes a dict shaped as the scene file, got {type(d).__name__}")
    lines, arrays = [], []
    _emit_table([], d, lines, arrays)
    bulk = [(p, n, _bulk(p, n, a)) for p, n, a in arrays]
    text = "\n".join(lines) + "\n"
    return load_string(
        text, base_dir, plugin_path=plugin_path, _arrays=bulk, _name="<dict>.toml", **overrides
    )


def plugins(plugin_path=None):
    """Every plugin on the plugin path: a list of dicts (class, kind,
    version, file); a library the loader refuses has kind "refused"."""
    return [
        {"class": c, "kind": k, "version": v, "file": f}
        for c, k, v, f in _rtk.plugins(_paths(plugin_path), _bundled())
    ]


def _image(a, what):
    a = np.asarray(a)
    if a.ndim != 3 or a.shape[2] != 3:
        raise ValueError(f"{what} must be an H x W x 3 array, got shape {a.shape}")
    return a


def write(path, image):
    """Write an H x W x 3 image: .png (8-bit sRGB) or .exr (linear float),
    as ``rtk render`` writes it (atomically: no partial file on failure)."""
    a = _image(image, "the image")
    flat = np.ascontiguousarray(a, dtype=np.float32).ravel()
    _rtk.write(str(path), flat, a.shape[1], a.shape[0])


def read(path):
    """An image file (.exr, .pfm, .npy, .png) as H x W x 3 float32 linear RGB."""
    w, h, data = _rtk.read_image(str(path))
    return data.reshape(h, w, 3)


def diff(a, b):
    """``rtk diff``'s error of image ``a`` against reference ``b`` (arrays
    or file paths): ``{"rmse": ..., "relmse": ...}``."""
    a = read(a) if isinstance(a, (str, os.PathLike)) else _image(a, "a")
    b = read(b) if isinstance(b, (str, os.PathLike)) else _image(b, "b")
    if a.shape != b.shape:
        raise ValueError(f"the images differ in size: {a.shape} and {b.shape}")
    rmse, relmse = _rtk.image_error(
        np.ascontiguousarray(a, dtype=np.float32).ravel(),
        np.ascontiguousarray(b, dtype=np.float32).ravel(),
    )
    return {"rmse": rmse, "relmse": relmse}


def converge(
    scene, out, *, reference=None, spp=None, seeds=None, threads=None, plugin_path=None, args=()
):
    """Run ``rtk converge`` on a scene file into folder ``out`` and return
    its table (``converge.csv``): a pandas DataFrame when pandas is
    installed, else a dict of NumPy arrays by column.

    ``reference`` (an image file), ``spp`` (a list of sample counts),
    ``seeds`` and ``threads`` are its flags; ``args`` passes any other.
    """
    argv = ["converge", str(scene), "--out", str(out)]
    if reference is not None:
        argv += ["--reference", str(reference)]
    if spp is not None:
        argv += ["--spp", ",".join(str(int(s)) for s in spp)]
    if seeds is not None:
        argv += ["--seeds", str(int(seeds))]
    if threads is not None:
        argv += ["--threads", str(int(threads))]
    for p in _paths(plugin_path) + ([_bundled()] if _bundled() else []):
        argv += ["--plugin-path", p]
    argv += [str(a) for a in args]
    _rtk.run_command(argv)
    csv = Path(out) / "converge.csv"
    try:
        import pandas

        return pandas.read_csv(csv, comment="#")
    except ImportError:
        pass
    rows = [l for l in csv.read_text().splitlines() if l and not l.startswith("#")]
    header = rows[0].split(",")
    cols = list(zip(*(r.split(",") for r in rows[1:])))
    table = {}
    for name, col in zip(header, cols):
        try:
            table[name] = np.array([float(x) for x in col])
        except ValueError:
            table[name] = np.array(col)
    return table
