"""Whole ceilings from Python: ``kappe.ceiling(file_or_text, client=None)`` designs, analyses
and plans every bay of a ceiling file (the format of ``kappe init --kind ceiling``) as
``kappe design ROOM.toml`` does, one bay after another here, or one bay per task on a Dask
cluster when given a ``dask.distributed.Client``. The room summary equals ``ceiling.json``."""

from __future__ import annotations

import json
from typing import Any, Dict, List, Optional, Tuple

from . import _kappe
from ._source import PathOrText, read_source

__all__ = ["ceiling", "CeilingResult"]

Files = List[Tuple[str, bytes]]


def _run_bay(text: str, index: int, no_robot: bool, allow_fail: bool) -> Tuple[str, Files]:
    # A module-level function: Dask pickles it by reference to run it on the workers.
    return _kappe.ceiling_run_bay(text, index, no_robot, allow_fail)


class CeilingResult:
    """``summary`` (the dict of ``ceiling.json``), ``json`` (its text), ``index_html`` (the
    room page), ``bays`` (each bay's row), ``ok``, and ``files``: every file of the output
    directory as ``(name, bytes)``; ``write(directory)`` writes them like ``kappe design``."""

    def __init__(self, summary_json: str, index_html: str, bay_files: List[Files]) -> None:
        self.json = summary_json
        self.summary: Dict[str, Any] = json.loads(summary_json)
        self.index_html = index_html
        self.bays: List[Dict[str, Any]] = self.summary["bays"]
        self.ok: bool = bool(self.summary["ok"])
        self.files: Files = [
            ("ceiling.json", summary_json.encode()),
            ("index.html", index_html.encode()),
        ]
        for i, files in enumerate(bay_files):
            self.files.extend((f"bay_{i + 1}/{name}", data) for name, data in files)

    def write(self, directory: str, force: bool = False) -> Optional[str]:
        """Write the output directory as ``kappe design --out`` does: a new directory or one
        Kappe wrote is replaced atomically; anything else raises ``ValueError`` unless
        ``force``, which moves it aside (nothing is deleted)."""
        return _kappe.write_output(directory, self.files, force, "python ceiling")

    def __repr__(self) -> str:
        return f"CeilingResult(bays={len(self.bays)}, ok={self.ok})"


def ceiling(
    ceiling: PathOrText,
    client: Optional[Any] = None,
    no_robot: bool = False,
    allow_fail: bool = False,
) -> CeilingResult:
    """Run a ceiling: ``ceiling`` is a path to a ceiling file or its TOML text. Here the bays
    run one after another (each bay's print states in parallel, the GIL released); with
    ``client`` (a ``dask.distributed.Client``) one task per bay runs on the cluster. Robot
    programs are included for passing bays, or for all with ``allow_fail``."""
    text, _, _ = read_source(ceiling, "ceiling")
    n = _kappe.ceiling_bays(text)
    if client is not None:
        futures = client.map(_run_bay, [text] * n, list(range(n)), [no_robot] * n, [allow_fail] * n, pure=False)
        runs = client.gather(futures)
    else:
        runs = [_run_bay(text, i, no_robot, allow_fail) for i in range(n)]
    summary_json, index_html = _kappe.ceiling_assemble(text, [row for row, _ in runs])
    return CeilingResult(summary_json, index_html, [files for _, files in runs])
