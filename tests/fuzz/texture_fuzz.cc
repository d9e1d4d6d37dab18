// Texture decoding (PNG, JPEG, Radiance HDR by content) on arbitrary bytes.
#include "fuzz_input.h"
#include "lf/core/texture_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    lf::fuzz::Quiet();
    (void)lf::DecodeTexture(std::string(reinterpret_cast<const char*>(data), size), "fuzz.png");
    return 0;
}
