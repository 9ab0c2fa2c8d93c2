/* The clock and the sort order the Embree harnesses (updates.c, rays.c) time with. */
#ifndef RAYPIPE_BENCH_TIMING_H
#define RAYPIPE_BENCH_TIMING_H

#include <stdlib.h>
#include <time.h>

/* Seconds on the monotonic clock. */
static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec + t.tv_nsec * 1e-9;
}

/* qsort's order for doubles, ascending. */
static int cmp(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

#endif
