/* Embree 3's ray queries on raypipe's rays (bench/embree_harness.py).
 *
 * Reads the triangles `raypipe rays --triangles` wrote ((T, 9) float32, raypipe's
 * triangle ids) and the rays of `raypipe rays` ((N, 6) or (N, 8) float32: origin,
 * direction[, t_min, t_max]; with `--block 4` every run of 16 rays is a 4x4 pixel
 * block), builds one triangle geometry at the build quality named, and traces the rays
 * with one of Embree's query paths:
 *   intersect1    rtcIntersect1, a ray at a time
 *   intersect16   rtcIntersect16 on each run of 16, the coherent flag set
 *   intersect1M   rtcIntersect1M (stream mode) on runs of 256, coherent flag
 *   intersect1Mi  the same with the incoherent flag (secondary rays)
 *   occluded1     rtcOccluded1
 *   occluded16    rtcOccluded16, coherent
 *   occluded1M    rtcOccluded1M (stream mode) on runs of 256, coherent flag
 * on THREADS threads, ROUNDS times. The threads take chunks of 4096 rays from a shared
 * counter as they finish the last (as raypipe's workers do): a fixed share per thread
 * left one thread idle while the other finished the costlier half of the image.
 * Prints the build time, then per round nothing; at the end one line:
 *   MODE threads=T rays=N median_s=S mrays=M build_ms=B bytes=M
 * (bytes: what Embree allocated for the scene, from its memory monitor).
 * and, with HITS, writes one record per ray: int32 prim (-1: miss) and float32 t for the
 * intersect modes, uint8 occluded for the occluded ones.
 *
 * Usage: rays TRIS.npy RAYS.npy MODE THREADS ROUNDS medium|high [HITS]
 */
#include <embree3/rtcore.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "timing.h"

static void die(const char *what, const char *why) {
  fprintf(stderr, "error: %s: %s\n", what, why);
  exit(1);
}

/* A 2-D little-endian float32 .npy array, C order: rows and columns. */
static float *load_npy(const char *path, size_t *rows, size_t *cols) {
  FILE *f = fopen(path, "rb");
  if (!f) die(path, "cannot open");
  unsigned char magic[8];
  if (fread(magic, 1, 8, f) != 8 || memcmp(magic, "\x93NUMPY", 6) != 0) die(path, "not a .npy file");
  size_t hlen = 0;
  if (magic[6] == 1) {
    unsigned char b[2];
    if (fread(b, 1, 2, f) != 2) die(path, "truncated header");
    hlen = b[0] | (size_t)b[1] << 8;
  } else {
    unsigned char b[4];
    if (fread(b, 1, 4, f) != 4) die(path, "truncated header");
    hlen = b[0] | (size_t)b[1] << 8 | (size_t)b[2] << 16 | (size_t)b[3] << 24;
  }
  if (hlen > 65536) die(path, "header too long");
  char *h = calloc(hlen + 1, 1);
  if (!h || fread(h, 1, hlen, f) != hlen) die(path, "truncated header");
  if (!strstr(h, "'descr': '<f4'")) die(path, "expected little-endian float32 ('<f4')");
  if (strstr(h, "'fortran_order': True")) die(path, "expected C order");
  const char *s = strstr(h, "'shape': (");
  if (!s || sscanf(s, "'shape': (%zu, %zu)", rows, cols) != 2) die(path, "expected a 2-D shape");
  free(h);
  if (*rows == 0 || *cols == 0 || *rows > (1u << 30) || *cols > 64) die(path, "absurd shape");
  float *data = malloc(*rows * *cols * sizeof(float));
  if (!data || fread(data, sizeof(float), *rows * *cols, f) != *rows * *cols) die(path, "truncated data");
  fclose(f);
  return data;
}

typedef struct {
  RTCScene scene;
  const float *rays;
  size_t cols, first, last; /* the chunk being traced: rays [first, last) */
  size_t count;             /* all rays */
  _Atomic size_t *next;     /* the next chunk's first ray, shared by the threads */
  int mode;
  int32_t *prim;
  float *t;
  uint8_t *occluded;
} Job;

/* Rays a thread takes at a time: a multiple of the packet (16) and stream (256) sizes. */
enum { CHUNK = 4096 };

/* Embree's allocations, summed by its memory monitor (bytes < 0: freed). */
static _Atomic long long allocated;
static bool monitor(void *ptr, ssize_t bytes, bool post) {
  (void)ptr, (void)post;
  allocated += bytes;
  return true;
}

enum { I1, I16, I1M, I1MI, O1, O16, O1M, MODE_COUNT };
static const char *MODES[] = {"intersect1",   "intersect16", "intersect1M", "intersect1Mi",
                              "occluded1",    "occluded16",  "occluded1M"};

static void ray_of(const Job *j, size_t i, struct RTCRay *r) {
  const float *p = j->rays + i * j->cols;
  r->org_x = p[0], r->org_y = p[1], r->org_z = p[2];
  r->dir_x = p[3], r->dir_y = p[4], r->dir_z = p[5];
  r->tnear = j->cols >= 8 ? p[6] : 0.0f;
  r->tfar = j->cols >= 8 ? p[7] : INFINITY;
  r->time = 0.0f, r->mask = 0xFFFFFFFF, r->id = (unsigned)i, r->flags = 0;
}

static void note_hit(const Job *j, size_t i, const struct RTCRay *r, const struct RTCHit *h) {
  if (j->prim) {
    int hit = h->geomID != RTC_INVALID_GEOMETRY_ID;
    j->prim[i] = hit ? (int32_t)h->primID : -1;
    j->t[i] = hit ? r->tfar : INFINITY;
  }
}

static void trace_chunk(Job *j) {
  struct RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  if (j->mode == I16 || j->mode == I1M || j->mode == O16 || j->mode == O1M) ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  if (j->mode == I1MI) ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
  if (j->mode == I1 || j->mode == O1) {
    for (size_t i = j->first; i < j->last; i++) {
      struct RTCRayHit rh;
      ray_of(j, i, &rh.ray);
      if (j->mode == I1) {
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(j->scene, &ctx, &rh);
        note_hit(j, i, &rh.ray, &rh.hit);
      } else {
        rtcOccluded1(j->scene, &ctx, &rh.ray);
        if (j->occluded) j->occluded[i] = rh.ray.tfar < 0.0f;
      }
    }
  } else if (j->mode == I16 || j->mode == O16) {
    struct RTCRayHit16 rh __attribute__((aligned(64)));
    int valid[16] __attribute__((aligned(64)));
    for (size_t b = j->first; b < j->last; b += 16) {
      size_t n = j->last - b < 16 ? j->last - b : 16;
      for (size_t k = 0; k < 16; k++) {
        struct RTCRay r;
        ray_of(j, b + (k < n ? k : 0), &r);
        valid[k] = k < n ? -1 : 0;
        rh.ray.org_x[k] = r.org_x, rh.ray.org_y[k] = r.org_y, rh.ray.org_z[k] = r.org_z;
        rh.ray.dir_x[k] = r.dir_x, rh.ray.dir_y[k] = r.dir_y, rh.ray.dir_z[k] = r.dir_z;
        rh.ray.tnear[k] = r.tnear, rh.ray.tfar[k] = r.tfar, rh.ray.time[k] = 0.0f;
        rh.ray.mask[k] = 0xFFFFFFFF, rh.ray.id[k] = (unsigned)(b + k), rh.ray.flags[k] = 0;
        rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
      }
      if (j->mode == I16) {
        rtcIntersect16(valid, j->scene, &ctx, &rh);
        if (j->prim)
          for (size_t k = 0; k < n; k++) {
            int hit = rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
            j->prim[b + k] = hit ? (int32_t)rh.hit.primID[k] : -1;
            j->t[b + k] = hit ? rh.ray.tfar[k] : INFINITY;
          }
      } else {
        rtcOccluded16(valid, j->scene, &ctx, &rh.ray);
        if (j->occluded)
          for (size_t k = 0; k < n; k++) j->occluded[b + k] = rh.ray.tfar[k] < 0.0f;
      }
    }
  } else {
    enum { STREAM = 256 };
    struct RTCRayHit *rh = aligned_alloc(64, STREAM * sizeof(struct RTCRayHit));
    if (!rh) die("stream", "out of memory");
    for (size_t b = j->first; b < j->last; b += STREAM) {
      size_t n = j->last - b < STREAM ? j->last - b : STREAM;
      for (size_t k = 0; k < n; k++) {
        ray_of(j, b + k, &rh[k].ray);
        rh[k].hit.geomID = RTC_INVALID_GEOMETRY_ID;
      }
      if (j->mode == O1M) {
        // The rays of a RTCRayHit array, one RTCRayHit apart: tfar < 0 marks a blocked one.
        rtcOccluded1M(j->scene, &ctx, &rh[0].ray, (unsigned)n, sizeof(struct RTCRayHit));
        if (j->occluded)
          for (size_t k = 0; k < n; k++) j->occluded[b + k] = rh[k].ray.tfar < 0.0f;
      } else {
        rtcIntersect1M(j->scene, &ctx, rh, (unsigned)n, sizeof(struct RTCRayHit));
        for (size_t k = 0; k < n; k++) note_hit(j, b + k, &rh[k].ray, &rh[k].hit);
      }
    }
    free(rh);
  }
}

static void *run(void *arg) {
  Job *j = arg;
  for (;;) {
    size_t first = atomic_fetch_add(j->next, CHUNK);
    if (first >= j->count) return NULL;
    j->first = first;
    j->last = first + CHUNK < j->count ? first + CHUNK : j->count;
    trace_chunk(j);
  }
}

int main(int argc, char **argv) {
  if (argc < 7) die("usage", "rays TRIS.npy RAYS.npy MODE THREADS ROUNDS medium|high [HITS]");
  size_t tn, tc, rn, rc;
  float *tris = load_npy(argv[1], &tn, &tc);
  float *rays = load_npy(argv[2], &rn, &rc);
  if (tc != 9) die(argv[1], "expected (T, 9) triangles");
  if (rc != 6 && rc != 8) die(argv[2], "expected (N, 6) or (N, 8) rays");
  int mode = -1;
  for (int m = 0; m < MODE_COUNT; m++)
    if (!strcmp(argv[3], MODES[m])) mode = m;
  if (mode < 0) die(argv[3], "not a mode (intersect1, intersect16, intersect1M, intersect1Mi, occluded1, occluded16, occluded1M)");
  int threads = atoi(argv[4]), rounds = atoi(argv[5]);
  if (threads < 1 || threads > 256 || rounds < 1 || rounds > 1000) die("threads/rounds", "out of range");
  enum RTCBuildQuality quality = RTC_BUILD_QUALITY_MEDIUM;
  if (!strcmp(argv[6], "high")) quality = RTC_BUILD_QUALITY_HIGH;
  else if (strcmp(argv[6], "medium")) die(argv[6], "not a build quality (medium, high)");

  char config[32];
  snprintf(config, sizeof config, "threads=%d", threads);
  RTCDevice device = rtcNewDevice(config);
  if (!device) die("embree", "no device");
  rtcSetDeviceMemoryMonitorFunction(device, monitor, NULL);
  double t0 = now();
  RTCScene scene = rtcNewScene(device);
  rtcSetSceneBuildQuality(scene, quality);
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetGeometryBuildQuality(geom, quality);
  float *v = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), tn * 3);
  unsigned *idx = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), tn);
  memcpy(v, tris, tn * 9 * sizeof(float));
  for (size_t i = 0; i < tn * 3; i++) idx[i] = (unsigned)i;
  rtcCommitGeometry(geom);
  rtcAttachGeometry(scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(scene);
  double build_ms = (now() - t0) * 1e3;

  const char *hits_path = argc > 7 ? argv[7] : NULL;
  int occl = mode == O1 || mode == O16 || mode == O1M;
  int32_t *prim = NULL;
  float *t = NULL;
  uint8_t *occluded = NULL;
  if (hits_path) {
    if (occl) occluded = calloc(rn, 1);
    else prim = calloc(rn, sizeof *prim), t = calloc(rn, sizeof *t);
  }
  pthread_t *tid = calloc(threads, sizeof *tid);
  Job *jobs = calloc(threads, sizeof *jobs);
  double *secs = calloc(rounds, sizeof *secs);
  long long scene_bytes = allocated;
  _Atomic size_t next;
  for (int r = 0; r < rounds; r++) {
    double s = now();
    atomic_store(&next, 0);
    for (int k = 0; k < threads; k++) {
      jobs[k] = (Job){scene, rays, rc, 0, 0, rn, &next, mode, prim, t, occluded};
      if (threads == 1) run(&jobs[k]);
      else pthread_create(&tid[k], NULL, run, &jobs[k]);
    }
    if (threads > 1)
      for (int k = 0; k < threads; k++) pthread_join(tid[k], NULL);
    secs[r] = now() - s;
  }
  qsort(secs, rounds, sizeof *secs, cmp);
  double med = secs[rounds / 2];
  printf("%s threads=%d rays=%zu median_s=%.6f mrays=%.3f build_ms=%.1f bytes=%lld\n", MODES[mode], threads, rn,
         med, rn / med / 1e6, build_ms, scene_bytes);
  if (hits_path) {
    FILE *f = fopen(hits_path, "wb");
    if (!f) die(hits_path, "cannot write");
    for (size_t i = 0; i < rn; i++) {
      if (occl) fwrite(&occluded[i], 1, 1, f);
      else fwrite(&prim[i], 4, 1, f), fwrite(&t[i], 4, 1, f);
    }
    fclose(f);
  }
  rtcReleaseScene(scene);
  rtcReleaseDevice(device);
  return 0;
}
