"""Type stubs of the rtk module (docs/python.md)."""

import os
from typing import Any, Iterable, Mapping, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

PathLike = Union[str, os.PathLike[str]]
PluginPath = Union[None, PathLike, Iterable[PathLike]]

class Scene:
    """A built scene; make one with load_file, load_string or load_dict."""

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) of the image."""
    @property
    def spp(self) -> int:
        """Samples per pixel the scene asks for."""
    def objects(self) -> list[str]:
        """Each instance's path, indexed by the `object` ids trace reports."""
    def stats(self) -> dict[str, Any]:
        """Plugins loaded, objects created, timings, bounds of the build."""
    def render(
        self,
        spp: Optional[int] = None,
        seed: Optional[int] = None,
        threads: Optional[int] = None,
        progress: bool = False,
    ) -> npt.NDArray[np.float32]:
        """H x W x 3 linear radiance, bit-identical to `rtk render`'s EXR.
        The GIL is released; Ctrl-C raises KeyboardInterrupt."""
    def trace(
        self,
        origins: npt.ArrayLike,
        directions: npt.ArrayLike,
        t_min: Union[float, npt.ArrayLike] = 0.0,
        t_max: Union[float, npt.ArrayLike] = ...,
        occluded: bool = False,
        threads: Optional[int] = None,
        surface: bool = True,
    ) -> dict[str, np.ndarray]:
        """Cast N rays as `rtk trace` does: t, prim, bary, hit (and object,
        normal, uv unless surface=False)."""

def load_file(
    path: PathLike, *, accel: Optional[str] = None, plugin_path: PluginPath = None, **overrides: Any
) -> Scene:
    """A scene file (TOML, or a .ply/.obj mesh under `accel`) with `--set` overrides."""

def load_string(
    text: str, base_dir: PathLike = ".", *, plugin_path: PluginPath = None, **overrides: Any
) -> Scene:
    """A scene from TOML text; files resolve against base_dir."""

def load_dict(
    d: Mapping[str, Any], base_dir: PathLike = ".", *, plugin_path: PluginPath = None, **overrides: Any
) -> Scene:
    """A scene from a dict shaped as the TOML file; 2-D arrays (mesh vertices,
    indices, normals, uvs) are passed by pointer."""

def plugins(plugin_path: PluginPath = None) -> list[dict[str, str]]:
    """Every plugin on the plugin path: class, kind, version, file."""

def write(path: PathLike, image: npt.ArrayLike) -> None:
    """Write an H x W x 3 image as PNG (sRGB) or EXR (linear), atomically."""

def read(path: PathLike) -> npt.NDArray[np.float32]:
    """An image file (.exr, .pfm, .npy, .png) as H x W x 3 linear RGB."""

def diff(a: Union[PathLike, npt.ArrayLike], b: Union[PathLike, npt.ArrayLike]) -> dict[str, float]:
    """`rtk diff`'s rmse and relmse of a against reference b."""

def converge(
    scene: PathLike,
    out: PathLike,
    *,
    reference: Optional[PathLike] = None,
    spp: Optional[Sequence[int]] = None,
    seeds: Optional[int] = None,
    threads: Optional[int] = None,
    plugin_path: PluginPath = None,
    args: Sequence[str] = (),
) -> Any:
    """`rtk converge`'s table: a pandas DataFrame, or a dict of arrays."""
