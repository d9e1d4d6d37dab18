// The blob store counts the bytes it receives: an upload that streams more than it declared is
// refused before the excess reaches the disk, and the temporary files of uploads a killed server
// never finished are swept.
#include "server/blob_store.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "test_dir.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

class BlobStoreTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = lf::testing::FreshTestDir("lf_blobs");
        blobs_ = std::move(*BlobStore::Open(dir_.string()));
    }
    void TearDown() override { fs::remove_all(dir_); }

    // Bytes in the folder's files: what reached the disk.
    uint64_t BytesOnDisk() const {
        uint64_t total = 0;
        for (const fs::directory_entry& e : fs::directory_iterator(dir_)) total += e.file_size();
        return total;
    }

    fs::path dir_;
    std::unique_ptr<BlobStore> blobs_;
};

TEST_F(BlobStoreTest, UploadOfMoreBytesThanDeclaredIsRefusedBeforeTheyAreWritten) {
    const std::string content(1 << 20, 'x');
    absl::StatusOr<std::unique_ptr<BlobStore::Upload>> upload =
        blobs_->StartUpload(Sha256Hex(content), 10);
    ASSERT_TRUE(upload.ok()) << upload.status();
    ASSERT_TRUE((*upload)->Append(content.substr(0, 6)).ok());
    const absl::Status more = (*upload)->Append(content.substr(6, 1 << 16));
    EXPECT_EQ(more.code(), absl::StatusCode::kResourceExhausted);
    EXPECT_NE(more.message().find("10 bytes declared"), std::string_view::npos) << more;
    EXPECT_LE(BytesOnDisk(), 10u);
    EXPECT_EQ((*upload)->Append(content.substr(6, 5)).code(), absl::StatusCode::kResourceExhausted)
        << "one byte over is over";
    upload->reset();
    EXPECT_EQ(BytesOnDisk(), 0u) << "the refused upload leaves nothing";
}

TEST_F(BlobStoreTest, UnfinishedUploadsAreSweptAndBlobsKept) {
    ASSERT_TRUE(blobs_->Put("kept").ok());
    absl::StatusOr<std::unique_ptr<BlobStore::Upload>> upload =
        blobs_->StartUpload(Sha256Hex("never finished"), 14);
    ASSERT_TRUE((*upload)->Append("never").ok());
    std::ofstream(dir_ / ".upload-from-a-killed-server") << "partial";
    EXPECT_EQ(blobs_->SweepUnfinishedUploads(), 2);
    EXPECT_TRUE(blobs_->Has(Sha256Hex("kept")));
    EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

}  // namespace
}  // namespace lf
