/* Embree's BVH updates on raypipe's vertex buffers (bench/embree-updates.sh).
 *
 * Reads the frames `raypipe bench-updates --dump FILE` wrote (u32 triangle, vertex and
 * frame counts; the triangles; each frame's vertices) and times, per frame, the commit
 * of one triangle geometry whose vertices moved, with the build quality named:
 *   refit   RTC_BUILD_QUALITY_REFIT (the first frame's tree refitted, as raypipe's refit)
 *   low     RTC_BUILD_QUALITY_LOW   (Embree's Morton builder)
 *   medium  RTC_BUILD_QUALITY_MEDIUM (Embree's binned SAH builder, its default)
 * on a device with the given thread count. Prints the median, p10 and p90 of the
 * milliseconds per million triangles, in the format raypipe's benchmark prints.
 *
 * Usage: updates DUMP QUALITY THREADS
 */
#include <embree3/rtcore.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "timing.h"

static double pct(double *v, int n, double p) {
  int k = (int)(p / 100.0 * n + 0.999999);
  if (k < 1) k = 1;
  if (k > n) k = n;
  return v[k - 1];
}

int main(int argc, char **argv) {
  if (argc != 4) {
    fprintf(stderr, "usage: %s DUMP refit|low|medium THREADS\n", argv[0]);
    return 2;
  }
  FILE *f = fopen(argv[1], "rb");
  if (!f) {
    fprintf(stderr, "error: %s: cannot open\n", argv[1]);
    return 1;
  }
  uint32_t head[3];
  if (fread(head, 4, 3, f) != 3) {
    fprintf(stderr, "error: %s: truncated\n", argv[1]);
    return 1;
  }
  uint32_t nt = head[0], nv = head[1], frames = head[2];
  uint32_t *tris = malloc((size_t)nt * 12);
  /* Embree reads vertices with 16-byte loads: one float of padding after the last. */
  float *verts = malloc((size_t)nv * 12 + 16);
  float *all = malloc((size_t)nv * 12 * frames);
  if (!tris || !verts || !all || fread(tris, 12, nt, f) != nt || fread(all, 12, (size_t)nv * frames, f) != (size_t)nv * frames) {
    fprintf(stderr, "error: %s: truncated\n", argv[1]);
    return 1;
  }
  fclose(f);
  enum RTCBuildQuality q = RTC_BUILD_QUALITY_MEDIUM;
  if (!strcmp(argv[2], "refit")) q = RTC_BUILD_QUALITY_REFIT;
  else if (!strcmp(argv[2], "low")) q = RTC_BUILD_QUALITY_LOW;
  char config[64];
  snprintf(config, sizeof config, "threads=%d", atoi(argv[3]));
  RTCDevice dev = rtcNewDevice(config);
  RTCScene scene = rtcNewScene(dev);
  rtcSetSceneFlags(scene, RTC_SCENE_FLAG_DYNAMIC);
  rtcSetSceneBuildQuality(scene, q == RTC_BUILD_QUALITY_REFIT ? RTC_BUILD_QUALITY_LOW : q);
  RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, verts, 0, 12, nv);
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, tris, 0, 12, nt);
  rtcSetGeometryBuildQuality(g, q);
  memcpy(verts, all, (size_t)nv * 12);
  rtcCommitGeometry(g);
  rtcAttachGeometry(scene, g);
  /* The first frame's build (for refit: the tree every later frame refits). */
  rtcCommitScene(scene);
  double *ms = malloc(sizeof(double) * frames);
  int n = 0;
  for (uint32_t k = 1; k < frames; k++) {
    memcpy(verts, all + (size_t)nv * 3 * k, (size_t)nv * 12);
    double t0 = now();
    rtcUpdateGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0);
    rtcCommitGeometry(g);
    rtcCommitScene(scene);
    ms[n++] = (now() - t0) * 1e3 / (nt / 1e6);
  }
  qsort(ms, n, sizeof(double), cmp);
  printf("embree %-7s %d thread%s %8.1f (%.1f … %.1f) ms per million triangles, %d frames\n", argv[2], atoi(argv[3]),
         atoi(argv[3]) == 1 ? " " : "s", pct(ms, n, 50), pct(ms, n, 10), pct(ms, n, 90), n);
  rtcReleaseScene(scene);
  rtcReleaseDevice(dev);
  return 0;
}
