// Google Benchmark kernels for lib/sdf: closest point (BVH vs CGAL AABB vs brute force) and the
// winding number (fast vs exact). Meshes are icospheres (synthetic, no data files needed).
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "../../tests/sdf/sdf_test_meshes.h"
#include "io/cgal/aabb_distance.h"
#include "sdf/closest_triangle.h"
#include "sdf/winding_number.h"

using namespace normalflow;

namespace {

std::vector<Vec3d> query_points(std::size_t n) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.3, 1.3);
    std::vector<Vec3d> p(n);
    for (auto& x : p) x = {u(rng), u(rng), u(rng)};
    return p;
}

template <class Make>
void closest(benchmark::State& st, Make make) {
    const Mesh m = test::icosphere(1.0, int(st.range(0)));
    const auto q = make(m);
    const auto pts = query_points(1024);
    std::size_t i = 0;
    for (auto _ : st) benchmark::DoNotOptimize(q->closest(pts[i++ & 1023]));
    st.counters["faces"] = double(m.triangles.size());
}

void BM_ClosestBvh(benchmark::State& st) {
    closest(st, [](const Mesh& m) { return make_bvh_query(m); });
}
void BM_ClosestCgalAabb(benchmark::State& st) {
    closest(st, [](const Mesh& m) { return make_aabb_query(m); });
}
void BM_ClosestBruteForce(benchmark::State& st) {
    closest(st, [](const Mesh& m) { return make_brute_force_query(m); });
}

void BM_WindingFast(benchmark::State& st) {
    const Mesh m = test::icosphere(1.0, int(st.range(0)));
    const WindingNumber w(m);
    const auto pts = query_points(1024);
    std::size_t i = 0;
    for (auto _ : st) benchmark::DoNotOptimize(w(pts[i++ & 1023]));
    st.counters["faces"] = double(m.triangles.size());
}

void BM_WindingExact(benchmark::State& st) {
    const Mesh m = test::icosphere(1.0, int(st.range(0)));
    const WindingNumber w(m);
    const auto pts = query_points(1024);
    std::size_t i = 0;
    for (auto _ : st) benchmark::DoNotOptimize(w.exact(pts[i++ & 1023]));
    st.counters["faces"] = double(m.triangles.size());
}

void BM_WindingBuild(benchmark::State& st) {
    const Mesh m = test::icosphere(1.0, int(st.range(0)));
    for (auto _ : st) benchmark::DoNotOptimize(WindingNumber(m));
    st.counters["faces"] = double(m.triangles.size());
}

}  // namespace

BENCHMARK(BM_ClosestBvh)->DenseRange(3, 7, 2);
BENCHMARK(BM_ClosestCgalAabb)->DenseRange(3, 7, 2);
BENCHMARK(BM_ClosestBruteForce)->DenseRange(3, 5, 2);
BENCHMARK(BM_WindingFast)->DenseRange(3, 7, 2);
BENCHMARK(BM_WindingExact)->DenseRange(3, 5, 2);
BENCHMARK(BM_WindingBuild)->Arg(7)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
