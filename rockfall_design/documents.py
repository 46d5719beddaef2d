"""Moved: the HTML and Markdown reports are now :mod:`rockfall_design.report.documents`.

This module stays so that ``from rockfall_design.documents import ...`` in
users' scripts and notebooks keeps working: it hands on the public names of
:mod:`rockfall_design.report.documents`, which new code imports instead.
"""

from .report.documents import (
    Table,
    render_html,
    render_markdown,
    report_context,
    write_report,
)

__all__ = ["Table", "report_context", "render_html", "render_markdown", "write_report"]
