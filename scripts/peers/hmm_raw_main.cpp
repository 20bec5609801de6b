// Benchmark driver (ours, not hmm's main.cpp): reads a raw little-endian f64 grid (missing cells
// not supported), converts to float like hmm's Heightmap, runs hmm's Triangulator, prints JSON.
// usage: hmm_raw GRID.f64 COLS ROWS MAX_ERROR
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include "triangulator.h"

int main(int argc, char **argv) {
    if (argc != 5) { fprintf(stderr, "usage: hmm_raw GRID.f64 COLS ROWS MAX_ERROR\n"); return 2; }
    const int w = atoi(argv[2]), h = atoi(argv[3]);
    const float e = atof(argv[4]);
    std::ifstream f(argv[1], std::ios::binary);
    std::vector<double> raw((size_t)w * h);
    f.read((char *)raw.data(), raw.size() * sizeof(double));
    std::vector<float> data(raw.begin(), raw.end());
    const auto t0 = std::chrono::steady_clock::now();
    auto hm = std::make_shared<Heightmap>(w, h, data);
    Triangulator tri(hm);
    tri.Run(e, 0, 0);
    const auto t1 = std::chrono::steady_clock::now();
    printf("{\"peer\": \"hmm\", \"points\": %d, \"triangles\": %d, \"max_error\": %g, \"seconds\": %g}\n",
        tri.NumPoints(), tri.NumTriangles(), tri.Error(),
        std::chrono::duration<double>(t1 - t0).count());
    return 0;
}
