// The OpenVDB side of LoadVolumeGrid (lf/core/volume_grid.h), built as its own module,
// liblf_vdb.so, that LoadVolumeGrid loads (dlopen) on first use: loading OpenVDB's library binds
// tens of thousands of symbols, most of a lightfarm program's start, so only a process that
// reads a .vdb file pays it (docs/architecture.md).
#pragma once

#include <array>
#include <string>

#include "absl/status/status.h"
#include "lf/core/medium.h"
#include "lf/version.h"

namespace lf {

// The module's file name, and where LoadVolumeGrid looks for it: beside the executable (its
// real path, symlinks resolved), then in ../lib/lightfarm from there (binaries in bin/).
inline constexpr char kVdbModuleFile[] = "liblf_vdb.so";
inline constexpr char kVdbModuleInstallDir[] = "../lib/lightfarm";

// What the module read of a float grid: `grid` with its name, box, values and background (its
// transforms unset), and the grid's own affine map from index to world space as OpenVDB holds
// it (acting on row vectors). `status` says why the bytes or the grid were refused, as
// LoadVolumeGrid documents; the values are not checked yet.
struct VdbGridRead {
    absl::Status status;
    VolumeGrid grid;
    std::array<std::array<double, 4>, 4> index_to_world{};
};

// The module's entry points, by name. It passes C++ objects, so a module is used only by a
// program of its own build: kVdbBuildSymbol returns the module's VdbModuleBuild().
using ReadVdbGridFunction = void (*)(const std::string& bytes, const std::string& file_name,
                                     const std::string& grid_name, VdbGridRead& out);
inline constexpr char kReadVdbGridSymbol[] = "lf_read_vdb_grid";
using VdbBuildFunction = const char* (*)();
inline constexpr char kVdbBuildSymbol[] = "lf_vdb_build";
// The commit and the configuration (compiler, flags) a program or module was built at.
inline std::string VdbModuleBuild() { return std::string(kBuildVersion) + ", " + kBuildConfig; }

}  // namespace lf
