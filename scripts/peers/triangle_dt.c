/* Shewchuk's Triangle as a peer for scripts/bench-core.sh (library build, -DTRILIBRARY).
 *
 *   triangle_dt FILE DIST N [REPEAT]
 *
 * FILE holds little-endian f64 (x, y) pairs, as written by `bench_core dump`. Each repetition
 * calls triangulate() with switches "zQNB": zero-based indices, quiet, no node or boundary-marker
 * output, triangles are output. That is the default divide-and-conquer algorithm with Triangle's
 * default exact (adaptive) arithmetic: no -X, no quality or area options. Only triangulate() is
 * timed. Duplicate vertices are dropped by Triangle itself. Prints one JSON line in the runner's
 * format. Triangle's source is never part of this repository; the script builds it elsewhere. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifndef REAL
#define REAL double
#endif
#ifndef VOID
#define VOID void
#endif
#include "triangle.h"

static long long status_bytes(const char *field) {
  FILE *f = fopen("/proc/self/status", "r");
  char line[256];
  long long v = 0;
  size_t k = strlen(field);
  if (!f) return 0;
  while (fgets(line, sizeof line, f)) {
    if (strncmp(line, field, k) == 0) {
      v = atoll(line + k) * 1024;
      break;
    }
  }
  fclose(f);
  return v;
}

static int reset_hwm(void) {
  FILE *f = fopen("/proc/self/clear_refs", "w");
  if (!f) return 0;
  int ok = fputs("5", f) >= 0;
  return (fclose(f) == 0) && ok;
}

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

static int cmp(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

int main(int argc, char **argv) {
  if (argc < 4) {
    fprintf(stderr, "usage: triangle_dt FILE DIST N [REPEAT]\n");
    return 2;
  }
  long long n = atoll(argv[3]);
  int repeat = argc > 4 ? atoi(argv[4]) : 3;
  FILE *f = fopen(argv[1], "rb");
  if (!f) {
    fprintf(stderr, "triangle_dt: cannot open %s\n", argv[1]);
    return 2;
  }
  double *xy = malloc(sizeof(double) * 2 * n);
  if (fread(xy, sizeof(double), 2 * n, f) != (size_t)(2 * n)) {
    fprintf(stderr, "triangle_dt: %s holds fewer than %lld points\n", argv[1], n);
    return 2;
  }
  fclose(f);
  double *times = malloc(sizeof(double) * repeat);
  long long peak = 0, triangles = 0;
  int reset = 1;
  char switches[] = "zQNB";
  for (int r = 0; r < repeat; ++r) {
    struct triangulateio in, out;
    memset(&in, 0, sizeof in);
    memset(&out, 0, sizeof out);
    in.pointlist = xy;
    in.numberofpoints = (int)n;
    reset = reset_hwm() && reset;
    double t0 = now();
    triangulate(switches, &in, &out, NULL);
    times[r] = now() - t0;
    if (r == 0) peak = status_bytes("VmHWM:"); /* first repetition, as in the Rust runner */
    triangles = out.numberoftriangles;
    free(out.trianglelist);
    free(out.pointlist);
    free(out.pointmarkerlist);
    free(out.pointattributelist);
  }
  double *sorted = malloc(sizeof(double) * repeat);
  memcpy(sorted, times, sizeof(double) * repeat);
  qsort(sorted, repeat, sizeof(double), cmp);
  printf("{\"algo\":\"triangle\",\"dist\":\"%s\",\"n\":%lld,\"threads\":1,\"repeat\":%d,"
         "\"median_s\":%.9f,\"min_s\":%.9f,\"triangles\":%lld,\"input_bytes\":%lld,"
         "\"peak_rss_bytes\":%lld,\"bytes_per_point\":%.3f,\"hwm_reset\":%s,\"times_s\":[",
         argv[2], n, repeat, sorted[repeat / 2], sorted[0], triangles, 16 * n, peak,
         n ? (double)peak / n : 0.0, reset ? "true" : "false");
  for (int i = 0; i < repeat; ++i) printf(i ? ",%.9f" : "%.9f", times[i]);
  printf("]}\n");
  return 0;
}
