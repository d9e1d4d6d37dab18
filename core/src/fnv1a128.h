// The hash behind Scene::content_hash. Private to core.
#pragma once

#include <string>
#include <string_view>

namespace lf::scene_internal {

// FNV-1a, 128-bit (Fowler, Noll, Vo): not cryptographic, but content_hash only has to tell
// changed inputs apart, and this needs no library.
class Fnv1a128 {
  public:
    void Update(std::string_view bytes) {
        constexpr unsigned __int128 kPrime = (unsigned __int128)1 << 88 | 0x13b;
        for (const char c : bytes) {
            state_ ^= static_cast<unsigned char>(c);
            state_ *= kPrime;
        }
    }
    std::string Hex() const {
        static constexpr char kDigits[] = "0123456789abcdef";
        std::string hex(32, '0');
        for (int i = 0; i < 32; ++i) hex[31 - i] = kDigits[int(state_ >> (4 * i)) & 15];
        return hex;
    }

  private:
    unsigned __int128 state_ = (unsigned __int128)0x6c62272e07bb0142 << 64 | 0x62b821756295c58d;
};

}  // namespace lf::scene_internal
