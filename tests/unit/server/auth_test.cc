// Who may do what: every role against every action, the visibility of jobs, and the
// authenticator's answers to missing, malformed, unknown and revoked tokens.
#include "lf/server/auth.h"

#include <gtest/gtest.h>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "test_dir.h"

namespace lf {
namespace {

constexpr Action kAllActions[] = {
    Action::kUploadBlobs,   Action::kSubmit,    Action::kReadJobs,    Action::kCancelJob,
    Action::kSetPriority,   Action::kDeleteJob, Action::kListWorkers, Action::kWork,
    Action::kManageWorkers, Action::kManageJobs};

TEST(Permit, AdminMayDoEverything) {
    for (Action a : kAllActions) EXPECT_TRUE(Permit({"root", Role::kAdmin}, a).ok());
}

TEST(Permit, WorkerMayOnlyWork) {
    const Caller worker{"node-1", Role::kWorker};
    for (Action a : kAllActions) {
        const absl::Status s = Permit(worker, a);
        if (a == Action::kWork) {
            EXPECT_TRUE(s.ok());
        } else {
            EXPECT_TRUE(absl::IsPermissionDenied(s)) << ActionName(a);
            EXPECT_TRUE(absl::StrContains(s.message(), "\"node-1\" has role worker")) << s;
        }
    }
}

TEST(Permit, SubmitterMayDoAllButWorkAndManageWorkers) {
    const Caller alice{"alice", Role::kSubmitter};
    for (Action a : kAllActions) {
        EXPECT_EQ(Permit(alice, a).ok(), a != Action::kWork && a != Action::kManageWorkers);
    }
    EXPECT_TRUE(absl::StrContains(Permit(alice, Action::kWork).message(), "lease and render"));
    EXPECT_TRUE(absl::StrContains(Permit(alice, Action::kManageWorkers).message(),
                                  "disable, enable or drain workers"));
}

TEST(MaySee, SubmittersSeeTheirOwnJobsAdminsAllWorkersNone) {
    EXPECT_TRUE(MaySee({"alice", Role::kSubmitter}, "alice"));
    EXPECT_FALSE(MaySee({"alice", Role::kSubmitter}, "bob"));
    EXPECT_FALSE(MaySee({"alice", Role::kSubmitter}, ""));  // jobs from before tokens: admins'
    EXPECT_TRUE(MaySee({"root", Role::kAdmin}, "bob"));
    EXPECT_TRUE(MaySee({"root", Role::kAdmin}, ""));
    EXPECT_FALSE(MaySee({"alice", Role::kWorker}, "alice"));
}

class AuthenticatorTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = testing::FreshTestDir("lf_auth");
        auto store = TokenStore::Open(dir_.string());
        ASSERT_TRUE(store.ok());
        auto admin_store = TokenStore::Open(dir_.string());
        ASSERT_TRUE(admin_store.ok());
        admin_ = std::move(*admin_store);
        auth_ = std::make_unique<Authenticator>(std::move(*store), false);
    }
    std::filesystem::path dir_;
    std::unique_ptr<TokenStore> admin_;  // `lightfarm-server token` beside the server
    std::unique_ptr<Authenticator> auth_;
};

TEST_F(AuthenticatorTest, OffWithoutTokensOnLoopbackEveryoneIsAnAnonymousAdmin) {
    EXPECT_FALSE(auth_->enabled());
    absl::StatusOr<Caller> caller = auth_->Authenticate(std::nullopt);
    ASSERT_TRUE(caller.ok());
    EXPECT_EQ(caller->role, Role::kAdmin);
    EXPECT_EQ(caller->name, "");
    EXPECT_FALSE(Authenticator::Off()->enabled());
}

TEST_F(AuthenticatorTest, RequiredWithoutTokensRefusesEveryone) {
    auto store = TokenStore::Open(dir_.string());
    ASSERT_TRUE(store.ok());
    Authenticator required(std::move(*store), true);
    EXPECT_TRUE(required.enabled());
    EXPECT_TRUE(absl::IsUnauthenticated(required.Authenticate(std::nullopt).status()));
    EXPECT_TRUE(absl::IsUnauthenticated(required.Authenticate("Bearer lf1_00").status()));
}

TEST_F(AuthenticatorTest, FirstTokenTurnsAuthenticationOnWithinASecond) {
    EXPECT_FALSE(auth_->enabled());
    const std::string token = *admin_->Create("alice", Role::kSubmitter);
    absl::SleepFor(absl::Milliseconds(1100));
    EXPECT_TRUE(auth_->enabled());
    EXPECT_TRUE(absl::IsUnauthenticated(auth_->Authenticate(std::nullopt).status()));
    absl::StatusOr<Caller> alice = auth_->Authenticate("Bearer " + token);
    ASSERT_TRUE(alice.ok()) << alice.status();
    EXPECT_EQ(alice->name, "alice");
    EXPECT_EQ(alice->role, Role::kSubmitter);
    // The scheme is case-insensitive (RFC 7235), the token is not.
    EXPECT_TRUE(auth_->Authenticate("bearer " + token).ok());
}

TEST_F(AuthenticatorTest, MissingMalformedUnknownAndRevokedTokensAreUnauthenticatedSayingWhy) {
    const std::string token = *admin_->Create("bob", Role::kSubmitter);
    ASSERT_TRUE(auth_->enabled());
    const auto message = [&](std::optional<std::string> header) {
        absl::Status s = auth_->Authenticate(header).status();
        EXPECT_TRUE(absl::IsUnauthenticated(s)) << s;
        return std::string(s.message());
    };
    EXPECT_TRUE(absl::StrContains(message(std::nullopt), "--token-file"));
    EXPECT_TRUE(absl::StrContains(message(token), "Bearer TOKEN"));  // no scheme
    EXPECT_TRUE(absl::StrContains(message("Basic " + token), "Bearer TOKEN"));
    EXPECT_TRUE(absl::StrContains(message("Bearer " + std::string(300, 'x')), "Bearer TOKEN"));
    EXPECT_TRUE(absl::StrContains(message("Bearer lf1_0123"), "not one of this server's"));
    const std::string upper = "Bearer " + absl::AsciiStrToUpper(token);
    EXPECT_TRUE(absl::StrContains(message(upper), "not one of this server's"));

    ASSERT_TRUE(auth_->Authenticate("Bearer " + token).ok());
    ASSERT_TRUE(admin_->Revoke("bob").ok());
    absl::SleepFor(absl::Milliseconds(1100));  // the cache's second
    EXPECT_TRUE(absl::StrContains(message("Bearer " + token), "\"bob\" was revoked"));
}

TEST_F(AuthenticatorTest, RotatedTokenIsRefusedAndItsSuccessorSeesTheSameJobs) {
    const std::string old = *admin_->Create("dave", Role::kSubmitter);
    absl::StatusOr<Caller> before = auth_->Authenticate("Bearer " + old);
    ASSERT_TRUE(before.ok()) << before.status();
    const std::string rotated = *admin_->Rotate("dave");
    absl::SleepFor(absl::Milliseconds(1100));  // the cache's second
    absl::Status refused = auth_->Authenticate("Bearer " + old).status();
    EXPECT_TRUE(absl::IsUnauthenticated(refused)) << refused;
    EXPECT_TRUE(absl::StrContains(refused.message(), "\"dave\" was revoked")) << refused;
    absl::StatusOr<Caller> after = auth_->Authenticate("Bearer " + rotated);
    ASSERT_TRUE(after.ok()) << after.status();
    EXPECT_EQ(after->name, before->name);
    EXPECT_EQ(after->role, Role::kSubmitter);
    // Jobs are owned by the name: those submitted with the old token are the new one's.
    EXPECT_TRUE(MaySee(*after, before->name));
}

}  // namespace
}  // namespace lf
