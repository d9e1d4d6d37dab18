// OBJ (with its MTL), and PLY, on arbitrary bytes (the first byte picks): an error or a mesh.
#include "fuzz_input.h"
#include "lf/core/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    lf::fuzz::Quiet();
    const lf::fuzz::Input in = lf::fuzz::Split(data, size);
    switch (in.choice % 3) {
        case 0:
            (void)lf::ParseMesh(in.bytes, "mesh.ply");
            break;
        case 1:
            (void)lf::ParseMesh(in.bytes, "mesh.obj");
            break;
        default:
            // The same bytes as the OBJ and as every MTL it names.
            (void)lf::ParseMeshWithMaterials(in.bytes, "mesh.obj", [&](const std::string&) {
                return absl::StatusOr<std::string>(in.bytes);
            });
    }
    return 0;
}
