# SPDX-License-Identifier: MIT
"""Every ```python snippet of docs/python.md runs, in order, in one namespace (a fresh folder)."""
import os
import re

import pytest


def snippets():
    here = os.path.dirname(os.path.abspath(__file__))
    page = os.path.join(here, "..", "..", "docs", "python.md")
    with open(page, encoding="utf-8") as f:
        return re.findall(r"```python\n(.*?)```", f.read(), flags=re.S)


def test_the_page_has_snippets():
    assert len(snippets()) >= 4


def test_every_snippet_runs(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    namespace = {}
    for i, code in enumerate(snippets()):
        try:
            exec(compile(code, f"docs/python.md snippet {i + 1}", "exec"), namespace)
        except Exception as e:  # name the snippet in the failure
            pytest.fail(f"docs/python.md snippet {i + 1} failed: {type(e).__name__}: {e}")
    assert (tmp_path / "contact-slices.png").stat().st_size > 1000
    assert (tmp_path / "elbow.png").stat().st_size > 1000
    assert (tmp_path / "cylinder-tracked.pc2").stat().st_size > 1000
