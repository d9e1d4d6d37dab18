// Little-endian fixed-width fields and exact sums, as the binary codecs of tile sums and splat
// lists write them (lf/core/tile_codec.h, lf/core/splat_codec.h): one definition, so both
// encode an ExactSum with the same bytes on every machine.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "lf/core/film.h"

namespace lf {

inline void PutU32(std::string& out, uint32_t v) {
    for (int i = 0; i < 4; ++i) out.push_back(char(uint8_t(v >> (8 * i))));
}
inline void PutU64(std::string& out, uint64_t v) {
    for (int i = 0; i < 8; ++i) out.push_back(char(uint8_t(v >> (8 * i))));
}
// The 128-bit fixed-point value, low half first.
inline void PutSum(std::string& out, const ExactSum& sum) {
    const auto v = static_cast<unsigned __int128>(sum.fixed());
    PutU64(out, uint64_t(v));
    PutU64(out, uint64_t(v >> 64));
}

// Reads what the Put functions wrote. It does not check bounds: the decoder checks the size
// first, from the header, before it reads a field.
class LeReader {
  public:
    explicit LeReader(std::string_view bytes) : p_(bytes.data()) {}
    uint8_t U8() { return uint8_t(*p_++); }
    uint32_t U32() {
        uint32_t v = 0;
        for (int i = 0; i < 4; ++i) v |= uint32_t(uint8_t(p_[i])) << (8 * i);
        p_ += 4;
        return v;
    }
    int32_t I32() { return int32_t(U32()); }
    uint64_t U64() { return uint64_t(U32()) | (uint64_t(U32()) << 32); }
    ExactSum Sum() {
        const uint64_t lo = U64(), hi = U64();
        return ExactSum::FromFixed(
            static_cast<__int128>((static_cast<unsigned __int128>(hi) << 64) | lo));
    }

  private:
    const char* p_;
};

}  // namespace lf
