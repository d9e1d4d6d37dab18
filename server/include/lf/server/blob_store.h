// Content-addressed files in one folder, named by their SHA-256. An upload writes into
// partial/HASH-SIZE and becomes visible as HASH only once its size and hash check out, so a blob
// that exists is always whole. The bytes of an upload that broke stay in partial/ so that the
// client resumes from UploadOffset instead of starting over.
#pragma once

#include <cstdint>
#include <fstream>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <string_view>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "lf/job/digest.h"

namespace lf {

// Puts `temp` in place as `path` durably: syncs its content, renames it, and syncs the folder,
// so that after a crash `path` is either absent or whole.
absl::Status RenameDurably(const std::string& temp, const std::string& path);

// Partial uploads kept at once; each is at most the server's scene size limit.
constexpr int kMaxPartialUploads = 16;

class BlobStore {
  public:
    // Creates `dir` and `dir`/partial when missing. Beyond `max_partial_uploads` partial uploads,
    // a new upload takes the place of the least recently written one.
    static absl::StatusOr<std::unique_ptr<BlobStore>> Open(
        const std::string& dir, int max_partial_uploads = kMaxPartialUploads);

    bool Has(const std::string& hash) const;
    // Has, and marks the blob as just used (its modification time), so that RemoveUnused spares
    // it for a while: a client that found it stored may be about to submit a job naming it.
    bool Touch(const std::string& hash);
    std::string PathOf(const std::string& hash) const;
    // The size of a blob that exists.
    absl::StatusOr<uint64_t> SizeOf(const std::string& hash) const;
    // Removes the temporary files of Put that never finished; only while no Put runs (at start,
    // with the data folder locked). Partial uploads stay. Returns how many.
    int SweepUnfinishedUploads();

    // Where an upload of `hash`, declared `size` bytes, resumes: `size` when the blob is stored
    // (touched, as Touch does), the bytes held of a partial upload of that size, else 0.
    // InvalidArgument for a malformed hash.
    absl::StatusOr<uint64_t> UploadOffset(const std::string& hash, uint64_t size);

    class Upload {
      public:
        // Keeps the bytes received in partial/ for a resume, unless they were found wrong.
        ~Upload();
        // ResourceExhausted, before writing any of `data`, once more bytes arrive than were
        // declared: the size limits are checked on declared sizes, so they hold only if the
        // bytes received are counted. The partial upload is removed.
        absl::Status Append(std::string_view data);
        // Moves the blob into place once its bytes are all there and hash to its name.
        // FailedPrecondition while bytes are missing (they are kept: resume at UploadOffset);
        // InvalidArgument, the partial upload removed, when the content hashes to another name.
        absl::Status Finish();
        uint64_t offset() const { return offset_; }      // where this upload started
        uint64_t received() const { return received_; }  // bytes it appended

      private:
        friend class BlobStore;
        Upload(BlobStore& store, std::string hash, uint64_t size, uint64_t offset,
               std::string partial_path);
        BlobStore& store_;
        std::string hash_;
        uint64_t size_, offset_, received_ = 0;
        std::string partial_path_;
        std::ofstream out_;
        Sha256 digest_;
        bool discard_ = false;
    };
    // Starts the upload of `hash` (declared `size` bytes) at byte `offset`: 0 starts over,
    // dropping any partial upload of it; otherwise the partial upload is continued there (cut
    // back to `offset` if it holds more) and its first `offset` bytes hashed again, so the hash
    // checked at Finish covers the whole blob. Errors:
    // - InvalidArgument: a malformed hash, `offset` beyond `size`, or a partial upload of another
    //   size (both remove the partial upload);
    // - OutOfRange: `offset` beyond the bytes held (kept: ask UploadOffset);
    // - AlreadyExists: the blob is stored (another upload finished it);
    // - Aborted: another upload of this hash is running (retry once it ended);
    // - ResourceExhausted: the partial uploads the store keeps are all being written.
    absl::StatusOr<std::unique_ptr<Upload>> StartUpload(const std::string& hash, uint64_t size,
                                                        uint64_t offset = 0);
    // Stores `data` (a blob the server makes itself) and returns its hash.
    absl::StatusOr<std::string> Put(std::string_view data);

    // Removes the blobs not in `keep` that were last written or touched before `unused_before`,
    // and the partial uploads not written since `partial_before` that no upload is writing.
    struct Removed {
        int blobs = 0;
        uint64_t blob_bytes = 0;
        int partials = 0;
    };
    Removed RemoveUnused(const std::set<std::string>& keep, absl::Time unused_before,
                         absl::Time partial_before);

  private:
    BlobStore(std::string dir, int max_partial_uploads)
        : dir_(std::move(dir)), max_partials_(max_partial_uploads) {}
    // The partial upload of `hash`, of any size; "" when there is none. Under mutex_.
    std::string FindPartial(const std::string& hash) const;
    std::string PartialPath(const std::string& hash, uint64_t size) const;
    // Makes room for one more partial upload by removing the least recently written one that
    // no upload is writing. Under mutex_.
    absl::Status MakeRoomForPartial();
    // StartUpload's checks and preparation of the partial file, under mutex_: on success the
    // hash is in `uploading_` until the Upload ends.
    absl::Status ClaimPartial(const std::string& hash, uint64_t size, uint64_t offset);
    void EndUpload(const std::string& hash);

    const std::string dir_;
    const int max_partials_;
    // Guards `uploading_`, and orders blob removal against Touch and the start of uploads.
    mutable std::mutex mutex_;
    std::set<std::string> uploading_;  // hashes with an Upload alive
};

}  // namespace lf
