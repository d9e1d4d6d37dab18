#include "lf/core/mesh_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "lf/core/scene_loader.h"
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
    // The triangle's corners have no normal, so they take their face's: vertices of their own.
    ASSERT_EQ(mesh->positions.size(), 7u);
    EXPECT_EQ(mesh->positions[2], Vec3d(1, 1, 0));
    EXPECT_EQ(mesh->positions[6], Vec3d(0, 1, 0));
    EXPECT_EQ(mesh->triangles, (Triangles{{0, 1, 2}, {0, 2, 3}, {4, 5, 6}}));
    ASSERT_EQ(mesh->normals.size(), 7u);
    for (const Vec3& n : mesh->normals) EXPECT_EQ(n, Vec3(0, 0, 1));
    EXPECT_TRUE(mesh->uvs.empty());
}

// Corners sharing a position but not a normal become separate vertices; the same (position,
// normal, uv) triple is one vertex. OBJ's v = 0 is the image's bottom, stored as 1 - v.
TEST_F(MeshIoTest, ObjNormalsAndUvsMakeOneVertexPerDistinctCorner) {
    absl::StatusOr<TriangleMesh> mesh = LoadMesh(Write("crease.obj",
                                                       "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                                                       "vn 0 0 2\nvn 1 0 0\nvn 0 0 0\n"
                                                       "vt 0 0\nvt 1 0.25\nvt 0 1\n"
                                                       "f 1/1/1 2/2/1 3/3/1\n"
                                                       "f 1/1/2 3/3/2 4/1/2\n"
                                                       "f 2/2/1 1/1/1 3/3/3\n"));
    ASSERT_TRUE(mesh.ok()) << mesh.status();
    // Face 1: three vertices; face 2: three more (normal 2); face 3 reuses two of face 1's, and
    // its zero normal at vertex 3 is replaced by the face's (0, 0, -1): a new vertex.
    EXPECT_EQ(mesh->triangles, (Triangles{{0, 1, 2}, {3, 4, 5}, {1, 0, 6}}));
    ASSERT_EQ(mesh->positions.size(), 7u);
    ASSERT_EQ(mesh->normals.size(), 7u);
    ASSERT_EQ(mesh->uvs.size(), 7u);
    EXPECT_EQ(mesh->normals[0], Vec3(0, 0, 1));  // normalised
    EXPECT_EQ(mesh->normals[3], Vec3(1, 0, 0));
    EXPECT_EQ(mesh->normals[6], Vec3(0, 0, -1));
    EXPECT_EQ(mesh->positions[5], Vec3d(0, 0, 1));
    EXPECT_FLOAT_EQ(mesh->uvs[0].x, 0);
    EXPECT_FLOAT_EQ(mesh->uvs[0].y, 1);
    EXPECT_FLOAT_EQ(mesh->uvs[1].x, 1);
    EXPECT_FLOAT_EQ(mesh->uvs[1].y, 0.75f);
    EXPECT_FLOAT_EQ(mesh->uvs[2].y, 0);

    ExpectError("n.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//2 3//1\n",
                "n.obj:5: face refers to normal 2 but the file has 1 normals");
    ExpectError("t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\n\nf 1/1 2/3 3/1\n",
                "t.obj:6: face refers to texture coordinate 3 but the file has 1 texture");
    ExpectError("nan.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 1e400 0 1\nf 1//1 2//2 3//1\n",
                "nan.obj:5: normal 2 is not finite");
}

// An OBJ's MTL file through the reader: faces split per material, Kd, map_Kd (with its -s and -o
// options on the flipped v), Ke, d and the Blinn-Phong terms.
TEST_F(MeshIoTest, ObjMtlMaterialsSplitTheFaces) {
    std::filesystem::create_directories(dir_ / "models" / "tex");
    Write("models/scene.mtl",
          "newmtl wood\n"
          "Kd 0.5 0.4 0.3\n"
          "map_Kd -s 2 4 1 -o 0.25 0.5 0 tex/wood.png\n"
          "\n"
          "newmtl lamp\n"
          "Kd 0 0 0\nKe 4 3 2\n"
          "newmtl leaf\n"
          "Kd 0.2 0.6 0.1\nd 0.4\nillum 2\nKs 0.1 0.2 0.3\nNs 250\nNi 1.45\n"
          "newmtl glass\n"
          "Kd 1 1 1\nd 0.1\nillum 7\nNi 1.5\nmap_Ks spec.png\n"
          "newmtl unused\nmap_Kd missing.png\n"
          "newmtl plain\n"
          "newmtl painted\nmap_Kd tex/wood.png\n");
    const std::string obj =
        "mtllib scene.mtl\n"
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
        "usemtl lamp\nf 1 2 3\n"
        "usemtl wood\nf 2 4 3\n"
        "usemtl lamp\nf 3 2 4\n"
        "usemtl leaf\nf 1 2 4\n"
        "usemtl glass\nf 1 3 4\n"
        "usemtl plain\nf 4 3 1\n"
        "usemtl painted\nf 4 1 3\n";
    absl::StatusOr<MeshFile> file =
        ParseMeshWithMaterials(obj, "models/scene.obj", ReadBeside(dir_.string()));
    ASSERT_TRUE(file.ok()) << file.status();
    ASSERT_EQ(file->meshes.size(), 6u);
    ASSERT_EQ(file->materials.size(), 6u);
    EXPECT_TRUE(file->unassigned_where.empty());
    const std::vector<Material>& m = file->materials;
    // In the order the faces first use them; the unused material is not converted.
    EXPECT_EQ(m[0].name, "models/scene.mtl#lamp");
    EXPECT_EQ(m[1].name, "models/scene.mtl#wood");
    EXPECT_EQ(file->meshes[0].material, 0);
    EXPECT_EQ(file->meshes[0].triangles.size(), 2u);  // both lamp faces
    EXPECT_EQ(file->meshes[1].material, 1);
    EXPECT_EQ(file->meshes[1].triangles.size(), 1u);
    EXPECT_EQ(file->meshes[1].positions.size(), 3u);  // only the vertices it uses

    EXPECT_EQ(m[0].type, Material::Type::kLambert);
    EXPECT_EQ(m[0].emission, Rgb(4, 3, 2));
    EXPECT_FALSE(m[0].IsTextured());

    EXPECT_EQ(m[1].type, Material::Type::kLambert);
    EXPECT_EQ(m[1].reflectance, Rgb(0.5f, 0.4f, 0.3f));
    ASSERT_TRUE(m[1].base_color_texture.valid());
    ASSERT_EQ(file->textures.size(), 1u);
    EXPECT_EQ(file->textures[0].name, "models/tex/wood.png");
    EXPECT_EQ(file->textures[0].where, "models/scene.mtl:3: map_Kd");
    const TextureRef& wood = m[1].base_color_texture;
    EXPECT_TRUE(wood.srgb);
    EXPECT_FLOAT_EQ(wood.scale.x, 2);
    EXPECT_FLOAT_EQ(wood.scale.y, 4);
    EXPECT_FLOAT_EQ(wood.offset.x, 0.25f);
    EXPECT_FLOAT_EQ(wood.offset.y, 1 - 4 - 0.5f);

    // d < 1 without a refracting illum: a cut-out at half the opacity.
    EXPECT_EQ(m[2].type, Material::Type::kPrincipled);
    EXPECT_EQ(m[2].alpha_mode, Material::AlphaMode::kMask);
    EXPECT_FLOAT_EQ(m[2].opacity, 0.4f);
    EXPECT_FLOAT_EQ(m[2].alpha_cutoff, 0.5f);
    EXPECT_FLOAT_EQ(m[2].specular, 0.4f);  // twice the mean of Ks: Blender's 0.5 is 1
    EXPECT_FLOAT_EQ(m[2].roughness, 1 - std::sqrt(0.25f));
    EXPECT_FLOAT_EQ(m[2].ior, 1.45f);

    // illum 7 refracts: d < 1 is transmission.
    EXPECT_EQ(m[3].type, Material::Type::kPrincipled);
    EXPECT_FLOAT_EQ(m[3].transmission, 0.9f);
    EXPECT_EQ(m[3].alpha_mode, Material::AlphaMode::kOpaque);
    EXPECT_FLOAT_EQ(m[3].specular, 0);
    // Without Kd: Blender's default, or white under a texture (shared with wood's).
    EXPECT_EQ(m[4].reflectance, Rgb(0.8f));
    EXPECT_EQ(m[5].reflectance, Rgb(1));
    EXPECT_EQ(m[5].base_color_texture.image, 0);
    ASSERT_EQ(file->warnings.size(), 1u);
    EXPECT_EQ(file->warnings[0],
              "models/scene.mtl:20: material \"glass\": map_Ks is not supported; its variation "
              "is lost");
}

TEST_F(MeshIoTest, ObjMaterialErrorsNameTheLine) {
    auto parse = [&](const std::string& obj) {
        return ParseMeshWithMaterials(obj, "m.obj", ReadBeside(dir_.string()));
    };
    const std::string triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    absl::StatusOr<MeshFile> missing = parse(triangle + "mtllib gone.mtl\nf 1 2 3\n");
    ASSERT_FALSE(missing.ok());
    EXPECT_NE(missing.status().message().find("m.obj:4: mtllib \"gone.mtl\": "), std::string::npos)
        << missing.status();
    Write("a.mtl", "newmtl a\nKd 0.5 0.5 0.5\n");
    absl::StatusOr<MeshFile> unknown = parse("mtllib a.mtl\n" + triangle + "usemtl b\nf 1 2 3\n");
    ASSERT_FALSE(unknown.ok());
    EXPECT_NE(unknown.status().message().find(
                  "m.obj:5: usemtl \"b\": no MTL file of this OBJ defines it"),
              std::string::npos)
        << unknown.status();
    Write("bad.mtl", "newmtl a\n\nKd 0.5 -1 0.5\n");
    absl::StatusOr<MeshFile> bad = parse("mtllib bad.mtl\n" + triangle + "usemtl a\nf 1 2 3\n");
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.status().message().find("m.obj: bad.mtl:3: material \"a\": Kd must be finite"),
              std::string::npos)
        << bad.status();

    // Faces before any usemtl have no material: the scene must give one.
    absl::StatusOr<MeshFile> partly =
        parse("mtllib a.mtl\n" + triangle + "\nf 1 2 3\nusemtl a\nf 3 2 1\n");
    ASSERT_TRUE(partly.ok()) << partly.status();
    ASSERT_EQ(partly->meshes.size(), 2u);
    EXPECT_EQ(partly->meshes[0].material, -1);
    EXPECT_EQ(partly->unassigned_where, std::vector<std::string>{"m.obj:6"});
}

TEST_F(MeshIoTest, PlyNormalsAndTextureCoordinates) {
    absl::StatusOr<TriangleMesh> mesh =
        LoadMesh(Write("n.ply",
                       "ply\nformat ascii 1.0\nelement vertex 3\n"
                       "property float x\nproperty float y\nproperty float z\n"
                       "property float nx\nproperty float ny\nproperty float nz\n"
                       "property float s\nproperty float t\n"
                       "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                       "0 0 0 0 0 3 0 0\n1 0 0 0 0 0 1 0.25\n0 1 0 0 1 0 0 1\n3 0 1 2\n"));
    ASSERT_TRUE(mesh.ok()) << mesh.status();
    ASSERT_EQ(mesh->normals.size(), 3u);
    EXPECT_EQ(mesh->normals[0], Vec3(0, 0, 1));
    EXPECT_EQ(mesh->normals[1], Vec3(0, 0, 1));  // zero: from the faces around it
    EXPECT_EQ(mesh->normals[2], Vec3(0, 1, 0));
    ASSERT_EQ(mesh->uvs.size(), 3u);
    EXPECT_FLOAT_EQ(mesh->uvs[1].x, 1);
    EXPECT_FLOAT_EQ(mesh->uvs[1].y, 0.75f);
    EXPECT_FLOAT_EQ(mesh->uvs[2].y, 0);
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
