"""Reading a file argument that may be a path or the file's TOML text (``kappe.study``,
``kappe.ceiling``, ``kappe.optimize``): a missing file is reported as a missing file, never
parsed as TOML text."""

from __future__ import annotations

import os
from typing import Any, Tuple, Union

PathOrText = Union[str, "os.PathLike[str]"]


def _looks_like_toml(text: str) -> bool:
    # A TOML file that sets anything has a line break, a table header or a key = value; a path
    # has none of these (a file name with "=" or "[" is not worth the confusion).
    return "\n" in text or "=" in text or text.lstrip().startswith("[")


def read_source(value: Any, what: str) -> Tuple[str, str, str]:
    """``(text, source name, directory)`` of ``value``: a path (``str`` or ``os.PathLike``) to a
    file, or TOML text. Relative paths inside the file resolve against its directory (against
    the working directory for text). Raises ``FileNotFoundError`` for a path that does not
    exist and ``TypeError`` for anything else."""
    if isinstance(value, os.PathLike):
        path = os.fspath(value)
        if not isinstance(path, str):
            raise TypeError(f"{what}: expected a str path, got {type(path).__name__}")
    elif isinstance(value, str):
        if _looks_like_toml(value):
            return value, f"{what}.toml", os.getcwd()
        path = value
    else:
        raise TypeError(f"{what}: expected a path or TOML text, got {type(value).__name__}")
    if not os.path.isfile(path):
        why = "is a directory, not a file" if os.path.isdir(path) else "no such file"
        raise FileNotFoundError(f"{what}: cannot read {path!r}: {why}")
    with open(path, encoding="utf-8") as f:
        text = f.read()
    return text, os.path.basename(path), os.path.dirname(os.path.abspath(path))
