"""Progress on the terminal: the one place that builds progress bars.

Every long run reports progress through a callback: rocks done (a
simulation or a check), ``stage, done, total`` (the optimiser's stages, a
calibration's fits) or ``done, total, rocks_done`` (a study's scenarios).
Each function here returns ``(bar, callback)``: ``bar`` a transient rich
progress display on stderr to enter around the run (or None when nothing is
shown), ``callback`` what the run calls (or None).

The command line's callbacks are also safe points: between batches they
stop the run if an interrupt was noted whose exception got lost
(:func:`~rockfall_design.report.interrupts.check_interrupt`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from .interrupts import check_interrupt

__all__ = [
    "progress_bar",
    "rocks_progress",
    "scenarios_progress",
    "fits_progress",
    "interruptible_rocks",
    "interruptible_stages",
]


def progress_bar(*columns: Any, remaining: bool = False) -> Any:
    """A transient rich progress display on stderr: description, bar, ``done/total``.

    Parameters
    ----------
    *columns
        More columns after ``done/total`` (e.g. ``"{task.fields[rate]}"``).
    remaining
        Show the time remaining instead of the time elapsed.

    Returns
    -------
    rich.progress.Progress
    """
    # rich is imported where a bar is drawn: a run without a terminal never needs it.
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    return Progress("[progress.description]{task.description}", BarColumn(),
                    MofNCompleteColumn(), *columns,
                    TimeRemainingColumn() if remaining else TimeElapsedColumn(),
                    console=Console(stderr=True), transient=True)


def _staged(bar: Any, label: Callable[[str], str] = str) -> Callable[[str, int, int], None]:
    """The callback ``(stage, done, total)`` that keeps one task of ``bar`` per stage."""
    tasks: dict[str, Any] = {}

    def staged(stage: str, done: int, total: int) -> None:
        if stage not in tasks:
            tasks[stage] = bar.add_task(label(stage), total=total)
        bar.update(tasks[stage], completed=done, total=total)

    return staged


def rocks_progress(progress: bool | Callable[..., None], total: int,
                   stages: bool = False) -> tuple[Any, Any]:
    """The API's ``progress=``: a bar of ``total`` rocks (or of stages), a callable, or nothing.

    Parameters
    ----------
    progress
        True shows a bar; a callable is called as the run reports (``done``
        rocks, or ``stage, done, total`` when ``stages``); False shows nothing.
    total
        Rocks of the run (the bar's total when not ``stages``).
    stages
        The run reports stages (the optimiser).
    """
    if callable(progress):
        return None, progress
    if not progress:
        return None, None
    bar = progress_bar()
    if not stages:
        task = bar.add_task("rocks", total=total)
        return bar, (lambda done: bar.update(task, completed=done))
    return bar, _staged(bar)


def fits_progress(progress: bool | Callable[[int, int], None]) -> tuple[Any, Any]:
    """The API's ``progress=`` of a calibration: ``callback(done, total)`` of its fits."""
    if callable(progress):
        return None, progress
    if not progress:
        return None, None
    bar, update = rocks_progress(True, 0, stages=True)
    return bar, (lambda done, total: update("fits (best + bootstrap)", done, total))


def scenarios_progress(progress: bool | Callable[[int, int, int], None]) -> tuple[Any, Any]:
    """The API's ``progress=`` of a study: ``callback(done, total, rocks_done)``, with rocks/s."""
    if callable(progress):
        return None, progress
    if not progress:
        return None, None
    bar = progress_bar("{task.fields[rate]}")
    task: list[Any] = []
    start = time.perf_counter()

    def callback(done: int, total: int, rocks_done: int) -> None:
        if not task:
            task.append(bar.add_task("scenarios", total=total, rate=""))
        elapsed = time.perf_counter() - start
        rate = f"{rocks_done / elapsed:,.0f} rocks/s" if rocks_done and elapsed > 0 else ""
        bar.update(task[0], completed=done, rate=rate)

    return bar, callback


def interruptible_rocks(shown: bool, total: int) -> tuple[Any, Callable[[int], None]]:
    """A command's bar of ``total`` rocks (time remaining) if ``shown``, and its safe point."""
    if not shown:
        return None, (lambda done: check_interrupt())
    bar = progress_bar(remaining=True)
    task = bar.add_task("rocks", total=total)

    def update(done: int) -> None:
        check_interrupt()
        bar.update(task, completed=done)

    return bar, update


def interruptible_stages(shown: bool) -> tuple[Any, Callable[[str, int, int], None]]:
    """The optimiser's stages as a command shows them (or not), and its safe point."""
    if not shown:
        return None, (lambda stage, done, total: check_interrupt())
    labels = {"search": "searching families", "check": "exact and fresh checks"}
    bar = progress_bar()
    staged = _staged(bar, lambda stage: labels.get(stage, stage))

    def callback(stage: str, done: int, total: int) -> None:
        check_interrupt()
        staged(stage, done, total)

    return bar, callback
