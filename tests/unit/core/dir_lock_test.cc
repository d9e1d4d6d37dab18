// DirLock: one process per folder, and the one refused hears who holds it (issue 27: two workers
// shared a --cache-dir and nothing said so).
#include "lf/core/dir_lock.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

namespace lf {
namespace {

namespace fs = std::filesystem;

constexpr DirUse kCache{"cache folder", "lightfarm-worker", "--cache-dir"};

TEST(DirLockTest, ASecondHolderIsRefusedNamingTheFolderAndThePid) {
    const fs::path dir = fs::path(testing::TempDir()) / "dir_lock_test";
    fs::create_directories(dir);
    {
        absl::StatusOr<std::unique_ptr<DirLock>> held = DirLock::Acquire(dir.string(), kCache);
        ASSERT_TRUE(held.ok()) << held.status();
        // flock locks an open file, so a second open in this process is refused as another
        // process would be.
        const absl::StatusOr<std::unique_ptr<DirLock>> second =
            DirLock::Acquire(dir.string(), kCache);
        ASSERT_EQ(second.status().code(), absl::StatusCode::kFailedPrecondition);
        const std::string message(second.status().message());
        EXPECT_NE(message.find("cache folder " + dir.string() +
                               " is in use by another "
                               "lightfarm-worker (pid " +
                               std::to_string(::getpid()) + ","),
                  std::string::npos)
            << message;
        EXPECT_NE(message.find("--cache-dir"), std::string::npos) << message;
    }
    EXPECT_TRUE(DirLock::Acquire(dir.string(), kCache).ok()) << "released with its holder";
    fs::remove_all(dir);
}

}  // namespace
}  // namespace lf
