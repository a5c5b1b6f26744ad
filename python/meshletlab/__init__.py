"""meshletlab: build, measure, compress and level-of-detail meshlets (triangle clusters for GPU
mesh shaders) from numpy arrays, with the Rust crate's strategies, validator and metrics.

>>> import numpy as np, meshletlab
>>> mesh = meshletlab.load("gen:knot-tube")
>>> ml = meshletlab.build(mesh, "meshopt", limits=(64, 126))
>>> meshletlab.validate(mesh, ml)
>>> meshletlab.metrics(mesh, ml)["meshlets"] == len(ml)
True
"""

from . import lod
from ._errors import (
    CompressError,
    Error,
    FileError,
    GpuError,
    LabelsError,
    LimitsError,
    MeshError,
    OptionError,
    StrategyError,
    ValidationError,
)
from ._meshletlab import (
    GPU,
    STRATEGY_OPTIONS,
    Compressed,
    Mesh,
    Meshlets,
    bounds,
    build,
    compress,
    export_glb,
    from_labels,
    gpu_strategies,
    load,
    load_meshlets,
    metrics,
    read_labels,
    strategies,
    validate,
    write_labels,
)

__all__ = [
    "GPU",
    "STRATEGY_OPTIONS",
    "Compressed",
    "CompressError",
    "Error",
    "FileError",
    "GpuError",
    "LabelsError",
    "LimitsError",
    "Mesh",
    "MeshError",
    "Meshlets",
    "OptionError",
    "StrategyError",
    "ValidationError",
    "bounds",
    "build",
    "compress",
    "export_glb",
    "from_labels",
    "gpu_strategies",
    "load",
    "load_meshlets",
    "lod",
    "metrics",
    "read_labels",
    "strategies",
    "validate",
    "write_labels",
]
