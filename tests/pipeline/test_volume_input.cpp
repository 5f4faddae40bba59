// Volumes in and out (issue 23): a real MRI volume through the engine, placed where its file says; a label
// map of a real surface round-tripping with anisotropic, rotated spacing; the CLI's volume inputs and
// outputs against its mesh path, and OpenVDB's own Python module reading what we write.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "core/errors.h"
#include "core/mesh_report.h"
#include "extract/extract_surface.h"
#include "extract/volume_sampler.h"
#include "io/formats/nifti.h"
#include "io/io.h"
#include "metrics/surface_distance.h"
#include "pipeline/pipeline.h"
#include "sdf/image_to_volume.h"
#include "sdf/sdf_test_meshes.h"
#include "support/test_files.h"

namespace normalflow {
namespace {

const std::string kData = NORMALFLOW_TEST_DATA;
const std::string kMri = kData + "/medical/pve_2_whitematter.nii.gz";
const std::string kBrain = kData + "/medical/brainmesh_icbm152_lh.ply";

Vec3d to_d(const Vec3f& p) { return {p.x, p.y, p.z}; }

VolumeInput iso_input(double iso) {
    VolumeInput in;
    in.iso = iso;
    return in;
}

VolumeInput label_input(double label) {
    VolumeInput in;
    in.label = label;
    return in;
}

/// Writes a uint8 label image as a detached NRRD header (name.nhdr) and its raw data (name.raw).
void write_label_nhdr(const std::string& nhdr, const ScalarImage& im) {
    const std::string raw = nhdr.substr(0, nhdr.size() - 5) + ".raw";
    std::ofstream h(nhdr);
    char buf[512];
    h << "NRRD0004\ntype: uint8\ndimension: 3\nspace: right-anterior-superior\n";
    h << "sizes: " << im.dims[0] << " " << im.dims[1] << " " << im.dims[2] << "\n";
    h << "space directions:";
    for (const Vec3d& a : im.axes) {
        std::snprintf(buf, sizeof buf, " (%.17g,%.17g,%.17g)", a.x, a.y, a.z);
        h << buf;
    }
    std::snprintf(buf, sizeof buf, "\nspace origin: (%.17g,%.17g,%.17g)\n", im.origin.x, im.origin.y, im.origin.z);
    h << buf
      << "kinds: domain domain domain\nencoding: raw\ndata file: " << std::filesystem::path(raw).filename().string()
      << "\n";
    std::vector<std::uint8_t> bytes(im.values.begin(), im.values.end());
    std::ofstream(raw, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

/// The image's value at a world position: trilinear in the image's own index space.
double image_value(const ScalarImage& im, const Vec3d& w) {
    double c[3];
    for (int a = 0; a < 3; ++a) c[a] = dot(w - im.origin, im.axes[a]) / dot(im.axes[a], im.axes[a]);
    int i0[3];
    double t[3];
    for (int a = 0; a < 3; ++a) {
        i0[a] = std::clamp(int(std::floor(c[a])), 0, im.dims[a] - 2);
        t[a] = std::clamp(c[a] - i0[a], 0.0, 1.0);
    }
    double v = 0;
    for (int d = 0; d < 8; ++d) {
        const int dx = d & 1, dy = (d >> 1) & 1, dz = (d >> 2) & 1;
        v += (dx ? t[0] : 1 - t[0]) * (dy ? t[1] : 1 - t[1]) * (dz ? t[2] : 1 - t[2]) *
             im.at(i0[0] + dx, i0[1] + dy, i0[2] + dz);
    }
    return v;
}

double percentile(std::vector<double> v, double p) {
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, std::size_t(p * double(v.size())))];
}

TEST(VolumeInput, MriWhiteMatterIsSmoothedWhereTheVolumeSays) {
    // FSL's white-matter partial-volume map of a T1 scan (NIfTI-1, uint8 scaled to [0, 1], 1 mm, a rotated sform).
    const ScalarImage im = read_nifti(kMri);
    VolumeReadInfo info;
    Volume v = read_volume(kMri, iso_input(0.5), &info);
    EXPECT_EQ(info.format, "nifti");
    EXPECT_TRUE(info.placed);  // the sform turns the grid by a few degrees
    EXPECT_FALSE(info.resampled);
    // Unsmoothed, the surface lies where the image's value is 0.5, in world coordinates.
    PipelineOptions raw;
    raw.smoothing = false;
    const Mesh iso = volume_to_mesh(v, raw);
    std::vector<double> off;
    for (std::size_t i = 0; i < iso.positions.size(); i += 37)
        off.push_back(std::abs(image_value(im, to_d(iso.positions[i])) - 0.5));
    EXPECT_LT(percentile(off, 0.5), 0.05);
    EXPECT_LT(percentile(off, 0.9), 0.15);
    // Smoothed with the defaults: closed, manifold, near the isosurface, and smoother than it.
    const PipelineResult r = smooth_volume_input(v, PipelineOptions{});
    const MeshReport rep = mesh_report(r.mesh);
    EXPECT_TRUE(rep.closed && rep.manifold);
    const SurfaceDistance d = surface_distance(r.mesh, iso);
    EXPECT_LT(d.mean, 1.0);                   // mm: within a voxel on average
    EXPECT_GT(d.mean_normal_angle_deg, 2.0);  // it did change the normals
}

TEST(VolumeInput, LabelMapOfARealSurfaceRoundTripsWithItsPlacement) {
    // The left hemisphere of the ICBM152 brain surface made a label map on a grid turned by 20° about (1, 2, 3)
    // with spacing 0.9 × 0.9 × 1.5 mm (a .nhdr with its raw data): read back, the surface lies on the
    // original in world coordinates, and smoothing takes the staircase off.
    const Mesh brain = read_mesh(kBrain);
    PipelineOptions scan;
    scan.smoothing = false;
    scan.scan.voxel_size = 0.5;
    const Volume sdf = mesh_to_volume(brain, scan);
    const detail::VolumeSampler phi(sdf);
    const double angle = 20 * std::numbers::pi / 180;
    const Vec3d k = Vec3d{1, 2, 3} / std::sqrt(14.0);
    const auto turn = [&](const Vec3d& v) {  // Rodrigues
        return v * std::cos(angle) + cross(k, v) * std::sin(angle) + k * (dot(k, v) * (1 - std::cos(angle)));
    };
    const std::array<double, 3> spacing{0.9, 0.9, 1.5};
    std::array<Vec3d, 3> u{turn({1, 0, 0}), turn({0, 1, 0}), turn({0, 0, 1})};
    std::array<double, 3> lo{1e30, 1e30, 1e30}, hi{-1e30, -1e30, -1e30};
    for (const Vec3f& p : brain.positions)
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], dot(u[a], to_d(p)));
            hi[a] = std::max(hi[a], dot(u[a], to_d(p)));
        }
    ScalarImage im;
    for (int a = 0; a < 3; ++a) {
        im.axes[a] = u[a] * spacing[a];
        im.dims[a] = int(std::ceil((hi[a] - lo[a] + 8) / spacing[a])) + 1;
        im.origin = im.origin + u[a] * (lo[a] - 4);
    }
    im.values.resize(im.sample_count());
    for (int z = 0; z < im.dims[2]; ++z)
        for (int y = 0; y < im.dims[1]; ++y)
            for (int x = 0; x < im.dims[0]; ++x)
                im.values[std::size_t(x) +
                          std::size_t(im.dims[0]) * (std::size_t(y) + std::size_t(im.dims[1]) * std::size_t(z))] =
                    phi.phi(im.origin + im.axes[0] * double(x) + im.axes[1] * double(y) + im.axes[2] * double(z),
                            nullptr) < 0
                        ? 1.0f
                        : 0.0f;
    test::TempDir dir;
    const std::string nhdr = dir / "label.nhdr";
    write_label_nhdr(nhdr, im);

    VolumeReadInfo info;
    Volume v = read_volume(nhdr, label_input(1), &info);
    EXPECT_EQ(info.format, "nrrd");
    EXPECT_TRUE(info.placed);
    EXPECT_TRUE(info.resampled);
    EXPECT_NEAR(v.grid.voxel_size, 0.9, 1e-12);
    PipelineOptions raw;
    raw.smoothing = false;
    const Mesh stairs = volume_to_mesh(v, raw);
    const SurfaceDistance ds = surface_distance(stairs, brain);
    EXPECT_LT(ds.mean, 0.35);      // mm, within the label map's sampling
    EXPECT_LT(ds.hausdorff, 1.5);  // the 1.5 mm steps, at most
    const PipelineResult smoothed = smooth_volume_input(v, PipelineOptions{});
    const SurfaceDistance dm = surface_distance(smoothed.mesh, brain);
    EXPECT_LT(dm.mean, 0.5);
    EXPECT_LT(dm.mean_normal_angle_deg, ds.mean_normal_angle_deg - 3.0);  // the staircase smoothed away
    EXPECT_TRUE(mesh_report(smoothed.mesh).closed && mesh_report(smoothed.mesh).manifold);

    // The smoothed volume written and read back (.vdb and .nrrd) keeps its placement: the same surface.
    for (const char* ext : {".nrrd", ".vdb"}) {
#ifndef NORMALFLOW_TEST_HAS_OPENVDB
        if (std::string(ext) == ".vdb") continue;
#endif
        const std::string path = dir / (std::string("smoothed") + ext);
        write_volume(path, v);
        const Volume back = read_volume(path);
        EXPECT_FALSE(back.grid.placement.is_identity()) << ext;
        const Mesh again = volume_to_mesh(back, raw);
        ASSERT_EQ(again.positions.size(), smoothed.mesh.positions.size()) << ext;
        double worst = 0;
        for (std::size_t i = 0; i < again.positions.size(); ++i)
            worst = std::max(worst, norm(to_d(again.positions[i]) - to_d(smoothed.mesh.positions[i])));
        EXPECT_LT(worst, 1e-4) << ext;
    }
}

#ifdef NORMALFLOW_TEST_CLI
int run(const std::string& command) { return std::system(command.c_str()); }

Mesh ball_mesh() { return test::icosphere(1.0, 4, Vec3d{0.1, -0.2, 0.05}); }

TEST(VolumeInput, CliVolumesInAndOutAgreeWithTheMeshPath) {
    test::TempDir dir;
    const std::string cli = std::string(NORMALFLOW_TEST_CLI) + " ";
    const std::string sphere = dir / "sphere.ply";
    write_mesh(sphere, ball_mesh());
    const std::string common = " --length-scale 0.1 --iterations 2 --quiet";
    // mesh → mesh, the reference
    ASSERT_EQ(run(cli + "smooth " + sphere + " " + dir / "mesh.ply --resolution 48 --connectivity remesh" + common), 0);
    const Mesh reference = read_mesh(dir / "mesh.ply");
    const auto same = [&](const std::string& path) {
        const Mesh m = read_mesh(path);
        if (m.positions.size() != reference.positions.size()) return false;
        for (std::size_t i = 0; i < m.positions.size(); ++i)
            if (norm(to_d(m.positions[i]) - to_d(reference.positions[i])) > 1e-6) return false;
        return true;
    };
    for (const std::string ext : {".nrrd", ".vdb"}) {
#ifndef NORMALFLOW_TEST_HAS_OPENVDB
        if (ext == ".vdb") continue;
#endif
        // mesh → volume, then extract
        const std::string smoothed = dir / ("smoothed" + ext);
        ASSERT_EQ(run(cli + "smooth " + sphere + " " + smoothed + " --resolution 48" + common), 0);
        ASSERT_EQ(run(cli + "extract " + smoothed + " " + dir / "extracted.ply --quiet"), 0);
        EXPECT_TRUE(same(dir / "extracted.ply")) << ext;
        // voxelize, then volume → mesh
        const std::string scanned = dir / ("scanned" + ext);
        ASSERT_EQ(run(cli + "voxelize " + sphere + " " + scanned + " --resolution 48 --quiet"), 0);
        ASSERT_EQ(run(cli + "smooth " + scanned + " " + dir / "from_volume.ply" + common), 0);
        EXPECT_TRUE(same(dir / "from_volume.ply")) << ext;
    }
#ifdef NORMALFLOW_TEST_HAS_OPENVDB
    // OpenVDB's own Python module (Debian python3-openvdb) reads the smoothed volume as a level set: inside
    // at the ball's centre, zero within a voxel on its surface (radius 1), outside beyond it.
    const std::string py =
        "/usr/bin/python3 -c \"import pyopenvdb as vdb, sys; g = vdb.read(sys.argv[1], 'surface'); "
        "assert g.gridClass == vdb.GridClass.LEVEL_SET, g.gridClass; "
        "h = g.transform.voxelSize()[0]; a = g.getConstAccessor(); "
        "v = lambda x: a.getValue(g.transform.worldToIndexCellCentered((0.1 + x, -0.2, 0.05))); "
        "assert v(0) < 0 and abs(v(1)) < h and v(1.2) > 0, (v(0), v(1), v(1.2), h)\" ";
    EXPECT_EQ(run(py + dir / "smoothed.vdb"), 0);
    // --normal-map adds the filtered normal map as a vector grid: unit vectors, outwards on the sphere.
    ASSERT_EQ(run(cli + "smooth " + sphere + " " + dir / "normals.vdb --resolution 48 --normal-map" + common), 0);
    const std::string pyn =
        "/usr/bin/python3 -c \"import pyopenvdb as vdb, sys, math; g = vdb.read(sys.argv[1], 'normals'); "
        "a = g.getConstAccessor(); t = g.transform; c = (0.1, -0.2, 0.05); n = 0; "
        "assert g.activeVoxelCount() > 1000, g.activeVoxelCount()\n"
        "for d in [(1, 0, 0), (0, -1, 0), (0, 0, 1), (0.6, 0.8, 0)]:\n"
        " v = a.getValue(t.worldToIndexCellCentered(tuple(c[i] + d[i] for i in range(3))))\n"
        " assert abs(math.sqrt(sum(x * x for x in v)) - 1) < 1e-3 and sum(v[i] * d[i] for i in range(3)) > 0.99, (d, "
        "v)\" ";
    EXPECT_EQ(run(pyn + dir / "normals.vdb"), 0);
    EXPECT_NE(
        run(cli + "smooth " + sphere + " " + dir / "normals.nrrd --resolution 48 --normal-map --quiet 2>/dev/null"), 0);
#endif
}

// A mesh's smoothed volume as the output runs in bricks where asked (or where the whole does not fit), as a mesh output
// does: before, the volume output ignored --brick-size and was refused over the memory
TEST(VolumeInput, AMeshsVolumeOutputRunsInBricksWhenAsked) {
    Mesh m = ball_mesh();
    for (std::size_t i = 0; i < m.positions.size(); ++i)  // deterministic radial noise of ±1.5%
        m.positions[i] *= float(1.0 + 0.015 * std::sin(double(i) * 12.9898));
    PipelineOptions o;
    o.scan.resolution = 48;
    o.smooth.iterations = 2;
    PipelineReport whole_report, bricked_report;
    const Volume whole = smooth_mesh_to_volume(m, o, &whole_report);
    EXPECT_FALSE(whole_report.bricked);
    PipelineOptions b = o;
    b.brick_voxels = 24;
    b.brick_halo_voxels = 16;
    const Volume bricked = smooth_mesh_to_volume(m, b, &bricked_report);
    ASSERT_TRUE(bricked_report.bricked);
    EXPECT_GE(bricked_report.bricks.total(), 8);
    ASSERT_EQ(bricked.grid.dims, whole.grid.dims);
    const double h = whole.grid.voxel_size;
    double largest = 0;
    int near = 0;
    for (int k = 0; k < whole.grid.dims[2]; ++k)
        for (int j = 0; j < whole.grid.dims[1]; ++j)
            for (int i = 0; i < whole.grid.dims[0]; ++i)
                if (std::abs(whole.value(i, j, k)) < h) {
                    largest = std::max(largest, double(std::abs(whole.value(i, j, k) - bricked.value(i, j, k))));
                    ++near;
                }
    EXPECT_GT(near, 1000);
    EXPECT_LT(largest, 0.05 * h);
    // the normal map is the whole run's: not in bricks
    NormalMap normals;
    PipelineReport with_normals;
    (void)smooth_mesh_to_volume(m, b, &with_normals, nullptr, &normals);
    EXPECT_FALSE(with_normals.bricked);
    EXPECT_FALSE(normals[0].values.empty());

    test::TempDir dir;
    const std::string in = dir / "ball.ply", out = dir / "ball.nrrd", json = dir / "report.json";
    write_mesh(in, m);
    ASSERT_EQ(run(std::string(NORMALFLOW_TEST_CLI) + " smooth " + in + " " + out +
                  " --resolution 48 --iterations 2 --brick-size 24 --brick-halo 16 --quiet --json > " + json),
              0);
    std::ifstream f(json);
    const std::string report((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    EXPECT_NE(report.find("\"bricks\":{\"brick_voxels\":24"), std::string::npos) << report;
}

TEST(VolumeInput, CliReadsAMaskAndRefusesBadVolumeInput) {
    test::TempDir dir;
    const std::string cli = std::string(NORMALFLOW_TEST_CLI) + " ";
    // a binary mask (0/1) of a ball, 0.5 mm spacing along x only: no --label needed
    const Vec3d c{10.3, 9.7, 10.1};
    ScalarImage im;
    im.dims = {41, 21, 21};
    im.axes = {Vec3d{0.5, 0, 0}, Vec3d{0, 1, 0}, Vec3d{0, 0, 1}};
    im.values.resize(im.sample_count());
    for (int z = 0; z < 21; ++z)
        for (int y = 0; y < 21; ++y)
            for (int x = 0; x < 41; ++x)
                im.values[std::size_t(x) + 41 * (std::size_t(y) + 21 * std::size_t(z))] =
                    norm(Vec3d{0.5 * x, double(y), double(z)} - c) < 6 ? 1.0f : 0.0f;
    const std::string mask = dir / "mask.nhdr", out = dir / "out.ply", json = dir / "r.json";
    write_label_nhdr(mask, im);
    ASSERT_EQ(run(cli + "smooth " + mask + " " + out + " --json > " + json), 0);
    const std::string j = test::slurp(json);
    EXPECT_NE(j.find("\"surface\":\"label 1 (a binary mask)\""), std::string::npos) << j;
    EXPECT_NE(j.find("\"resampled\":true"), std::string::npos) << j;
    const auto radial = [&](const Mesh& m) {  // mean and max |distance to c − 6| over the vertices
        std::pair<double, double> e{0, 0};
        for (const Vec3f& p : m.positions) {
            const double d = std::abs(norm(to_d(p) - c) - 6.0);
            e.first += d / double(m.positions.size());
            e.second = std::max(e.second, d);
        }
        return e;
    };
    const Mesh m = read_mesh(out);
    EXPECT_TRUE(mesh_report(m).closed);
    const auto smoothed = radial(m);
    std::filesystem::remove(out);
    // extract takes the same reading: the mask's staircase, unsmoothed, within the coarse spacing's half
    ASSERT_EQ(run(cli + "extract " + mask + " " + out + " --label 1 --quiet"), 0);
    const auto stairs = radial(read_mesh(out));
    std::filesystem::remove(out);
    EXPECT_LT(stairs.second, 0.5 + 0.05);
    EXPECT_LT(smoothed.second, 0.5);
    EXPECT_LT(smoothed.first, stairs.first);

    // Bad input: one line naming the file and the problem, a non-zero status, no output file.
    const std::string err = dir / "err.txt";
    const auto refused = [&](const std::string& args, const std::string& says) {
        const int rc = run(cli + args + " 2> " + err);
        const std::string e = test::slurp(err);
        EXPECT_NE(rc, 0) << args;
        EXPECT_NE(e.find(says), std::string::npos) << args << "\n" << e;
        EXPECT_FALSE(std::filesystem::exists(out)) << args;
    };
    {  // the input itself as the output: refused before anything is written, the file unchanged
        const std::string before = test::slurp(mask);
        refused("smooth " + mask + " " + mask, "is the input file");
        refused("extract " + mask + " " + dir.path().string() + "/./mask.nhdr --label 1", "is the input file");
        EXPECT_EQ(test::slurp(mask), before);
    }
    refused("smooth " + mask + " " + out + " --iso 0.5 --label 1", "either an iso value or a label");
    refused("smooth " + mask + " " + out + " --resolution 64", "resolution and shell apply to a mesh input");
    refused("smooth " + mask + " " + out + " --label 7", "holds no surface");
    refused("smooth " + dir / "sphere.ply" + " " + out + " --iso 1", "apply to a volume input");
    const std::string garbage = dir / "garbage.nii.gz";
    std::ofstream(garbage) << "this is not a NIfTI file";
    refused("smooth " + garbage + " " + out, garbage);
    refused("smooth " + kMri + " " + out, "give --iso");
#ifdef NORMALFLOW_TEST_HAS_OPENVDB
    const std::string vdb = dir / "mask.vdb";
    ASSERT_EQ(run(cli + "smooth " + mask + " " + vdb + " --quiet"), 0);
    refused("smooth " + vdb + " " + out + " --label 1", "a .vdb level set is used as it is");
#endif
}
#endif

}  // namespace
}  // namespace normalflow
