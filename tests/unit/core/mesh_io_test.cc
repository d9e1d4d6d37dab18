#include "lf/core/mesh_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "test_dir.h"

namespace lf {
namespace {

// A directory of its own per test process: ctest may run test cases in parallel.
class MeshIoTest : public ::testing::Test {
  protected:
    void SetUp() override { dir_ = lf::testing::FreshTestDir("lf_mesh_io"); }
    void TearDown() override { std::filesystem::remove_all(dir_); }

    std::string Write(const std::string& name, const std::string& bytes) {
        const std::string path = (dir_ / name).string();
        std::ofstream(path, std::ios::binary) << bytes;
        return path;
    }

    // Loading `bytes` as file `name` must fail with a message containing `expected`.
    void ExpectError(const std::string& name, const std::string& bytes,
                     const std::string& expected) {
        absl::StatusOr<TriangleMesh> mesh = LoadMesh(Write(name, bytes));
        ASSERT_FALSE(mesh.ok()) << "expected an error containing: " << expected;
        EXPECT_TRUE(absl::IsInvalidArgument(mesh.status())) << mesh.status();
        EXPECT_NE(mesh.status().message().find(expected), std::string::npos)
            << "message: " << mesh.status().message() << "\nexpected: " << expected;
    }

    std::filesystem::path dir_;
};

template <typename T>
void Put(std::string& out, T value, bool big_endian) {
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    if (big_endian == (std::endian::native == std::endian::little)) {
        std::reverse(bytes, bytes + sizeof(T));
    }
    out.append(bytes, sizeof(T));
}

using Triangles = std::vector<std::array<uint32_t, 3>>;

TEST_F(MeshIoTest, ObjPolygonsAreFanTriangulated) {
    absl::StatusOr<TriangleMesh> mesh = LoadMesh(Write("square.obj",
                                                       "# a unit square and a triangle\n"
                                                       "mtllib ignored.mtl\n"
                                                       "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                                       "vn 0 0 1\n"
                                                       "o square\n"
                                                       "f 1//1 2//1 3//1 4//1\n"
                                                       "o triangle\n"
                                                       "f -4 -3 -1\n"));
    ASSERT_TRUE(mesh.ok()) << mesh.status();
    EXPECT_EQ(mesh->name, "square");
    ASSERT_EQ(mesh->positions.size(), 4u);
    EXPECT_EQ(mesh->positions[2], Vec3d(1, 1, 0));
    EXPECT_EQ(mesh->triangles, (Triangles{{0, 1, 2}, {0, 2, 3}, {0, 1, 3}}));
}

TEST_F(MeshIoTest, ObjErrorsNameTheLine) {
    const std::string vertices = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    ExpectError("a.obj", vertices + "\n# comment\nf 1 2 3\nf 1 2 7\n",
                "a.obj:7: face refers to vertex 7 but the file has 3 vertices");
    ExpectError("b.obj", vertices + "f 1 2 -9\n", "b.obj:4: face refers to vertex -5");
    ExpectError("c.obj", vertices + "f 1 2 3\nf 0 1 2\n", "c.obj:5: ");
    ExpectError("d.obj", vertices + "f 1 2 3\r\nf 1 2\r\n", "d.obj:5: face with fewer than 3");
    ExpectError("e.obj", "v 0 0 0\nv 1e400 0 0\nv 0 1 0\nf 1 2 3\n",
                "e.obj:2: vertex 2 is not finite");
    ExpectError("f.obj", "# nothing\n", "f.obj: no vertices");
    ExpectError("g.obj", vertices, "g.obj: no faces");
}

TEST_F(MeshIoTest, AsciiPlySkipsOtherPropertiesAndElements) {
    absl::StatusOr<TriangleMesh> mesh =
        LoadMesh(Write("square.ply",
                       "ply\r\n"
                       "format ascii 1.0\r\n"
                       "comment written by hand\r\n"
                       "element vertex 4\r\n"
                       "property float x\r\n"
                       "property float nx\r\n"
                       "property double y\r\n"
                       "property float z\r\n"
                       "element face 2\r\n"
                       "property uchar red\r\n"
                       "property list uint int vertex_index\r\n"
                       "element tag 1\r\n"
                       "property list uchar uchar bytes\r\n"
                       "end_header\r\n"
                       "0 9 0 0\r\n1 9 0 0\r\n1 9 1 0\r\n0 9 1 0\r\n"
                       "255 4 0 1 2 3\r\n7 3 3 2 1\r\n"
                       "3 1 2 3\r\n"));
    ASSERT_TRUE(mesh.ok()) << mesh.status();
    ASSERT_EQ(mesh->positions.size(), 4u);
    EXPECT_EQ(mesh->positions[2], Vec3d(1, 1, 0));
    EXPECT_EQ(mesh->triangles, (Triangles{{0, 1, 2}, {0, 2, 3}, {3, 2, 1}}));
}

// Two triangles over three vertices, in either byte order, with properties to skip.
std::string BinaryPly(bool big_endian, bool truncate = false) {
    std::string ply = std::string("ply\nformat ") +
                      (big_endian ? "binary_big_endian" : "binary_little_endian") +
                      " 1.0\n"
                      "element vertex 3\n"
                      "property double x\nproperty double y\nproperty double z\n"
                      "property list uchar float texture\n"
                      "element face 2\n"
                      "property list uchar uint vertex_indices\n"
                      "property short flags\n"
                      "end_header\n";
    const double xyz[3][3] = {{0, 0, 0}, {2, 0, 0}, {0, 3, 0.5}};
    for (const auto& p : xyz) {
        for (double c : p) Put(ply, c, big_endian);
        Put<uint8_t>(ply, 2, big_endian);
        Put(ply, 0.25f, big_endian);
        Put(ply, 0.75f, big_endian);
    }
    for (const uint32_t first : {0u, 2u}) {
        Put<uint8_t>(ply, 3, big_endian);
        for (uint32_t i = 0; i < 3; ++i) Put(ply, (first + i) % 3, big_endian);
        Put<int16_t>(ply, -1, big_endian);
    }
    if (truncate) ply.resize(ply.size() - 3);
    return ply;
}

TEST_F(MeshIoTest, BinaryPlyInBothByteOrders) {
    for (const bool big_endian : {false, true}) {
        absl::StatusOr<TriangleMesh> mesh = LoadMesh(Write("tri.ply", BinaryPly(big_endian)));
        ASSERT_TRUE(mesh.ok()) << mesh.status();
        EXPECT_EQ(mesh->positions, (std::vector<Vec3d>{{0, 0, 0}, {2, 0, 0}, {0, 3, 0.5}}));
        EXPECT_EQ(mesh->triangles, (Triangles{{0, 1, 2}, {2, 0, 1}}));
    }
}

TEST_F(MeshIoTest, PlyErrorsNameTheElement) {
    ExpectError("t.ply", BinaryPly(false, true), "t.ply: face 1: unexpected end of file");
    const std::string header =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    const std::string vertices = "0 0 0\n1 0 0\n0 1 0\n";
    ExpectError("a.ply", header + vertices + "3 0 1 3\n",
                "a.ply:13: face 0: vertex index 3 out of range (3 vertices)");
    ExpectError("b.ply", header + vertices + "2 0 1\n", "b.ply:13: face 0: has 2 vertex indices");
    ExpectError("c.ply", header + "0 0 0\n1 nan 0\n",
                "c.ply:11: vertex 1: coordinate is not finite");
    ExpectError("d.ply", header + vertices + "3 0 1 x\n",
                "d.ply:13: face 0: expected a number, got \"x\"");
    ExpectError("e.ply", header + vertices + "3 0 1\n", "e.ply:13: face 0: unexpected end of file");
    ExpectError("f.ply", "ply\nformat binary_middle_endian 1.0\n", "f.ply:2: unknown format");
    ExpectError("g.ply", "ply\nformat ascii 1.0\nelement vertex 1\n",
                "g.ply: the header has no end_header");
    ExpectError("h.ply", "solid cube\n", "h.ply:1: not a PLY file");
    ExpectError("i.ply",
                "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n",
                "i.ply: vertex element has no property y");
    ExpectError("j.ply",
                "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                "property float z\nend_header\n0 0 0\n",
                "j.ply: no face element");
    ExpectError("k.ply",
                "ply\nformat ascii 1.0\nelement vertex 99999999999\nproperty float x\n"
                "property float y\nproperty float z\nelement face 0\n"
                "property list uchar int vertex_indices\nend_header\n0 0 0\n",
                "k.ply: too many vertices");
}

TEST_F(MeshIoTest, MissingFileAndUnknownFormat) {
    absl::StatusOr<TriangleMesh> missing = LoadMesh((dir_ / "missing.obj").string());
    ASSERT_FALSE(missing.ok());
    EXPECT_TRUE(absl::IsNotFound(missing.status()));
    EXPECT_NE(missing.status().message().find("missing.obj"), std::string::npos);
    ExpectError("mesh.stl", "solid\n", "mesh.stl: unknown mesh format \".stl\"");
}

}  // namespace
}  // namespace lf
