#include "lf/core/volume_grid.h"

#include <dlfcn.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <vector>

#include "absl/strings/str_cat.h"
#include "lf/core/vdb_reader.h"

namespace lf {
namespace {

// OpenVDB's maps act on row vectors (world = index * M): M's transpose is our M.
Affine FromVdb(const std::array<std::array<double, 4>, 4>& m) {
    Affine a;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 4; ++c) a.m[size_t(r)][size_t(c)] = m[size_t(c)][size_t(r)];
    }
    return a;
}

// liblf_vdb.so's entry point, loaded once (and never unloaded: the grids it made free their
// memory through it).
absl::StatusOr<ReadVdbGridFunction> LoadVdbModule() {
    std::error_code error;
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
    if (error) {
        return absl::FailedPreconditionError(
            absl::StrCat("reading OpenVDB grids: cannot tell where this program is (",
                         error.message(), ") to find ", kVdbModuleFile));
    }
    std::string tried;
    for (const std::filesystem::path& dir :
         {exe.parent_path(), exe.parent_path() / kVdbModuleInstallDir}) {
        const std::string path = (dir / kVdbModuleFile).lexically_normal().string();
        if (void* module = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL)) {
            if (void* read = dlsym(module, kReadVdbGridSymbol)) {
                return reinterpret_cast<ReadVdbGridFunction>(read);
            }
        }
        const char* why = dlerror();
        absl::StrAppend(&tried, tried.empty() ? "" : "; ", why ? why : path);
    }
    return absl::FailedPreconditionError(absl::StrCat(
        "reading OpenVDB grids needs ", kVdbModuleFile, " beside the lightfarm binaries or in ",
        kVdbModuleInstallDir, " from them (docs/deploy.md): ", tried));
}

}  // namespace

absl::StatusOr<std::shared_ptr<const VolumeGrid>> LoadVolumeGrid(const std::string& bytes,
                                                                 const std::string& file_name,
                                                                 const std::string& grid_name,
                                                                 const Affine& medium_transform) {
    // Thread-safe once: a static's initialisation.
    static const absl::StatusOr<ReadVdbGridFunction> read = LoadVdbModule();
    if (!read.ok()) return read.status();
    VdbGridRead got;
    (*read)(bytes, file_name, grid_name, got);
    if (!got.status.ok()) return got.status;
    auto out = std::make_shared<VolumeGrid>(std::move(got.grid));
    const auto invalid = [&](const std::string& why) {
        return absl::InvalidArgumentError(
            absl::StrCat(file_name, " grid \"", grid_name, "\": ", why));
    };
    out->index_to_world = FromVdb(got.index_to_world).Then(medium_transform);
    out->world_to_index = out->index_to_world.Inverse();
    if (!out->world_to_index.IsFinite()) return invalid("its transform is singular");
    for (size_t i = 0; i < out->values.size(); ++i) {
        const float v = out->values[i];
        if (std::isfinite(v) && v >= 0) continue;
        const int64_t x = int64_t(i % size_t(out->size[0])),
                      y = int64_t(i / size_t(out->size[0]) % size_t(out->size[1])),
                      z = int64_t(i / (size_t(out->size[0]) * size_t(out->size[1])));
        return invalid(absl::StrCat("value ", v, " at voxel (", out->min[0] + x, ", ",
                                    out->min[1] + y, ", ", out->min[2] + z,
                                    "): expected a finite value >= 0 (negative density, emission "
                                    "or temperature is unphysical)"));
    }
    return std::shared_ptr<const VolumeGrid>(std::move(out));
}

}  // namespace lf
