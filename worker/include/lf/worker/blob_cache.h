// Scene blobs on the worker's disk, by content hash, least recently used evicted first once
// they add up to more than the budget. A blob enters only after its hash checks out.
#pragma once

#include <cstdint>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <string>

#include "absl/status/statusor.h"

namespace lf {

class BlobCache {
  public:
    // Writes blob `hash` to the given path.
    using Fetch = std::function<absl::Status(const std::string& hash, const std::string& path)>;

    // Creates `dir` when missing and adopts the blobs already in it.
    static absl::StatusOr<std::unique_ptr<BlobCache>> Open(const std::string& dir,
                                                           uint64_t max_bytes);

    // The file of blob `hash`, fetched when missing.
    absl::StatusOr<std::string> Get(const std::string& hash, const Fetch& fetch);

    // Evicts least recently used blobs until the rest fit the budget. Separate from Get so the
    // blobs of one scene all stay until the scene is loaded.
    void Trim();

    uint64_t bytes() const { return bytes_; }

  private:
    BlobCache(std::string dir, uint64_t max_bytes) : dir_(std::move(dir)), max_bytes_(max_bytes) {}
    std::string PathOf(const std::string& hash) const { return dir_ + "/" + hash; }
    void Touch(const std::string& hash, uint64_t size);
    struct Entry {
        uint64_t size;
        std::list<std::string>::iterator position;
    };
    void Forget(std::map<std::string, Entry>::iterator it);

    std::string dir_;
    uint64_t max_bytes_;
    uint64_t bytes_ = 0;
    std::list<std::string> lru_;  // most recent first
    std::map<std::string, Entry> entries_;
};

}  // namespace lf
