// The blob store counts the bytes it receives (an upload that streams more than it declared is
// refused before the excess reaches the disk), keeps the bytes of a broken upload so that it
// resumes where they end, hashes the whole blob whatever the resumes, lets one upload of a hash
// run at a time, bounds the partial uploads it keeps, and removes what no one uses.
#include "lf/server/blob_store.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>

#include "test_dir.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

std::string RandomBytes(size_t n, uint32_t seed) {
    std::mt19937 random(seed);
    std::string bytes(n, '\0');
    for (char& c : bytes) c = char(random());
    return bytes;
}

std::string ReadAll(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

// Sets the file's modification time `ago` before now.
void Age(const fs::path& path, absl::Duration ago) {
    const timespec t = absl::ToTimespec(absl::Now() - ago);
    const timespec times[2] = {t, t};
    ASSERT_EQ(::utimensat(AT_FDCWD, path.c_str(), times, 0), 0) << path;
}

class BlobStoreTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = lf::testing::FreshTestDir("lf_blobs");
        blobs_ = std::move(*BlobStore::Open(dir_.string()));
    }
    void TearDown() override { fs::remove_all(dir_); }

    // Bytes in the folder's files, partial uploads included: what reached the disk.
    uint64_t BytesOnDisk() const {
        uint64_t total = 0;
        for (const fs::directory_entry& e : fs::recursive_directory_iterator(dir_)) {
            if (e.is_regular_file()) total += e.file_size();
        }
        return total;
    }
    int Partials() const {
        return int(
            std::distance(fs::directory_iterator(dir_ / "partial"), fs::directory_iterator()));
    }
    // Uploads `content[from, to)` of the blob as one stream that then breaks (or ends).
    absl::Status Send(const std::string& content, uint64_t from, uint64_t to, bool finish = false) {
        absl::StatusOr<std::unique_ptr<BlobStore::Upload>> upload =
            blobs_->StartUpload(Sha256Hex(content), content.size(), from);
        if (!upload.ok()) return upload.status();
        for (uint64_t at = from; at < to; at += 1 << 16) {
            const uint64_t n = std::min<uint64_t>(1 << 16, to - at);
            if (absl::Status s = (*upload)->Append(std::string_view(content).substr(at, n));
                !s.ok()) {
                return s;
            }
        }
        return finish ? (*upload)->Finish() : absl::OkStatus();
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

TEST_F(BlobStoreTest, TemporaryFilesOfPutAreSweptAndPartialUploadsKept) {
    ASSERT_TRUE(blobs_->Put("kept").ok());
    ASSERT_TRUE(Send("never finished", 0, 5).ok());
    std::ofstream(dir_ / ".upload-from-a-killed-server") << "partial";
    EXPECT_EQ(blobs_->SweepUnfinishedUploads(), 1);
    EXPECT_TRUE(blobs_->Has(Sha256Hex("kept")));
    EXPECT_EQ(*blobs_->UploadOffset(Sha256Hex("never finished"), 14), 5u);
    EXPECT_EQ(BytesOnDisk(), 4u + 5u);
}

TEST_F(BlobStoreTest, BrokenUploadResumesFromTheServersOffsetAndTheWholeBlobIsHashed) {
    const std::string content = RandomBytes(3 << 20, 1);
    const std::string hash = Sha256Hex(content);
    EXPECT_EQ(*blobs_->UploadOffset(hash, content.size()), 0u);
    ASSERT_TRUE(Send(content, 0, 1500000).ok());  // then the stream breaks
    EXPECT_FALSE(blobs_->Has(hash));
    ASSERT_EQ(*blobs_->UploadOffset(hash, content.size()), 1500000u);
    EXPECT_EQ(*blobs_->UploadOffset(hash, content.size() + 1), 0u) << "another declared size";

    // A stream that ends early is told where to resume, and its bytes stay.
    const absl::Status short_stream = Send(content, 1500000, 2000000, /*finish=*/true);
    EXPECT_EQ(short_stream.code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_NE(short_stream.message().find("resume the upload at offset 2000000"),
              std::string_view::npos)
        << short_stream;
    ASSERT_EQ(*blobs_->UploadOffset(hash, content.size()), 2000000u);

    absl::StatusOr<std::unique_ptr<BlobStore::Upload>> rest =
        blobs_->StartUpload(hash, content.size(), 2000000);
    ASSERT_TRUE(rest.ok()) << rest.status();
    ASSERT_TRUE((*rest)->Append(std::string_view(content).substr(2000000)).ok());
    ASSERT_TRUE((*rest)->Finish().ok());
    EXPECT_EQ((*rest)->received(), content.size() - 2000000);
    rest->reset();
    EXPECT_EQ(ReadAll(blobs_->PathOf(hash)), content);
    EXPECT_EQ(Partials(), 0);
    EXPECT_EQ(*blobs_->UploadOffset(hash, content.size()), content.size());
}

TEST_F(BlobStoreTest, ResumeAfterBytesTheServerHoldsButTheClientNeverSawCutsThemBack) {
    const std::string content = RandomBytes(100000, 2);
    ASSERT_TRUE(Send(content, 0, 60000).ok());
    ASSERT_TRUE(Send(content, 40000, content.size(), /*finish=*/true).ok());
    EXPECT_EQ(ReadAll(blobs_->PathOf(Sha256Hex(content))), content);
}

TEST_F(BlobStoreTest, BytesChangedOnDiskBeforeAResumeFailTheHashAndAreDropped) {
    const std::string content = RandomBytes(200000, 3);
    const std::string hash = Sha256Hex(content);
    ASSERT_TRUE(Send(content, 0, 100000).ok());
    {
        // The first half as it came, but for one byte: only a hash over the bytes on disk,
        // not over the bytes of this stream, sees it.
        std::fstream held(dir_ / "partial" / (hash + "-200000"),
                          std::ios::binary | std::ios::in | std::ios::out);
        held.seekp(1234);
        held.put(char(content[1234] ^ 1));
    }
    const absl::Status s = Send(content, 100000, content.size(), /*finish=*/true);
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(s.message().find("the content hashes to"), std::string_view::npos) << s;
    EXPECT_FALSE(blobs_->Has(hash));
    EXPECT_EQ(Partials(), 0);
    EXPECT_EQ(*blobs_->UploadOffset(hash, content.size()), 0u) << "starts over";
    EXPECT_TRUE(Send(content, 0, content.size(), /*finish=*/true).ok());
}

TEST_F(BlobStoreTest, WrongHashFailsAtTheEndAndClearsThePartialUpload) {
    const std::string content = RandomBytes(50000, 4);
    const std::string claimed = Sha256Hex("something else");
    absl::StatusOr<std::unique_ptr<BlobStore::Upload>> upload =
        blobs_->StartUpload(claimed, content.size());
    ASSERT_TRUE(upload.ok());
    ASSERT_TRUE((*upload)->Append(content).ok());
    EXPECT_EQ((*upload)->Finish().code(), absl::StatusCode::kInvalidArgument);
    upload->reset();
    EXPECT_FALSE(blobs_->Has(claimed));
    EXPECT_EQ(BytesOnDisk(), 0u);
}

TEST_F(BlobStoreTest, OffsetsAndSizesThatDoNotFitTheBytesHeldAreRefused) {
    const std::string content = RandomBytes(10000, 5);
    const std::string hash = Sha256Hex(content);
    EXPECT_EQ(blobs_->StartUpload(hash, 10000, 10).status().code(), absl::StatusCode::kOutOfRange)
        << "nothing held";
    ASSERT_TRUE(Send(content, 0, 4000).ok());
    const absl::Status beyond_held = blobs_->StartUpload(hash, 10000, 5000).status();
    EXPECT_EQ(beyond_held.code(), absl::StatusCode::kOutOfRange);
    EXPECT_NE(beyond_held.message().find("holds 4000 bytes"), std::string_view::npos)
        << beyond_held;
    EXPECT_EQ(Partials(), 1) << "the bytes held are fine: kept";

    const absl::Status other_size = blobs_->StartUpload(hash, 20000, 4000).status();
    EXPECT_EQ(other_size.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(other_size.message().find("another size"), std::string_view::npos) << other_size;
    EXPECT_EQ(Partials(), 0);

    ASSERT_TRUE(Send(content, 0, 4000).ok());
    const absl::Status beyond_size = blobs_->StartUpload(hash, 10000, 10001).status();
    EXPECT_EQ(beyond_size.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(beyond_size.message().find("offset 10001 of a blob of 10000 bytes"),
              std::string_view::npos)
        << beyond_size;
    EXPECT_EQ(Partials(), 0);
    EXPECT_EQ(blobs_->StartUpload("not-a-hash", 1).status().code(),
              absl::StatusCode::kInvalidArgument);
}

TEST_F(BlobStoreTest, ASecondDeclaredSizeFromTheStartIsRefusedAndThePartialRemoved) {
    const std::string content = RandomBytes(10000, 6);
    const std::string hash = Sha256Hex(content);
    ASSERT_TRUE(Send(content, 0, 4000).ok());
    const absl::Status other_size = blobs_->StartUpload(hash, 20000, 0).status();
    EXPECT_EQ(other_size.code(), absl::StatusCode::kInvalidArgument) << other_size;
    EXPECT_NE(other_size.message().find("another size"), std::string_view::npos) << other_size;
    EXPECT_EQ(Partials(), 0) << "neither upload's bytes are kept";
    EXPECT_TRUE(Send(content, 0, content.size(), /*finish=*/true).ok()) << "then starts afresh";
}

TEST_F(BlobStoreTest, AMalformedHashIsQuotedCut) {
    const absl::Status s = blobs_->StartUpload(std::string(1 << 20, 'z'), 1).status();
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_LT(s.message().size(), 200u) << s;
}

TEST_F(BlobStoreTest, OneUploadOfAHashAtATimeAndTheOtherFindsItStored) {
    const std::string content = RandomBytes(100000, 6);
    const std::string hash = Sha256Hex(content);
    absl::StatusOr<std::unique_ptr<BlobStore::Upload>> first =
        blobs_->StartUpload(hash, content.size());
    ASSERT_TRUE(first.ok());
    ASSERT_TRUE((*first)->Append(std::string_view(content).substr(0, 50000)).ok());
    EXPECT_EQ(blobs_->StartUpload(hash, content.size()).status().code(), absl::StatusCode::kAborted)
        << "a second stream from 0 would truncate the first one's file";
    EXPECT_EQ(blobs_->StartUpload(hash, content.size(), 50000).status().code(),
              absl::StatusCode::kAborted);
    ASSERT_TRUE((*first)->Append(std::string_view(content).substr(50000)).ok());
    ASSERT_TRUE((*first)->Finish().ok());
    first->reset();
    EXPECT_EQ(blobs_->StartUpload(hash, content.size()).status().code(),
              absl::StatusCode::kAlreadyExists);
    EXPECT_EQ(ReadAll(blobs_->PathOf(hash)), content);
}

TEST_F(BlobStoreTest, TwoClientsUploadingOneHashAtOnceStoreItWhole) {
    const std::string content = RandomBytes(4 << 20, 7);
    const std::string hash = Sha256Hex(content);
    // Each client as lightfarm submit does it: ask where to start, send the rest in chunks;
    // retry when told another stream runs. Each stream breaks after a few chunks, so the two
    // keep resuming from each other's bytes.
    auto client = [&](int chunks_per_stream, int* streams) {
        while (true) {
            const uint64_t offset = *blobs_->UploadOffset(hash, content.size());
            if (offset == content.size()) return;
            absl::StatusOr<std::unique_ptr<BlobStore::Upload>> upload =
                blobs_->StartUpload(hash, content.size(), offset);
            if (absl::IsAborted(upload.status())) {
                std::this_thread::yield();
                continue;
            }
            if (absl::IsAlreadyExists(upload.status())) return;
            ASSERT_TRUE(upload.ok()) << upload.status();
            ++*streams;
            uint64_t at = offset;
            for (int i = 0; i < chunks_per_stream && at < content.size(); ++i) {
                const uint64_t n = std::min<uint64_t>(1 << 16, content.size() - at);
                ASSERT_TRUE((*upload)->Append(std::string_view(content).substr(at, n)).ok());
                at += n;
            }
            if (at == content.size()) {
                ASSERT_TRUE((*upload)->Finish().ok());
                return;
            }
        }
    };
    int streams_a = 0, streams_b = 0;
    std::thread a(client, 3, &streams_a), b(client, 5, &streams_b);
    a.join();
    b.join();
    EXPECT_EQ(ReadAll(blobs_->PathOf(hash)), content);
    EXPECT_EQ(Partials(), 0);
    EXPECT_GE(streams_a + streams_b, 64 / 5) << "the blob came in many resumed streams";
}

TEST_F(BlobStoreTest, PartialUploadsAreBoundedTheLeastRecentlyWrittenGivingWay) {
    blobs_ = std::move(*BlobStore::Open(dir_.string(), 2));
    const std::string a = RandomBytes(1000, 8), b = RandomBytes(1000, 9), c = RandomBytes(1000, 10);
    ASSERT_TRUE(Send(a, 0, 500).ok());
    ASSERT_TRUE(Send(b, 0, 500).ok());
    Age(dir_ / "partial" / (Sha256Hex(a) + "-1000"), absl::Minutes(5));
    ASSERT_TRUE(Send(c, 0, 500).ok());
    EXPECT_EQ(Partials(), 2);
    EXPECT_EQ(*blobs_->UploadOffset(Sha256Hex(a), 1000), 0u) << "the oldest gave way";
    EXPECT_EQ(*blobs_->UploadOffset(Sha256Hex(b), 1000), 500u);
    EXPECT_EQ(*blobs_->UploadOffset(Sha256Hex(c), 1000), 500u);

    // While both kept ones are being written, a third upload is refused rather than evicting.
    auto upload_b = blobs_->StartUpload(Sha256Hex(b), 1000, 500);
    auto upload_c = blobs_->StartUpload(Sha256Hex(c), 1000, 500);
    ASSERT_TRUE(upload_b.ok() && upload_c.ok());
    EXPECT_EQ(blobs_->StartUpload(Sha256Hex(a), 1000).status().code(),
              absl::StatusCode::kResourceExhausted);
}

TEST_F(BlobStoreTest, RemoveUnusedSparesKeptFreshAndRunningUploads) {
    const std::string kept = *blobs_->Put("a job's scene");
    const std::string old = *blobs_->Put("nobody's");
    const std::string fresh = *blobs_->Put("just uploaded");
    const std::string touched = *blobs_->Put("found stored by MissingBlobs");
    for (const std::string& hash : {kept, old, touched}) Age(blobs_->PathOf(hash), absl::Hours(2));
    ASSERT_TRUE(blobs_->Touch(touched));

    const std::string stale = RandomBytes(100, 11), writing = RandomBytes(100, 12),
                      recent = RandomBytes(100, 13);
    ASSERT_TRUE(Send(stale, 0, 10).ok());
    ASSERT_TRUE(Send(writing, 0, 10).ok());
    ASSERT_TRUE(Send(recent, 0, 10).ok());
    Age(dir_ / "partial" / (Sha256Hex(stale) + "-100"), absl::Hours(25));
    Age(dir_ / "partial" / (Sha256Hex(writing) + "-100"), absl::Hours(25));
    auto running = blobs_->StartUpload(Sha256Hex(writing), 100, 10);
    ASSERT_TRUE(running.ok());

    const absl::Time now = absl::Now();
    const BlobStore::Removed removed =
        blobs_->RemoveUnused({kept}, now - absl::Hours(1), now - absl::Hours(24));
    EXPECT_EQ(removed.blobs, 1);
    EXPECT_EQ(removed.blob_bytes, std::string("nobody's").size());
    EXPECT_EQ(removed.partials, 1);
    EXPECT_TRUE(blobs_->Has(kept));
    EXPECT_FALSE(blobs_->Has(old));
    EXPECT_TRUE(blobs_->Has(fresh));
    EXPECT_TRUE(blobs_->Has(touched));
    EXPECT_EQ(*blobs_->UploadOffset(Sha256Hex(stale), 100), 0u);
    EXPECT_EQ(*blobs_->UploadOffset(Sha256Hex(recent), 100), 10u);
    EXPECT_TRUE((*running)->Append(writing.substr(10)).ok());
    EXPECT_TRUE((*running)->Finish().ok()) << "the upload being written was left alone";
}

}  // namespace
}  // namespace lf
