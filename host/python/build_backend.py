"""PEP 517 backend: maturin's, after building rtk's plugins into the package.

Why: a wheel that can load no plugin renders nothing, and maturin builds
only the extension crate. Before each wheel this builds the workspace's
libraries (`cargo build --release --lib`, sharing the checkout's target
folder, so after `cargo build --release` it only links) and copies every
plugin library (`librtk_<class>.so`) into `python/rtk/plugins/`, which the
wheel includes and the module searches after `plugin_path=` and
`RTK_PLUGIN_PATH`.
"""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import maturin
from maturin import *  # noqa: F401,F403  (the other PEP 517 hooks)

HERE = Path(__file__).resolve().parent
STAGED = HERE / "python" / "rtk" / "plugins"


def _stage_plugins():
    cargo = os.environ.get("CARGO", "cargo")
    meta = json.loads(
        subprocess.check_output(
            [cargo, "metadata", "--format-version", "1", "--no-deps"], cwd=HERE
        )
    )
    members = set(meta["workspace_members"])
    plugin_crates = [
        p["name"]
        for p in meta["packages"]
        if p["id"] in members
        and Path(p["manifest_path"]).parent.parent.name == "plugins"
    ]
    args = [cargo, "build", "--release", "--lib"]
    for name in plugin_crates:
        args += ["-p", name]
    print("rtk: building the plugins:", " ".join(args), file=sys.stderr)
    subprocess.check_call(args, cwd=HERE)
    release = Path(meta["target_directory"]) / "release"
    suffix = {"darwin": ".dylib", "win32": ".dll"}.get(sys.platform, ".so")
    prefix = "" if sys.platform == "win32" else "lib"
    if STAGED.exists():
        shutil.rmtree(STAGED)
    STAGED.mkdir(parents=True)
    found = sorted(release.glob(f"{prefix}rtk_*{suffix}"))
    if not found:
        raise RuntimeError(f"no plugin libraries in {release} after building them")
    for lib in found:
        shutil.copy2(lib, STAGED / lib.name)
    print(f"rtk: staged {len(found)} plugins in {STAGED}", file=sys.stderr)


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    _stage_plugins()
    return maturin.build_wheel(wheel_directory, config_settings, metadata_directory)


def build_editable(wheel_directory, config_settings=None, metadata_directory=None):
    _stage_plugins()
    return maturin.build_editable(wheel_directory, config_settings, metadata_directory)
