#!/usr/bin/env python3
"""Compare two kappe summary.json files' buckling factors state by state (docs/convergence.md,
"The `twogrid` branch"): every state's `blf` and `blf_error`, the largest relative difference
of each, and the governing state (the `blf_min` constraint's worst state and value).

    python3 scripts/blf_cmp.py A/summary.json B/summary.json

Exit status 1 when the governing state differs or a state has a factor in one file only."""
import json
import sys


def load(path):
    with open(path) as f:
        s = json.load(f)
    states = {i: e for i, e in enumerate(s["states"])}
    gov = next((c for c in s.get("constraints") or [] if c["name"] == "blf_min"), None)
    return states, gov


def rel(a, b):
    return abs(a - b) / max(abs(a), abs(b), 1e-300)


def main(a_path, b_path):
    a, ga = load(a_path)
    b, gb = load(b_path)
    bad = False
    worst = {"blf": (0.0, None), "blf_error": (0.0, None)}
    for i in sorted(set(a) | set(b)):
        ea, eb = a.get(i, {}), b.get(i, {})
        for key in worst:
            va, vb = ea.get(key), eb.get(key)
            if (va is None) != (vb is None):
                print(f"state {i}: {key} {va} vs {vb}")
                bad = True
                continue
            if va is None:
                continue
            # blf_error is itself relative: compare it absolutely.
            d = rel(va, vb) if key == "blf" else abs(va - vb)
            if d > worst[key][0]:
                worst[key] = (d, i)
    print(f"states: {len(a)} / {len(b)}")
    print(f"largest relative |Δblf|: {worst['blf'][0]:.3e} (state {worst['blf'][1]})")
    print(f"largest |Δblf_error|: {worst['blf_error'][0]:.3e} (state {worst['blf_error'][1]})")
    sa = ga and (ga["state"], ga["worst"])
    sb = gb and (gb["state"], gb["worst"])
    print(f"governing: {sa} vs {sb}")
    if (sa and sa[0]) != (sb and sb[0]):
        bad = True
    return 1 if bad else 0


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1], sys.argv[2]))
