// Loading a large glTF scene: time and memory. Writes (to a temporary folder) a glTF of about a
// million triangles in six textured meshes, as an exporter writes them (positions, normals,
// texture coordinates, 32-bit indices, one PNG base colour texture per mesh: six 2048 x 2048
// RGBA images, 100 MB of texels), then measures in this process:
//  - LoadScene's time, and the heap it leaves allocated per triangle (geometry and attributes)
//    and per texel (the decoded images);
//  - EmbreeScene::Build's time, its heap (the kernels' own float copies) and the resident
//    memory it adds (with Embree's BVH, which Embree maps itself).
// Heap is malloc's count of bytes in use (mallinfo2: small blocks and mmapped ones), so freed
// temporaries (tinygltf's model, file bytes) do not count.
//
//   build/bin/scene_load_bench [--triangles 1000000] [--texture-side 2048] [--textures 6]
//                              [--dir /tmp] [--keep]
#include <malloc.h>
#include <stb_image_write.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "gltf_files.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/embree_scene.h"

namespace {

namespace fs = std::filesystem;

double HeapBytes() {
    const struct mallinfo2 m = mallinfo2();
    return double(m.uordblks) + double(m.hblkhd);
}

// Resident memory now: Embree maps its BVH itself (not through malloc), so only this sees it.
double ResidentBytes() {
    long pages = 0, resident = 0;
    std::FILE* f = std::fopen("/proc/self/statm", "r");
    if (f && std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
    if (f) std::fclose(f);
    return double(resident) * double(sysconf(_SC_PAGESIZE));
}

double Seconds(std::chrono::steady_clock::time_point since) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// A texture with structure at several scales (PNG compresses it about as well as a photo-like
// base colour map), different per image.
void WritePng(const fs::path& path, int side, int seed) {
    std::vector<uint8_t> texels(size_t(side) * side * 4);
    for (int y = 0; y < side; ++y) {
        for (int x = 0; x < side; ++x) {
            uint8_t* t = &texels[(size_t(y) * side + x) * 4];
            const uint32_t h = uint32_t(x * 73856093u ^ y * 19349663u ^ seed * 83492791u);
            t[0] = uint8_t(128 + 100 * std::sin(x * 0.01 + seed) + (h & 15));
            t[1] = uint8_t(128 + 100 * std::sin(y * 0.013 - seed) + ((h >> 4) & 15));
            t[2] = uint8_t((x ^ y) + (h >> 8 & 31));
            t[3] = 255;
        }
    }
    stbi_write_png(path.c_str(), side, side, 4, texels.data(), side * 4);
}

// `meshes` wavy grids of about `triangles` triangles in all, each with its own textured
// material, and a camera that sees them and a light.
void WriteScene(const fs::path& dir, int64_t triangles, int meshes, int texture_side) {
    lf::testing::GltfBuilder b;
    nlohmann::json& j = b.json();
    const int n = std::max(2, int(std::sqrt(double(triangles) / meshes / 2)) + 1);  // vertices
    std::vector<int> nodes;
    for (int m = 0; m < meshes; ++m) {
        std::vector<std::array<float, 3>> positions, normals;
        std::vector<std::array<float, 2>> uvs;
        for (int y = 0; y < n; ++y) {
            for (int x = 0; x < n; ++x) {
                const float u = float(x) / (n - 1), v = float(y) / (n - 1);
                const float h = 0.05f * std::sin(40 * u) * std::cos(37 * v);
                positions.push_back({u + 1.1f * m, h, v});
                const float dx = 0.05f * 40 * std::cos(40 * u) * std::cos(37 * v);
                const float dz = -0.05f * 37 * std::sin(40 * u) * std::sin(37 * v);
                const float len = std::sqrt(dx * dx + 1 + dz * dz);
                normals.push_back({-dx / len, 1 / len, -dz / len});
                uvs.push_back({u, v});
            }
        }
        std::vector<uint32_t> indices;
        for (int y = 0; y + 1 < n; ++y) {
            for (int x = 0; x + 1 < n; ++x) {
                const uint32_t a = uint32_t(y * n + x), c = a + uint32_t(n);
                indices.insert(indices.end(), {a, c, a + 1, a + 1, c, c + 1});
            }
        }
        const std::string image = "texture" + std::to_string(m) + ".png";
        WritePng(dir / image, texture_side, m);
        j["images"].push_back({{"uri", image}});
        j["textures"].push_back({{"source", m}});
        j["materials"].push_back({{"pbrMetallicRoughness",
                                   {{"baseColorTexture", {{"index", m}}}, {"metallicFactor", 0}}}});
        const int mesh = b.AddMesh("grid" + std::to_string(m),
                                   {{"POSITION", b.AddFloats<3>(positions)},
                                    {"NORMAL", b.AddFloats<3>(normals)},
                                    {"TEXCOORD_0", b.AddFloats<2>(uvs)}},
                                   b.AddIndices(indices), m);
        nodes.push_back(b.AddNode({{"mesh", mesh}}));
    }
    j["cameras"] = {{{"type", "perspective"},
                     {"perspective", {{"yfov", 0.8}, {"aspectRatio", 1.5}, {"znear", 0.01}}}}};
    // Pitched 30 degrees down, so the grids fill the view and `lightfarm bench --keep`'s scene
    // measures shading, not misses.
    nodes.push_back(b.AddNode(
        {{"camera", 0}, {"translation", {3.3, 2, 4}}, {"rotation", {-0.258819, 0, 0, 0.965926}}}));
    j["extensionsUsed"] = {"KHR_lights_punctual"};
    j["extensions"]["KHR_lights_punctual"]["lights"] = {{{"type", "point"}, {"intensity", 5000}}};
    nodes.push_back(b.AddNode({{"translation", {3.3, 3, 0.5}},
                               {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}}));
    j["scenes"] = {{{"nodes", nodes}}};
    std::ofstream(dir / "scene.gltf") << b.Gltf("scene.bin");
    std::ofstream(dir / "scene.bin", std::ios::binary) << b.bin();
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app("glTF scene load time and memory");
    int64_t triangles = 1'000'000;
    int side = 2048, textures = 6;
    std::string dir_option = fs::temp_directory_path().string();
    bool keep = false;
    app.add_option("--triangles", triangles, "triangles in all")->capture_default_str();
    app.add_option("--texture-side", side, "side of each RGBA texture")->capture_default_str();
    app.add_option("--textures", textures, "meshes, one texture each")
        ->capture_default_str()
        ->check(CLI::Range(1, 64));
    app.add_option("--dir", dir_option, "where the scene is written")->capture_default_str();
    app.add_flag("--keep", keep, "keep the written scene");
    CLI11_PARSE(app, argc, argv);

    const fs::path dir = fs::path(dir_option) / ("lf_scene_load_bench_" + std::to_string(getpid()));
    fs::create_directories(dir);
    auto start = std::chrono::steady_clock::now();
    WriteScene(dir, triangles, textures, side);
    uintmax_t file_bytes = 0;
    for (const auto& e : fs::directory_iterator(dir)) file_bytes += e.file_size();
    std::printf("wrote %s: %.1f MB of files in %.1f s\n", dir.c_str(), file_bytes / 1e6,
                Seconds(start));

    const double heap0 = HeapBytes();
    start = std::chrono::steady_clock::now();
    absl::StatusOr<lf::Scene> scene = lf::LoadScene((dir / "scene.gltf").string());
    const double load_seconds = Seconds(start);
    if (!scene.ok()) {
        std::fprintf(stderr, "%s\n", std::string(scene.status().message()).c_str());
        return 1;
    }
    const double heap_scene = HeapBytes() - heap0;
    double tris = 0, texels = 0, texel_bytes = 0;
    for (const lf::TriangleMesh& m : scene->meshes) tris += double(m.triangles.size());
    for (const auto& t : scene->textures) {
        texels += double(t->width) * t->height;
        texel_bytes += double(t->texels8.size() + 4 * t->texels32.size());
    }
    const double geometry = heap_scene - texel_bytes;
    std::printf("load: %.2f s for %.0f triangles and %.1f M texels (%.0f MB decoded)\n",
                load_seconds, tris, texels / 1e6, texel_bytes / 1e6);
    std::printf(
        "scene heap: %.1f MB: %.1f B per triangle (geometry and attributes), "
        "%.2f B per texel\n",
        heap_scene / 1e6, geometry / tris, texel_bytes / texels);

    const double resident0 = ResidentBytes();
    start = std::chrono::steady_clock::now();
    absl::StatusOr<std::unique_ptr<lf::EmbreeScene>> embree = lf::EmbreeScene::Build(*scene);
    const double build_seconds = Seconds(start);
    if (!embree.ok()) {
        std::fprintf(stderr, "%s\n", std::string(embree.status().message()).c_str());
        return 1;
    }
    const double heap_embree = HeapBytes() - heap0 - heap_scene;
    const double resident_embree = ResidentBytes() - resident0;
    std::printf(
        "EmbreeScene build: %.2f s, heap %.1f MB (%.1f B per triangle), resident "
        "+%.1f MB (%.1f B per triangle, with the BVH)\n",
        build_seconds, heap_embree / 1e6, heap_embree / tris, resident_embree / 1e6,
        resident_embree / tris);
    if (!keep) fs::remove_all(dir);
    return 0;
}
