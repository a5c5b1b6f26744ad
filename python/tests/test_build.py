"""build(): every strategy's meshlets in meshoptimizer's layout, the options, limits, devices and
their errors, and the GIL left free while a build runs."""

import threading
import time

import numpy as np
import pytest

import meshletlab
from conftest import canonical, global_triangles

# kmedoids-paper is slow by design (the command line's `all` leaves it out too).
FAST = [s for s in meshletlab.strategies() if s != "kmedoids-paper"]


@pytest.mark.parametrize("strategy", FAST)
def test_every_strategy_builds_a_valid_partition(small, strategy):
    ml = meshletlab.build(small, strategy, limits=(64, 84))
    meshletlab.validate(small, ml)
    assert ml.limits == (64, 84) and ml.source == strategy and ml.build_ms > 0
    rows = ml.meshlets
    assert rows.dtype == np.uint32 and rows.shape == (len(ml), 4)
    assert ml.vertices.dtype == np.uint32 and ml.triangles.dtype == np.uint8
    assert rows[:, 2].max() <= 64 and rows[:, 3].max() <= 84
    # The arrays alone give back the mesh's triangles, each once: the layout is meshoptimizer's.
    np.testing.assert_array_equal(global_triangles(ml), canonical(small.indices))


def test_builds_are_deterministic_and_the_suffixes_work(small):
    a = meshletlab.build(small, "kmedoids")
    b = meshletlab.build(small, "kmedoids")
    for k in ("meshlets", "vertices", "triangles"):
        np.testing.assert_array_equal(getattr(a, k), getattr(b, k))
    base = meshletlab.build(small, "greedy")
    refined = meshletlab.build(small, "greedy+refine-fast")
    meshletlab.validate(small, refined)
    assert len(refined) <= len(base)


def test_options_reach_the_strategy(small):
    plain = meshletlab.build(small, "meshopt")
    ordered = meshletlab.build(small, "meshopt", meshlet_order="triangles")
    counts = ordered.meshlets[:, 3]
    assert (np.diff(counts.astype(np.int64)) <= 0).all()
    assert sorted(counts) == sorted(plain.meshlets[:, 3])
    coned = meshletlab.build(small, "meshopt", cone_weight=1.0)
    assert not np.array_equal(coned.vertices, plain.vertices)
    hops = meshletlab.build(small, "kmedoids", kmedoids_grow="hops", kmedoids_iterations=2)
    meshletlab.validate(small, hops)
    local = meshletlab.build(small, "greedy", local_order=True)
    np.testing.assert_array_equal(global_triangles(local), canonical(small.indices))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"cone_wieght": 0.5}, "build\\(\\) got an unexpected keyword argument 'cone_wieght'"),
        ({"cone_weight": 2.0}, "cone_weight must be a number in 0..=1, not 2.0"),
        ({"cone_weight": "x"}, "cone_weight must be a number in 0..=1, not 'x'"),
        ({"cache_size": 0}, "cache_size must be an integer in 1..=256, not 0"),
        ({"fill_weight": -1}, "fill_weight must be a finite number >= 0"),
        ({"kmedoids_iterations": -3}, "kmedoids_iterations must be an integer"),
        ({"kmedoids_threshold": float("nan")}, "kmedoids_threshold must be a finite number >= 0"),
        ({"kmedoids_grow": "up"}, "kmedoids_grow: unknown k-medoids growth 'up'"),
        ({"kmedoids_regions": 0}, "kmedoids_regions must be an integer in 1"),
        ({"paper_budget": 0}, "paper_budget must be a positive number of seconds"),
        ({"local_order": 1}, "local_order must be True or False"),
        ({"meshlet_order": "random"}, "meshlet_order: unknown meshlet order 'random'"),
        ({"device": "tpu"}, "device must be 'cpu' or 'gpu', not 'tpu'"),
    ],
)
def test_bad_options_are_option_errors(small, kwargs, match):
    with pytest.raises(meshletlab.OptionError, match=match) as e:
        meshletlab.build(small, "meshopt", **kwargs)
    assert isinstance(e.value, TypeError) and isinstance(e.value, meshletlab.Error)


def test_bad_strategies_and_limits(small):
    with pytest.raises(meshletlab.StrategyError, match="unknown strategy 'nope'"):
        meshletlab.build(small, "nope")
    with pytest.raises(meshletlab.StrategyError, match="retired: use kmedoids-parallel"):
        meshletlab.build(small, "kmedoids-tiled")
    for limits, match in [
        ((2, 10), "max vertices must be in 3..=256, got 2"),
        ((64, 257), "max triangles must be in 1..=256, got 257"),
        ((-1, 10), "max vertices must be in 3..=256, got 0"),
        ("64", "limits '64' must look like 64/126"),
        ("x/126", "'x' is not a vertex count"),
        ((64,), "must be a \\(max_vertices, max_triangles\\) pair"),
    ]:
        with pytest.raises(meshletlab.LimitsError, match=match):
            meshletlab.build(small, "meshopt", limits=limits)
    assert meshletlab.build(small, "meshopt", limits="128/128").limits == (128, 128)


def test_gpu_builds_equal_the_cpu_or_say_why_not(small):
    if not meshletlab.GPU:
        with pytest.raises(meshletlab.GpuError, match="built without GPU support"):
            meshletlab.build(small, "kmedoids-parallel", device="gpu")
        assert meshletlab.gpu_strategies() == []
        return
    assert "kmedoids-parallel" in meshletlab.gpu_strategies()
    # A strategy without a GPU path is refused before any adapter is opened.
    with pytest.raises(meshletlab.StrategyError, match="strategy 'meshopt' has no GPU path"):
        meshletlab.build(small, "meshopt", device="gpu")
    try:
        gpu = meshletlab.build(small, "kmedoids-parallel", device="gpu")
    except meshletlab.GpuError as e:
        if "no Vulkan adapter" in str(e):
            pytest.skip(str(e))
        raise
    cpu = meshletlab.build(small, "kmedoids-parallel")
    for k in ("meshlets", "vertices", "triangles"):
        np.testing.assert_array_equal(getattr(gpu, k), getattr(cpu, k))


def test_the_gil_is_released_during_a_build(medium):
    """A Python thread keeps running while another builds: the longest pause between its steps
    is far shorter than the build."""
    done = []
    t = threading.Thread(target=lambda: done.append(meshletlab.build(medium, "kmedoids-flat")))
    last, gap = time.perf_counter(), 0.0
    t.start()
    while t.is_alive():
        now = time.perf_counter()
        gap, last = max(gap, now - last), now
    t.join()
    build_s = done[0].build_ms / 1e3
    assert build_s > 0.1, "the build is too quick to tell"
    assert gap < build_s / 2, (gap, build_s)
