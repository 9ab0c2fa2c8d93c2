#!/usr/bin/env python3
"""raypipe against Embree 3's C API on the same rays, in the same run.

For each scene raypipe writes its triangles (in its triangle-id order) and the primary
rays of one view (runs of 16 are 4x4 pixel blocks, runs of 64 are 8x8), and traces
them; from its hits this script makes shadow rays to a point light above the scene and
one cosine-distributed diffuse bounce (the same rays for both sides). The C harness
bench/embree/rays.c (built here against Debian's libembree-dev) traces every set with
Embree's paths: rtcIntersect1, rtcIntersect16 (coherent), rtcIntersect1M (stream mode;
coherent for primary rays, incoherent for bounces), rtcOccluded1, rtcOccluded16 and
rtcOccluded1M (stream mode, coherent).
raypipe runs its single-ray and packet paths on the 4- and 8-wide BVHs. Rounds are
interleaved (every path once per round); the medians are reported, one core pinned
(taskset) and then two. Hits are checked: a ray agrees when both miss, both hit the same
triangle, or both hit at the same distance within a relative 1e-5; shadow rays agree
when both say occluded or both say free. `--generate forest:trees=6400@inside` adds a
scene raypipe generates (5.2 M triangles, seen from inside the forest). `--kinds path`
times a path-traced frame's own rays (`raypipe render --algo path --ray-log`): each side's
tracing time for the frame beside raypipe's whole frame.

    apt-get install libembree-dev gcc
    cargo build --release -p raypipe
    python3 bench/embree_harness.py scenes/stanford_bunny/stanford-bunny.obj \\
        scenes/sponza_dabrovic/sponza.obj.gz:fixtures/cameras/sponza.camera
"""
import argparse
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def run(cmd, pin=None):
    if pin is not None and shutil.which("taskset"):
        cmd = ["taskset", "-c", pin, *cmd]
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


def save_rays(path, origins, dirs, t_min, t_max):
    rays = np.zeros((len(origins), 8), dtype=np.float32)
    rays[:, 0:3], rays[:, 3:6], rays[:, 6], rays[:, 7] = origins, dirs, t_min, t_max
    np.save(path, rays)


def secondary_rays(tmp, rays, hits, tris, seed=1):
    """Shadow rays to a point light above the scene's box, and one diffuse bounce, from
    every primary hit (in the primary rays' order, so coherent rays stay together)."""
    hit = hits["prim"] >= 0
    o, d = rays[hit, 0:3].astype(np.float64), rays[hit, 3:6].astype(np.float64)
    p = o + d * hits["t"][hit, None]
    lo, hi = tris.reshape(-1, 3).min(axis=0), tris.reshape(-1, 3).max(axis=0)
    extent = float(np.max(hi - lo))
    eps = 1e-4 * extent
    n = hits["ng"][hit].astype(np.float64)
    n = np.where((np.sum(n * d, axis=1) > 0)[:, None], -n, n)  # facing the ray
    start = p + n * eps
    light = (lo + hi) / 2 + np.array([0.1, 0.9, 0.2]) * (hi - lo)
    save_rays(os.path.join(tmp, "shadow.npy"), start, light - start, 0.0, 1.0 - 1e-4)
    # Cosine-weighted directions about the normal (Malley's method).
    rng = np.random.default_rng(seed)
    u1, u2 = rng.random(len(n)), rng.random(len(n))
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    a = np.where(np.abs(n[:, 0:1]) > 0.9, [[0.0, 1.0, 0.0]], [[1.0, 0.0, 0.0]])
    t = np.cross(n, a)
    t /= np.linalg.norm(t, axis=1)[:, None]
    b = np.cross(n, t)
    w = t * (r * np.cos(phi))[:, None] + b * (r * np.sin(phi))[:, None] + n * np.sqrt(1 - u1)[:, None]
    save_rays(os.path.join(tmp, "bounce.npy"), start, w, 0.0, np.inf)
    return int(hit.sum())


def agree_closest(hits, path):
    e = np.fromfile(path, dtype=[("prim", "<i4"), ("t", "<f4")])
    r_prim, r_t = hits["prim"].astype(np.int64), hits["t"]
    e_prim, e_t = e["prim"].astype(np.int64), e["t"]
    both = (r_prim >= 0) & (e_prim >= 0)
    with np.errstate(invalid="ignore"):  # misses carry t = inf on both sides
        close = np.abs(e_t - r_t) <= 1e-5 * np.maximum(np.abs(e_t), np.abs(r_t))
    same = (r_prim == e_prim) | (both & close)
    return int((~same).sum())


def agree_any(hits, path):
    e = np.fromfile(path, dtype=np.uint8)
    return int((hits["occluded"].astype(np.uint8) != e).sum())


def time_builds(rp, harness, mesh, name, tris_p, rays_p, tmp, a):
    """Build time and bytes per triangle of each raypipe structure (`raypipe bench`: the
    build alone, the OBJ already parsed) and of Embree's MEDIUM and HIGH builds (the
    harness's commit time; bytes from Embree's memory monitor), one core pinned and then
    all the threads asked for. Rounds interleaved, medians."""
    few = os.path.join(tmp, "few.npy")
    np.save(few, np.load(rays_p, mmap_mode="r")[:16])
    n_tris = len(np.load(tris_p, mmap_mode="r"))
    out = []
    for threads in [int(t) for t in a.threads.split(",")]:
        pin = "1" if threads == 1 else None
        got = {}
        for _ in range(a.rounds):
            for accel in ("grid", "kd", "bvh", "bvh4", "bvh8"):
                text = run([rp, "bench", mesh, "--accel", accel, "--runs", "1", "--threads", str(threads),
                            "--size", "16x16", "--no-default", "--packet", "1"], pin)
                row = [line for line in text.splitlines() if line.startswith(os.path.basename(mesh)[:28])][-1]
                m = re.search(r"\s([0-9.]+)\s+([0-9.]+) single", row)
                got.setdefault(f"raypipe {accel}", []).append((float(m.group(1)), float(m.group(2))))
            for quality in ("medium", "high"):
                text = run([harness, tris_p, few, "occluded1", str(threads), "1", quality], pin)
                ms = float(re.search(r"build_ms=([0-9.]+)", text).group(1))
                size = float(re.search(r"bytes=([0-9]+)", text).group(1))
                got.setdefault(f"Embree {quality}", []).append((ms / 1e3, size / n_tris))
        cells = [(k, statistics.median(x[0] for x in v), statistics.median(x[1] for x in v)) for k, v in got.items()]
        out.append((name, threads, cells))
        print(f"{name} builds {threads}T: " + ", ".join(f"{k} {sec:.3f} s {bpt:.0f} B/tri" for k, sec, bpt in cells),
              file=sys.stderr)
    return out


def time_batch(rp, harness, tris_p, images, rays_k, query, embree_modes, threads, rounds, tmp, coherent=True,
               scattered=False):
    """Medians (Mrays/s) of raypipe's paths and Embree's `embree_modes` on one batch of
    rays, rounds interleaved, one core pinned if `threads` is 1; the best of each side;
    how many rays' answers differ. Returns (rays, medians, raypipe best, Embree best,
    rays that differ)."""
    n = len(np.load(rays_k, mmap_mode="r"))
    raypipe_modes = [(f"{acc} single", images[acc], "1", []) for acc in ("bvh4", "bvh8")]
    if coherent:
        # The frustum packets are for coherent rays: a batch marked incoherent (the
        # path-traced frame's secondary rays) leaves them out, where they ran at 0.1
        # Mrays/s (the bunny) and would take the run's whole time.
        raypipe_modes += [(f"bvh4 packets of {p}", images["bvh4"], p, []) for p in ("16", "64")]
        if query == "closest":
            # The 8-wide BVH's packet walk is closest-hit only (its shadow packets would
            # go ray by ray).
            raypipe_modes += [(f"bvh8 packets of {p}", images["bvh8"], p, []) for p in ("16", "64")]
    if scattered or not coherent:
        # What `trace`'s reordering of incoherent rays buys: the same path in the file's
        # order.
        raypipe_modes += [("bvh8 single, input order", images["bvh8"], "1", ["--order", "input"])]
    pin = "1" if threads == 1 else None
    times = {m[0]: [] for m in raypipe_modes}
    times.update({f"embree {m}": [] for m in embree_modes})
    for _ in range(rounds):
        for label, image, packet, extra in raypipe_modes:
            out = run([rp, "trace", image, "--rays", rays_k, "--hits", os.path.join(tmp, "h.npy"), "--query", query,
                       "--threads", str(threads), "--runs", "3", "--packet", packet, *extra], pin)
            times[label].append(float(re.search(r"\(([0-9.]+) Mrays/s\)", out).group(1)))
        for m in embree_modes:
            out = run([harness, tris_p, rays_k, m, str(threads), "3", "medium"], pin)
            times[f"embree {m}"].append(float(re.search(r"mrays=([0-9.]+)", out).group(1)))
    med = {k: statistics.median(v) for k, v in times.items()}
    # Agreement: raypipe's hits against Embree's first path.
    ours = os.path.join(tmp, "ours.npy")
    fields = ["--fields", "t,u,v,prim"] if query == "closest" else []
    run([rp, "trace", images["bvh4"], "--rays", rays_k, "--hits", ours, "--query", query, *fields])
    theirs = os.path.join(tmp, "theirs.bin")
    run([harness, tris_p, rays_k, embree_modes[0], "1", "1", "medium", theirs])
    differ = (agree_closest if query == "closest" else agree_any)(np.load(ours), theirs)
    best_r = max((k for k in med if not k.startswith("embree")), key=med.get)
    best_e = max((k for k in med if k.startswith("embree")), key=med.get)
    print(f"{os.path.basename(rays_k)} {threads}T: " + ", ".join(f"{k} {v:.1f}" for k, v in med.items()),
          file=sys.stderr)
    return n, med, best_r, best_e, differ


def time_path(rp, harness, tris_p, images, cam, name, rows, tmp, a):
    """A path-traced frame (`raypipe render --algo path`, --path-size, --path-samples,
    the image's default bounces and light) and Embree on the very rays it traced: the
    frame logs its rays (`--ray-log`), each batch — eye rays, closest-hit secondaries,
    shadow rays — is timed on both sides' paths (rows added to `rows`), and each side's
    tracing time for the frame is the sum over the batches of rays / best rate. The
    frame's own time (median of the rounds) includes what tracing does not: eye rays,
    shading, sampling, the ray stream."""
    log = os.path.join(tmp, "path")
    render = [rp, "render", images["bvh4"], *cam, "--algo", "path", "--size", a.path_size, "--samples",
              str(a.path_samples), "-o", os.path.join(tmp, "path.png")]
    run([*render, "--ray-log", log])
    batches = [("eye", "closest", ["intersect1", "intersect16", "intersect1M"], True),
               ("secondary", "closest", ["intersect1", "intersect16", "intersect1Mi"], False),
               ("shadow", "any", ["occluded1", "occluded16", "occluded1M"], True)]
    out = []
    for threads in [int(t) for t in a.threads.split(",")]:
        pin = "1" if threads == 1 else None
        frame = statistics.median(
            float(re.search(r"render ([0-9.]+) s", run([*render, "--threads", str(threads)], pin)).group(1))
            for _ in range(a.rounds))
        ours = theirs = 0.0
        n_all = 0
        for batch, query, modes, coherent in batches:
            rays_k = os.path.join(log, f"{batch}.npy")
            n, med, br, be, differ = time_batch(rp, harness, tris_p, images, rays_k, query, modes, threads, a.rounds,
                                                tmp, coherent)
            rows.append((name, f"path {batch}", threads, n, med, br, be, differ))
            ours, theirs, n_all = ours + n / med[br] / 1e6, theirs + n / med[be] / 1e6, n_all + n
        out.append((name, threads, n_all, frame, ours, theirs))
        print(f"{name} path frame {threads}T: render {frame:.3f} s, raypipe tracing {ours:.3f} s, "
              f"Embree tracing {theirs:.3f} s", file=sys.stderr)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="*", help="MESH or MESH:CAMERA (a raypipe camera file)")
    ap.add_argument("--generate", action="append", default=[], metavar="SPEC[@VIEW]",
                    help="also a scene raypipe generates (`raypipe build --generate SPEC --view VIEW`), e.g. "
                         "forest:trees=6400@inside (5.2 M triangles); its builds are not timed")
    ap.add_argument("--size", default="1024x1024")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--threads", default="1,2", help="thread counts; 1 is pinned to one core")
    ap.add_argument("--kinds", default="primary,shadow,bounce",
                    help="ray kinds to time: primary, shadow, bounce, and path (a path-traced frame's rays)")
    ap.add_argument("--path-size", default="512x512", help="the path-traced frame's size")
    ap.add_argument("--path-samples", type=int, default=4, help="the path-traced frame's samples per pixel")
    ap.add_argument("--builds", action="store_true", help="also time every structure's build beside Embree's")
    ap.add_argument("--keep", metavar="DIR",
                    help="keep each scene's triangles, rays and images in DIR/SCENE (for bench/embree/visits.sh)")
    ap.add_argument("--raypipe", default=os.path.join(HERE, "..", "target", "release", "raypipe"))
    a = ap.parse_args()
    if not shutil.which("gcc") or not os.path.exists("/usr/include/embree3/rtcore.h"):
        sys.exit("error: needs gcc and Embree 3's headers: apt-get install gcc libembree-dev")
    rp = a.raypipe
    rows, builds, frames = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        harness = os.path.join(tmp, "rays")
        subprocess.run(["gcc", "-O2", "-o", harness, os.path.join(HERE, "embree", "rays.c"), "-lembree3",
                        "-lpthread"], check=True)
        for spec in [("mesh", s) for s in a.scenes] + [("generate", g) for g in a.generate]:
            rays_p, tris_p = os.path.join(tmp, "primary.npy"), os.path.join(tmp, "tris.npy")
            images = {accel: os.path.join(tmp, f"{accel}.rpsi") for accel in ("bvh4", "bvh8")}
            if spec[0] == "mesh":
                mesh, _, camera = spec[1].partition(":")
                name = os.path.basename(mesh).split(".")[0]
                cam = ["--camera", camera] if camera else []
                run([rp, "rays", mesh, "-o", rays_p, "--triangles", tris_p, "--size", a.size, "--block", "8", *cam])
                for accel, image in images.items():
                    run([rp, "build", mesh, "-o", image, "--accel", accel, "--triangles", "blocks"])
            else:
                # A generated scene, seen from its view's camera (the images' default).
                gen, _, view = spec[1].partition("@")
                mesh, name = None, gen.replace(":", "-").replace(",", "-").replace("=", "")
                camera, cam = None, []
                for accel, image in images.items():
                    run([rp, "build", "--generate", gen, *(["--view", view] if view else []), "-o", image,
                         "--accel", accel, "--triangles", "blocks"])
                run([rp, "rays", images["bvh4"], "-o", rays_p, "--triangles", tris_p, "--size", a.size,
                     "--block", "8"])
            hits_p = os.path.join(tmp, "primary-hits.npy")
            run([rp, "trace", images["bvh4"], "--rays", rays_p, "--hits", hits_p, "--fields", "t,u,v,prim,ng"])
            rays, tris = np.load(rays_p), np.load(tris_p)
            primary_hits = np.load(hits_p)
            secondary_rays(tmp, rays, primary_hits, tris)
            if a.keep:
                # The scene's inputs for later runs (bench/embree/visits.sh, raypipe trace).
                kept = os.path.join(a.keep, name)
                os.makedirs(kept, exist_ok=True)
                for f in ["tris.npy", "primary.npy", "shadow.npy", "bounce.npy", "bvh4.rpsi", "bvh8.rpsi"]:
                    shutil.copy(os.path.join(tmp, f), kept)
            if a.builds and mesh is not None:
                builds.extend(time_builds(rp, harness, mesh, name, tris_p, rays_p, tmp, a))
            kinds = [("primary", "closest", ["intersect1", "intersect16", "intersect1M"]),
                     ("shadow", "any", ["occluded1", "occluded16", "occluded1M"]),
                     ("bounce", "closest", ["intersect1", "intersect16", "intersect1Mi"])]
            for kind, query, embree_modes in [k for k in kinds if k[0] in a.kinds.split(",")]:
                rays_k = os.path.join(tmp, f"{kind}.npy")
                for threads in [int(t) for t in a.threads.split(",")]:
                    rows.append((name, kind, threads, *time_batch(rp, harness, tris_p, images, rays_k, query,
                                                                  embree_modes, threads, a.rounds, tmp,
                                                                  scattered=kind == "bounce")))
            if "path" in a.kinds.split(","):
                frames.extend(time_path(rp, harness, tris_p, images, cam, name, rows, tmp, a))
    print("| scene | rays | threads | raypipe best (Mrays/s) | Embree best (Mrays/s) | ratio | rays that differ |")
    print("|---|---|---|---|---|---|---|")
    for name, kind, threads, n, med, br, be, differ in rows:
        print(f"| {name} | {kind} ({n}) | {threads} | {br}: {med[br]:.1f} | {be[7:]}: {med[be]:.1f} | "
              f"{med[br] / med[be]:.2f} | {differ} ({100 * differ / max(n, 1):.3f}%) |")
    if builds:
        print("\nBuilds (median of the rounds; seconds, bytes per triangle):\n")
        print("| scene | threads | " + " | ".join(b[0] for b in builds[0][2]) + " |")
        print("|---|---|" + "---|" * len(builds[0][2]))
        for name, threads, cells in builds:
            print(f"| {name} | {threads} | " + " | ".join(f"{sec:.3f} s, {bpt:.0f} B" for _, sec, bpt in cells) + " |")
    if frames:
        print("\nPath tracing: the frame's rays traced by each side's best path per batch, beside "
              "raypipe's whole frame (eye rays, shading, sampling; seconds):\n")
        print("| scene | threads | rays | raypipe frame | raypipe tracing | Embree tracing | tracing ratio |")
        print("|---|---|---|---|---|---|---|")
        for name, threads, n, frame, ours, theirs in frames:
            print(f"| {name} | {threads} | {n} | {frame:.3f} | {ours:.3f} | {theirs:.3f} | {theirs / ours:.2f} |")
    print("\nEvery path, medians in Mrays/s:\n")
    for name, kind, threads, n, med, _, _, _ in rows:
        print(f"- {name} {kind}, {threads} thread(s): " + ", ".join(f"{k} {v:.1f}" for k, v in med.items()))


if __name__ == "__main__":
    main()
