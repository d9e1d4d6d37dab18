// OpenVDB grids (LoadVolumeGrid) on arbitrary bytes: a scene's .vdb file comes from the user.
#include <cstdio>
#include <cstdlib>

#include "fuzz_input.h"
#include "lf/core/volume_grid.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    lf::fuzz::Quiet();
    const std::string bytes(reinterpret_cast<const char*>(data), size);
    absl::StatusOr<std::shared_ptr<const lf::VolumeGrid>> grid =
        lf::LoadVolumeGrid(bytes, "fuzz.vdb", "density", lf::Affine{});
    // Without OpenVDB's module every input would be refused unread: that tests nothing.
    if (absl::IsFailedPrecondition(grid.status())) {
        std::fprintf(stderr, "%s\n", std::string(grid.status().message()).c_str());
        std::abort();
    }
    // A grid that loads is read back at a few points, as the kernels would.
    if (grid.ok()) (void)(*grid)->Lookup(lf::Vec3d(0.5, 0.5, 0.5));
    return 0;
}
