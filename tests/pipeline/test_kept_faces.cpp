// The kept mesh (connectivity keep) against known answers: a noisy cube and octahedron come back with flat sides
// at their true dihedral angles, a sphere does not drift, heavy noise turns no face over, the threads do not
// matter, the engine runs only where its surface is used; and the automatic spatial scale that follows the input's
// noise (auto_sigma_spatial).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <tbb/global_control.h>

#include "core/mesh_report.h"
#include "fit/face_filter.h"
#include "io/io.h"
#include "metrics/compare.h"
#include "metrics/metric_test_meshes.h"
#include "metrics/noise.h"
#include "pipeline/pipeline.h"
#include "pipeline/report_json.h"
#include "sdf/sdf_test_meshes.h"

namespace normalflow {
namespace {

constexpr double kDeg = 57.29577951308232;

/// The octahedron |x| + |y| + |z| = 1, each of its 8 sides an n × n grid of triangles, shared vertices, outward.
Mesh subdivided_octahedron(int n) {
    Mesh m;
    std::map<std::array<int, 3>, std::uint32_t> index;
    const auto vertex = [&](std::array<int, 3> k) {
        const auto [it, added] = index.emplace(k, std::uint32_t(m.positions.size()));
        if (added) m.positions.push_back(Vec3f(float(k[0]) / float(n), float(k[1]) / float(n), float(k[2]) / float(n)));
        return it->second;
    };
    for (int s = 0; s < 8; ++s) {
        const int sx = s & 1 ? -1 : 1, sy = s & 2 ? -1 : 1, sz = s & 4 ? -1 : 1;
        const auto at = [&](int i, int j) { return vertex({sx * i, sy * j, sz * (n - i - j)}); };
        const bool flip = sx * sy * sz < 0;
        for (int i = 0; i < n; ++i)
            for (int j = 0; i + j < n; ++j) {
                std::array<Tri, 2> t = {Tri{at(i, j), at(i + 1, j), at(i, j + 1)},
                                        Tri{at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)}};
                for (int k = 0; k < (i + j + 1 < n ? 2 : 1); ++k) {
                    if (flip) std::swap(t[std::size_t(k)][1], t[std::size_t(k)][2]);
                    m.triangles.push_back(t[std::size_t(k)]);
                }
            }
    }
    return m;
}

/// Each side of a polyhedron (the faces whose clean normals agree) from its faces off the polyhedron's edges (no
/// vertex on two sides): the kept faces' mean normal, and how far those faces are from it (mean angle, degrees).
struct Sides {
    std::vector<Vec3d> normal;
    double flatness = 0;
};
Sides sides(const Mesh& clean, const Mesh& kept) {
    std::vector<Vec3d> keys;
    std::vector<std::size_t> side(clean.triangles.size());
    std::vector<int> vertex_side(clean.positions.size(), -1);  // -2: on two sides
    for (std::size_t f = 0; f < clean.triangles.size(); ++f) {
        const Vec3d n = normalized(face_area_vector(clean, clean.triangles[f]));
        std::size_t k = 0;
        while (k < keys.size() && dot(keys[k], n) < 0.999) ++k;
        if (k == keys.size()) keys.push_back(n);
        side[f] = k;
        for (std::uint32_t v : clean.triangles[f])
            vertex_side[v] = vertex_side[v] == -1 || vertex_side[v] == int(k) ? int(k) : -2;
    }
    const auto inner = [&](std::size_t f) {
        const Tri& t = clean.triangles[f];
        return vertex_side[t[0]] >= 0 && vertex_side[t[1]] >= 0 && vertex_side[t[2]] >= 0;
    };
    Sides s;
    s.normal.assign(keys.size(), Vec3d(0, 0, 0));
    for (std::size_t f = 0; f < kept.triangles.size(); ++f)
        if (inner(f)) s.normal[side[f]] += face_area_vector(kept, kept.triangles[f]);
    for (Vec3d& n : s.normal) n = normalized(n);
    double sum = 0;
    std::size_t count = 0;
    for (std::size_t f = 0; f < kept.triangles.size(); ++f) {
        if (!inner(f)) continue;
        const Vec3d n = normalized(face_area_vector(kept, kept.triangles[f]));
        sum += std::acos(std::clamp(dot(n, s.normal[side[f]]), -1.0, 1.0)) * kDeg;
        ++count;
    }
    s.flatness = sum / double(count);
    return s;
}

/// The largest error of the kept sides' dihedral angles against the clean ones, degrees.
double dihedral_error(const Sides& clean, const Sides& kept) {
    double worst = 0;
    for (std::size_t a = 0; a < clean.normal.size(); ++a)
        for (std::size_t b = a + 1; b < clean.normal.size(); ++b) {
            const double c = std::acos(std::clamp(dot(clean.normal[a], clean.normal[b]), -1.0, 1.0));
            const double k = std::acos(std::clamp(dot(kept.normal[a], kept.normal[b]), -1.0, 1.0));
            worst = std::max(worst, std::abs(c - k) * kDeg);
        }
    return worst;
}

/// m less its faces whose centroid lies above z = 0.6: a unit sphere opened at the top.
Mesh without_cap(Mesh m) {
    std::erase_if(m.triangles,
                  [&](const Tri& t) { return m.positions[t[0]].z + m.positions[t[1]].z + m.positions[t[2]].z > 1.8f; });
    return m;
}

PipelineOptions kept() {
    PipelineOptions o;
    o.connectivity = Connectivity::Keep;
    return o;
}

TEST(KeptFaces, NoisyCubeAndOctahedronComeBackFlatAtTheirDihedralAngles) {
    // σ = 0.3 edges along the normals; the sides judged off their edges (the grid rounds the edges and corners);
    // measured 0.73° / 0.68° / 0.59° and flatness 0.69 / 3.32 / 4.18 (own faces / volume-guided / fit alone); the own
    // faces' estimated error still falls at the bound of 100 rounds (at the bound of 30: 0.48° and 1.88)
    Mesh cube = test::subdivided_cube(16);
    Mesh noisy = cube;
    NoiseOptions n;
    n.sigma = 0.3;
    add_noise(noisy, n);
    PipelineOptions o = kept();
    const PipelineResult own_result = smooth_mesh(noisy, o);
    const Sides truth = sides(cube, cube), own = sides(cube, own_result.mesh);
    o.keep_filter = KeepFilter::Volume;
    const Sides guided = sides(cube, smooth_mesh(noisy, o).mesh);
    o.keep_filter = KeepFilter::Fit;
    const Sides fitted = sides(cube, smooth_mesh(noisy, o).mesh);
    std::printf(
        "cube: dihedral error %.2f / %.2f / %.2f deg, flatness %.3f / %.3f / %.3f (faces / volume / fit); the "
        "face filter kept %d of %d rounds\n",
        dihedral_error(truth, own), dihedral_error(truth, guided), dihedral_error(truth, fitted), own.flatness,
        guided.flatness, fitted.flatness, own_result.report.faces.rounds, own_result.report.faces.rounds_run);
    for (const Sides* s : {&own, &guided}) {
        EXPECT_LT(dihedral_error(truth, *s), 1.0);
        EXPECT_LT(s->flatness, 0.15 * sides(cube, noisy).flatness);
    }
    EXPECT_LT(guided.flatness, 0.85 * fitted.flatness);  // the volume-guided face filter flattens the fitted sides
    // the octahedron's 109.5° dihedral angles: measured 2.22° with the own faces (the rounds stop at the noise
    // before the sides near the corners are flat), 1.86° guided by the volume (its sides are a few voxels wide
    // between rounded edges and corners, and bend): issue 37's target of 1° is missed here
    const Mesh octahedron = subdivided_octahedron(16);
    noisy = octahedron;
    add_noise(noisy, n);
    const Sides octa = sides(octahedron, smooth_mesh(noisy, kept()).mesh);
    o.keep_filter = KeepFilter::Volume;
    const Sides octa_guided = sides(octahedron, smooth_mesh(noisy, o).mesh);
    std::printf("octahedron: dihedral error %.2f / %.2f deg, flatness %.3f / %.3f (faces / volume)\n",
                dihedral_error(sides(octahedron, octahedron), octa),
                dihedral_error(sides(octahedron, octahedron), octa_guided), octa.flatness, octa_guided.flatness);
    EXPECT_LT(dihedral_error(sides(octahedron, octahedron), octa), 2.5);
    EXPECT_LT(octa.flatness, 0.2 * sides(octahedron, noisy).flatness);
    EXPECT_LT(dihedral_error(sides(octahedron, octahedron), octa_guided), 2.5);
}

TEST(KeptFaces, ASphereDoesNotDriftAndHeavyNoiseTurnsNoFaceOver) {
    const Mesh sphere = test::icosphere(1.0, 4);
    Mesh noisy = sphere;
    NoiseOptions n;
    n.sigma = 0.3;
    add_noise(noisy, n);
    const PipelineResult result = smooth_mesh(noisy, kept());
    const Mesh& round = result.mesh;
    // the own faces filtered (no fit to the volume) for the rounds of least estimated error (SURE), at most
    // kMaxFaceRounds: the error it estimates is a fraction of the noise, and the vertices moved about as far as it
    EXPECT_FALSE(result.report.fitted);
    ASSERT_TRUE(result.report.faces_filtered);
    EXPECT_GT(result.report.faces.rounds, 1);
    EXPECT_LE(result.report.faces.rounds_run, kMaxFaceRounds);
    EXPECT_GT(result.report.noise, 0.0);
    EXPECT_LT(result.report.faces.estimated_error, 0.5 * result.report.noise);
    EXPECT_GT(result.report.faces.rms_displacement, 0.8 * result.report.noise);
    EXPECT_NEAR(mesh_report(round).volume, mesh_report(sphere).volume, 0.005 * mesh_report(sphere).volume);
    double radius = 0;
    for (const Vec3f& p : round.positions) radius += norm(Vec3d(p));
    EXPECT_NEAR(radius / double(round.positions.size()), 1.0, 0.002);

    // σ = 0.6 edges along the normals (the data's convention): no face turns over; 1 and 2 threads agree
    const Mesh cube = test::subdivided_cube(12);
    const auto turned = [&](const Mesh& m, std::vector<char>* which = nullptr) {
        std::size_t count = 0;
        for (std::size_t f = 0; f < cube.triangles.size(); ++f) {
            const bool t = dot(face_area_vector(m, m.triangles[f]), face_area_vector(cube, cube.triangles[f])) <= 0;
            count += t;
            if (which) which->push_back(t);
        }
        return count;
    };
    Mesh heavy = cube;
    n.sigma = 0.6;
    add_noise(heavy, n);
    Mesh one, two;
    {
        const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        one = smooth_mesh(heavy, kept()).mesh;
    }
    {
        const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
        two = smooth_mesh(heavy, kept()).mesh;
    }
    EXPECT_EQ(one.positions, two.positions);
    EXPECT_EQ(turned(one), 0u);
    // in random directions it folds the triangles over along the surface (144 of 1,728 turned from the true normals,
    // 235 pairs of faces intersecting), which the filter's vertex update cannot undo (116 turned and 138 pairs left
    // without the untangling); the untangling unfolds what the volume shows (measured 91 → 2 folded against it, 13
    // turned from the true normals: beside the cube's edges the volume's rounded normal lets a face 90–135° from the
    // truth pass), moving the vertices along the volume's surface no farther than 3σ, and no pair intersects
    heavy = cube;
    n.direction = NoiseDirection::Random;
    add_noise(heavy, n);
    std::vector<char> before, after;
    const std::size_t input_turned = turned(heavy, &before);
    const PipelineResult untangled = smooth_mesh(heavy, kept());
    const std::size_t output_turned = turned(untangled.mesh, &after);
    EXPECT_GT(input_turned, 100u);
    EXPECT_LE(output_turned, input_turned / 5) << input_turned << " -> " << output_turned;
    ASSERT_TRUE(untangled.report.untangled);
    EXPECT_EQ(untangled.report.untangle_input.folded_before, std::size_t(untangled.report.input_flipped_faces));
    EXPECT_LT(untangled.report.untangle_input.folded_after, untangled.report.untangle_input.folded_before / 10);
    EXPECT_LE(untangled.report.flipped_faces, untangled.report.input_flipped_faces / 20);
    EXPECT_EQ(untangled.report.untangle_filtered.folded_after, 0u);
    const double reach = kUntangleNoiseReach * untangled.report.noise;
    // the filter's moves are along the normals, the untangling's no farther than its reach: no vertex wanders
    double farthest = 0;
    for (std::size_t i = 0; i < heavy.positions.size(); ++i)
        farthest = std::max(farthest, norm(Vec3d(untangled.mesh.positions[i]) - Vec3d(heavy.positions[i])));
    EXPECT_LT(farthest, 3 * reach);
    // the report says so: {"untangle": {"input": {"folded_before": 91, "folded_after": 3, ...}, "filtered": ...}}
    const std::string json = to_json(untangled.report).dump();
    EXPECT_NE(json.find("\"untangle\":{\"input\":{\"folded_before\":" +
                        std::to_string(untangled.report.untangle_input.folded_before)),
              std::string::npos);
    if (untangled.report.output_self_intersections >= 0) {  // a build with CGAL counts them
        EXPECT_GT(untangled.report.input_self_intersections, 0);
        EXPECT_EQ(untangled.report.output_self_intersections, 0);
    }
}

TEST(KeptFaces, TheEngineRunsOnlyWhereItsSurfaceIsUsed) {
    // An open input kept on its own faces reads nothing of the smoothed volume (the guard takes the input's own
    // distance): the engine does not run, its options change nothing, the memory check does not count it, and its
    // options are still checked
    const Mesh sphere = test::icosphere(1.0, 3);
    Mesh noisy = sphere;
    NoiseOptions n;
    n.sigma = 0.3;
    add_noise(noisy, n);
    const Mesh open = without_cap(noisy);
    PipelineOptions o = kept();
    o.scan.resolution = 64;
    const PipelineResult faces = smooth_mesh(open, o);
    EXPECT_FALSE(faces.report.smoothed);
    EXPECT_EQ(faces.report.seconds.smooth, 0.0);
    // the stop still follows the noise
    EXPECT_DOUBLE_EQ(faces.report.noise, estimate_noise(open, NoiseNormals::Steady).sigma);
    EXPECT_GT(faces.report.faces.rounds, 0);
    EXPECT_LT(faces.report.faces.estimated_error, faces.report.noise);
    PipelineOptions other = o;
    other.smooth.iterations = 3;
    other.smooth.sigma_spatial = 0.5;
    EXPECT_EQ(smooth_mesh(open, other).mesh.positions, faces.mesh.positions);
    other.smooth.iterations = -1;
    EXPECT_THROW((void)smooth_mesh(open, other), InvalidInput);
    // the memory the engine would need is not asked for: a limit between the two runs kept, not fitted
    PipelineOptions scan = o;
    scan.smoothing = false;
    const double with = check_memory(open, o), without = check_memory(open, scan);
    ASSERT_LT(without, with);
    o.max_memory_bytes = std::size_t(0.5 * (with + without));
    EXPECT_NO_THROW((void)smooth_mesh(open, o));
    o.keep_filter = KeepFilter::Volume;
    EXPECT_THROW((void)smooth_mesh(open, o), OutOfMemory);
    // auto keeps an open input without a decision: the same
    o.max_memory_bytes = 0;
    o.keep_filter = KeepFilter::Faces;
    o.connectivity = Connectivity::Auto;
    EXPECT_FALSE(smooth_mesh(open, o).report.smoothed);
    // where the smoothed surface is used, the engine runs: the guard of a closed input, auto's decision on one, the
    // fit (keep-filter volume), a re-meshing
    for (const Connectivity c : {Connectivity::Keep, Connectivity::Auto, Connectivity::Remesh}) {
        o.connectivity = c;
        EXPECT_TRUE(smooth_mesh(noisy, o).report.smoothed) << to_string(c);
    }
    o.connectivity = Connectivity::Keep;
    o.keep_filter = KeepFilter::Volume;
    EXPECT_TRUE(smooth_mesh(open, o).report.smoothed);
}

TEST(KeptFaces, AClosedInputKeptOnItsOwnFacesStopsTheEngineAfterItsFirstIteration) {
    // The engine's volume serves a closed input kept on its own faces only as the guard's reference, and auto only for
    // the keep-or-re-mesh decision: both read the first iteration's surface, and the engine goes on only where the
    // result is re-meshed. A re-meshed result is bit for bit the one decided after the whole run.
    const Mesh sphere = test::icosphere(1.0, 3);
    const auto noisy_sphere = [&](double sigma) {
        Mesh m = sphere;
        NoiseOptions n;
        n.sigma = sigma;
        add_noise(m, n);
        return m;
    };
    const Mesh noisy = noisy_sphere(0.3);
    PipelineOptions o = kept();
    o.scan.resolution = 64;
    const int all = 3;  // given: no stop when the normal map is smooth, which this small sphere reaches at once
    o.smooth.iterations = all;
    const PipelineResult keep = smooth_mesh(noisy, o);
    EXPECT_TRUE(keep.report.smoothed);
    EXPECT_EQ(keep.report.smooth.iterations_run(), 1);
    EXPECT_TRUE(keep.report.smooth.stopped_at_checkpoint);
    EXPECT_FALSE(keep.report.fitted);  // nothing to decide
    // auto keeps it after the first iteration, its kept result clean, with keep's result
    o.connectivity = Connectivity::Auto;
    const PipelineResult automatic = smooth_mesh(noisy, o);
    ASSERT_TRUE(automatic.report.connectivity_kept);
    EXPECT_TRUE(automatic.report.keep_declined.empty());
    EXPECT_EQ(automatic.report.smooth.iterations_run(), 1);
    EXPECT_EQ(automatic.mesh.positions, keep.mesh.positions);
#ifdef NORMALFLOW_TEST_HAS_CGAL  // the intersections are CGAL's to count
    // two spheres that overlap: the kept result keeps their intersections, so it is re-meshed after the whole run, the
    // same as auto with the fit's filter, which decides after it
    Mesh beside = noisy_sphere(0.3);
    for (Vec3f& p : beside.positions) p.x += 0.8f;
    const Mesh overlapping = test::concat(noisy, beside);
    const PipelineResult remeshed = smooth_mesh(overlapping, o);
    ASSERT_FALSE(remeshed.report.connectivity_kept);
    EXPECT_FALSE(remeshed.report.keep_declined.empty());
    EXPECT_EQ(remeshed.report.smooth.iterations_run(), all);
    EXPECT_FALSE(remeshed.report.smooth.stopped_at_checkpoint);
    PipelineOptions fit = o;
    fit.keep_filter = KeepFilter::Volume;
    const PipelineResult decided_after = smooth_mesh(overlapping, fit);
    ASSERT_FALSE(decided_after.report.connectivity_kept);
    EXPECT_FALSE(decided_after.report.keep_declined.empty());
    EXPECT_EQ(decided_after.mesh.positions, remeshed.mesh.positions);
    EXPECT_EQ(decided_after.mesh.triangles, remeshed.mesh.triangles);
#endif
    // where the result is the engine's surface or fitted to it, the whole run
    o.connectivity = Connectivity::Remesh;
    EXPECT_EQ(smooth_mesh(noisy, o).report.smooth.iterations_run(), all);
    o.connectivity = Connectivity::Keep;
    o.keep_filter = KeepFilter::Volume;
    EXPECT_EQ(smooth_mesh(noisy, o).report.smooth.iterations_run(), all);
}

TEST(KeptFaces, TheRiskEstimateNotTheBoundEndsAPartsRounds) {
    // The face filter's rounds end where the risk estimate found its least (kRiskPatience rounds past it); the bound
    // only bounds the cost. fandisk_n6 (heavy noise on a CAD part) has its least at round 40: the bound of 30 it had
    // cut it short, 0.15° face by face worse.
    const std::string data = std::string(NORMALFLOW_TEST_DATA) + "/pairs_gcn/";
    if (!std::filesystem::exists(data + "fandisk_n6.ply")) GTEST_SKIP() << data << " missing";
    const Mesh noisy = read_mesh(data + "fandisk_n6.ply"), truth = read_mesh(data + "fandisk_gt.ply");
    PipelineOptions o = kept();
    const PipelineResult free = smooth_mesh(noisy, o);
    ASSERT_TRUE(free.report.faces_filtered);
    EXPECT_GT(free.report.faces.rounds, 30);
    EXPECT_EQ(free.report.faces.rounds_run, free.report.faces.rounds + kRiskPatience);
    EXPECT_LT(free.report.faces.rounds_run, kMaxFaceRounds);
    const std::string json = to_json(free.report).dump();  // the report gives the rounds and the blend
    EXPECT_NE(json.find("\"face_filter\":{"), std::string::npos);
    EXPECT_NE(json.find("\"blend\":"), std::string::npos);
    // a part's creases: the risk estimate keeps the weight on the guidance (RangeWeight::Chosen), and says so
    EXPECT_TRUE(free.report.faces.guided);
    EXPECT_NE(json.find("\"guided\":true"), std::string::npos);
    o.faces.normal_steps = 30;
    const PipelineResult cut = smooth_mesh(noisy, o);
    EXPECT_EQ(cut.report.faces.rounds_run, 30);
    EXPECT_LT(correspondence_errors(free.mesh, truth).mean_face_angle_deg,
              correspondence_errors(cut.mesh, truth).mean_face_angle_deg - 0.05);
}

TEST(KeptFaces, AKeptMeshsVolumeHasVoxelsOfTwiceItsNoise) {
    // The kept mesh's volume (the guard's alone on an open input, the engine's first iteration on a closed one): at
    // the automatic resolution, or coarser so that a voxel is twice the noise (the gradient over two voxels then sees
    // the surface, not the noise), but no coarser than half the automatic resolution nor its floor; a resolution given
    // stays
    const Mesh sphere = test::icosphere(1.0, 5);
    const auto check = [&](const Mesh& input, const PipelineOptions& o, bool closed, double sigma) {
        const PipelineReport r = smooth_mesh(input, o).report;
        EXPECT_TRUE(r.connectivity_kept);
        EXPECT_EQ(r.smoothed, closed);  // the engine runs on a closed input only
        const int automatic = auto_resolution(input, o), resolution = r.scan_options.resolution;
        const int floor = std::max(kAutoResolutionMin, (automatic + 1) / 2);
        const double noise = r.noise, h = r.scan.grid.voxel_size;
        EXPECT_GT(noise, 0.0);
        EXPECT_GT(automatic, kAutoResolutionMin);
        const double extent = h * resolution;  // the same box in more or fewer voxels
        if (2 * noise <= extent / automatic) {
            EXPECT_EQ(resolution, automatic) << sigma;
            return 0;
        }
        if (2 * noise < extent / floor) {
            EXPECT_LT(resolution, automatic) << sigma;
            EXPECT_NEAR(h, 2 * noise, 0.1 * 2 * noise) << sigma;
            return 1;
        }
        EXPECT_EQ(resolution, floor) << sigma;  // no coarser than the floor
        return floor > kAutoResolutionMin ? 3 : 2;
    };
    std::set<int> cases;
    for (const double sigma : {0.1, 0.2, 0.6}) {  // below a voxel; between; beyond the floor
        Mesh noisy = sphere;
        NoiseOptions n;
        n.sigma = sigma;
        add_noise(noisy, n);
        const Mesh open = without_cap(noisy);
        PipelineOptions o = kept();
        cases.insert(check(open, o, false, sigma));
        o.scan.resolution = 100;
        EXPECT_EQ(smooth_mesh(open, o).report.scan_options.resolution, 100);
        if (sigma == 0.6) {
            // closed, with a length unit that puts the automatic resolution at 300: its half binds
            o.scan.resolution = 0;
            o.length_scale = kAutoVoxelsPerLength * bounding_box(noisy).longest_side() / 300;
            cases.insert(check(noisy, o, true, sigma));
        }
    }
    EXPECT_EQ(cases, (std::set<int>{0, 1, 2, 3}));  // each branch of the rule, the half of the automatic included
}

TEST(NoiseScale, AutoSigmaSpatialIsTwiceTheNoiseWithinAVoxelAndTheFixedValue) {
    const double unit = 0.1, voxel = 0.02;  // five voxels per length unit, as the automatic resolution
    EXPECT_DOUBLE_EQ(auto_sigma_spatial(0.01, unit, voxel), 0.2);  // 2 × 0.1 unit
    EXPECT_DOUBLE_EQ(auto_sigma_spatial(0.025, unit, voxel), 0.5);
    EXPECT_DOUBLE_EQ(auto_sigma_spatial(0.2, unit, voxel), kMaxAutoSigmaSpatial);  // a coarse model's curvature
    EXPECT_DOUBLE_EQ(auto_sigma_spatial(0.001, unit, voxel), 0.2);                 // one voxel, 0.2 unit
    EXPECT_DOUBLE_EQ(auto_sigma_spatial(0.0, unit, voxel), kMaxAutoSigmaSpatial);  // unknown: a volume input
    EXPECT_DOUBLE_EQ(auto_sigma_spatial(0.001, unit, 1.0), kMaxAutoSigmaSpatial);  // a voxel above the cap
}

TEST(NoiseScale, SmoothMeshRunsWithTwiceTheMeasuredNoise) {
    const Mesh sphere = test::icosphere(1.0, 4);
    PipelineOptions o;
    o.scan.resolution = 128;  // a voxel is 0.2 length units: below every σ here
    o.smooth.iterations = 1;
    o.smooth.sigma_spatial = 0;  // auto
    for (const double sigma : {0.15, 0.25, 0.5}) {
        Mesh noisy = sphere;
        NoiseOptions n;
        n.sigma = sigma;
        const NoiseReport added = add_noise(noisy, n);
        const PipelineResult r = smooth_mesh(noisy, o);
        EXPECT_NEAR(r.report.noise, added.sigma_world, 0.1 * added.sigma_world) << sigma;
        EXPECT_DOUBLE_EQ(r.report.noise, estimate_noise(noisy, NoiseNormals::Steady).sigma);
        ASSERT_LT(r.report.scan.grid.voxel_size, 0.25 * r.report.length_scale);
        const double expected = std::min(2.0 * r.report.noise / r.report.length_scale, kMaxAutoSigmaSpatial);
        EXPECT_NEAR(r.report.sigma_spatial, expected, 1e-6) << sigma;
        // σ = 0.5 edge caps at the fixed value; 0.15 and 0.25 run with less
        EXPECT_EQ(r.report.sigma_spatial < kMaxAutoSigmaSpatial - 1e-6, sigma < 0.3) << sigma;
    }
    // the default is the fixed value; a value given is used as given
    EXPECT_FLOAT_EQ(PipelineOptions{}.smooth.sigma_spatial, float(kMaxAutoSigmaSpatial));
    o.smooth.sigma_spatial = 0.45f;
    EXPECT_FLOAT_EQ(float(smooth_mesh(sphere, o).report.sigma_spatial), 0.45f);
}

}  // namespace
}  // namespace normalflow
