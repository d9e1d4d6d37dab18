// The OpenVDB side of LoadVolumeGrid (lf/core/volume_grid.h), built as its own module,
// liblf_vdb.so, that LoadVolumeGrid loads (dlopen) on first use. Loading OpenVDB's library binds
// about 57,000 symbols, 22 of the 35 ms every lightfarm process took to start; now only a process
// that reads a .vdb file pays it.
#pragma once

#include <array>
#include <string>

#include "absl/status/status.h"
#include "lf/core/medium.h"

namespace lf {

// The module's file name, and where LoadVolumeGrid looks for it: beside the executable, then in
// ../lib/lightfarm from it (an install with the binaries in bin/).
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

// The module's one entry point, by name (kReadVdbGridSymbol), compiled with the same compiler
// and libraries as the executables that load it.
using ReadVdbGridFunction = void (*)(const std::string& bytes, const std::string& file_name,
                                     const std::string& grid_name, VdbGridRead& out);
inline constexpr char kReadVdbGridSymbol[] = "lf_read_vdb_grid";

}  // namespace lf
