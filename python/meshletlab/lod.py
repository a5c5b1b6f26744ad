"""Cluster level of detail: ``build(mesh, strategy="meshopt", limits=(64, 126), group_size=8,
**options)`` makes the meshlet DAG (level 0 is the strategy's meshlets; each level above groups
about ``group_size`` meshlets, simplifies them to half and splits them again). The result's
``levels`` hold each level's meshlets and errors; ``save(path)`` writes the LOD file that
``meshletlab lod-check`` reads.
"""

from ._meshletlab import Lod, LodLevel
from ._meshletlab import lod_build as build

__all__ = ["Lod", "LodLevel", "build"]
