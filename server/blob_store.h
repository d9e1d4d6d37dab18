// Content-addressed files in one folder, named by their SHA-256. An upload lands in a temporary
// file and becomes visible only once its size and hash check out, so a blob that exists is
// always whole.
#pragma once

#include <cstdint>
#include <fstream>
#include <memory>
#include <string>
#include <string_view>

#include "absl/status/statusor.h"
#include "lf/job/digest.h"

namespace lf {

// Puts `temp` in place as `path` durably: syncs its content, renames it, and syncs the folder,
// so that after a crash `path` is either absent or whole.
absl::Status RenameDurably(const std::string& temp, const std::string& path);

class BlobStore {
  public:
    // Creates `dir` when missing.
    static absl::StatusOr<std::unique_ptr<BlobStore>> Open(const std::string& dir);

    bool Has(const std::string& hash) const;
    std::string PathOf(const std::string& hash) const;
    // The size of a blob that exists.
    absl::StatusOr<uint64_t> SizeOf(const std::string& hash) const;
    // Removes the temporary files of uploads that never finished; only while no upload runs
    // (at start, with the data folder locked). Returns how many.
    int SweepUnfinishedUploads();

    class Upload {
      public:
        ~Upload();  // removes the temporary file unless Finish succeeded
        // ResourceExhausted, before writing any of `data`, once more bytes arrive than were
        // declared: the size limits are checked on declared sizes, so they hold only if the
        // bytes received are counted.
        absl::Status Append(std::string_view data);
        absl::Status Finish();

      private:
        friend class BlobStore;
        Upload(std::string hash, uint64_t size, std::string final_path, std::string temp_path);
        std::string hash_;
        uint64_t size_, received_ = 0;
        std::string final_path_, temp_path_;
        std::ofstream out_;
        Sha256 digest_;
        bool finished_ = false;
    };
    // InvalidArgument for a malformed hash.
    absl::StatusOr<std::unique_ptr<Upload>> StartUpload(const std::string& hash, uint64_t size);
    // Stores `data` (a blob the server makes itself) and returns its hash.
    absl::StatusOr<std::string> Put(std::string_view data);

  private:
    explicit BlobStore(std::string dir) : dir_(std::move(dir)) {}
    std::string dir_;
};

}  // namespace lf
