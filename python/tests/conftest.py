"""Shared fixtures: small generated meshes and the command line the round trips compare with."""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import meshletlab

ROOT = pathlib.Path(__file__).resolve().parents[2]

# Triangles of the generated meshes the tests use (a test checks them, so a changed generator
# is seen here rather than as a puzzling metric).
SMALL = "gen:cad-part-128"  # 3072 triangles
MEDIUM = "gen:noisy-sphere"  # 20480 triangles


def cli_path() -> pathlib.Path:
    """The meshletlab binary: MESHLETLAB_BIN, else the one `cargo test --all-targets` builds."""
    return pathlib.Path(os.environ.get("MESHLETLAB_BIN", ROOT / "target" / "debug" / "meshletlab"))


@pytest.fixture(scope="session")
def cli():
    """Runs the command line; returns its parsed JSON when `--json` is among the arguments."""
    exe = cli_path()
    if not exe.is_file():
        pytest.fail(f"{exe} is missing: build it with `cargo build` (or set MESHLETLAB_BIN)")

    def run(*args, check=True):
        p = subprocess.run([str(exe), "-q", *map(str, args)], capture_output=True, text=True)
        if check and p.returncode != 0:
            raise AssertionError(f"meshletlab {' '.join(map(str, args))}: exit {p.returncode}\n{p.stderr}")
        if "--json" in args and p.returncode == 0:
            return json.loads(p.stdout)
        return p

    return run


@pytest.fixture(scope="session")
def small():
    return meshletlab.load(SMALL)


@pytest.fixture(scope="session")
def medium():
    return meshletlab.load(MEDIUM)


def row(report, name):
    """The `stats --json` row of strategy (or file) `name`."""
    rows = {r["strategy"]: r for r in report["strategies"]}
    assert name in rows, f"no row {name}: {sorted(rows)}"
    return rows[name]


def same_metrics(ours, theirs):
    """Every metric but the build time equal (times are measured, never equal)."""
    a = {k: v for k, v in ours.items() if k != "build_ms"}
    b = {k: v for k, v in theirs.items() if k != "build_ms"}
    assert a.keys() == b.keys()
    for k in a:
        assert a[k] == pytest.approx(b[k], rel=1e-12, abs=0), k


def global_triangles(ml):
    """Every meshlet's triangles as global vertex indices, from the three numpy arrays alone
    (meshoptimizer's layout), each rotated to start at its smallest index."""
    rows, verts, tris = ml.meshlets, ml.vertices, ml.triangles
    out = []
    for vo, to, vc, tc in rows:
        corners = tris[to : to + 3 * tc].reshape(-1, 3).astype(np.int64)
        assert corners.max(initial=0) < vc
        out.append(verts[vo : vo + vc][corners])
    return canonical(np.concatenate(out))


def canonical(t):
    """Triangles (k, 3) rotated so the smallest index is first (winding kept), sorted."""
    t = np.asarray(t, dtype=np.int64)
    r = np.argmin(t, axis=1)
    idx = (r[:, None] + np.arange(3)[None, :]) % 3
    rot = np.take_along_axis(t, idx, axis=1)
    return rot[np.lexsort(rot.T[::-1])]
