// io/render: the software renderer (known answers on a sphere), colour maps, legend, PNG bytes, and the
// compare pictures. PNG files are decoded independently by check_png.py (tests/render/CMakeLists.txt).
#include "io/render/render.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "core/errors.h"
#include "io/io.h"
#include "io/render/color_map.h"
#include "io/render/comparison_pictures.h"
#include "io/render/png.h"
#include "sdf/sdf_test_meshes.h"
#include "support/test_files.h"

namespace normalflow {
namespace {

constexpr Rgb8 kWhite{255, 255, 255};

Camera head_on_ortho(double half_size) {
    Camera c;
    c.projection = Projection::Orthographic;
    c.eye = {0, 0, 5};
    c.target = {0, 0, 0};
    c.up = {0, 1, 0};
    c.half_size = half_size;
    return c;
}

std::size_t covered(const Image& img, Rgb8 bg = kWhite) {
    std::size_t n = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) n += !(img.at(x, y) == bg);
    return n;
}

int brightness(Rgb8 c) { return int(c.r) + int(c.g) + int(c.b); }

std::uint32_t be32(const std::vector<std::uint8_t>& b, std::size_t at) {
    return (std::uint32_t(b[at]) << 24) | (std::uint32_t(b[at + 1]) << 16) | (std::uint32_t(b[at + 2]) << 8) |
           b[at + 3];
}

// Analytic: a unit sphere seen head-on covers a disc of pi r^2 pixels; its centre faces the headlight.
TEST(RenderMesh, UnitSphereOrthographicDiscAreaAndShading) {
    const Mesh sphere = test::icosphere(1.0, 4);
    RenderOptions o;
    o.light = {0, 0, 1};
    const Image img = render_mesh(sphere, head_on_ortho(1.25), o);
    ASSERT_EQ(img.width, 400);
    ASSERT_EQ(img.rgb.size(), 400u * 400u * 3u);
    const double r_px = 200.0 / 1.25;  // 160 pixels
    const double expected = std::numbers::pi * r_px * r_px;
    EXPECT_NEAR(double(covered(img)), expected, 0.03 * expected);
    // Centre (normal towards the light) brighter than near the rim (normal at ~70 degrees).
    const Rgb8 centre = img.at(200, 200), rim = img.at(200 + 150, 200);
    EXPECT_FALSE(rim == kWhite);
    EXPECT_GT(brightness(centre), brightness(rim) + 100);
    // The centre is lit fully: base colour (190, 190, 200) times (ambient + (1 - ambient) * 1) = base.
    EXPECT_NEAR(centre.r, 190, 2);
    EXPECT_NEAR(centre.b, 200, 2);
    for (auto [x, y] : {std::pair{0, 0}, {399, 0}, {0, 399}, {399, 399}}) EXPECT_EQ(img.at(x, y), kWhite);
    // Left-right and up-down symmetric coverage (the disc is centred).
    EXPECT_FALSE(img.at(200 - 155, 200) == kWhite);
    EXPECT_FALSE(img.at(200, 200 + 155) == kWhite);
    EXPECT_EQ(img.at(200 - 165, 200), kWhite);
    EXPECT_EQ(img.at(200, 200 - 165), kWhite);
}

TEST(RenderMesh, UnitSpherePerspectiveDiscArea) {
    const Mesh sphere = test::icosphere(1.0, 4);
    Camera c = head_on_ortho(1.0);
    c.projection = Projection::Perspective;
    c.eye = {0, 0, 4};
    c.fov_deg = 40;
    const Image img = render_mesh(sphere, c);
    // The silhouette is a circle of angular radius asin(1/4); f = 200 / tan(20 deg).
    const double f = 200.0 / std::tan(20.0 * std::numbers::pi / 180.0);
    const double r_px = f * std::tan(std::asin(0.25));
    const double expected = std::numbers::pi * r_px * r_px;
    EXPECT_NEAR(double(covered(img)), expected, 0.03 * expected);
}

TEST(RenderMesh, ScalarZeroIsTheFirstColourAndMaxTheLast) {
    const Mesh sphere = test::icosphere(1.0, 2);
    RenderOptions o;
    o.ambient = 1.0;  // no lighting term: the pixel is the map's colour
    std::vector<float> s(sphere.positions.size(), 0.0f);
    o.vertex_scalars = s;
    o.scalar_min = 0;
    o.scalar_max = 2;
    Image img = render_mesh(sphere, head_on_ortho(1.25), o);
    EXPECT_EQ(img.at(200, 200), map_color(ColorMap::Viridis, 0.0));
    EXPECT_EQ(img.at(200, 200), (Rgb8{68, 1, 84}));
    for (float& v : s) v = 5.0f;  // above the range: clamped to the last colour
    img = render_mesh(sphere, head_on_ortho(1.25), o);
    EXPECT_EQ(img.at(200, 200), (Rgb8{253, 231, 37}));
    o.color_map = ColorMap::Diverging;
    for (float& v : s) v = 1.0f;  // middle of the diverging map: white-ish
    img = render_mesh(sphere, head_on_ortho(1.25), o);
    EXPECT_EQ(img.at(200, 200), map_color(ColorMap::Diverging, 0.5));
    EXPECT_EQ(img.at(200, 200), (Rgb8{247, 247, 247}));
}

TEST(RenderMesh, NearerTriangleWinsInEitherOrder) {
    // Two squares facing the camera: z = 0 (scalar 0) and z = 1 (nearer, scalar 1).
    Mesh m;
    for (float z : {0.0f, 1.0f})
        for (auto [x, y] : {std::pair{-1.f, -1.f}, {1.f, -1.f}, {1.f, 1.f}, {-1.f, 1.f}})
            m.positions.push_back({x, y, z});
    const std::vector<Tri> far{{0, 1, 2}, {0, 2, 3}}, near{{4, 5, 6}, {4, 6, 7}};
    std::vector<float> s{0, 0, 0, 0, 1, 1, 1, 1};
    RenderOptions o;
    o.ambient = 1.0;
    o.vertex_scalars = s;
    for (int order = 0; order < 2; ++order) {
        m.triangles = order == 0 ? far : near;
        m.triangles.insert(m.triangles.end(), (order == 0 ? near : far).begin(), (order == 0 ? near : far).end());
        const Image img = render_mesh(m, head_on_ortho(2.0), o);
        EXPECT_EQ(img.at(200, 200), map_color(ColorMap::Viridis, 1.0)) << "order " << order;
        EXPECT_EQ(img.at(200 + 50, 200 - 60), map_color(ColorMap::Viridis, 1.0)) << "order " << order;
        EXPECT_EQ(img.at(5, 5), kWhite);
    }
}

TEST(RenderMesh, SameInputSameBytesAndShadingModesDiffer) {
    const Mesh sphere = test::icosphere(1.0, 2);
    const Camera c = camera_from_box(bounding_box(sphere), {-1, -1, -1});
    RenderOptions o;
    const Image a = render_mesh(sphere, c, o), b = render_mesh(sphere, c, o);
    EXPECT_EQ(a.rgb, b.rgb);
    EXPECT_EQ(encode_png(a), encode_png(b));
    o.shading = Shading::Flat;
    const Image f = render_mesh(sphere, c, o);
    EXPECT_NE(a.rgb, f.rgb);
    EXPECT_EQ(covered(a), covered(f));  // same coverage, different shading
    // Flat shading of a level-2 icosphere shows at most ~#F distinct colours plus background; smooth shows more.
    std::set<std::tuple<int, int, int>> ca, cf;
    for (int y = 0; y < 400; ++y)
        for (int x = 0; x < 400; ++x) {
            ca.insert({a.at(x, y).r, a.at(x, y).g, a.at(x, y).b});
            cf.insert({f.at(x, y).r, f.at(x, y).g, f.at(x, y).b});
        }
    EXPECT_LE(cf.size(), sphere.triangles.size() + 1);
    EXPECT_GT(ca.size(), cf.size());
}

// Property: camera_from_box fits the bounding sphere, so no view direction touches the image border.
TEST(CameraFromBox, EveryViewSeesTheWholeMesh) {
    const Mesh m = test::box_mesh({-3, 0, 1}, {5, 1, 2});
    for (Projection p : {Projection::Orthographic, Projection::Perspective})
        for (Vec3d d : {Vec3d{0, 0, -1}, Vec3d{-1, 0, 0}, Vec3d{0, -1, 0}, Vec3d{-1, -1, -1}, Vec3d{1, 2, 3}}) {
            const Image img = render_mesh(m, camera_from_box(bounding_box(m), d, p));
            ASSERT_GT(covered(img), 100u);
            for (int k = 0; k < 400; ++k) {
                EXPECT_EQ(img.at(k, 0), kWhite);
                EXPECT_EQ(img.at(k, 399), kWhite);
                EXPECT_EQ(img.at(0, k), kWhite);
                EXPECT_EQ(img.at(399, k), kWhite);
            }
        }
}

TEST(ColorMap, EndsStopsAndClamping) {
    EXPECT_EQ(map_color(ColorMap::Viridis, 0), (Rgb8{68, 1, 84}));
    EXPECT_EQ(map_color(ColorMap::Viridis, 1), (Rgb8{253, 231, 37}));
    EXPECT_EQ(map_color(ColorMap::Viridis, 0.5), (Rgb8{33, 144, 140}));
    EXPECT_EQ(map_color(ColorMap::Viridis, -3), map_color(ColorMap::Viridis, 0));
    EXPECT_EQ(map_color(ColorMap::Viridis, 7), map_color(ColorMap::Viridis, 1));
    EXPECT_EQ(map_color(ColorMap::Viridis, std::nan("")), map_color(ColorMap::Viridis, 0));
    EXPECT_EQ(map_color(ColorMap::Gray, 0.5), (Rgb8{128, 128, 128}));
    EXPECT_EQ(map_color(ColorMap::Diverging, 0), (Rgb8{33, 102, 172}));
    EXPECT_EQ(map_color(ColorMap::Diverging, 1), (Rgb8{178, 24, 43}));
    // Viridis gets lighter monotonically.
    int last = -1;
    for (int k = 0; k <= 100; ++k) {
        const int b = brightness(map_color(ColorMap::Viridis, k / 100.0));
        EXPECT_GE(b, last - 3) << k;
        last = b;
    }
}

TEST(Legend, BarRunsFromFirstToLastColourWithLabels) {
    const Image img = render_legend(ColorMap::Viridis, 0.0, 0.25);
    ASSERT_EQ(img.width, 400);
    ASSERT_EQ(img.height, 48);
    EXPECT_EQ(img.at(5, 10), map_color(ColorMap::Viridis, 0));
    EXPECT_EQ(img.at(394, 10), map_color(ColorMap::Viridis, 1));
    EXPECT_EQ(img.at(4, 10), (Rgb8{0, 0, 0}));  // border
    // Labels ("0", "0.125", "0.25") put ink below the bar.
    std::size_t ink = 0;
    for (int y = 30; y < 48; ++y)
        for (int x = 0; x < 400; ++x) ink += img.at(x, y) == (Rgb8{0, 0, 0});
    EXPECT_GT(ink, 100u);
    EXPECT_EQ(text_width("0.25"), 4 * 12 - 2);
    EXPECT_THROW(render_legend(ColorMap::Viridis, 0, 1, LegendOptions{.width = 10}), InvalidInput);
    EXPECT_THROW(render_legend(ColorMap::Viridis, 0, std::nan("")), InvalidInput);
}

TEST(Png, Crc32CheckValueAndChunkLayout) {
    const std::string check = "123456789";
    EXPECT_EQ(crc32_png(reinterpret_cast<const std::uint8_t*>(check.data()), check.size()), 0xCBF43926u);
    Image img(3, 2, {10, 20, 30});
    img.set(2, 1, {255, 0, 0});
    for (PngCompression mode : {PngCompression::Deflate, PngCompression::Stored}) {
        const std::vector<std::uint8_t> b = encode_png(img, mode);
        ASSERT_GT(b.size(), 8u + 25u + 12u + 12u);
        EXPECT_EQ(std::vector<std::uint8_t>(b.begin(), b.begin() + 8),
                  (std::vector<std::uint8_t>{0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'}));
        // Walk the chunks: length, type, data, CRC over type + data.
        std::vector<std::string> types;
        std::size_t at = 8;
        while (at + 12 <= b.size()) {
            const std::uint32_t len = be32(b, at);
            ASSERT_LE(at + 12 + len, b.size());
            types.emplace_back(b.begin() + std::ptrdiff_t(at + 4), b.begin() + std::ptrdiff_t(at + 8));
            EXPECT_EQ(be32(b, at + 8 + len), crc32_png(b.data() + at + 4, len + 4)) << types.back();
            if (types.back() == "IHDR") {
                EXPECT_EQ(len, 13u);
                EXPECT_EQ(be32(b, at + 8), 3u);
                EXPECT_EQ(be32(b, at + 12), 2u);
                EXPECT_EQ(b[at + 16], 8);  // bit depth
                EXPECT_EQ(b[at + 17], 2);  // RGB
            }
            at += 12 + len;
        }
        EXPECT_EQ(at, b.size());
        EXPECT_EQ(types, (std::vector<std::string>{"IHDR", "IDAT", "IEND"}));
    }
    // Stored blocks hold the filtered rows verbatim: 2 rows of (1 + 9) bytes.
    const std::vector<std::uint8_t> s = encode_png(img, PngCompression::Stored);
    EXPECT_EQ(be32(s, 8 + 25), 2u + 5u + 20u + 4u);  // zlib header, block header, data, Adler-32
}

TEST(Png, WritesAtomicallyAndRejectsBadImages) {
    test::TempDir dir;
    const Image img = render_legend(ColorMap::Diverging, -1, 1);
    write_png(dir / "legend.png", img);
    const std::vector<std::uint8_t> bytes = encode_png(img);
    EXPECT_EQ(test::slurp(dir / "legend.png"), std::string(bytes.begin(), bytes.end()));
    try {
        write_png(dir / "no/such/folder/x.png", img);
        ADD_FAILURE() << "expected IoError";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("x.png"), std::string::npos) << e.what();
    }
    EXPECT_THROW(encode_png(Image{}), InvalidInput);
    Image bad(4, 4);
    bad.rgb.pop_back();
    EXPECT_THROW(encode_png(bad), InvalidInput);
    std::size_t files = 0;
    for (const auto& e : std::filesystem::directory_iterator(dir.path())) files += e.is_regular_file();
    EXPECT_EQ(files, 1u);  // no temporary left behind
}

TEST(RenderMesh, BadInputThrowsWithAMessage) {
    const Mesh sphere = test::icosphere(1.0, 1);
    RenderOptions o;
    o.width = 0;
    EXPECT_THROW(render_mesh(sphere, head_on_ortho(1), o), InvalidInput);
    o = {};
    std::vector<float> s(3, 0.0f);
    o.vertex_scalars = s;
    try {
        render_mesh(sphere, head_on_ortho(1), o);
        ADD_FAILURE() << "expected InvalidInput";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("3 vertex scalars"), std::string::npos) << e.what();
    }
    Camera c = head_on_ortho(1);
    c.target = c.eye;
    EXPECT_THROW(render_mesh(sphere, c, {}), InvalidInput);
    c = head_on_ortho(1);
    c.up = {0, 0, 1};  // parallel to the view direction
    EXPECT_THROW(render_mesh(sphere, c, {}), InvalidInput);
    Mesh broken = sphere;
    broken.triangles[3][1] = 100000;
    try {
        render_mesh(broken, head_on_ortho(1), {});
        ADD_FAILURE() << "expected InvalidInput";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("render_mesh"), std::string::npos) << e.what();
    }
    EXPECT_THROW(camera_from_box(Box3d{}, {0, 0, -1}), InvalidInput);
    EXPECT_THROW(camera_from_box(bounding_box(sphere), {0, 0, 0}), InvalidInput);
    // An empty mesh is not an error: the background.
    EXPECT_EQ(covered(render_mesh(Mesh{}, head_on_ortho(1), {})), 0u);
}

TEST(ComparisonPictures, VertexDistancesOfAConcentricSphere) {
    const Mesh ref = test::icosphere(1.0, 4);
    const Mesh big = test::icosphere(1.1, 2);
    const auto q = make_bvh_query(ref);
    const std::vector<float> d = vertex_distances(big, *q);
    ASSERT_EQ(d.size(), big.positions.size());
    const double chord = test::sphere_chord_error(ref, 1.0);
    for (float v : d) EXPECT_NEAR(v, 0.1, chord + 1e-5);
}

TEST(ComparisonPictures, WritesEveryPictureWithASharedRange) {
    test::TempDir dir;
    const Mesh ref = test::icosphere(1.0, 3);
    std::vector<Mesh> cands{test::icosphere(1.05, 3), test::icosphere(1.2, 2)};
    const ComparisonPictures p = write_comparison_pictures(dir.path().string(), ref, cands);
    ASSERT_EQ(p.views.size(), 3u);
    ASSERT_EQ(p.meshes.size(), 3u);
    EXPECT_EQ(p.meshes[0].max_distance, 0.0);
    EXPECT_NEAR(p.meshes[1].max_distance, 0.05, 0.01);
    EXPECT_NEAR(p.meshes[2].max_distance, 0.2, 0.01);
    // The 99th percentile of both candidates' vertex distances: within the far candidate's, at most its top 1%.
    EXPECT_EQ(p.percentile, 99.0);
    EXPECT_LE(p.distance_max, p.meshes[2].max_distance);
    EXPECT_GT(p.distance_max, 0.19);
    EXPECT_EQ(p.meshes[1].clipped_fraction, 0.0);
    EXPECT_LE(p.meshes[2].clipped_fraction * double(cands[1].positions.size()),
              0.01 * double(cands[0].positions.size() + cands[1].positions.size()) + 1);
    EXPECT_EQ(p.legend, "pictures/legend.png");
    std::size_t files = 0;
    for (const auto& e : std::filesystem::directory_iterator(dir.path() / "pictures")) files += e.is_regular_file();
    EXPECT_EQ(files, 3u * 3u * 2u + 1u);
    for (const MeshPictures& m : p.meshes)
        for (const auto* list : {&m.shaded, &m.distance})
            for (const std::string& f : *list) {
                EXPECT_EQ(f.rfind("pictures/mesh", 0), 0u) << f;  // relative
                EXPECT_GT(std::filesystem::file_size(dir.path() / f), 1000u) << f;
            }
    // The biggest candidate is drawn in the map's last colour (with ambient + Lambert shading it is a
    // scaled version of it): its front distance picture has yellowish pixels, the reference's none.
    const Mesh& m2 = cands[1];
    const std::vector<float> d2 = vertex_distances(m2, *make_bvh_query(ref));
    RenderOptions o;
    o.ambient = 1.0;
    o.vertex_scalars = d2;
    o.scalar_max = p.distance_max;
    const Image img = render_mesh(m2, camera_from_box(bounding_box(ref), {0, 0, -1}), o);
    const Rgb8 c = img.at(200, 200);
    EXPECT_GT(c.r, 200);
    EXPECT_GT(c.g, 200);
    // Same call again: same bytes.
    test::TempDir dir2;
    write_comparison_pictures(dir2.path().string(), ref, cands);
    EXPECT_EQ(test::slurp(dir.path() / p.meshes[1].distance[2]), test::slurp(dir2.path() / p.meshes[1].distance[2]));
    EXPECT_EQ(test::slurp(dir.path() / p.legend), test::slurp(dir2.path() / p.legend));
}

std::size_t count_color(const Image& img, Rgb8 c) {
    std::size_t n = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) n += img.at(x, y) == c;
    return n;
}

// One far vertex (a spike) does not set the colour range of every candidate: the range is the 99th percentile of
// the candidates' vertex distances, the spike's vertex is counted as clipped and drawn in the over-range colour,
// and the legend has a swatch of it. The files are named after the meshes.
TEST(ComparisonPictures, OneFarVertexDoesNotSetTheRangeAndIsMarked) {
    const Mesh ref = test::icosphere(1.0, 3);
    std::vector<Mesh> cands{test::icosphere(1.02, 3), test::icosphere(1.05, 3)};
    Mesh& spiky = cands[0];
    std::size_t top = 0;  // the vertex nearest the front camera (views along -z see +z)
    for (std::size_t v = 1; v < spiky.positions.size(); ++v)
        if (spiky.positions[v].z > spiky.positions[top].z) top = v;
    spiky.positions[top] = spiky.positions[top] * 1.5f;
    ComparisonPicturesOptions o;
    o.render.ambient = 1.0;  // colours unshaded, so that the over-range colour is exact
    o.names = {"/data/gt.ply", "runs/a b.ply", "other/a b.ply"};
    test::TempDir dir;
    const ComparisonPictures p = write_comparison_pictures(dir.path().string(), ref, cands, o);
    EXPECT_NEAR(p.meshes[1].max_distance, 0.53, 0.02);
    EXPECT_NEAR(p.distance_max, 0.05, 0.01);  // not 0.53: the spike is one vertex of 1284
    EXPECT_NEAR(p.meshes[1].clipped_fraction, 1.0 / double(spiky.positions.size()), 1e-12);
    EXPECT_EQ(p.meshes[0].shaded[0], "pictures/reference_gt_front.png");
    EXPECT_EQ(p.meshes[1].distance[0], "pictures/a_b_front_distance.png");
    EXPECT_EQ(p.meshes[2].distance[2], "pictures/a_b_2_oblique_distance.png");
    // The front distance picture is the spiky sphere drawn with the over-range colour (the same bytes), which shows
    // at the spike; without that colour the spike is the map's last colour, like the top of the range.
    RenderOptions ro = o.render;
    const std::vector<float> d = vertex_distances(spiky, *make_bvh_query(ref));
    ro.vertex_scalars = d;
    ro.scalar_max = p.distance_max;
    const Camera front_camera = camera_from_box(bounding_box(ref), {0, 0, -1});
    EXPECT_EQ(count_color(render_mesh(spiky, front_camera, ro), o.over_color), 0u);
    ro.over_color = o.over_color;
    const Image front = render_mesh(spiky, front_camera, ro);
    EXPECT_GT(count_color(front, o.over_color), 0u);
    const std::vector<std::uint8_t> bytes = encode_png(front);
    EXPECT_EQ(test::slurp(dir.path() / p.meshes[1].distance[0]), std::string(bytes.begin(), bytes.end()));
    // The legend has a swatch of it, and only when asked.
    EXPECT_GT(
        count_color(render_legend(ColorMap::Viridis, 0, 1, LegendOptions{.over_color = o.over_color}), o.over_color),
        0u);
    EXPECT_EQ(count_color(render_legend(ColorMap::Viridis, 0, 1), o.over_color), 0u);
    o.names = {"only_one.ply"};
    EXPECT_THROW(write_comparison_pictures(dir.path().string(), ref, cands, o), InvalidInput);
    o.names.clear();
    o.distance_percentile = 0;
    EXPECT_THROW(write_comparison_pictures(dir.path().string(), ref, cands, o), InvalidInput);
}

// Real model: the GNF bunny (70k faces) and its noisy version; the pictures must be well under 2 s.
TEST(ComparisonPictures, RealBunnyPair) {
    const std::filesystem::path data = std::filesystem::path(NORMALFLOW_TEST_DATA) / "pairs_gnf";
    if (!std::filesystem::exists(data / "bunny_gt.ply")) GTEST_SKIP() << "no " << data;
    const Mesh ref = read_mesh((data / "bunny_gt.ply").string());
    std::vector<Mesh> cands{read_mesh((data / "bunny_n0.2.ply").string())};
    test::TempDir dir;
    const ComparisonPictures p = write_comparison_pictures(dir.path().string(), ref, cands);
    EXPECT_LT(p.seconds, 5.0);  // generous for a loaded CI machine; about 0.3 s measured
    EXPECT_GT(p.meshes[1].max_distance, 0.0);
    EXPECT_LT(p.meshes[1].max_distance, 0.05 * bounding_box(ref).diagonal());
    const Image img = render_mesh(ref, camera_from_box(bounding_box(ref), {0, 0, -1}));
    const double fraction = double(covered(img)) / (400.0 * 400.0);
    EXPECT_GT(fraction, 0.15);
    EXPECT_LT(fraction, 0.9);
}

}  // namespace
}  // namespace normalflow
