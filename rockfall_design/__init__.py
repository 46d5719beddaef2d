"""rockfall-design: rockfall trajectories and the least-cost design of protection."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("rockfall-design")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"

__all__ = ["__version__"]
