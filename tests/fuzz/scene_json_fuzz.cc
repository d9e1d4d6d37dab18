// The JSON scene loader on arbitrary text: an error or a scene, never a crash.
#include "fuzz_input.h"
#include "lf/core/scene_loader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    lf::fuzz::Quiet();
    const std::string text(reinterpret_cast<const char*>(data), size);
    (void)lf::ParseScene(text, "scene.json", lf::fuzz::NoFile);
    return 0;
}
