// Bad input for the mesh readers and writers (io/formats/mesh_formats.h, io/io.h): every truncation
// of a small valid file, garbage, bit flips, NaN, out-of-range indices, faces with < 3 corners,
// absurd header counts, missing files, unknown extensions, unwritable paths, failed writes.
#include "io/formats/mesh_formats.h"
#include "support/test_files.h"

#include <gtest/gtest.h>
#include <unistd.h>
#include <vector>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>

#include "core/errors.h"
#include "io/io.h"

namespace fs = std::filesystem;
using namespace normalflow;

using normalflow::test::slurp;
using normalflow::test::TempDir;

namespace {

const std::string kFixtures = std::string(NORMALFLOW_TEST_FIXTURES);

using Reader = std::function<Mesh(std::string_view, const std::string&)>;

Mesh cube() {
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    m.triangles = {{0, 3, 2}, {0, 2, 1}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                   {2, 3, 7}, {2, 7, 6}, {0, 4, 7}, {0, 7, 3}, {1, 2, 6}, {1, 6, 5}};
    return m;
}

bool identical(const Mesh& a, const Mesh& b) {
    return a.positions.size() == b.positions.size() && a.triangles == b.triangles &&
           std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(Vec3f)) == 0;
}

/// Runs the reader over an exact-size heap copy of bytes (so an over-read is an ASan error):
/// returns the mesh, or nullopt with the InvalidInput message. Any other exception fails the test.
std::optional<Mesh> try_read(const Reader& read, std::string_view bytes, const std::string& name,
                             std::string* message = nullptr) {
    std::unique_ptr<char[]> copy(new char[bytes.size() + 1]);
    std::memcpy(copy.get(), bytes.data(), bytes.size());
    try {
        return read(std::string_view(copy.get(), bytes.size()), name);
    } catch (const InvalidInput& e) {
        if (message) *message = e.what();
        return std::nullopt;
    }
}

/// Whatever a reader returns is a valid soup: finite positions, indices in range, >= 1 triangle.
void expect_valid(const Mesh& m) {
    ASSERT_FALSE(m.triangles.empty());
    for (const auto& p : m.positions) ASSERT_TRUE(is_finite(p));
    for (const auto& t : m.triangles)
        for (const auto i : t) ASSERT_LT(i, m.positions.size());
}

/// Expects InvalidInput whose single-line message contains each of `parts`.
void expect_invalid(const Reader& read, std::string_view bytes, const std::string& name,
                    std::initializer_list<std::string_view> parts) {
    std::string msg;
    const auto r = try_read(read, bytes, name, &msg);
    ASSERT_FALSE(r.has_value()) << "accepted: " << std::string(bytes.substr(0, 200));
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    EXPECT_NE(msg.find(name), std::string::npos) << msg;
    for (const auto p : parts) EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
}

const Reader kObj = [](std::string_view b, const std::string& n) { return read_obj_memory(b, n); };
const Reader kPly = [](std::string_view b, const std::string& n) { return read_ply_memory(b, n); };
const Reader kOff = [](std::string_view b, const std::string& n) { return read_off_memory(b, n); };
const Reader kStl = [](std::string_view b, const std::string& n) { return read_stl_memory(b, n); };

std::size_t trimmed_size(const std::string& s) {
    std::size_t n = s.size();
    while (n > 0 && std::isspace(static_cast<unsigned char>(s[n - 1]))) --n;
    return n;
}

}  // namespace

// ------------------------------------------------------------------------------------- truncation
//
// Decision, per format, for the prefix of length L of a valid file of length N:
// - binary PLY and binary STL: every L < N is an error.
// - ASCII PLY and OFF declare their counts in the header, so every prefix that cuts any element is
//   an error; the only accepted prefixes drop trailing whitespace (L >= last non-space byte) and
//   give the identical mesh. (The fixtures end with a one-digit token, so no cut can shorten a
//   number into another valid number.)
// - ASCII STL needs its 'endsolid': accepted iff the prefix contains the whole keyword.
// - OBJ has no counts: a prefix is either an error or a valid shorter file whose vertices are all
//   there (they precede the faces in the fixture) and whose triangles are a non-empty prefix of
//   the full list.

TEST(Truncation, BinaryPlyEveryLength) {
    TempDir dir;
    write_ply(dir / "c.ply", cube());
    const std::string full = slurp(dir / "c.ply");
    ASSERT_TRUE(identical(*try_read(kPly, full, "c.ply"), cube()));
    for (std::size_t L = 0; L < full.size(); ++L)
        ASSERT_FALSE(try_read(kPly, std::string_view(full).substr(0, L), "c.ply")) << "L = " << L;
}

TEST(Truncation, BigEndianPlyEveryLength) {
    const std::string full = slurp(kFixtures + "/cube_be.ply");
    ASSERT_TRUE(try_read(kPly, full, "be.ply"));
    for (std::size_t L = 0; L < full.size(); ++L)
        ASSERT_FALSE(try_read(kPly, std::string_view(full).substr(0, L), "be.ply")) << "L = " << L;
}

TEST(Truncation, BinaryStlEveryLength) {
    TempDir dir;
    write_stl(dir / "c.stl", cube());
    const std::string full = slurp(dir / "c.stl");
    ASSERT_TRUE(try_read(kStl, full, "c.stl"));
    for (std::size_t L = 0; L < full.size(); ++L)
        ASSERT_FALSE(try_read(kStl, std::string_view(full).substr(0, L), "c.stl")) << "L = " << L;
    // the same with a header that starts with "solid": a truncated one is tried as ASCII and fails
    std::string solid = full;
    std::memcpy(solid.data(), "solid cube", 10);
    ASSERT_TRUE(try_read(kStl, solid, "s.stl"));
    for (std::size_t L = 0; L < solid.size(); ++L)
        ASSERT_FALSE(try_read(kStl, std::string_view(solid).substr(0, L), "s.stl")) << "L = " << L;
}

TEST(Truncation, CountedTextFormatsAcceptOnlyTrailingWhitespaceCuts) {
    TempDir dir;
    write_ply(dir / "w.ply", cube(), WriteOptions{false});
    write_off(dir / "w.off", cube());
    const struct {
        std::string path;
        Reader read;
    } cases[] = {{kFixtures + "/cube_ascii.ply", kPly},
                 {kFixtures + "/cube_colors.off", kOff},
                 {dir / "w.ply", kPly},
                 {dir / "w.off", kOff}};
    for (const auto& c : cases) {
        SCOPED_TRACE(c.path);
        const std::string full = slurp(c.path);
        const Mesh whole = *try_read(c.read, full, "t");
        const std::size_t last = trimmed_size(full);
        for (std::size_t L = 0; L <= full.size(); ++L) {
            const auto r = try_read(c.read, std::string_view(full).substr(0, L), "t");
            if (L >= last) {
                ASSERT_TRUE(r) << "L = " << L;
                ASSERT_TRUE(identical(*r, whole)) << "L = " << L;
            } else {
                ASSERT_FALSE(r) << "L = " << L;
            }
        }
    }
}

TEST(Truncation, AsciiStlNeedsEndsolid) {
    TempDir dir;
    write_stl(dir / "a.stl", cube(), WriteOptions{false});
    for (const std::string& path : std::vector<std::string>{kFixtures + "/tet_ascii.stl", dir / "a.stl"}) {
        SCOPED_TRACE(path);
        const std::string full = slurp(path);
        const Mesh whole = *try_read(kStl, full, "t.stl");
        const std::size_t keyword_end = full.rfind("endsolid") + 8;
        for (std::size_t L = 0; L <= full.size(); ++L) {
            const auto r = try_read(kStl, std::string_view(full).substr(0, L), "t.stl");
            if (L >= keyword_end) {
                ASSERT_TRUE(r) << "L = " << L;
                ASSERT_TRUE(identical(*r, whole)) << "L = " << L;
            } else {
                ASSERT_FALSE(r) << "L = " << L;
            }
        }
    }
}

TEST(Truncation, ObjPrefixIsErrorOrShorterValidFile) {
    TempDir dir;
    write_obj(dir / "w.obj", cube());
    for (const std::string& path : std::vector<std::string>{kFixtures + "/cube_quads.obj", dir / "w.obj"}) {
        SCOPED_TRACE(path);
        const std::string full = slurp(path);
        const auto read_whole = try_read(kObj, full, "t.obj");
        ASSERT_TRUE(read_whole);
        const Mesh& whole = *read_whole;
        std::size_t file_vertices = full.starts_with("v ") ? 1 : 0;
        for (std::size_t at = full.find("\nv "); at != std::string::npos; at = full.find("\nv ", at + 1))
            ++file_vertices;
        const std::size_t first_face = full.find("\nf ");
        ASSERT_NE(first_face, std::string::npos);
        // end of the first face line (its '\n'): a prefix shorter than this has no complete face
        const std::size_t first_face_end = full.find('\n', first_face + 1);
        int accepted = 0;
        for (std::size_t L = 0; L <= full.size(); ++L) {
            const auto r = try_read(kObj, std::string_view(full).substr(0, L), "t.obj");
            // A prefix that ends at a line end and holds a complete face is a valid shorter file.
            const bool whole_lines = L == full.size() || (L > 0 && full[L - 1] == '\n');
            if (!r) {
                ASSERT_TRUE(L < first_face_end || !whole_lines) << "rejected a valid prefix, L = " << L;
                continue;
            }
            ASSERT_GT(L, first_face + 4) << "accepted a prefix without a face, L = " << L;
            ++accepted;
            // the file's vertices come first; copies split off for differing texture coordinates follow
            ASSERT_GE(r->positions.size(), file_vertices) << "L = " << L;
            ASSERT_TRUE(std::equal(whole.positions.begin(), whole.positions.begin() + std::ptrdiff_t(file_vertices),
                                   r->positions.begin()))
                << "L = " << L;
            ASSERT_FALSE(r->triangles.empty());
            ASSERT_LE(r->triangles.size(), whole.triangles.size());
            // same corners in the same places (a cut corner may lose its texture coordinate, and so use the
            // file's vertex where the whole file uses a copy of it)
            for (std::size_t t = 0; t < r->triangles.size(); ++t)
                for (std::size_t c = 0; c < 3; ++c)
                    ASSERT_EQ(r->positions[r->triangles[t][c]], whole.positions[whole.triangles[t][c]])
                        << "L = " << L << ", triangle " << t;
            if (L >= trimmed_size(full)) {
                ASSERT_TRUE(identical(*r, whole)) << "L = " << L;
            }
        }
        EXPECT_GT(accepted, 0);
    }
}

// ------------------------------------------------------------------------------------- garbage

TEST(Garbage, RandomBytesNeverCrash) {
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> byte(0, 255);
    for (int trial = 0; trial < 200; ++trial) {
        std::string g(std::size_t(1 + trial * 13 % 700), '\0');
        for (char& c : g) c = char(byte(rng));
        if (trial % 4 == 1)
            g = "ply\nformat binary_little_endian 1.0\nelement vertex 8\nproperty float x\n"
                "property float y\nproperty float z\nelement face 12\n"
                "property list uchar int vertex_indices\nend_header\n" +
                g;
        if (trial % 4 == 2) g = "solid x\n" + g;
        if (trial % 4 == 3) g = "OFF\n8 12 0\n" + g;
        for (const Reader* r : {&kObj, &kPly, &kOff, &kStl}) {
            const auto m = try_read(*r, g, "g");
            if (m) expect_valid(*m);
        }
    }
}

TEST(Garbage, BitFlipsGiveAnErrorOrAValidMesh) {
    TempDir dir;
    const Mesh c = cube();
    write_ply(dir / "b.ply", c);
    write_ply(dir / "a.ply", c, WriteOptions{false});
    write_stl(dir / "b.stl", c);
    write_stl(dir / "a.stl", c, WriteOptions{false});
    write_obj(dir / "a.obj", c);
    write_off(dir / "a.off", c);
    const std::pair<std::string, const Reader*> files[] = {{"b.ply", &kPly}, {"a.ply", &kPly}, {"b.stl", &kStl},
                                                           {"a.stl", &kStl}, {"a.obj", &kObj}, {"a.off", &kOff}};
    std::mt19937 rng(11);
    for (const auto& [name, read] : files) {
        const std::string full = slurp(dir / name);
        std::uniform_int_distribution<std::size_t> pos(0, full.size() - 1);
        std::uniform_int_distribution<int> bit(0, 7);
        for (int trial = 0; trial < 300; ++trial) {
            std::string s = full;
            for (int k = 0; k < 1 + trial % 3; ++k) s[pos(rng)] ^= char(1 << bit(rng));
            const auto m = try_read(*read, s, name);
            if (m) expect_valid(*m);
        }
    }
}

// ------------------------------------------------------------------------------------- contents

TEST(BadContents, EmptyFile) {
    for (const Reader* r : {&kObj, &kPly, &kOff, &kStl}) expect_invalid(*r, "", "e.x", {"empty file"});
}

TEST(BadContents, NanAndInfCoordinates) {
    expect_invalid(kObj, "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n", "n.obj", {"line 2", "NaN"});
    expect_invalid(kObj, "v 0 0 0\nv 1 0 0\nv 0 1 1e39\nf 1 2 3\n", "n.obj", {"line 3", "NaN or infinite"});
    expect_invalid(kOff, "OFF\n3 1 0\n0 0 0\n1 0 0\ninf 1 0\n3 0 1 2\n", "n.off", {"line 5", "NaN"});
    expect_invalid(
        kPly,
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 -inf\n0 1 0\n3 0 1 2\n",
        "n.ply", {"line 11", "NaN"});
    // binary PLY with a NaN float, and with a double beyond float range
    std::string b =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float v[9] = {0, 0, 0, 1, 0, 0, 0, nan, 0};
    b.append(reinterpret_cast<const char*>(v), sizeof v);
    const char face[13] = {3, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0};
    b.append(face, sizeof face);
    expect_invalid(kPly, b, "n.ply", {"vertex 2", "NaN"});
    std::string d =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
        "property double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    const double dv[9] = {0, 0, 0, 1, 0, 0, 0, 1e300, 0};
    d.append(reinterpret_cast<const char*>(dv), sizeof dv);
    d.append(face, sizeof face);
    expect_invalid(kPly, d, "d.ply", {"vertex 2", "out-of-float-range"});
    expect_invalid(kStl,
                   "solid s\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex nan 0 0\nvertex 0 1 0\n"
                   "endloop\nendfacet\nendsolid s\n",
                   "n.stl", {"line 5", "NaN"});
    // binary STL with an infinite coordinate
    std::string s(80, 'x');
    const std::uint32_t one = 1;
    s.append(reinterpret_cast<const char*>(&one), 4);
    const float f[12] = {0, 0, 1, 0, 0, 0, std::numeric_limits<float>::infinity(), 0, 0, 0, 1, 0};
    s.append(reinterpret_cast<const char*>(f), sizeof f);
    s.append(2, '\0');
    expect_invalid(kStl, s, "n.stl", {"facet 0", "NaN or infinite"});
}

TEST(BadContents, IndexOutOfRange) {
    expect_invalid(kObj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n", "r.obj", {"line 5", "index 4 out of range"});
    expect_invalid(kObj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", "r.obj", {"line 4", "index 0"});
    expect_invalid(kObj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", "r.obj", {"line 4", "-4"});
    expect_invalid(kObj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999\n", "r.obj", {"line 4"});
    expect_invalid(kOff, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "r.off", {"line 6", "index 3 out of range"});
    expect_invalid(kOff, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", "r.off", {"line 6", "index -1"});
    expect_invalid(kPly,
                   "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                   "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
                   "r.ply", {"line 13", "index 7 out of range"});
    std::string b =
        "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    b.append(36, '\0');
    const char face[13] = {3, 0, 0, 0, 0, 0, 0, 0, 1, char(0xff), char(0xff), char(0xff), char(0xff)};
    b.append(face, sizeof face);
    expect_invalid(kPly, b, "r.ply", {"face 0", "index -1 out of range"});
}

TEST(BadContents, FacesWithFewerThanThreeCorners) {
    expect_invalid(kObj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2\n", "c.obj", {"line 5", "2 corners"});
    expect_invalid(kObj, "v 0 0 0\nf\n", "c.obj", {"line 2", "0 corners"});
    expect_invalid(kOff, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "c.off", {"line 6", "2 corners"});
    expect_invalid(kOff, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", "c.off", {"line 6", "3 indices, expected 4"});
    expect_invalid(kPly,
                   "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                   "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n",
                   "c.ply", {"line 13", "2 corners"});
    expect_invalid(kStl,
                   "solid s\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                   "endloop\nendfacet\nendsolid s\n",
                   "c.stl", {"line 6", "2 vertices"});
}

TEST(BadContents, NoFaces) {
    expect_invalid(kObj, "# only points\nv 0 0 0\nv 1 0 0\n", "p.obj", {"no faces"});
    expect_invalid(kOff, "OFF\n1 0 0\n0 0 0\n", "p.off", {"no faces"});
    expect_invalid(kPly,
                   "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                   "property float z\nend_header\n0 0 0\n",
                   "p.ply", {"no 'face' element"});
    expect_invalid(kPly,
                   "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                   "property float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n",
                   "p.ply", {"no faces"});
    expect_invalid(kStl, "solid s\nendsolid s\n", "p.stl", {"no faces"});
    std::string s(80, 'x');
    s.append(4, '\0');
    expect_invalid(kStl, s, "p.stl", {"no faces"});
}

TEST(BadContents, AbsurdCountsFailBeforeAllocating) {
    // 10^12 vertices would need 12 TB: the check against the file size must come first.
    expect_invalid(kPly,
                   "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\nproperty float x\n"
                   "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                   "end_header\n\x01\x02\x03",
                   "a.ply", {"1000000000000", "bytes"});
    expect_invalid(kPly,
                   "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                   "property float y\nproperty float z\nelement face 18446744073709551615\n"
                   "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                   "a.ply", {"18446744073709551615"});
    expect_invalid(kPly, "ply\nformat ascii 1.0\nelement vertex 99999999999999999999999\nend_header\n", "a.ply",
                   {"line 3"});
    expect_invalid(kOff, "OFF\n1000000000000 1 0\n0 0 0\n3 0 0 0\n", "a.off", {"line 2", "1000000000000"});
    expect_invalid(kOff, "OFF\n3 4000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "a.off", {"4000000000"});
    std::string s(80, 'x');
    const std::uint32_t n = 0xffffffffu;
    s.append(reinterpret_cast<const char*>(&n), 4);
    s.append(50, '\0');
    expect_invalid(kStl, s, "a.stl", {"4294967295 triangles"});
    // a binary list that claims more items than remain
    std::string b =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n";
    b.append(36, '\0');
    const std::uint32_t items = 0x7fffffffu;
    b.append(reinterpret_cast<const char*>(&items), 4);
    b.append(12, '\0');
    expect_invalid(kPly, b, "a.ply", {"truncated"});
}

TEST(BadContents, MalformedSyntax) {
    expect_invalid(kObj, "v 0 0 0\nv 1 0 zero\n", "m.obj", {"line 2", "'zero'"});
    expect_invalid(kObj, "v 0 0\n", "m.obj", {"line 1", "fewer than 3"});
    expect_invalid(kObj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3x\n", "m.obj", {"line 4", "'3x'"});
    expect_invalid(kObj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2/a 3\n", "m.obj", {"line 4"});
    // (a string_view with its size: a plain literal would stop at the NUL)
    expect_invalid(kObj, std::string_view("v 0 0 0\n\0v 1 0 0\n", 17), "m.obj", {"line 2", "NUL"});
    expect_invalid(kPly, "ply\nformat xml 1.0\nend_header\n", "m.ply", {"line 2", "unknown format"});
    expect_invalid(kPly, "plyx\n", "m.ply", {"not a PLY"});
    expect_invalid(kPly, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", "m.ply", {"end_header"});
    expect_invalid(kPly, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float32x x\nend_header\n", "m.ply",
                   {"line 4", "unknown property type"});
    expect_invalid(kPly,
                   "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                   "element face 1\nproperty list uchar int vertex_indices\nend_header\n",
                   "m.ply", {"x, y or z"});
    expect_invalid(kPly,
                   "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                   "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n"
                   "3 0 1 2\n5 5 5\n",
                   "m.ply", {"line 14", "after the last element"});
    expect_invalid(kOff, "NOPE\n3 1 0\n", "m.off", {"line 1", "not an OFF file"});
    expect_invalid(kOff, "4OFF\n3 1 0\n", "m.off", {"line 1", "unsupported"});
    expect_invalid(kOff, "OFF BINARY\n3 1 0\n", "m.off", {"line 1", "binary OFF"});
    expect_invalid(kOff, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0 \n", "m.off", {"truncated", "0 of 1 faces"});
    expect_invalid(kStl,
                   "solid s\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
                   "endloop\nendfacet\n",
                   "m.stl", {"endsolid"});
    expect_invalid(kStl, "solid s\nfacet normal 0 0 0\nouter lop\n", "m.stl", {"line 3", "'lop'"});
    expect_invalid(kStl, "tiny", "m.stl", {"not an STL"});
}

// ------------------------------------------------------------------------------------- file system

TEST(Files, MissingFileIsIoErrorNamingTheFile) {
    for (const std::string ext : {".obj", ".ply", ".off", ".stl"}) {
        const std::string path = "/nonexistent-dir/missing" + ext;
        try {
            read_mesh(path);
            FAIL() << "no exception for " << path;
        } catch (const IoError& e) {
            EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos) << e.what();
        }
    }
}

TEST(Files, DirectoryIsIoError) {
    TempDir dir;
    fs::create_directories(dir / "d.ply");
    EXPECT_THROW(read_mesh(dir / "d.ply"), IoError);
}

TEST(Files, UnknownExtensionIsInvalidInput) {
    TempDir dir;
    for (const std::string name : {"m.xyz", "m", "m.ply.bak"}) {
        try {
            read_mesh(dir / name);
            FAIL() << name;
        } catch (const InvalidInput& e) {
            EXPECT_NE(std::string(e.what()).find("unknown mesh file"), std::string::npos) << e.what();
        }
        EXPECT_THROW(write_mesh(dir / name, cube()), InvalidInput);
        EXPECT_FALSE(fs::exists(dir / name));
    }
    EXPECT_THROW(write_mesh(dir / "m.gltf", cube()), InvalidInput);
    EXPECT_THROW(read_volume(dir / "v.xyz"), InvalidInput);
}

TEST(Files, UnwritablePathThrowsIoErrorAndLeavesNothing) {
    for (const std::string ext : {".obj", ".ply", ".off", ".stl"}) {
        const std::string path = "/nonexistent-dir/x" + ext;
        EXPECT_THROW(write_mesh(path, cube()), IoError) << path;
        EXPECT_FALSE(fs::exists("/nonexistent-dir"));
    }
    TempDir dir;
    fs::create_directories(dir / "folder.ply");
    EXPECT_THROW(write_mesh(dir / "folder.ply", cube()), IoError);
}

TEST(Files, FailedWriteNeverDamagesTheExistingFile) {
    TempDir dir;
    Mesh bad_index = cube();
    bad_index.triangles[5][1] = 8;
    Mesh bad_nan = cube();
    bad_nan.positions[3].y = std::numeric_limits<float>::quiet_NaN();
    const Mesh empty;
    for (const std::string ext : {".obj", ".ply", ".off", ".stl"})
        for (const bool binary : {true, false}) {
            const std::string path = dir / ("old" + ext);
            write_mesh(path, cube(), WriteOptions{binary});
            const std::string before = slurp(path);
            for (const Mesh* m : std::vector<const Mesh*>{&bad_index, &bad_nan, &empty}) {
                try {
                    write_mesh(path, *m, WriteOptions{binary});
                    FAIL() << "no exception writing an invalid mesh to " << path;
                } catch (const InvalidInput& e) {
                    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
                }
                ASSERT_EQ(slurp(path), before) << path;
            }
            // no temporary files left beside it
            EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator{}), 1);
            fs::remove(path);
        }
}

TEST(Files, ErrorMessagesNameReaderFileAndLine) {
    TempDir dir;
    const std::string path = dir / "scan.ply";
    {
        std::ofstream f(path, std::ios::binary);
        f << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n5 0 1 2\n";
    }
    try {
        read_mesh(path);
        FAIL();
    } catch (const InvalidInput& e) {
        const std::string msg = e.what();
        EXPECT_EQ(msg.rfind("read_ply: " + path + ", line 13: ", 0), 0u) << msg;
    }
}
