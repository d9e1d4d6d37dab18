#include "lf/worker/blob_cache.h"

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <vector>

#include "lf/job/digest.h"

namespace lf {

namespace fs = std::filesystem;

namespace {

absl::StatusOr<std::string> HashFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return absl::InternalError(path + ": cannot be read");
    Sha256 digest;
    std::string buffer(1 << 20, '\0');
    while (in) {
        in.read(buffer.data(), std::streamsize(buffer.size()));
        digest.Update(std::string_view(buffer.data(), size_t(in.gcount())));
    }
    return digest.HexDigest();
}

}  // namespace

absl::StatusOr<std::unique_ptr<BlobCache>> BlobCache::Open(const std::string& dir,
                                                           uint64_t max_bytes) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) return absl::InternalError(dir + ": " + ec.message());
    std::unique_ptr<BlobCache> cache(new BlobCache(dir, max_bytes));
    // Oldest first, so the newest end up most recently used.
    std::vector<std::pair<fs::file_time_type, fs::path>> found;
    for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
        if (e.is_regular_file() && IsSha256Hex(e.path().filename().string())) {
            found.emplace_back(e.last_write_time(), e.path());
        }
    }
    std::sort(found.begin(), found.end());
    for (const auto& [time, path] : found) {
        cache->Touch(path.filename().string(), fs::file_size(path, ec));
    }
    return cache;
}

void BlobCache::Touch(const std::string& hash, uint64_t size) {
    auto it = entries_.find(hash);
    if (it != entries_.end()) {
        lru_.splice(lru_.begin(), lru_, it->second.position);
        return;
    }
    lru_.push_front(hash);
    entries_[hash] = {size, lru_.begin()};
    bytes_ += size;
}

void BlobCache::Forget(std::map<std::string, Entry>::iterator it) {
    bytes_ -= it->second.size;
    lru_.erase(it->second.position);
    entries_.erase(it);
}

absl::StatusOr<std::string> BlobCache::Get(const std::string& hash, const Fetch& fetch) {
    if (!IsSha256Hex(hash)) return absl::InvalidArgumentError("bad blob hash '" + hash + "'");
    const std::string path = PathOf(hash);
    if (auto it = entries_.find(hash); it != entries_.end()) {
        if (fs::exists(path)) {
            Touch(hash, 0);
            return path;
        }
        Forget(it);  // deleted from under us
    }
    const std::string temp = path + ".part-" + std::to_string(::getpid());
    absl::Status fetched = fetch(hash, temp);
    absl::StatusOr<std::string> got = fetched.ok() ? HashFile(temp) : fetched;
    std::error_code ec;
    if (got.ok() && *got != hash) {
        got = absl::DataLossError("blob " + hash + " arrived with content hashing to " + *got);
    }
    if (got.ok()) fs::rename(temp, path, ec);
    if (!got.ok() || ec) {
        fs::remove(temp, ec);
        return got.ok() ? absl::InternalError(path + ": " + ec.message()) : got.status();
    }
    Touch(hash, fs::file_size(path, ec));
    return path;
}

void BlobCache::Trim() {
    while (bytes_ > max_bytes_ && !lru_.empty()) {
        std::error_code ignored;
        fs::remove(PathOf(lru_.back()), ignored);
        Forget(entries_.find(lru_.back()));
    }
}

}  // namespace lf
