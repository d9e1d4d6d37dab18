// The farm's bearer tokens: who may call the server and in which role. A name is a principal
// (jobs are owned by it) whose token can be replaced (rotated) without losing them. Kept in their
// own SQLite file in the data folder (tokens.db), apart from the job store, so that
// `lightfarm-server token` can add and revoke tokens while a server runs on the folder (the server
// reads the file, never holds it). Only each token's SHA-256 is stored: the file does not let
// anyone call the farm.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"

struct sqlite3;

namespace lf {

// What a token may do (lf/server/auth.h says exactly): submit and follow its own jobs; anything
// on every job; or lease, render and return tasks.
enum class Role { kSubmitter, kAdmin, kWorker };
const char* RoleName(Role role);
// InvalidArgument naming the roles for anything else.
absl::StatusOr<Role> RoleFromName(std::string_view name);

struct TokenInfo {
    std::string name;
    Role role = Role::kSubmitter;
    absl::Time created;
    absl::Time revoked = absl::InfinitePast();  // InfinitePast while valid
    bool valid() const { return revoked == absl::InfinitePast(); }
};

// Names are shown in logs and job listings, and typed on command lines.
inline constexpr size_t kMaxTokenNameBytes = 64;
// Ok for 1..64 of [A-Za-z0-9._@-]; InvalidArgument saying so otherwise.
absl::Status CheckTokenName(std::string_view name);

class TokenStore {
  public:
    static constexpr const char* kFileName = "tokens.db";

    // Opens (creating when missing) `data_dir`/tokens.db, and `data_dir` when missing.
    static absl::StatusOr<std::unique_ptr<TokenStore>> Open(const std::string& data_dir);
    ~TokenStore();
    TokenStore(const TokenStore&) = delete;
    TokenStore& operator=(const TokenStore&) = delete;

    // A new token for `name`, returned once and never stored. AlreadyExists when the name is
    // taken, even by a revoked token: a name stays one identity in the job records.
    absl::StatusOr<std::string> Create(const std::string& name, Role role);
    // A new token for the existing `name` (revoked or not), same role: the name's jobs stay its
    // own, its earlier tokens are found as revoked from now on. NotFound for an unknown name.
    absl::StatusOr<std::string> Rotate(const std::string& name);
    // NotFound for an unknown name; revoking twice is fine.
    absl::Status Revoke(const std::string& name);
    absl::StatusOr<std::vector<TokenInfo>> List() const;
    // The token's record, revoked ones included; nullopt for a token never made here.
    absl::StatusOr<std::optional<TokenInfo>> Find(std::string_view token) const;
    // Whether any token was ever made (revoked ones count): from the first token on, the
    // server asks every caller for one.
    absl::StatusOr<bool> Any() const;

  private:
    TokenStore(sqlite3* db, std::string path) : db_(db), path_(std::move(path)) {}
    sqlite3* db_;
    std::string path_;
};

}  // namespace lf
