#!/usr/bin/env python3
"""Prints Purcell 2002's Tables 2 and 3 and the text figures behind Figures 7-9 beside
raypipe's, from the reports bench/purcell_tables.sh writes (markdown, for
docs/stream-model.md). Usage: purcell_tables.py OUT_DIR"""
import json
import os
import sys

out = sys.argv[1]


def load(name):
    path = os.path.join(out, name + ".json")
    return json.load(open(path)) if os.path.exists(path) else None


# Table 2 as printed in the paper: total, traversal, intersection, other passes, the
# most steps and tests per ray, SIMD efficiency. Soda Hall inside is legible only in
# part.
PAPER_T2 = {
    "building-outside": (2443, 692, 1747, 4, 384, 1123, 0.009),
    "building-inside": (1198, 70, 1124, 4, None, None, None),
    "forest-top": (1999, 311, 1684, 4, 137, 1435, 0.062),
    "forest-inside": (2835, 1363, 1468, 4, 898, 990, 0.068),
    "bunny": (1085, 610, 471, 4, 221, 328, 0.105),
    "bunny-framed": (1085, 610, 471, 4, 221, 328, 0.105),
}
NAMES = {
    "building-outside": "Soda Hall outside / building outside",
    "building-inside": "Soda Hall inside / building inside",
    "forest-top": "forest top / forest top",
    "forest-inside": "forest inside / forest inside",
    "bunny": "bunny / bunny",
    "bunny-framed": "bunny / bunny, 17° (77% of pixels hit)",
}
# Table 3: instructions and bandwidth relative to ray casting, branching machine.
PAPER_T3 = {"shadow": (0.85, 1.15), "whitted": (2.62, 3.00), "path": (3.24, 4.06)}


def fmt(x, digits=0):
    if x is None:
        return "—"
    return f"{x:.{digits}f}" if digits else f"{x}"


def ratio(a, b):
    return f"{a / b:.2f}" if a is not None and b else "—"


print("### Table 2 (multipass, Delany's oracle): paper / raypipe\n")
print("| Scene (paper / raypipe) | passes | Tr | In | other | max Tr | max In | SIMD | passes ratio |")
print("|---|---|---|---|---|---|---|---|---|")
for key, p in PAPER_T2.items():
    r = load(key + "-multipass")
    if r is None:
        continue
    t = r["table2"]
    ours = (t["total_passes"], t["traverse_passes"], t["intersect_passes"], t["other_passes"],
            t["max_steps"], t["max_intersections"], t["simd_screen"])
    cells = [f"{fmt(a, 3 if i == 6 else 0)} / {fmt(b, 3 if i == 6 else 0)}" for i, (a, b) in enumerate(zip(p, ours))]
    print(f"| {NAMES[key]} | " + " | ".join(cells) + f" | {ratio(ours[0], p[0])} |")

for framing in ("bunny", "bunny-framed"):
    cast = load(framing + "-branching")
    if not cast:
        continue
    print(f"\n### Table 3 ({framing}, branching, relative to ray casting at 1024²): paper / raypipe\n")
    print("| Algorithm | instructions | bandwidth | instructions ratio | bandwidth ratio | rays ÷ cast's |")
    print("|---|---|---|---|---|---|")
    for algo, (pi, pb) in PAPER_T3.items():
        r = load(f"{framing}-{algo}")
        if r is None:
            continue
        i = r["instructions"] / cast["instructions"]
        b = r["traffic"]["total"] / cast["traffic"]["total"]
        rays = sum(r["rays_by_wave"]) / sum(cast["rays_by_wave"])
        print(f"| {algo} | {pi:.2f} / {i:.2f} | {pb:.2f} / {b:.2f} | {i / pi:.2f} | {b / pb:.2f} | {rays:.2f} |")

print("\n### Figures 7–9 (1024², Delany's oracle): raypipe's figures\n")
print("| Scene | machine | G instr | GB | stencil GB | state GB | data GB | with cache ÷ without | triangle hit rate |")
print("|---|---|---|---|---|---|---|---|---|")
for key in PAPER_T2:
    for arch in ("multipass", "branching"):
        r = load(f"{key}-{arch}")
        n = load(f"{key}-{arch}-nocache" if arch == "branching" else f"{key}-nocache")
        if r is None:
            continue
        t = r["traffic"]
        tri = next((c for c in r["classes"] if c["class"] == "vertices"), None)
        hit = f"{100 * tri['hit_rate']:.1f}%" if tri and tri["hit_rate"] is not None else "—"
        cache = ratio(t["total"], n["traffic"]["total"]) if n else "—"
        print(f"| {key} | {arch} | {r['instructions'] / 1e9:.2f} | {t['total'] / 1e9:.2f} | {t['stencil'] / 1e9:.2f} "
              f"| {t['state'] / 1e9:.2f} | {t['random'] / 1e9:.2f} | {cache} | {hit} |")

base, unrolled, suppressed = load("bunny-multipass"), load("bunny-unrolled"), load("bunny-unrolled-suppressed")
if base and unrolled and suppressed:
    b0, i0 = base["traffic"]["total"], base["instructions"]
    print("\n### Unrolling (bunny, traverse 4, intersect 2): paper / raypipe\n")
    print("| | bandwidth saved | instructions added (paper: under 10%) |")
    print("|---|---|---|")
    for label, r, paper in (("unrolled", unrolled, "50%"), ("unrolled, suppressed", suppressed, "60%")):
        saved = 1 - r["traffic"]["total"] / b0
        added = r["instructions"] / i0 - 1
        print(f"| {label} | {paper} / {100 * saved:.0f}% | {100 * added:+.0f}% |")
