#!/usr/bin/env python3
"""The floor plan of crates/kappe/src (issue 22): every top-level module imports only the
modules on floors below it, so the import graph has no cycle. Prints each module's imports and
exits 1 on a violation. CI runs it (through the kappe test `floors`, which calls the same rule
in Rust); this script is the readable version for a developer."""
import os, re, sys

FLOORS = ["input", "form", "robot_plan", "schedule", "analysis", "verdict", "run", "output",
          "commands", "class"]
SRC = os.path.join(os.path.dirname(__file__), "..", "crates", "kappe", "src")

def code(path):
    text = open(path).read()
    # test modules may import anything (fixtures); comments are not imports
    text = re.split(r"#\[cfg\(test\)\]\s*mod tests", text)[0]
    return "\n".join(l for l in text.splitlines() if not l.lstrip().startswith("//"))

def deps(mod):
    p = os.path.join(SRC, mod)
    paths = [p + ".rs"] if os.path.exists(p + ".rs") else [
        os.path.join(d, f) for d, _, fs in os.walk(p) for f in fs if f.endswith(".rs")]
    found = set()
    for path in paths:
        found |= set(re.findall(r"\bcrate::([a-z_]+)", code(path)))
    return sorted(found - {mod})

bad = 0
for i, mod in enumerate(FLOORS):
    d = deps(mod)
    up = [x for x in d if x not in FLOORS[:i]]
    print(f"{i} {mod:10} imports {', '.join(d) or '-'}" + (f"   VIOLATION: {up}" if up else ""))
    bad += bool(up)
sys.exit(1 if bad else 0)
