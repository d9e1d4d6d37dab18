#include "lf/server/blob_store.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <vector>

#include "absl/strings/str_cat.h"
#include "lf/core/log.h"

namespace lf {

namespace fs = std::filesystem;

namespace {

constexpr char kPutPrefix[] = ".upload-";
constexpr char kPartialDir[] = "partial";

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

// When the file was last written or touched; InfiniteFuture when it cannot be read, so that
// nothing is removed on a doubt.
absl::Time ModifiedAt(const std::string& path) {
    struct stat st;
    if (::stat(path.c_str(), &st) != 0) return absl::InfiniteFuture();
    return absl::TimeFromTimespec(st.st_mtim);
}

absl::Status MalformedHash(const std::string& hash) {
    return absl::InvalidArgumentError("blob hash '" + LogSafe(hash, 64) +
                                      "' is not a SHA-256 hex digest");
}

}  // namespace

absl::Status RenameDurably(const std::string& temp, const std::string& path) {
    if (absl::Status s = Sync(temp, O_RDONLY); !s.ok()) return s;
    std::error_code ec;
    fs::rename(temp, path, ec);
    if (ec) return absl::InternalError(path + ": " + ec.message());
    return Sync(fs::path(path).parent_path().string(), O_RDONLY | O_DIRECTORY);
}

absl::StatusOr<std::unique_ptr<BlobStore>> BlobStore::Open(const std::string& dir,
                                                           int max_partial_uploads) {
    std::error_code ec;
    fs::create_directories(fs::path(dir) / kPartialDir, ec);
    if (ec) return absl::InternalError(dir + ": " + ec.message());
    return std::unique_ptr<BlobStore>(new BlobStore(dir, max_partial_uploads));
}

bool BlobStore::Has(const std::string& hash) const {
    return IsSha256Hex(hash) && fs::exists(PathOf(hash));
}

bool BlobStore::Touch(const std::string& hash) {
    if (!IsSha256Hex(hash)) return false;
    std::lock_guard<std::mutex> lock(mutex_);
    return ::utimensat(AT_FDCWD, PathOf(hash).c_str(), nullptr, 0) == 0;
}

std::string BlobStore::PathOf(const std::string& hash) const { return dir_ + "/" + hash; }

std::string BlobStore::PartialPath(const std::string& hash, uint64_t size) const {
    return absl::StrCat(dir_, "/", kPartialDir, "/", hash, "-", size);
}

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
        if (entry.path().filename().string().rfind(kPutPrefix, 0) != 0) continue;
        std::error_code ignored;
        if (fs::remove(entry.path(), ignored)) ++removed;
    }
    return removed;
}

std::string BlobStore::FindPartial(const std::string& hash) const {
    std::error_code ec;
    for (const fs::directory_entry& entry :
         fs::directory_iterator(fs::path(dir_) / kPartialDir, ec)) {
        if (entry.path().filename().string().rfind(hash + "-", 0) == 0)
            return entry.path().string();
    }
    return "";
}

absl::StatusOr<uint64_t> BlobStore::UploadOffset(const std::string& hash, uint64_t size) {
    if (!IsSha256Hex(hash)) return MalformedHash(hash);
    if (Touch(hash)) return size;
    std::lock_guard<std::mutex> lock(mutex_);
    std::error_code ec;
    const uint64_t held = fs::file_size(PartialPath(hash, size), ec);
    return ec ? 0 : std::min(held, size);
}

absl::Status BlobStore::MakeRoomForPartial() {
    std::vector<std::pair<absl::Time, fs::path>> idle;
    int count = 0;
    std::error_code ec;
    for (const fs::directory_entry& entry :
         fs::directory_iterator(fs::path(dir_) / kPartialDir, ec)) {
        ++count;
        const std::string name = entry.path().filename().string();
        if (uploading_.count(name.substr(0, name.find('-')))) continue;
        idle.emplace_back(ModifiedAt(entry.path().string()), entry.path());
    }
    if (count < max_partials_) return absl::OkStatus();
    if (idle.empty()) {
        return absl::ResourceExhaustedError(
            absl::StrCat("the server is receiving ", count, " uploads already; retry later"));
    }
    std::error_code ignored;
    fs::remove(std::min_element(idle.begin(), idle.end())->second, ignored);
    return absl::OkStatus();
}

absl::StatusOr<std::unique_ptr<BlobStore::Upload>> BlobStore::StartUpload(const std::string& hash,
                                                                          uint64_t size,
                                                                          uint64_t offset) {
    if (!IsSha256Hex(hash)) return MalformedHash(hash);
    const std::string path = PartialPath(hash, size);
    if (absl::Status s = ClaimPartial(hash, size, offset); !s.ok()) return s;
    // From here the Upload owns the claim: its destructor releases it.
    std::unique_ptr<Upload> upload(new Upload(*this, hash, size, offset, path));
    if (offset > 0) {
        std::ifstream in(path, std::ios::binary);
        std::string buffer(1 << 20, '\0');
        uint64_t left = offset;
        while (left > 0 &&
               in.read(buffer.data(), std::streamsize(std::min<uint64_t>(left, buffer.size())))) {
            upload->digest_.Update(std::string_view(buffer.data(), size_t(in.gcount())));
            left -= uint64_t(in.gcount());
        }
        if (left > 0) return absl::InternalError(path + ": cannot be read back");
    }
    upload->out_.open(path, std::ios::binary | std::ios::app);
    if (!upload->out_) return absl::InternalError(path + ": cannot be opened");
    return upload;
}

absl::Status BlobStore::ClaimPartial(const std::string& hash, uint64_t size, uint64_t offset) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (fs::exists(PathOf(hash))) {
        return absl::AlreadyExistsError(absl::StrCat("blob ", hash, " is stored already"));
    }
    // Two streams appending to one file would interleave their bytes.
    if (uploading_.count(hash)) {
        return absl::AbortedError(absl::StrCat(
            "blob ", hash, " is being uploaded by another stream; retry when it has ended"));
    }
    const std::string found = FindPartial(hash), path = PartialPath(hash, size);
    std::error_code ec;
    auto refuse = [&](absl::Status why) {
        std::error_code ignored;
        if (!found.empty()) fs::remove(found, ignored);
        return why;
    };
    if (offset > size) {
        return refuse(absl::InvalidArgumentError(absl::StrCat(
            "blob ", hash, ": upload at offset ", offset, " of a blob of ", size, " bytes")));
    }
    if (!found.empty() && found != path) {
        return refuse(absl::InvalidArgumentError(
            absl::StrCat("blob ", hash, ": upload of ", size, " bytes at offset ", offset,
                         ", the bytes held are of an upload declared with another size; removed")));
    }
    if (offset == 0) {
        if (!found.empty()) {
            fs::remove(found, ec);
        } else if (absl::Status s = MakeRoomForPartial(); !s.ok()) {
            return s;
        }
        // Created here, under the lock, so that the count MakeRoomForPartial keeps holds.
        if (!std::ofstream(path, std::ios::binary)) {
            return absl::InternalError(path + ": cannot be created");
        }
    } else if (found.empty()) {
        return absl::OutOfRangeError(absl::StrCat("blob ", hash, ": upload at offset ", offset,
                                                  ", the server holds none of it; start at 0"));
    } else {
        const uint64_t held = fs::file_size(path, ec);
        if (ec) return absl::InternalError(path + ": " + ec.message());
        if (offset > held) {
            return absl::OutOfRangeError(absl::StrCat("blob ", hash, ": upload at offset ", offset,
                                                      ", the server holds ", held, " bytes"));
        }
        // The client did not see the last bytes arrive: it sends them again.
        if (offset < held) fs::resize_file(path, offset, ec);
        if (ec) return absl::InternalError(path + ": " + ec.message());
    }
    uploading_.insert(hash);
    return absl::OkStatus();
}

void BlobStore::EndUpload(const std::string& hash) {
    std::lock_guard<std::mutex> lock(mutex_);
    uploading_.erase(hash);
}

BlobStore::Upload::Upload(BlobStore& store, std::string hash, uint64_t size, uint64_t offset,
                          std::string partial_path)
    : store_(store),
      hash_(std::move(hash)),
      size_(size),
      offset_(offset),
      partial_path_(std::move(partial_path)) {}

BlobStore::Upload::~Upload() {
    out_.close();
    if (discard_) {
        std::error_code ignored;
        fs::remove(partial_path_, ignored);
    }
    store_.EndUpload(hash_);
}

absl::Status BlobStore::Upload::Append(std::string_view data) {
    if (data.size() > size_ - offset_ - received_) {
        discard_ = true;
        return absl::ResourceExhaustedError(absl::StrCat("blob ", hash_, ": more than the ", size_,
                                                         " bytes declared arrived; refused"));
    }
    received_ += data.size();
    digest_.Update(data);
    out_.write(data.data(), std::streamsize(data.size()));
    if (!out_) return absl::InternalError(partial_path_ + ": " + std::strerror(errno));
    return absl::OkStatus();
}

absl::Status BlobStore::Upload::Finish() {
    if (const uint64_t held = offset_ + received_; held != size_) {
        return absl::FailedPreconditionError(
            absl::StrCat("blob ", hash_, ": ", held, " bytes arrived of ", size_,
                         "; they are kept: resume the upload at offset ", held));
    }
    if (const std::string got = digest_.HexDigest(); got != hash_) {
        discard_ = true;
        return absl::InvalidArgumentError(absl::StrCat("blob ", hash_, ": the content hashes to ",
                                                       got, "; the upload is dropped"));
    }
    out_.close();
    if (!out_) return absl::InternalError(partial_path_ + ": " + std::strerror(errno));
    // Durable before any job that names it is recorded.
    if (absl::Status s = RenameDurably(partial_path_, store_.PathOf(hash_)); !s.ok()) return s;
    return absl::OkStatus();
}

absl::StatusOr<std::string> BlobStore::Put(std::string_view data) {
    std::string hash = Sha256Hex(data);
    if (Touch(hash)) return hash;
    // Not through StartUpload: two jobs may publish the same blob at once, and each must succeed.
    static std::atomic<uint64_t> counter{0};
    const std::string temp =
        absl::StrCat(dir_, "/", kPutPrefix, hash, "-", ::getpid(), "-", ++counter);
    {
        std::ofstream out(temp, std::ios::binary);
        out.write(data.data(), std::streamsize(data.size()));
        out.close();
        if (!out) {
            std::error_code ignored;
            fs::remove(temp, ignored);
            return absl::InternalError(temp + ": cannot be written");
        }
    }
    if (absl::Status s = RenameDurably(temp, PathOf(hash)); !s.ok()) return s;
    return hash;
}

BlobStore::Removed BlobStore::RemoveUnused(const std::set<std::string>& keep,
                                           absl::Time unused_before, absl::Time partial_before) {
    Removed removed;
    std::lock_guard<std::mutex> lock(mutex_);
    std::error_code ec;
    for (const fs::directory_entry& entry : fs::directory_iterator(dir_, ec)) {
        const std::string name = entry.path().filename().string();
        if (!IsSha256Hex(name) || keep.count(name)) continue;
        if (ModifiedAt(entry.path().string()) >= unused_before) continue;
        std::error_code size_ec, ignored;
        const uint64_t bytes = fs::file_size(entry.path(), size_ec);
        if (fs::remove(entry.path(), ignored)) {
            ++removed.blobs;
            removed.blob_bytes += size_ec ? 0 : bytes;
        }
    }
    for (const fs::directory_entry& entry :
         fs::directory_iterator(fs::path(dir_) / kPartialDir, ec)) {
        const std::string name = entry.path().filename().string();
        if (uploading_.count(name.substr(0, name.find('-')))) continue;
        if (ModifiedAt(entry.path().string()) >= partial_before) continue;
        std::error_code ignored;
        removed.partials += fs::remove(entry.path(), ignored);
    }
    return removed;
}

}  // namespace lf
