// SHA-256 content hashes: the names of scene blobs on the farm.
#pragma once

#include <memory>
#include <string>
#include <string_view>

namespace lf {

// Incremental, for content that arrives in chunks.
class Sha256 {
  public:
    Sha256();
    ~Sha256();
    Sha256(const Sha256&) = delete;
    Sha256& operator=(const Sha256&) = delete;

    void Update(std::string_view data);
    std::string HexDigest();  // lowercase hex; ends the hash

  private:
    struct State;
    std::unique_ptr<State> state_;
};

std::string Sha256Hex(std::string_view data);

// True for 64 lowercase hex digits: a hash that is safe to use as a file name.
bool IsSha256Hex(std::string_view text);

}  // namespace lf
