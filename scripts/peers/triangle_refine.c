/* Shewchuk's Triangle as a peer for scripts/bench-refine.sh (library build, -DTRILIBRARY).
 *
 *   triangle_refine FILE MIN_ANGLE [REPEAT]
 *
 * FILE is a PSLG written by `bench_refine prep` (little-endian: "SWPSLG01", u64 vertex count,
 * u64 segment count, x y z f64 per vertex, two u32 per segment). Each repetition calls
 * triangulate() with switches "pzQq<MIN_ANGLE>": the constrained Delaunay triangulation of the
 * PSLG (-p), refined until no angle is below MIN_ANGLE (-q, with Triangle 1.6's off-centres),
 * zero-based, quiet. Only triangulate() is timed (minimum of REPEAT). Prints one JSON line:
 * vertices, triangles, smallest angle of the output (degrees, atan2 at each corner) and the
 * triangles under the bound. Triangle's source is never part of this repository; the script
 * builds it elsewhere. */
#include <math.h>
#include <stdint.h>
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

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

static double corner(const double *o, const double *p, const double *q) {
  double ux = p[0] - o[0], uy = p[1] - o[1], vx = q[0] - o[0], vy = q[1] - o[1];
  return atan2(fabs(ux * vy - uy * vx), ux * vx + uy * vy) * 180.0 / M_PI;
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: triangle_refine FILE MIN_ANGLE [REPEAT]\n");
    return 2;
  }
  double bound = atof(argv[2]);
  int repeat = argc > 3 ? atoi(argv[3]) : 3;
  FILE *f = fopen(argv[1], "rb");
  char magic[8];
  uint64_t n, m;
  if (!f || fread(magic, 1, 8, f) != 8 || memcmp(magic, "SWPSLG01", 8) != 0 ||
      fread(&n, 8, 1, f) != 1 || fread(&m, 8, 1, f) != 1) {
    fprintf(stderr, "triangle_refine: %s is not a bench_refine PSLG\n", argv[1]);
    return 2;
  }
  double *xyz = malloc(sizeof(double) * 3 * n);
  uint32_t *seg = malloc(sizeof(uint32_t) * 2 * m);
  if (fread(xyz, sizeof(double), 3 * n, f) != 3 * n || fread(seg, 4, 2 * m, f) != 2 * m) {
    fprintf(stderr, "triangle_refine: %s is truncated\n", argv[1]);
    return 2;
  }
  fclose(f);
  double *xy = malloc(sizeof(double) * 2 * n);
  int *segs = malloc(sizeof(int) * 2 * m);
  for (uint64_t i = 0; i < n; ++i) {
    xy[2 * i] = xyz[3 * i];
    xy[2 * i + 1] = xyz[3 * i + 1];
  }
  for (uint64_t i = 0; i < 2 * m; ++i) segs[i] = (int)seg[i];
  char switches[64];
  snprintf(switches, sizeof switches, "pzQq%g", bound);
  double best = 1e300;
  long long triangles = 0, vertices = 0, skinny = 0;
  double min_angle = 180.0;
  for (int r = 0; r < repeat; ++r) {
    struct triangulateio in, out;
    memset(&in, 0, sizeof in);
    memset(&out, 0, sizeof out);
    in.pointlist = xy;
    in.numberofpoints = (int)n;
    in.segmentlist = segs;
    in.numberofsegments = (int)m;
    double t0 = now();
    triangulate(switches, &in, &out, NULL);
    double dt = now() - t0;
    if (dt < best) best = dt;
    if (r == repeat - 1) {
      triangles = out.numberoftriangles;
      vertices = out.numberofpoints;
      for (int t = 0; t < out.numberoftriangles; ++t) {
        const double *p[3];
        for (int k = 0; k < 3; ++k) p[k] = out.pointlist + 2 * out.trianglelist[3 * t + k];
        double a = corner(p[0], p[1], p[2]);
        double b = corner(p[1], p[2], p[0]);
        double c = corner(p[2], p[0], p[1]);
        double lo = a < b ? (a < c ? a : c) : (b < c ? b : c);
        if (lo < min_angle) min_angle = lo;
        if (lo < bound) skinny++;
      }
    }
    trifree(out.pointlist);
    trifree(out.pointmarkerlist);
    trifree(out.trianglelist);
    trifree(out.segmentlist);
    trifree(out.segmentmarkerlist);
  }
  printf("{\"tool\":\"triangle\",\"input\":\"%s\",\"points\":%llu,\"segments\":%llu,"
         "\"vertices\":%lld,\"triangles\":%lld,\"min_angle\":%.6f,\"skinny\":%lld,"
         "\"seconds\":%.6f,\"repeat\":%d}\n",
         argv[1], (unsigned long long)n, (unsigned long long)m, vertices, triangles, min_angle,
         skinny, best, repeat);
  return 0;
}
