// The task result codecs a coordinator decodes from workers' messages (tile sums, splat lists,
// radiosity and sweep results) on arbitrary bytes; the first byte picks the codec.
#include "fuzz_input.h"
#include "lf/core/radiosity_codec.h"
#include "lf/core/splat_codec.h"
#include "lf/core/tile_codec.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    lf::fuzz::Quiet();
    const lf::fuzz::Input in = lf::fuzz::Split(data, size);
    switch (in.choice % 4) {
        case 0:
            (void)lf::DecodeTileSums(in.bytes);
            break;
        case 1:
            (void)lf::DecodeSplatList(in.bytes);
            break;
        case 2:
            (void)lf::DecodeRadiosity(in.bytes);
            break;
        default:
            (void)lf::DecodeSweepResults(in.bytes, 1024);
    }
    return 0;
}
