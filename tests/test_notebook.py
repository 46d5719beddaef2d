"""The example notebook runs from top to bottom, as a reader would run it."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

NOTEBOOK = Path(__file__).resolve().parents[1] / "examples" / "design_walkthrough.ipynb"


@pytest.mark.slow  # optimises a design in a real kernel: about half a minute
def test_the_walkthrough_notebook_runs():
    try:
        import nbformat
        from nbclient import NotebookClient
    except ImportError:  # pragma: no cover - the test extra installs both
        NotebookClient = None
    if NotebookClient is not None:
        nb = nbformat.read(NOTEBOOK, as_version=4)
        # Around the reader's cells: the kernel's backend (inline) is the same after them.
        nb.cells.insert(0, nbformat.v4.new_code_cell(
            "import matplotlib\n_backend_before = matplotlib.get_backend()"))
        nb.cells.append(nbformat.v4.new_code_cell(
            "assert matplotlib.get_backend() == _backend_before, "
            "(_backend_before, matplotlib.get_backend())\n"
            "print('backend', _backend_before)"))
        # A real kernel, started in examples/ as Jupyter would.
        NotebookClient(nb, timeout=600, kernel_name="python3",
                       resources={"metadata": {"path": str(NOTEBOOK.parent)}}).execute()
        errors = [o for c in nb.cells if c.cell_type == "code"
                  for o in c.get("outputs", []) if o.get("output_type") == "error"]
        assert not errors
        last = nb.cells[-1]["outputs"][0]["text"]
        assert "inline" in last  # the kernel's inline backend, left as it was
        figures = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
                   if "image/png" in o.get("data", {})]
        assert len(figures) >= 4  # envelopes, profile, alternatives, chosen design
        return
    # Without nbclient: the code cells as one script, in the notebook's folder.
    cells = json.loads(NOTEBOOK.read_text(encoding="utf-8"))["cells"]
    here = os.getcwd()
    os.chdir(NOTEBOOK.parent)
    try:
        namespace: dict = {}
        for cell in cells:
            if cell["cell_type"] == "code":
                source = "".join(cell["source"])
                exec(compile(source, str(NOTEBOOK), "exec"), namespace)  # noqa: S102
    finally:
        os.chdir(here)
    assert namespace["opt"].best is not None
