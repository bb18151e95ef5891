# The native extension (PyO3, `crates/python`). It is private: the typed public API is the
# package's modules (`kappe`, `kappe.cem`, `kappe.fe`, `kappe.robot`), which wrap these functions
# and convert their JSON strings and NumPy arrays; so this stub only tells type checkers that
# the module exists (PEP 484 partial stub).
from typing import Any

def __getattr__(name: str) -> Any: ...
