#include "server/blob_store.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include "absl/strings/str_cat.h"

namespace lf {

namespace fs = std::filesystem;

namespace {

constexpr char kUploadPrefix[] = ".upload-";

absl::Status Sync(const std::string& path, int flags) {
    const int fd = ::open(path.c_str(), flags | O_CLOEXEC);
    if (fd < 0 || ::fsync(fd) != 0) {
        const absl::Status s = absl::InternalError(path + ": " + std::strerror(errno));
        if (fd >= 0) ::close(fd);
        return s;
    }
    ::close(fd);
    return absl::OkStatus();
}

}  // namespace

absl::Status RenameDurably(const std::string& temp, const std::string& path) {
    if (absl::Status s = Sync(temp, O_RDONLY); !s.ok()) return s;
    std::error_code ec;
    fs::rename(temp, path, ec);
    if (ec) return absl::InternalError(path + ": " + ec.message());
    return Sync(fs::path(path).parent_path().string(), O_RDONLY | O_DIRECTORY);
}

absl::StatusOr<std::unique_ptr<BlobStore>> BlobStore::Open(const std::string& dir) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) return absl::InternalError(dir + ": " + ec.message());
    return std::unique_ptr<BlobStore>(new BlobStore(dir));
}

bool BlobStore::Has(const std::string& hash) const {
    return IsSha256Hex(hash) && fs::exists(PathOf(hash));
}

std::string BlobStore::PathOf(const std::string& hash) const { return dir_ + "/" + hash; }

absl::StatusOr<uint64_t> BlobStore::SizeOf(const std::string& hash) const {
    std::error_code ec;
    const uint64_t size = fs::file_size(PathOf(hash), ec);
    if (ec) return absl::NotFoundError(absl::StrCat("blob ", hash, ": ", ec.message()));
    return size;
}

int BlobStore::SweepUnfinishedUploads() {
    int removed = 0;
    std::error_code ec;
    for (const fs::directory_entry& entry : fs::directory_iterator(dir_, ec)) {
        if (entry.path().filename().string().rfind(kUploadPrefix, 0) != 0) continue;
        std::error_code ignored;
        if (fs::remove(entry.path(), ignored)) ++removed;
    }
    return removed;
}

absl::StatusOr<std::unique_ptr<BlobStore::Upload>> BlobStore::StartUpload(const std::string& hash,
                                                                          uint64_t size) {
    if (!IsSha256Hex(hash)) {
        return absl::InvalidArgumentError("blob hash '" + hash + "' is not a SHA-256 hex digest");
    }
    static std::atomic<uint64_t> counter{0};
    const std::string temp =
        absl::StrCat(dir_, "/", kUploadPrefix, hash, "-", ::getpid(), "-", ++counter);
    std::unique_ptr<Upload> upload(new Upload(hash, size, PathOf(hash), temp));
    if (!upload->out_) return absl::InternalError(temp + ": cannot create");
    return upload;
}

BlobStore::Upload::Upload(std::string hash, uint64_t size, std::string final_path,
                          std::string temp_path)
    : hash_(std::move(hash)),
      size_(size),
      final_path_(std::move(final_path)),
      temp_path_(std::move(temp_path)),
      out_(temp_path_, std::ios::binary) {}

BlobStore::Upload::~Upload() {
    if (finished_) return;
    out_.close();
    std::error_code ignored;
    fs::remove(temp_path_, ignored);
}

absl::Status BlobStore::Upload::Append(std::string_view data) {
    if (data.size() > size_ - received_) {
        return absl::ResourceExhaustedError(absl::StrCat("blob ", hash_, ": more than the ", size_,
                                                         " bytes declared arrived; refused"));
    }
    received_ += data.size();
    digest_.Update(data);
    out_.write(data.data(), std::streamsize(data.size()));
    if (!out_) return absl::InternalError(temp_path_ + ": " + std::strerror(errno));
    return absl::OkStatus();
}

absl::Status BlobStore::Upload::Finish() {
    if (received_ != size_) {
        return absl::InvalidArgumentError(
            absl::StrCat("blob ", hash_, ": ", received_, " bytes arrived of ", size_));
    }
    if (const std::string got = digest_.HexDigest(); got != hash_) {
        return absl::InvalidArgumentError(
            absl::StrCat("blob ", hash_, ": the content hashes to ", got));
    }
    out_.close();
    if (!out_) return absl::InternalError(temp_path_ + ": " + std::strerror(errno));
    // Durable before any job that names it is recorded.
    if (absl::Status s = RenameDurably(temp_path_, final_path_); !s.ok()) return s;
    finished_ = true;
    return absl::OkStatus();
}

absl::StatusOr<std::string> BlobStore::Put(std::string_view data) {
    std::string hash = Sha256Hex(data);
    if (Has(hash)) return hash;
    absl::StatusOr<std::unique_ptr<Upload>> upload = StartUpload(hash, data.size());
    if (!upload.ok()) return upload.status();
    if (absl::Status s = (*upload)->Append(data); !s.ok()) return s;
    if (absl::Status s = (*upload)->Finish(); !s.ok()) return s;
    return hash;
}

}  // namespace lf
