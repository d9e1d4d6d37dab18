#include "lf/core/volume_grid.h"

#include <dlfcn.h>

#include <cmath>
#include <filesystem>
#include <mutex>
#include <vector>

#include "absl/strings/str_cat.h"
#include "lf/core/vdb_reader.h"
#include "lf/version.h"

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

// liblf_vdb.so's entry point, from the first place that has a module of this build.
absl::StatusOr<ReadVdbGridFunction> LoadVdbModule() {
    std::error_code error;
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
    if (error) {
        return absl::FailedPreconditionError(
            absl::StrCat("reading OpenVDB grids: cannot tell where this program is (",
                         error.message(), ") to find ", kVdbModuleFile));
    }
    // A module opened is never closed, not even one refused: closing would run the destructors
    // of OpenVDB's and its libraries' globals. Opened again it is the same one (refused again
    // until the program restarts); a missing one is looked for again at the next grid.
    std::string tried;
    const auto refuse = [&](const std::string& why) {
        absl::StrAppend(&tried, tried.empty() ? "" : "; ", why);
    };
    for (const std::filesystem::path& dir :
         {exe.parent_path(), exe.parent_path() / kVdbModuleInstallDir}) {
        const std::string path = (dir / kVdbModuleFile).lexically_normal().string();
        void* module = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!module) {
            const char* why = dlerror();  // no such file, or a library it needs is missing
            refuse(why ? why : path);
            continue;
        }
        const auto build = reinterpret_cast<VdbBuildFunction>(dlsym(module, kVdbBuildSymbol));
        const auto read = reinterpret_cast<ReadVdbGridFunction>(dlsym(module, kReadVdbGridSymbol));
        if (!build || !read) {
            refuse(absl::StrCat(path, ": not lightfarm's OpenVDB module"));
        } else if (const std::string its = build(); its != VdbModuleBuild()) {
            // It passes C++ objects: another build's layout would be read as this one's.
            refuse(absl::StrCat(path, ": of build ", its));
        } else {
            return read;
        }
    }
    return absl::FailedPreconditionError(
        absl::StrCat("reading OpenVDB grids: no ", kVdbModuleFile, " of this build (",
                     VdbModuleBuild(), ") beside this program or in ", kVdbModuleInstallDir,
                     " from it (docs/deploy.md): ", tried));
}

// Found once; a failure is tried again at the next grid (a module installed meanwhile).
absl::StatusOr<ReadVdbGridFunction> VdbModule() {
    static std::mutex mutex;
    static ReadVdbGridFunction found = nullptr;
    std::lock_guard<std::mutex> lock(mutex);
    if (found) return found;
    absl::StatusOr<ReadVdbGridFunction> loaded = LoadVdbModule();
    if (loaded.ok()) found = *loaded;
    return loaded;
}

}  // namespace

absl::StatusOr<std::shared_ptr<const VolumeGrid>> LoadVolumeGrid(const std::string& bytes,
                                                                 const std::string& file_name,
                                                                 const std::string& grid_name,
                                                                 const Affine& medium_transform) {
    const absl::StatusOr<ReadVdbGridFunction> read = VdbModule();
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
