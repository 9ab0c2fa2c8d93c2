#!/usr/bin/env python3
"""Compare raypipe with Embree 4 on the same mesh and the same primary rays.

raypipe writes the rays and the triangles (in its triangle-id order) as .npy files and
traces the rays single-threaded; Embree (PyPI package `embreex`, whose `run` is a
single-ray `rtcIntersect1` loop) traces the same rays through the same triangles in
this process. The script checks that the hits agree and prints raypipe's throughput
divided by Embree's.

    pip install embreex numpy
    cargo build --release -p raypipe
    python3 bench/embree_compare.py scenes/stanford_bunny/stanford-bunny.obj

A ray agrees when both miss, or both hit the same triangle, or both hit at the same
distance within a relative 1e-6 (Embree's test is not watertight, so a few grazing
rays may differ: they are counted and reported).
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

try:
    from embreex import rtcore_scene as rtcs
    from embreex.mesh_construction import TriangleMesh
except ImportError:
    sys.exit("error: the embreex package is missing: pip install embreex")


def raypipe(binary, *args):
    out = subprocess.run([binary, *args], check=True, capture_output=True, text=True)
    return out.stdout


def embree_scene(tris, origins, dirs):
    scene = rtcs.EmbreeScene()
    TriangleMesh(scene, tris.reshape(-1, 3, 3))
    scene.run(origins[:1024], dirs[:1024], output=1)  # warm-up, builds the BVH
    return scene


def embree_run(scene, origins, dirs, runs=3):
    """The median time of `runs` traces, as `raypipe trace --runs 3` reports its own:
    both sides of a round are the median of three, so that a transient slowdown of the
    machine weighs the same on each."""
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        res = scene.run(origins, dirs, output=1)
        times.append(time.perf_counter() - t)
    return res, statistics.median(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mesh", help="OBJ (or .obj.gz) file")
    ap.add_argument("--size", default="1024x1024")
    ap.add_argument("--accel", default="bvh4,bvh8,bvh4+blocks,bvh8+blocks",
                    help="raypipe structures for single rays (comma-separated): grid, kd, bvh, bvh4, bvh8; "
                         "'+blocks' builds the wide BVHs with leaf triangle blocks (--triangles blocks)")
    ap.add_argument("--packet-accel", default="bvh4+blocks",
                    help="raypipe structure for packets (bvh4 has the 8x8 frustum kernel; bvh8 has none)")
    ap.add_argument("--packet", default="64", help="raypipe packet size for the packet figure: 4, 16 or 64")
    ap.add_argument("--runs", type=int, default=7, help="interleaved rounds (the median is reported)")
    ap.add_argument("--camera", help="raypipe camera file for the view")
    ap.add_argument("--raypipe", default=os.path.join(os.path.dirname(__file__), "..", "target", "release", "raypipe"))
    a = ap.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        rays_p, tris_p, hits_p = (os.path.join(tmp, n) for n in ("rays.npy", "tris.npy", "hits.npy"))
        cam = ["--camera", a.camera] if a.camera else []
        side = {"4": "2", "16": "4", "64": "8"}[a.packet]
        raypipe(a.raypipe, "rays", a.mesh, "-o", rays_p, "--triangles", tris_p, "--size", a.size,
                "--block", side, *cam)
        # Single rays on each structure asked for (by default the 4- and the 8-wide BVH),
        # packets on the 4-wide BVH's frustum kernel.
        singles = a.accel.split(",")
        images = {}
        for accel in set(singles) | {a.packet_accel}:
            images[accel] = os.path.join(tmp, f"scene-{accel}.rpsi")
            structure, _, layout = accel.partition("+")
            layout_args = ["--triangles", layout] if layout else []
            raypipe(a.raypipe, "build", a.mesh, "-o", images[accel], "--accel", structure, *layout_args)
        # (label, image, packet size)
        modes = [(f"{s} single rays", images[s], "1") for s in singles]
        modes.append((f"{a.packet_accel} packets of {a.packet}", images[a.packet_accel], a.packet))
        rays = np.load(rays_p)
        tris = np.load(tris_p).astype(np.float32)
        origins = np.ascontiguousarray(rays[:, 0:3], dtype=np.float32)
        dirs = np.ascontiguousarray(rays[:, 3:6], dtype=np.float32)
        scene = embree_scene(tris, origins, dirs)
        # Interleaved rounds (raypipe single, raypipe packets, Embree), so that all three
        # see the same machine: medians over the rounds, ratios of the medians. Each
        # round of each side is itself the median of 3 runs (raypipe's in one process,
        # warm, as Embree's scene is).
        secs = {label: [] for label, _, _ in modes}
        secs["embree"] = []
        for _ in range(a.runs):
            for k, (label, image, packet) in enumerate(modes):
                out = raypipe(a.raypipe, "trace", image, "--rays", rays_p, "--hits", f"{hits_p}{k}",
                              "--threads", "1", "--runs", "3", "--packet", packet)
                # From the throughput, printed to four significant digits: the time is
                # printed in whole milliseconds, a 3% step for the bunny's packets.
                mrays = float(re.search(r"\(([0-9.]+) Mrays/s\)", out).group(1))
                secs[label].append(len(origins) / (mrays * 1e6))
            res, t = embree_run(scene, origins, dirs)
            secs["embree"].append(t)
        # Each round's raypipe/Embree ratio, both sides measured back to back: on a
        # machine whose speed drifts over minutes this pairing cancels the drift that a
        # ratio of medians keeps.
        paired = {label: sorted(e / r for r, e in zip(secs[label], secs["embree"])) for label, _, _ in modes}
        secs = {k: statistics.median(v) for k, v in secs.items()}
        em_secs = secs["embree"]
        hits = np.load(f"{hits_p}0")
        for k in range(1, len(modes)):
            if np.load(f"{hits_p}{k}").tobytes() != hits.tobytes():
                sys.exit(f"error: raypipe's hits with {modes[k][0]} differ from those with {modes[0][0]}")

    n = len(rays)
    e_prim = np.asarray(res["primID"]).astype(np.int64)
    e_geom = np.asarray(res["geomID"]).astype(np.int64)
    e_hit = e_geom != -1
    e_prim = np.where(e_hit, e_prim, -1)
    e_t = np.asarray(res["tfar"], dtype=np.float32)
    r_prim = hits["prim"].astype(np.int64)
    r_t = hits["t"]
    r_hit = r_prim >= 0
    same_miss = ~e_hit & ~r_hit
    same_prim = e_hit & r_hit & (e_prim == r_prim)
    close_t = e_hit & r_hit & (np.abs(e_t - r_t) <= 1e-6 * np.maximum(np.abs(e_t), np.abs(r_t)))
    agree = same_miss | same_prim | close_t
    differ = n - int(agree.sum())

    em = n / em_secs / 1e6
    print(f"mesh        {a.mesh} ({len(tris)} triangles), {n} primary rays, single thread, median of {a.runs} interleaved rounds")
    print(f"embree      {'rtcIntersect1':<22} {em:8.2f} Mrays/s")
    for label, _, _ in modes:
        r = n / secs[label] / 1e6
        p = paired[label]
        print(f"raypipe     {label:<22} {r:8.2f} Mrays/s   ratio {r / em:.2f}   "
              f"(per round: median {statistics.median(p):.2f}, range {p[0]:.2f}-{p[-1]:.2f})")
    print(f"agreement   {100.0 * agree.mean():.4f}% ({differ} rays differ: "
          f"{int((e_hit != r_hit).sum())} hit/miss, {int((e_hit & r_hit & ~same_prim & ~close_t).sum())} other triangle)")
    return 0 if agree.mean() >= 0.9999 else 1


if __name__ == "__main__":
    sys.exit(main())
