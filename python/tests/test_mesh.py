"""Meshes from numpy arrays and files: every dtype the module takes, and every way to get it wrong."""

import numpy as np
import pytest

import meshletlab

QUAD_P = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype=np.float32)
QUAD_I = np.array([[0, 1, 2], [2, 1, 3]])

INT_TYPES = [np.int8, np.int16, np.int32, np.int64, np.uint8, np.uint16, np.uint32, np.uint64]


@pytest.mark.parametrize("itype", INT_TYPES)
@pytest.mark.parametrize("ptype", [np.float32, np.float64])
def test_every_dtype_gives_the_same_mesh(itype, ptype):
    m = meshletlab.Mesh(QUAD_P.astype(ptype), QUAD_I.astype(itype))
    assert m.vertex_count == 4 and m.triangle_count == 2
    assert m.positions.dtype == np.float32 and m.indices.dtype == np.uint32
    np.testing.assert_array_equal(m.positions, QUAD_P)
    np.testing.assert_array_equal(m.indices, QUAD_I)


def test_flat_and_strided_inputs(small):
    p, i = small.positions, small.indices
    flat = meshletlab.Mesh(p, i.reshape(-1))
    np.testing.assert_array_equal(flat.indices, i)
    # Non-contiguous views: every other column of a wider array, a reversed copy of the rows.
    wide = np.zeros((p.shape[0], 6), dtype=np.float64)
    wide[:, ::2] = p
    strided = meshletlab.Mesh(wide[:, ::2], np.asfortranarray(i))
    np.testing.assert_array_equal(strided.positions, p)
    np.testing.assert_array_equal(strided.indices, i)
    assert meshletlab.Mesh(p.tolist(), i.tolist()).triangle_count == small.triangle_count


def test_loaded_and_generated_meshes_match_their_arrays(small):
    assert small.triangle_count == 3072 and small.name == "gen:cad-part-128"
    again = meshletlab.Mesh(small.positions, small.indices, name="copy")
    np.testing.assert_array_equal(again.positions, small.positions)
    assert "copy" in repr(again)


def test_a_ply_file_loads_like_its_arrays(tmp_path):
    ply = tmp_path / "quad.ply"
    ply.write_text(
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
        "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n3 2 1 3\n"
    )
    m = meshletlab.load(ply)
    np.testing.assert_array_equal(m.positions, QUAD_P)
    np.testing.assert_array_equal(m.indices, QUAD_I)


def bad(p, i, match):
    with pytest.raises(meshletlab.MeshError, match=match) as e:
        meshletlab.Mesh(p, i, name="bad")
    assert isinstance(e.value, meshletlab.Error) and isinstance(e.value, ValueError)
    assert str(e.value).startswith("bad")


def test_bad_arrays_are_mesh_errors():
    bad(QUAD_P[:, :2], QUAD_I, r"positions must have shape \(n, 3\), not \[4, 2\]")
    bad(QUAD_P.astype(np.int32), QUAD_I, "positions must be float32 or float64, not int32")
    bad(QUAD_P, QUAD_I.astype(np.float32), "indices must be an integer array")
    bad(QUAD_P, QUAD_I.reshape(-1)[:5], r"indices must have shape \(m, 3\)")
    bad(QUAD_P, QUAD_I.reshape(3, 2), r"indices must have shape \(m, 3\)")
    neg = QUAD_I.copy()
    neg[1, 2] = -1
    bad(QUAD_P, neg, r"index -1 \(triangle 1, corner 2\) is not a vertex index")
    big = QUAD_I.astype(np.uint64)
    big[0, 0] = 2**32
    bad(QUAD_P, big, r"index 4294967296 \(triangle 0, corner 0\)")
    # The crate's own checks, with its message.
    far = QUAD_I.copy()
    far[0, 1] = 9
    bad(QUAD_P, far, "triangle 0 references vertex 9, but there are only 4 vertices")
    nan = QUAD_P.copy()
    nan[2, 1] = np.nan
    bad(nan, QUAD_I, "vertex 2 has a non-finite coordinate")
    huge = QUAD_P.astype(np.float64)
    huge[3, 0] = 1e300  # past f32: infinite once rounded
    bad(huge, QUAD_I, "vertex 3 has a non-finite coordinate")
    bad(QUAD_P, np.zeros((0, 3), dtype=np.int32), "bad")


def test_bad_files_are_mesh_errors_naming_the_file(tmp_path):
    cases = [
        ("gen:no-such-mesh", "no generated mesh of that name"),
        (tmp_path / "missing.ply", "missing.ply: cannot read file"),
        (tmp_path, "is a directory"),
        (tmp_path / "mesh.xyz", "unknown mesh format"),
    ]
    broken = tmp_path / "broken.ply"
    broken.write_text("ply\nformat ascii 1.0\nelement vertex 3\nend_header\n0 0\n")
    cases.append((broken, "broken.ply"))
    for path, match in cases:
        with pytest.raises(meshletlab.MeshError, match=match):
            meshletlab.load(path)
