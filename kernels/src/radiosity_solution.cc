#include "lf/kernels/radiosity_solution.h"

#include <array>
#include <bit>
#include <cstring>
#include <fstream>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace lf {

namespace {

static_assert(std::endian::native == std::endian::little, "the solution file is little-endian");

constexpr char kMagic[8] = {'L', 'F', 'R', 'A', 'D', 'S', 'O', 'L'};
constexpr uint32_t kVersion = 3;  // 1: no split cells; 1 and 2: no irradiance
// A scene hash is a hex digest; anything longer is a corrupt length field.
constexpr uint32_t kMaxHashLength = 1024;

template <typename T>
void Put(std::ofstream& out, const T& value) {
    out.write(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <typename T>
bool Get(std::ifstream& in, T& value) {
    return bool(in.read(reinterpret_cast<char*>(&value), sizeof(T)));
}

}  // namespace

absl::Status SaveRadiositySolution(const std::string& path, const RadiositySolution& solution) {
    if (solution.irradiance.size() != solution.radiosity.size()) {
        return absl::InvalidArgumentError(
            absl::StrCat(path, ": a radiosity solution needs one irradiance per side"));
    }
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    if (!out) return absl::NotFoundError(absl::StrCat(path, ": cannot write radiosity solution"));
    out.write(kMagic, sizeof kMagic);
    Put(out, kVersion);
    Put(out, uint32_t(solution.scene_hash.size()));
    out.write(solution.scene_hash.data(), std::streamsize(solution.scene_hash.size()));
    Put(out, solution.patch_size);
    Put(out, solution.patches);
    Put(out, int64_t(solution.radiosity.size()));
    Put(out, int32_t(solution.iterations));
    Put(out, solution.residual);
    Put(out, int64_t(solution.split.size()));
    for (const PatchCell& c : solution.split) {
        for (int32_t v : {c.mesh, c.primitive, c.level, c.i, c.j, int32_t(c.up)}) Put(out, v);
    }
    static_assert(sizeof(Rgb) == 3 * sizeof(float));
    for (const std::vector<Rgb>* values : {&solution.radiosity, &solution.irradiance}) {
        out.write(reinterpret_cast<const char*>(values->data()),
                  std::streamsize(values->size() * sizeof(Rgb)));
    }
    out.close();
    if (!out) return absl::DataLossError(absl::StrCat(path, ": error writing radiosity solution"));
    return absl::OkStatus();
}

absl::StatusOr<RadiositySolution> LoadRadiositySolution(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return absl::NotFoundError(absl::StrCat(path, ": cannot open radiosity solution"));
    auto corrupt = [&path](const std::string& what) {
        return absl::InvalidArgumentError(
            absl::StrCat(path, ": not a lightfarm radiosity solution (", what, ")"));
    };
    char magic[sizeof kMagic];
    uint32_t version = 0, hash_length = 0;
    if (!in.read(magic, sizeof magic) || std::memcmp(magic, kMagic, sizeof kMagic) != 0) {
        return corrupt("bad magic");
    }
    if (!Get(in, version) || version < 1 || version > kVersion) {
        return corrupt(absl::StrCat("version ", version, ", expected ", kVersion));
    }
    if (version < kVersion) {
        return absl::FailedPreconditionError(absl::StrCat(
            path, ": a version ", version,
            " radiosity solution holds no irradiance, which the illuminance needs; solve again"));
    }
    if (!Get(in, hash_length) || hash_length > kMaxHashLength) return corrupt("bad scene hash");
    RadiositySolution solution;
    solution.scene_hash.resize(hash_length);
    int64_t sides = 0;
    int32_t iterations = 0;
    if (!in.read(solution.scene_hash.data(), hash_length) || !Get(in, solution.patch_size) ||
        !Get(in, solution.patches) || !Get(in, sides) || !Get(in, iterations) ||
        !Get(in, solution.residual) || sides < 0 || solution.patches < 0) {
        return corrupt("truncated header");
    }
    solution.iterations = iterations;
    int64_t split = 0;
    if (!Get(in, split) || split < 0) return corrupt("truncated header");
    for (int64_t n = 0; n < split; ++n) {
        std::array<int32_t, 6> v;
        for (int32_t& x : v) {
            if (!Get(in, x)) return corrupt("truncated split cells");
        }
        solution.split.push_back({v[0], v[1], v[2], v[3], v[4], v[5] != 0});
    }
    // The side count must match the bytes that follow before anything is allocated.
    const std::streamoff header_end = in.tellg();
    in.seekg(0, std::ios::end);
    const std::streamoff payload = in.tellg() - header_end;
    const std::streamoff per_vector = std::streamoff(sides) * std::streamoff(sizeof(Rgb));
    if (payload != 2 * per_vector) {
        return corrupt(
            absl::StrCat(payload, " bytes of radiosity and irradiance for ", sides, " sides"));
    }
    in.seekg(header_end);
    for (std::vector<Rgb>* values : {&solution.radiosity, &solution.irradiance}) {
        values->resize(size_t(sides));
        if (!in.read(reinterpret_cast<char*>(values->data()), per_vector)) {
            return corrupt("truncated radiosity");
        }
    }
    return solution;
}

absl::Status CheckRadiositySolution(const RadiositySolution& solution, const std::string& path,
                                    const std::string& scene_hash, const PatchMesh& mesh) {
    if (solution.scene_hash != scene_hash) {
        return absl::FailedPreconditionError(absl::StrFormat(
            "%s: solution was computed for scene %s but this scene is %s; solve again", path,
            solution.scene_hash.empty() ? "(no hash)" : solution.scene_hash,
            scene_hash.empty() ? "(no hash)" : scene_hash));
    }
    if (solution.patches != int64_t(mesh.patches().size()) ||
        solution.radiosity.size() != mesh.sides().size()) {
        return absl::FailedPreconditionError(absl::StrFormat(
            "%s: solution has %d patches and %d sides but meshing the scene at patch size %g "
            "with %d split cells gives %d and %d; solve again",
            path, solution.patches, solution.radiosity.size(), solution.patch_size,
            solution.split.size(), mesh.patches().size(), mesh.sides().size()));
    }
    return absl::OkStatus();
}

}  // namespace lf
