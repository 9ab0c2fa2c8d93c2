#!/usr/bin/env python3
"""Compare raypipe with Embree 4 on the same mesh and the same primary rays.

raypipe writes the rays and the triangles (in its triangle-id order) as .npy files and
traces the rays single-threaded; Embree (PyPI package `embreex`, whose `run` is a
single-ray `rtcIntersect1` loop) traces the same rays through the same triangles in
this process. The script checks that the hits agree and prints raypipe's throughput
divided by Embree's.

    pip install embreex numpy
    cargo build --release -p raypipe
    python3 bench/embree_compare.py ../shared/models/stanford_bunny/stanford-bunny.obj

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


def embree_run(scene, origins, dirs):
    t = time.perf_counter()
    res = scene.run(origins, dirs, output=1)
    return res, time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mesh", help="OBJ (or .obj.gz) file")
    ap.add_argument("--size", default="1024x1024")
    ap.add_argument("--accel", default="bvh8",
                    help="raypipe structure for single rays: grid, kd, bvh, bvh4 or bvh8")
    ap.add_argument("--packet-accel", default="bvh4",
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
        # Each mode on its fastest structure: single rays on the 8-wide BVH, packets on the
        # 4-wide BVH's frustum kernel (by default).
        images = {}
        for accel in {a.accel, a.packet_accel}:
            images[accel] = os.path.join(tmp, f"scene-{accel}.rpsi")
            raypipe(a.raypipe, "build", a.mesh, "-o", images[accel], "--accel", accel)
        image_of = {"1": images[a.accel], a.packet: images[a.packet_accel]}
        rays = np.load(rays_p)
        tris = np.load(tris_p).astype(np.float32)
        origins = np.ascontiguousarray(rays[:, 0:3], dtype=np.float32)
        dirs = np.ascontiguousarray(rays[:, 3:6], dtype=np.float32)
        scene = embree_scene(tris, origins, dirs)
        # Interleaved rounds (raypipe single, raypipe packets, Embree), so that all three
        # see the same machine: medians over the rounds, ratios of the medians. Each
        # raypipe round is itself the median of 3 runs in one process (warm, as Embree's
        # scene is).
        secs = {"1": [], a.packet: [], "embree": []}
        for _ in range(a.runs):
            for packet in ("1", a.packet):
                out = raypipe(a.raypipe, "trace", image_of[packet], "--rays", rays_p, "--hits", hits_p + packet,
                              "--threads", "1", "--runs", "3", "--packet", packet)
                secs[packet].append(float(re.search(r"in ([0-9.]+) s", out).group(1)))
            res, t = embree_run(scene, origins, dirs)
            secs["embree"].append(t)
        secs = {k: statistics.median(v) for k, v in secs.items()}
        em_secs = secs["embree"]
        hits = np.load(hits_p + "1")
        packet_hits = np.load(hits_p + a.packet)
        if packet_hits.tobytes() != hits.tobytes():
            sys.exit("error: raypipe's packet hits differ from its single-ray hits")

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

    rp = n / secs["1"] / 1e6
    rpp = n / secs[a.packet] / 1e6
    em = n / em_secs / 1e6
    print(f"mesh        {a.mesh} ({len(tris)} triangles), {n} primary rays, single thread, median of {a.runs} interleaved rounds")
    print(f"embree      rtcIntersect1           {em:8.2f} Mrays/s")
    print(f"raypipe     {a.accel} single rays      {rp:8.2f} Mrays/s   ratio {rp / em:.2f}")
    print(f"raypipe     {a.packet_accel} packets of {a.packet:<3}  {rpp:8.2f} Mrays/s   ratio {rpp / em:.2f}")
    print(f"agreement   {100.0 * agree.mean():.4f}% ({differ} rays differ: "
          f"{int((e_hit != r_hit).sum())} hit/miss, {int((e_hit & r_hit & ~same_prim & ~close_t).sum())} other triangle)")
    return 0 if agree.mean() >= 0.9999 else 1


if __name__ == "__main__":
    sys.exit(main())
