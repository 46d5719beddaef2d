"""Build real, installed-looking plugin distributions in a temporary directory.

``importlib.metadata`` finds a distribution through a ``NAME-VERSION.dist-info``
directory on ``sys.path``; its ``entry_points.txt`` declares the plugin. So a
directory holding a package and its dist-info, put on ``sys.path``, is seen
exactly as a ``pip install``-ed plugin would be, without pip.
"""

from __future__ import annotations

import importlib
import textwrap
from pathlib import Path

__all__ = ["write_distribution"]


def write_distribution(
    tmp_path: Path,
    name: str,
    module_source: str,
    entry_name: str,
    *,
    version: str = "1.0",
    dist_name: str | None = None,
    group: str = "rockfall_design",
) -> Path:
    """Write package ``name`` and its dist-info with one entry point into ``tmp_path``.

    Parameters
    ----------
    tmp_path
        Directory to write into; put it on ``sys.path`` (e.g.
        ``monkeypatch.syspath_prepend(tmp_path)``) for it to be found.
    name
        Import name of the package (``thirdparty_rockfall``).
    module_source
        Source of the package's ``__init__.py`` (dedented here).
    entry_name
        Name of the entry point (``third``), which becomes the plugin name.
    version
        Version of the distribution.
    dist_name
        Distribution name; by default ``name`` with ``_`` replaced by ``-``.
    group
        Entry-point group.

    Returns
    -------
    Path
        The dist-info directory.
    """
    tmp_path = Path(tmp_path)
    dist = dist_name or name.replace("_", "-")
    pkg = tmp_path / name
    pkg.mkdir(parents=True, exist_ok=True)
    (pkg / "__init__.py").write_text(textwrap.dedent(module_source), encoding="utf-8")
    info = tmp_path / f"{dist.replace('-', '_')}-{version}.dist-info"
    info.mkdir(parents=True, exist_ok=True)
    (info / "METADATA").write_text(
        f"Metadata-Version: 2.1\nName: {dist}\nVersion: {version}\n", encoding="utf-8"
    )
    (info / "entry_points.txt").write_text(
        f"[{group}]\n{entry_name} = {name}\n", encoding="utf-8"
    )
    importlib.invalidate_caches()
    return info


#: The example third-party plugin of the repository (a rockfall embankment).
EMBANKMENT_EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "rockfall-embankment"


def install_embankment_example(tmp_path: Path, monkeypatch: object) -> Path:
    """Install ``examples/rockfall-embankment`` as the distribution rockfall-embankment.

    As ``python -m pip install ./examples/rockfall-embankment`` would, without
    pip: its package and a dist-info with its entry point, put on ``sys.path``
    with ``monkeypatch.syspath_prepend``. Cached registries of the API are
    cleared, so that the helpers of ``rockfall_design.testing`` see it.

    Returns
    -------
    Path
        The directory put on ``sys.path``.
    """
    import rockfall_design.api as api

    site = Path(tmp_path) / "site-embankment"
    source = (EMBANKMENT_EXAMPLE / "rockfall_embankment" / "__init__.py").read_text(
        encoding="utf-8")
    write_distribution(site, "rockfall_embankment", source, "embankment",
                       dist_name="rockfall-embankment")
    monkeypatch.syspath_prepend(str(site))  # type: ignore[attr-defined]
    monkeypatch.setattr(api, "_REGISTRIES", {})  # type: ignore[attr-defined]
    return site
