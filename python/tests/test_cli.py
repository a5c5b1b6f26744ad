"""Round trips with the command line: the module measures what `meshletlab stats --json` measures,
the files each writes the other reads."""

import numpy as np
import pytest

import meshletlab
from conftest import MEDIUM, SMALL, row, same_metrics
from test_labels import grid_labels


@pytest.mark.parametrize(
    "strategy, limits, options, flags",
    [
        ("meshopt", (64, 126), {}, []),
        ("kmedoids", (64, 84), {}, ["-l", "64/84"]),
        ("meshopt", (128, 128), {"cone_weight": 0.5, "meshlet_order": "vertices"},
         ["-l", "128/128", "--cone-weight", "0.5", "--meshlet-order", "vertices"]),
        ("kmedoids-parallel", (64, 126), {"kmedoids_regions": 1024}, ["--kmedoids-regions", "1024"]),
    ],
)
def test_metrics_equal_the_command_lines(cli, medium, strategy, limits, options, flags):
    report = cli("stats", MEDIUM, "-s", strategy, *flags, "--json")
    ours = meshletlab.metrics(medium, meshletlab.build(medium, strategy, limits, **options))
    theirs = row(report, strategy)["metrics"]
    same_metrics(ours, theirs)
    assert ours["meshlets"] == theirs["meshlets"] > 0


def test_labels_from_numpy_measure_as_the_command_lines_labels(cli, small, tmp_path):
    labels = grid_labels(small, 6)
    path = tmp_path / "grid.txt"
    meshletlab.write_labels(path, labels)
    report = cli("stats", SMALL, "--labels", path, "--split", "--json")
    ours = meshletlab.metrics(small, meshletlab.from_labels(small, labels, split=True))
    same_metrics(ours, row(report, "labels:grid.txt")["metrics"])
    # Without --split the command line refuses the same cluster the module does.
    ml = meshletlab.from_labels(small, grid_labels(small, 12))
    meshletlab.write_labels(tmp_path / "fine.npy", ml.triangle_labels())
    fine = cli("stats", SMALL, "--labels", tmp_path / "fine.npy", "--json")
    same_metrics(meshletlab.metrics(small, ml), row(fine, "labels:fine.npy")["metrics"])


def test_an_npz_the_module_wrote_round_trips_through_the_command_line(cli, medium, tmp_path):
    ml = meshletlab.build(medium, "kmedoids", limits=(64, 84))
    path = tmp_path / "km.npz"
    ml.save_npz(path)
    with np.load(path) as z:
        assert sorted(z.files) == ["meshlets", "triangles", "vertices"]
        assert z["meshlets"].dtype == np.uint32 and z["triangles"].dtype == np.uint8
        np.testing.assert_array_equal(z["meshlets"], ml.meshlets)
        np.testing.assert_array_equal(z["vertices"], ml.vertices)
        np.testing.assert_array_equal(z["triangles"], ml.triangles)
    report = cli("stats", MEDIUM, "--meshlets", path, "-l", "64/84", "--json")
    same_metrics(meshletlab.metrics(medium, ml), row(report, "meshlets:km.npz")["metrics"])
    back = meshletlab.load_meshlets(path, medium, limits=(64, 84))
    np.testing.assert_array_equal(back.meshlets, ml.meshlets)
    np.testing.assert_array_equal(back.triangles, ml.triangles)
    # np.savez_compressed of the same arrays reads too (any integer dtype).
    np.savez_compressed(tmp_path / "c.npz", meshlets=ml.meshlets.astype(np.int64),
                        vertices=ml.vertices, triangles=ml.triangles)
    np.testing.assert_array_equal(meshletlab.load_meshlets(tmp_path / "c.npz", medium).vertices, ml.vertices)


def test_files_the_command_line_wrote_load_in_the_module(cli, small, tmp_path):
    mlt, labels = tmp_path / "out.mlt", tmp_path / "labels.txt"
    cli("build", SMALL, "-s", "greedy", "-o", mlt, "--labels-out", labels)
    ours = meshletlab.build(small, "greedy")
    theirs = meshletlab.load_meshlets(mlt, small)
    for k in ("meshlets", "vertices", "triangles"):
        np.testing.assert_array_equal(getattr(theirs, k), getattr(ours, k))
    np.testing.assert_array_equal(meshletlab.read_labels(labels, small), ours.triangle_labels())
    # A meshlet file is bound to its mesh: another mesh's is a FileError naming it.
    with pytest.raises(meshletlab.FileError, match="out.mlt"):
        meshletlab.load_meshlets(mlt, meshletlab.load(MEDIUM))


def test_bad_meshlet_files_are_file_errors(small, tmp_path):
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"not a zip")
    with pytest.raises(meshletlab.FileError, match="junk.npz: neither an .npz of meshlets"):
        meshletlab.load_meshlets(junk, small)
    with pytest.raises(meshletlab.FileError, match="missing.npz: cannot read"):
        meshletlab.load_meshlets(tmp_path / "missing.npz", small)
    ml = meshletlab.build(small, "meshopt")
    with pytest.raises(meshletlab.FileError, match="cannot write"):
        ml.save_npz(tmp_path / "no" / "dir.npz")
    # Another mesh's meshlets: the file is read, the check names what is wrong.
    part = tmp_path / "part.npz"
    np.savez(part, meshlets=ml.meshlets[:3], vertices=ml.vertices, triangles=ml.triangles)
    with pytest.raises(meshletlab.FileError, match="part.npz: not the mesh's meshlets"):
        meshletlab.load_meshlets(part, small)


def test_the_gpu_row_equals_the_module_gpu_build(cli, small):
    if not meshletlab.GPU:
        pytest.skip("module built without the gpu feature")
    try:
        ours = meshletlab.build(small, "kmedoids-flat", device="gpu")
    except meshletlab.GpuError as e:
        pytest.skip(str(e))
    report = cli("stats", SMALL, "-s", "kmedoids-flat", "--device", "gpu", "--json")
    same_metrics(meshletlab.metrics(small, ours), row(report, "kmedoids-flat")["metrics"])
