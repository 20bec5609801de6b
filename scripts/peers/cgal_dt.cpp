// CGAL peer for scripts/bench-core.sh: Delaunay_triangulation_2 with the exact-predicates kernel.
//
//   cgal_dt FILE DIST N [REPEAT]
//
// FILE holds little-endian f64 (x, y) pairs, as written by `bench_core dump`. The points are read
// once; each repetition builds a fresh triangulation with the range insert (which spatially sorts
// the points along a Hilbert curve first: CGAL's fast path). Only the insert is timed. Peak RSS is
// VmHWM of the first repetition, the mark reset once the input is in memory (as the Rust runner
// does). Prints
// one JSON line in the runner's format.
#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/version.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef CGAL::Delaunay_triangulation_2<K> DT;

static long long status_bytes(const char* field) {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line)) {
    if (line.rfind(field, 0) == 0) return std::atoll(line.c_str() + std::string(field).size() + 1) * 1024;
  }
  return 0;
}

static bool reset_hwm() {
  std::ofstream f("/proc/self/clear_refs");
  f << "5";
  f.flush();
  return f.good();
}

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: cgal_dt FILE DIST N [REPEAT]\n");
    return 2;
  }
  const char* path = argv[1];
  const char* dist = argv[2];
  long long n = std::atoll(argv[3]);
  int repeat = argc > 4 ? std::atoi(argv[4]) : 3;
  std::FILE* f = std::fopen(path, "rb");
  if (!f) {
    std::fprintf(stderr, "cgal_dt: cannot open %s\n", path);
    return 2;
  }
  std::vector<double> raw(2 * n);
  if (std::fread(raw.data(), sizeof(double), raw.size(), f) != raw.size()) {
    std::fprintf(stderr, "cgal_dt: %s holds fewer than %lld points\n", path, n);
    return 2;
  }
  std::fclose(f);
  std::vector<K::Point_2> pts;
  pts.reserve(n);
  for (long long i = 0; i < n; ++i) pts.emplace_back(raw[2 * i], raw[2 * i + 1]);
  std::vector<double>().swap(raw);
  std::vector<double> times;
  long long peak = 0, triangles = 0;  // peak of the first repetition, as in the Rust runner
  bool reset = true;
  for (int r = 0; r < repeat; ++r) {
    reset = reset_hwm() && reset;
    auto t0 = std::chrono::steady_clock::now();
    DT* dt = new DT();
    dt->insert(pts.begin(), pts.end());
    auto t1 = std::chrono::steady_clock::now();
    times.push_back(std::chrono::duration<double>(t1 - t0).count());
    if (r == 0) peak = status_bytes("VmHWM:");
    triangles = dt->number_of_faces();
    delete dt;
  }
  std::vector<double> sorted = times;
  std::sort(sorted.begin(), sorted.end());
  std::printf("{\"algo\":\"cgal\",\"dist\":\"%s\",\"n\":%lld,\"threads\":1,\"repeat\":%d,"
              "\"median_s\":%.9f,\"min_s\":%.9f,\"triangles\":%lld,\"input_bytes\":%lld,"
              "\"peak_rss_bytes\":%lld,\"bytes_per_point\":%.3f,\"hwm_reset\":%s,"
              "\"version\":\"%s\",\"times_s\":[",
              dist, n, repeat, sorted[sorted.size() / 2], sorted[0], triangles,
              (long long)(n * sizeof(K::Point_2)), peak, n ? (double)peak / n : 0.0,
              reset ? "true" : "false", CGAL_VERSION_STR);
  for (size_t i = 0; i < times.size(); ++i) std::printf(i ? ",%.9f" : "%.9f", times[i]);
  std::printf("]}\n");
  return 0;
}
