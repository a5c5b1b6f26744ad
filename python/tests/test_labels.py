"""Clusterings made in numpy: labels of any integer dtype, the label files, the way back through
triangle_labels(), and every error of the labels path."""

import numpy as np
import pytest

import meshletlab
from conftest import canonical, global_triangles, same_metrics

INT_TYPES = [np.int8, np.int16, np.int32, np.int64, np.uint8, np.uint16, np.uint32, np.uint64]


def grid_labels(mesh, cells):
    """A spatial grid over the triangle centroids: cells**3 cells, ids in 0..cells**3."""
    p = mesh.positions[mesh.indices].mean(axis=1)
    lo, hi = p.min(axis=0), p.max(axis=0)
    ijk = np.minimum(((p - lo) / (hi - lo) * cells).astype(np.int64), cells - 1)
    return (ijk[:, 0] * cells + ijk[:, 1]) * cells + ijk[:, 2]


def same_meshlets(a, b):
    for k in ("meshlets", "vertices", "triangles"):
        np.testing.assert_array_equal(getattr(a, k), getattr(b, k))


def test_labels_of_every_dtype_give_the_same_meshlets(small):
    labels = grid_labels(small, 4)  # 64 cells: ids below 127 fit int8
    ref = meshletlab.from_labels(small, labels, split=True)
    meshletlab.validate(small, ref)
    np.testing.assert_array_equal(global_triangles(ref), canonical(small.indices))
    assert ref.source == "labels" and ref.clusters == len(np.unique(labels))
    assert len(ref) >= ref.clusters
    for t in INT_TYPES:
        same_meshlets(meshletlab.from_labels(small, labels.astype(t), split=True), ref)
    same_meshlets(meshletlab.from_labels(small, labels.reshape(-1, 1), split=True), ref)
    same_meshlets(meshletlab.from_labels(small, list(labels), split=True), ref)


def test_without_split_each_cluster_is_one_meshlet_in_id_order(small):
    labels = grid_labels(small, 12)
    ml = meshletlab.from_labels(small, labels)
    assert ml.split_clusters == 0 and len(ml) == ml.clusters
    ids = np.unique(labels)
    back = ml.triangle_labels()
    # Meshlet k holds exactly the triangles of the k-th smallest id.
    np.testing.assert_array_equal(ids[back], labels)


def test_a_strategys_labels_give_back_its_meshlets(small):
    built = meshletlab.build(small, "meshopt")
    labels = built.triangle_labels()
    assert labels.dtype == np.uint32 and labels.shape == (small.triangle_count,)
    again = meshletlab.from_labels(small, labels)
    assert len(again) == len(built) and again.split_clusters == 0
    for i in range(len(built)):
        assert sorted(again.vertices[again.meshlets[i, 0] : again.meshlets[i, 0] + again.meshlets[i, 2]]) == sorted(
            built.vertices[built.meshlets[i, 0] : built.meshlets[i, 0] + built.meshlets[i, 2]]
        )
    same_metrics(meshletlab.metrics(small, again), meshletlab.metrics(small, built))


@pytest.mark.parametrize("suffix", [".txt", ".npy"])
def test_labels_from_numpy_equal_the_same_labels_from_a_file(small, tmp_path, suffix):
    labels = grid_labels(small, 6)
    path = tmp_path / f"labels{suffix}"
    meshletlab.write_labels(path, labels)
    if suffix == ".txt":
        assert path.read_text().split() == [str(x) for x in labels]
    else:
        np.testing.assert_array_equal(np.load(path), labels)
    read = meshletlab.read_labels(path, small)
    assert read.dtype == np.uint64
    np.testing.assert_array_equal(read, labels)
    same_meshlets(meshletlab.from_labels(small, read, split=True), meshletlab.from_labels(small, labels, split=True))
    # A file numpy wrote itself reads the same.
    np.savetxt(tmp_path / "np.txt", labels, fmt="%d")
    np.testing.assert_array_equal(meshletlab.read_labels(tmp_path / "np.txt", small), labels)


def test_bad_labels_are_labels_errors(small):
    t = small.triangle_count
    ok = np.zeros(t, dtype=np.int64)
    with pytest.raises(meshletlab.LabelsError, match=f"{t - 1} cluster ids for a mesh of {t} triangles"):
        meshletlab.from_labels(small, ok[1:])
    neg = ok.copy()
    neg[5] = -2
    with pytest.raises(meshletlab.LabelsError, match=r"labels\[5\] = -2: cluster ids are non-negative"):
        meshletlab.from_labels(small, neg)
    with pytest.raises(meshletlab.LabelsError, match="must be an integer array, not float64"):
        meshletlab.from_labels(small, ok.astype(np.float64))
    with pytest.raises(meshletlab.LabelsError, match="labels must be one axis"):
        meshletlab.from_labels(small, ok.reshape(-1, 3))
    # One cluster of every triangle is over the limits: refused by id unless split.
    seven = np.full(t, 7, dtype=np.uint16)
    with pytest.raises(meshletlab.LabelsError, match=f"cluster 7: {t} triangles and .* over the limits 64/126"):
        meshletlab.from_labels(small, seven)
    split = meshletlab.from_labels(small, seven, split=True, limits=(64, 84))
    assert split.clusters == 1 and split.split_clusters == 1 and len(split) >= t / 84
    meshletlab.validate(small, split)
    with pytest.raises(meshletlab.LimitsError):
        meshletlab.from_labels(small, ok, limits=(0, 0))
    with pytest.raises(meshletlab.LabelsError, match=r"labels\[0\] = 4294967296: a label file holds ids"):
        meshletlab.write_labels("/tmp/never-written.txt", np.array([2**32], dtype=np.uint64))


def test_bad_label_files_are_file_errors(small, tmp_path):
    missing = tmp_path / "missing.txt"
    with pytest.raises(meshletlab.FileError, match="missing.txt: cannot read") as e:
        meshletlab.read_labels(missing, small)
    assert isinstance(e.value, OSError)
    text = tmp_path / "bad.txt"
    text.write_text("0\n-4\n")
    with pytest.raises(meshletlab.FileError, match="bad.txt: line 2: negative cluster id -4"):
        meshletlab.read_labels(text, small)
    short = tmp_path / "short.txt"
    short.write_text("0\n1\n")
    with pytest.raises(meshletlab.FileError, match=f"2 cluster ids for a mesh of {small.triangle_count}"):
        meshletlab.read_labels(short, small)
    with pytest.raises(meshletlab.FileError, match="cannot write"):
        meshletlab.write_labels(tmp_path / "no" / "dir" / "l.txt", np.zeros(3, dtype=np.uint8))
