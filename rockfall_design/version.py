"""The installed version of rockfall-design, recorded in every run's outputs.

A file of its own, at the bottom of the house (it imports nothing of the
package), so that any room can stamp its outputs without importing the
public face.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__: str = version("rockfall-design")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"
