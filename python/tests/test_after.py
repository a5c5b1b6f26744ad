"""After building: validate, bounds, compression, the glTF export and the LOD DAG, each checked
against the mesh and against the command line's checkers."""

import numpy as np
import pytest

import meshletlab
from conftest import SMALL


def test_validate_names_the_broken_rule(small, medium):
    ml = meshletlab.build(small, "meshopt")
    meshletlab.validate(small, ml)
    with pytest.raises(meshletlab.ValidationError, match=r"meshlet \d+ has \d+ vertices / \d+ triangles, limits 64/32"):
        meshletlab.validate(small, ml, limits=(64, 32))
    with pytest.raises(meshletlab.ValidationError) as e:
        meshletlab.validate(medium, ml)
    assert isinstance(e.value, ValueError)
    # Every measuring function checks first: another mesh's meshlets never reach the crate.
    for f in (meshletlab.metrics, meshletlab.bounds, meshletlab.export_glb, meshletlab.compress):
        with pytest.raises(meshletlab.ValidationError, match="meshlets of meshopt for this mesh"):
            f(medium, ml)


def test_meshlets_from_arrays_are_checked(small):
    ml = meshletlab.build(small, "greedy")
    same = meshletlab.Meshlets(small, ml.meshlets, ml.vertices.astype(np.int64), ml.triangles)
    assert same.source == "arrays" and same.build_ms is None
    assert meshletlab.metrics(small, same)["meshlets"] == len(ml)
    corners = ml.triangles.copy()
    corners[0] = 255
    with pytest.raises(meshletlab.ValidationError, match="meshlet 0: corner 255 is not below its vertex count"):
        meshletlab.Meshlets(small, ml.meshlets, ml.vertices, corners)
    with pytest.raises(meshletlab.ValidationError, match="its vertex or triangle range runs past the array"):
        meshletlab.Meshlets(small, ml.meshlets, ml.vertices[:10], ml.triangles)
    with pytest.raises(meshletlab.ValidationError, match=r"must have shape \(M, 4\)"):
        meshletlab.Meshlets(small, ml.meshlets[:, :3], ml.vertices, ml.triangles)
    with pytest.raises(meshletlab.ValidationError, match=r"triangles\[2\] = 300 is not a u8"):
        meshletlab.Meshlets(small, ml.meshlets, ml.vertices, np.array([0, 1, 300]))
    # Structurally sound but missing meshlets: built, then refused by validate, with the rule.
    part = meshletlab.Meshlets(small, ml.meshlets[:-1], ml.vertices, ml.triangles)
    with pytest.raises(meshletlab.ValidationError, match="triangle multiset differs"):
        meshletlab.validate(small, part)


def test_bounds_enclose_every_vertex(small):
    ml = meshletlab.build(small, "kmedoids")
    b = meshletlab.bounds(small, ml)
    n = len(ml)
    assert b["center"].shape == (n, 3) and b["radius"].shape == (n,)
    assert b["cone_axis"].shape == (n, 3) and b["cone_cutoff"].shape == (n,)
    p = small.positions.astype(np.float64)
    for i, (vo, _, vc, _) in enumerate(ml.meshlets):
        d = np.linalg.norm(p[ml.vertices[vo : vo + vc]] - b["center"][i], axis=1)
        assert d.max() <= b["radius"][i] * (1 + 1e-6)
    axis_len = np.linalg.norm(b["cone_axis"], axis=1)
    np.testing.assert_allclose(axis_len, 1.0, atol=1e-5)
    assert ((b["cone_cutoff"] <= 1.0) & (b["cone_cutoff"] >= -1.0)).all()
    # The metric counts the same cones as cullable.
    cullable = (b["cone_cutoff"] < 1.0).mean()
    assert meshletlab.metrics(small, ml)["cone_cullable"] == pytest.approx(cullable)


@pytest.mark.parametrize("fmt", ["meshopt", "laced-wires", "ts", "ix-compact", "sc-compact", "gi-compact"])
def test_compression_decodes_back_to_the_mesh(cli, small, tmp_path, fmt):
    ml = meshletlab.build(small, "meshopt")
    c = meshletlab.compress(small, ml, format=fmt, relative_tolerance=1e-4)
    assert c.format == fmt and len(c) == len(ml)
    assert c.max_error <= c.tolerance
    assert c.sizes["total"] == sum(c.sizes[k] for k in ("connectivity", "positions", "headers", "culling", "padding"))
    p = small.positions
    for i in (0, len(ml) - 1):
        verts, tris, pos = c.decode(i)
        vo, _, vc, _ = ml.meshlets[i]
        assert sorted(verts) == sorted(ml.vertices[vo : vo + vc])
        assert tris.shape[1] == 3 and tris.max() < len(verts)
        assert np.abs(pos - p[verts]).max() <= c.tolerance
    path = tmp_path / f"c-{fmt}.mlc"
    c.save(path)
    assert path.read_bytes() == c.to_bytes()
    cli("check", SMALL, path)


def test_compression_errors(small):
    ml = meshletlab.build(small, "meshopt")
    with pytest.raises(meshletlab.CompressError, match="unknown format 'zip' \\(formats: meshopt, laced-wires"):
        meshletlab.compress(small, ml, format="zip")
    with pytest.raises(meshletlab.CompressError, match="tolerance must be a positive number, not -1"):
        meshletlab.compress(small, ml, tolerance=-1.0)
    with pytest.raises(meshletlab.CompressError, match="not both"):
        meshletlab.compress(small, ml, tolerance=1e-3, relative_tolerance=1e-3)
    wide = meshletlab.build(small, "meshopt", limits=(128, 128))
    with pytest.raises(meshletlab.CompressError, match="gen:cad-part-128: .*64"):
        meshletlab.compress(small, wide, format="laced-wires")
    c = meshletlab.compress(small, ml)
    with pytest.raises(meshletlab.CompressError, match=f"meshlet {len(ml)} out of range"):
        c.decode(len(ml))
    with pytest.raises(meshletlab.FileError, match="no-such-dir.*cannot write"):
        c.save("/nonexistent/no-such-dir/c.mlc")


def test_glb_export(small, tmp_path):
    ml = meshletlab.build(small, "meshopt")
    data = meshletlab.export_glb(small, ml)
    assert data[:4] == b"glTF" and int.from_bytes(data[8:12], "little") == len(data)
    path = tmp_path / "m.glb"
    assert meshletlab.export_glb(small, ml, path) is None
    assert path.read_bytes() == data
    # The file is a mesh again: every meshlet's triangles, vertices split where meshlets meet.
    back = meshletlab.load(path)
    assert back.triangle_count == small.triangle_count
    with pytest.raises(meshletlab.FileError, match="cannot write"):
        meshletlab.export_glb(small, ml, tmp_path / "no" / "m.glb")


def test_lod_levels_and_errors(cli, medium, tmp_path):
    lod = meshletlab.lod.build(medium, "meshopt", group_size=8)
    levels = lod.levels
    assert len(levels) >= 3 and lod.meshlet_count == sum(len(l) for l in levels)
    base = levels[0].meshlets
    meshletlab.validate(medium, base)
    assert (levels[0].errors == 0).all()
    triangles = [int(l.meshlets.meshlets[:, 3].sum()) for l in levels]
    assert triangles[0] == medium.triangle_count
    assert all(b < a for a, b in zip(triangles, triangles[1:])), triangles
    for l in levels:
        assert len(l.errors) == len(l) == len(l.parent_errors) == len(l.groups)
        assert (l.parent_errors >= l.errors).all()
    assert np.isinf(levels[-1].parent_errors).all() and lod.roots == len(levels[-1])
    path = tmp_path / "m.lod"
    lod.save(path)
    cli("lod-check", "gen:noisy-sphere", path, "--views", "20")
    with pytest.raises(meshletlab.FileError, match="cannot write"):
        lod.save(tmp_path / "no" / "m.lod")
    with pytest.raises(meshletlab.OptionError, match="group_size must be at least 1"):
        meshletlab.lod.build(medium, group_size=0)
    with pytest.raises(meshletlab.OptionError, match="lod.build\\(\\) got an unexpected keyword argument 'levels'"):
        meshletlab.lod.build(medium, levels=3)
    with pytest.raises(meshletlab.StrategyError):
        meshletlab.lod.build(medium, "nope")
