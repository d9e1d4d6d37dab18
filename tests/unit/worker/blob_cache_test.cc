// The worker's blob cache: a blob is fetched once, checked against its hash, kept across
// restarts, and the least recently used go first when the budget is exceeded.
#include "lf/worker/blob_cache.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>

#include "lf/job/digest.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

class BlobCacheTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("lf_blob_cache_" + std::to_string(::getpid()));
        fs::remove_all(dir_);
        for (const char* text : {"aaaa", "bbbb", "cccc"}) blobs_[Sha256Hex(text)] = text;
    }
    void TearDown() override { fs::remove_all(dir_); }

    // Serves `blobs_`, counting fetches.
    BlobCache::Fetch Server() {
        return [this](const std::string& hash, const std::string& path) {
            ++fetches_;
            std::ofstream(path) << blobs_[hash];
            return absl::OkStatus();
        };
    }

    fs::path dir_;
    std::map<std::string, std::string> blobs_;
    int fetches_ = 0;
};

TEST_F(BlobCacheTest, FetchesOnceAndKeepsAcrossRestarts) {
    const std::string hash = Sha256Hex("aaaa");
    {
        auto cache = *BlobCache::Open(dir_.string(), 1 << 20);
        absl::StatusOr<std::string> path = cache->Get(hash, Server());
        ASSERT_TRUE(path.ok()) << path.status();
        EXPECT_TRUE(cache->Get(hash, Server()).ok());
        EXPECT_EQ(fetches_, 1);
    }
    auto reopened = *BlobCache::Open(dir_.string(), 1 << 20);
    EXPECT_EQ(reopened->bytes(), 4u);
    EXPECT_TRUE(reopened->Get(hash, Server()).ok());
    EXPECT_EQ(fetches_, 1);
}

TEST_F(BlobCacheTest, EvictsLeastRecentlyUsedBeyondTheBudget) {
    auto cache = *BlobCache::Open(dir_.string(), 8);  // two blobs of 4 bytes
    const std::string a = Sha256Hex("aaaa"), b = Sha256Hex("bbbb"), c = Sha256Hex("cccc");
    ASSERT_TRUE(cache->Get(a, Server()).ok());
    ASSERT_TRUE(cache->Get(b, Server()).ok());
    ASSERT_TRUE(cache->Get(a, Server()).ok());  // a is now the most recent
    ASSERT_TRUE(cache->Get(c, Server()).ok());
    EXPECT_EQ(cache->bytes(), 12u);  // nothing goes before Trim
    cache->Trim();
    EXPECT_EQ(cache->bytes(), 8u);
    EXPECT_FALSE(fs::exists(dir_ / b));
    EXPECT_TRUE(fs::exists(dir_ / a));
    EXPECT_TRUE(fs::exists(dir_ / c));
}

TEST_F(BlobCacheTest, RefusesContentThatDoesNotMatchItsHash) {
    auto cache = *BlobCache::Open(dir_.string(), 1 << 20);
    const std::string hash = Sha256Hex("aaaa");
    blobs_[hash] = "tampered";
    absl::StatusOr<std::string> path = cache->Get(hash, Server());
    EXPECT_EQ(path.status().code(), absl::StatusCode::kDataLoss);
    EXPECT_FALSE(fs::exists(dir_ / hash));
    EXPECT_EQ(cache->bytes(), 0u);
    EXPECT_EQ(cache->Get("../../etc/passwd", Server()).status().code(),
              absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace lf
