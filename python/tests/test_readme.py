"""The README's Python example runs as written (on a generated mesh's arrays)."""

import pathlib
import re

import meshletlab
from conftest import ROOT


def test_the_readme_example_runs(tmp_path, monkeypatch):
    text = (ROOT / "README.md").read_text()
    section = text[text.index("\n## Python\n") :]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    mesh = meshletlab.load("gen:knot-tube")
    monkeypatch.chdir(tmp_path)
    scope = {"positions": mesh.positions, "indices": mesh.indices}
    exec(compile(code, "README.md", "exec"), scope)
    mine = scope["mine"]
    meshletlab.validate(scope["mesh"], mine)
    assert mine.clusters > 1 and pathlib.Path("mine.npz").is_file()
