// The glTF and GLB loader on arbitrary bytes (the first byte picks .gltf or .glb): an error or a
// scene, never a crash, whatever the accessors, buffers and node transforms hold.
#include "fuzz_input.h"
#include "lf/core/scene_loader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    lf::fuzz::Quiet();
    const lf::fuzz::Input in = lf::fuzz::Split(data, size);
    (void)lf::ParseScene(in.bytes, in.choice & 1 ? "scene.glb" : "scene.gltf", lf::fuzz::NoFile);
    return 0;
}
