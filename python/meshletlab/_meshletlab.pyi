"""Type stubs of the Rust extension (python/src/)."""

import os
from typing import Any, Literal, Optional, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, os.PathLike[str]]
_Limits = Union[tuple[int, int], str]

GPU: bool
"""Whether the module was built with the ``gpu`` feature."""
STRATEGY_OPTIONS: list[str]
"""The keyword options ``build`` and ``lod.build`` take."""

class Mesh:
    """A triangle mesh, checked on construction; the arrays are copied once, into the mesh."""

    def __init__(
        self,
        positions: npt.ArrayLike,
        indices: npt.ArrayLike,
        name: str = "<arrays>",
    ) -> None: ...
    @property
    def positions(self) -> npt.NDArray[np.float32]:
        """(n, 3) float32, a copy."""
    @property
    def indices(self) -> npt.NDArray[np.uint32]:
        """(m, 3) uint32, a copy."""
    @property
    def vertex_count(self) -> int: ...
    @property
    def triangle_count(self) -> int: ...
    @property
    def name(self) -> str: ...

class Meshlets:
    """Meshlets of a mesh in meshoptimizer's layout, with the limits they were made for."""

    def __init__(
        self,
        mesh: Mesh,
        meshlets: npt.ArrayLike,
        vertices: npt.ArrayLike,
        triangles: npt.ArrayLike,
        limits: _Limits = (64, 126),
    ) -> None: ...
    @property
    def meshlets(self) -> npt.NDArray[np.uint32]:
        """M x 4: vertex offset, triangle offset, vertex count, triangle count."""
    @property
    def vertices(self) -> npt.NDArray[np.uint32]: ...
    @property
    def triangles(self) -> npt.NDArray[np.uint8]: ...
    @property
    def limits(self) -> tuple[int, int]: ...
    @property
    def mesh(self) -> Mesh: ...
    @property
    def source(self) -> str: ...
    @property
    def build_ms(self) -> Optional[float]: ...
    @property
    def clusters(self) -> Optional[int]: ...
    @property
    def split_clusters(self) -> Optional[int]: ...
    def triangle_labels(self) -> npt.NDArray[np.uint32]: ...
    def save_npz(self, path: _Path) -> None: ...
    def __len__(self) -> int: ...

class Compressed:
    """A compressed-meshlet file, checked by decoding every meshlet."""

    @property
    def format(self) -> str: ...
    @property
    def tolerance(self) -> float: ...
    @property
    def max_error(self) -> float: ...
    @property
    def sizes(self) -> dict[str, int]: ...
    def to_bytes(self) -> bytes: ...
    def save(self, path: _Path) -> None: ...
    def decode(
        self, i: int
    ) -> tuple[
        npt.NDArray[np.uint32], npt.NDArray[np.uint8], npt.NDArray[np.float32]
    ]: ...
    def __len__(self) -> int: ...

class LodLevel:
    @property
    def meshlets(self) -> Meshlets: ...
    @property
    def errors(self) -> npt.NDArray[np.float32]: ...
    @property
    def parent_errors(self) -> npt.NDArray[np.float32]: ...
    @property
    def groups(self) -> npt.NDArray[np.uint32]: ...
    def __len__(self) -> int: ...

class Lod:
    @property
    def levels(self) -> list[LodLevel]: ...
    @property
    def meshlet_count(self) -> int: ...
    @property
    def roots(self) -> int: ...
    @property
    def stuck_groups(self) -> int: ...
    def save(self, path: _Path) -> None: ...

def load(path: _Path) -> Mesh: ...
def build(
    mesh: Mesh,
    strategy: str = "kmedoids",
    limits: _Limits = (64, 126),
    device: Literal["cpu", "gpu"] = "cpu",
    *,
    cone_weight: float = ...,
    cache_size: int = ...,
    fill_weight: float = ...,
    kmedoids_iterations: int = ...,
    kmedoids_threshold: float = ...,
    kmedoids_grow: Literal["centre", "hops"] = ...,
    kmedoids_regions: int = ...,
    kmedoids_moves: int = ...,
    paper_budget: float = ...,
    local_order: bool = ...,
    meshlet_order: Literal["built", "triangles", "vertices"] = ...,
) -> Meshlets: ...
def from_labels(
    mesh: Mesh,
    labels: npt.ArrayLike,
    split: bool = False,
    limits: _Limits = (64, 126),
) -> Meshlets: ...
def read_labels(path: _Path, mesh: Mesh) -> npt.NDArray[np.uint64]: ...
def write_labels(path: _Path, labels: npt.ArrayLike) -> None: ...
def load_meshlets(path: _Path, mesh: Mesh, limits: _Limits = (64, 126)) -> Meshlets: ...
def validate(mesh: Mesh, meshlets: Meshlets, limits: Optional[_Limits] = None) -> None: ...
def metrics(mesh: Mesh, meshlets: Meshlets) -> dict[str, Any]: ...
def bounds(mesh: Mesh, meshlets: Meshlets) -> dict[str, npt.NDArray[np.float32]]: ...
def export_glb(
    mesh: Mesh, meshlets: Meshlets, path: Optional[_Path] = None
) -> Optional[bytes]: ...
def compress(
    mesh: Mesh,
    meshlets: Meshlets,
    format: str = "meshopt",
    tolerance: Optional[float] = None,
    relative_tolerance: Optional[float] = None,
) -> Compressed: ...
def lod_build(
    mesh: Mesh,
    strategy: str = "meshopt",
    limits: _Limits = (64, 126),
    group_size: int = 8,
    **options: Any,
) -> Lod: ...
def strategies() -> list[str]: ...
def gpu_strategies() -> list[str]: ...
