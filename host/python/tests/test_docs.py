"""docs/python.md's walkthrough runs as written: every ```python block, in
order, in one namespace, from the checkout's root. It needs ../shared (the
Mitsuba reference); it fails, not skips, without it."""

import os
import re


def test_docs_python_md_walkthrough_runs(root, monkeypatch):
    assert (root.parent / "shared" / "anchors" / "mitsuba" / "ref_cornell.exr").is_file(), (
        "docs/python.md compares against ../shared/anchors/mitsuba/ref_cornell.exr: "
        "put ../shared beside the checkout"
    )
    text = (root / "docs" / "python.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert len(blocks) >= 3
    monkeypatch.chdir(root)
    ns = {}
    for i, code in enumerate(blocks):
        exec(compile(code, f"docs/python.md block {i + 1}", "exec"), ns)
