// The token store: tokens are shown once and stored hashed, names are unique for good,
// revocation keeps the record, and the file is usable by a second process while a server reads.
#include "lf/server/token_store.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <vector>

#include "absl/strings/match.h"
#include "test_dir.h"

namespace lf {
namespace {

TEST(TokenStore, CreatedTokenIsFoundWithItsRoleAndStoredOnlyHashed) {
    const auto dir = testing::FreshTestDir("lf_tokens");
    auto store = TokenStore::Open(dir.string());
    ASSERT_TRUE(store.ok()) << store.status();
    EXPECT_FALSE(*(*store)->Any());
    absl::StatusOr<std::string> token = (*store)->Create("render-node-1", Role::kWorker);
    ASSERT_TRUE(token.ok()) << token.status();
    EXPECT_TRUE(absl::StartsWith(*token, "lf1_"));
    EXPECT_EQ(token->size(), 4u + 64u);  // 256 random bits in hex
    EXPECT_TRUE(*(*store)->Any());

    auto found = (*store)->Find(*token);
    ASSERT_TRUE(found.ok() && found->has_value());
    EXPECT_EQ((*found)->name, "render-node-1");
    EXPECT_EQ((*found)->role, Role::kWorker);
    EXPECT_TRUE((*found)->valid());
    // Not another token, nor a prefix of this one.
    EXPECT_FALSE((*store)->Find(token->substr(0, token->size() - 1))->has_value());
    EXPECT_FALSE((*store)->Find("")->has_value());

    // The file holds no token in the clear.
    store->reset();
    std::ifstream in(dir / TokenStore::kFileName, std::ios::binary);
    std::stringstream bytes;
    bytes << in.rdbuf();
    EXPECT_FALSE(absl::StrContains(bytes.str(), token->substr(4)));
}

TEST(TokenStore, TwoTokensDiffer) {
    const auto dir = testing::FreshTestDir("lf_tokens");
    auto store = TokenStore::Open(dir.string());
    ASSERT_TRUE(store.ok());
    EXPECT_NE(*(*store)->Create("a", Role::kAdmin), *(*store)->Create("b", Role::kAdmin));
}

TEST(TokenStore, NamesAreUniqueEvenAfterRevocation) {
    const auto dir = testing::FreshTestDir("lf_tokens");
    auto store = TokenStore::Open(dir.string());
    ASSERT_TRUE(store.ok());
    ASSERT_TRUE((*store)->Create("alice", Role::kSubmitter).ok());
    EXPECT_TRUE(absl::IsAlreadyExists((*store)->Create("alice", Role::kAdmin).status()));
    ASSERT_TRUE((*store)->Revoke("alice").ok());
    EXPECT_TRUE(absl::IsAlreadyExists((*store)->Create("alice", Role::kAdmin).status()));
}

TEST(TokenStore, RevokedTokenIsFoundAsRevokedAndListed) {
    const auto dir = testing::FreshTestDir("lf_tokens");
    auto store = TokenStore::Open(dir.string());
    ASSERT_TRUE(store.ok());
    const std::string token = *(*store)->Create("bob", Role::kSubmitter);
    ASSERT_TRUE((*store)->Revoke("bob").ok());
    ASSERT_TRUE((*store)->Revoke("bob").ok());  // twice is fine
    EXPECT_FALSE((*(*store)->Find(token))->valid());
    EXPECT_TRUE(absl::IsNotFound((*store)->Revoke("nobody")));
    auto list = (*store)->List();
    ASSERT_TRUE(list.ok());
    ASSERT_EQ(list->size(), 1u);
    EXPECT_FALSE((*list)[0].valid());
    EXPECT_TRUE(*(*store)->Any());  // a revoked token keeps authentication on
}

// A leaked token is replaced under the same name, so its owner keeps its jobs; the old one is
// found as revoked. Before `rotate`, a revoked name could never have a token again.
TEST(TokenStore, RotateGivesTheSameNameANewTokenAndRevokesTheOld) {
    const auto dir = testing::FreshTestDir("lf_tokens");
    auto store = TokenStore::Open(dir.string());
    ASSERT_TRUE(store.ok());
    const std::string first = *(*store)->Create("carol", Role::kSubmitter);
    absl::StatusOr<std::string> second = (*store)->Rotate("carol");
    ASSERT_TRUE(second.ok()) << second.status();
    EXPECT_NE(*second, first);
    EXPECT_FALSE((*(*store)->Find(first))->valid());
    EXPECT_EQ((*(*store)->Find(first))->name, "carol");
    auto now = *(*store)->Find(*second);
    ASSERT_TRUE(now.has_value());
    EXPECT_TRUE(now->valid());
    EXPECT_EQ(now->name, "carol");
    EXPECT_EQ(now->role, Role::kSubmitter);

    // After a revocation (the usual first step with a leak) too.
    ASSERT_TRUE((*store)->Revoke("carol").ok());
    const std::string third = *(*store)->Rotate("carol");
    EXPECT_TRUE((*(*store)->Find(third))->valid());
    EXPECT_FALSE((*(*store)->Find(*second))->valid());
    EXPECT_FALSE((*(*store)->Find(first))->valid());
    ASSERT_EQ((*store)->List()->size(), 1u);
    EXPECT_TRUE((*(*store)->List())[0].valid());

    EXPECT_TRUE(absl::IsNotFound((*store)->Rotate("nobody").status()));
    EXPECT_TRUE(absl::StrContains((*store)->Create("carol", Role::kAdmin).status().message(),
                                  "token rotate --name carol"));
}

TEST(TokenStore, SecondConnectionSeesTokensAtOnce) {
    // `lightfarm-server token create` while a server holds the file open.
    const auto dir = testing::FreshTestDir("lf_tokens");
    auto server = TokenStore::Open(dir.string());
    auto command = TokenStore::Open(dir.string());
    ASSERT_TRUE(server.ok() && command.ok());
    const std::string token = *(*command)->Create("late", Role::kSubmitter);
    EXPECT_TRUE((*(*server)->Find(token)).has_value());
}

TEST(TokenStore, BadNamesAndRolesAreRefusedSayingWhy) {
    const auto dir = testing::FreshTestDir("lf_tokens");
    auto store = TokenStore::Open(dir.string());
    ASSERT_TRUE(store.ok());
    for (const std::string& name : std::vector<std::string>{
             "", "has space", "semi;colon", std::string(65, 'a'), std::string("nul\0byte", 8)}) {
        absl::Status s = (*store)->Create(name, Role::kSubmitter).status();
        EXPECT_TRUE(absl::IsInvalidArgument(s)) << name;
        EXPECT_TRUE(absl::StrContains(s.message(), "letters, digits")) << s;
    }
    EXPECT_TRUE((*store)->Create(std::string(64, 'a'), Role::kSubmitter).ok());
    EXPECT_TRUE(absl::IsInvalidArgument(RoleFromName("root").status()));
    EXPECT_EQ(*RoleFromName("worker"), Role::kWorker);
}

TEST(TokenStore, UnwritableFolderIsAnErrorNamingIt) {
    absl::StatusOr<std::unique_ptr<TokenStore>> store = TokenStore::Open("/proc/lf-no-such-dir");
    ASSERT_FALSE(store.ok());
    EXPECT_TRUE(absl::StrContains(store.status().message(), "/proc/lf-no-such-dir"));
}

}  // namespace
}  // namespace lf
