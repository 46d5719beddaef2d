"""The terrain extra: its libraries imported on demand, its errors one line each."""

from __future__ import annotations

import importlib
from types import ModuleType

from ..errors import InputError

__all__ = ["INSTALL_HINT", "TerrainError", "require"]

#: What to run when a library of the extra is missing.
INSTALL_HINT = ("python -m pip install 'rockfall-design[terrain]' "
                "(or '.[terrain]' in the repository)")


class TerrainError(InputError):
    """A terrain input that cannot be used: one line naming the file and the point.

    An :class:`~rockfall_design.errors.InputError`: exit code 2 (bad input).
    """

    def __init__(self, file: str, message: str) -> None:
        self.file = file
        super().__init__(f"{file}: {message}" if file else message)


def require(module: str, what: str) -> ModuleType:
    """Import ``module`` of the terrain extra, or say which extra to install.

    Parameters
    ----------
    module
        The module's name (``rasterio``, ``pyogrio``, ``laspy``, ...).
    what
        What needs it, for the message (``reading the DEM terrain.tif``).

    Returns
    -------
    module
        The imported module.

    Raises
    ------
    TerrainError
        The module is not installed: one line naming the extra (exit code 2).
    """
    try:
        return importlib.import_module(module)
    except ImportError:
        raise TerrainError(
            "", f"{what} needs {module}, of the optional extra [terrain]: {INSTALL_HINT}"
        ) from None
