"""The exception classes of meshletlab.

Every error the module raises is an :class:`Error`; each family also derives from the built-in
exception a caller would catch for it, and carries the Rust crate's message (which names the
file, the argument or the element at fault).
"""


class Error(Exception):
    """Base class of every meshletlab error."""


class MeshError(Error, ValueError):
    """Arrays or a file that make no valid mesh (shape, dtype, index range, non-finite
    positions, an unreadable or malformed file, an unknown ``gen:`` name)."""


class LimitsError(Error, ValueError):
    """Limits outside 3..=256 vertices and 1..=256 triangles, or not a pair."""


class StrategyError(Error, ValueError):
    """A strategy name that no strategy (or, with ``device="gpu"``, no GPU strategy) answers to."""


class OptionError(Error, TypeError, ValueError):
    """A keyword that is no option, or an option value of the wrong type or range."""


class ValidationError(Error, ValueError):
    """Meshlets that are not a valid partition of their mesh within their limits."""


class LabelsError(Error, ValueError):
    """Cluster ids that make no meshlets: wrong length, negative, or a cluster over the limits
    without ``split=True``."""


class FileError(Error, OSError):
    """A meshlet, LOD, label or output file that cannot be read, parsed or written."""


class CompressError(Error, ValueError):
    """Meshlets a codec cannot encode, an unknown format, or a tolerance that is not positive."""


class GpuError(Error, RuntimeError):
    """No Vulkan adapter, a device fault, or a module built without GPU support."""


__all__ = [
    "Error",
    "MeshError",
    "LimitsError",
    "StrategyError",
    "OptionError",
    "ValidationError",
    "LabelsError",
    "FileError",
    "CompressError",
    "GpuError",
]
