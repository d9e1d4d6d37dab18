#include "lf/server/token_store.h"

#include <openssl/rand.h>
#include <sqlite3.h>

#include <algorithm>
#include <array>
#include <filesystem>

#include "absl/strings/ascii.h"
#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "lf/job/digest.h"
#include "lf/server/sqlite_statement.h"

namespace lf {

namespace {

constexpr std::array<Role, 3> kRoles = {Role::kSubmitter, Role::kAdmin, Role::kWorker};

// 256 random bits: guessing one is hopeless, so a fast hash (SHA-256) stores them safely; a slow
// password hash would only slow every call. The prefix lets secret scanners and people tell a
// lightfarm token when they see one.
constexpr size_t kTokenBytes = 32;
constexpr char kTokenPrefix[] = "lf1_";

absl::StatusOr<std::string> NewToken() {
    std::array<unsigned char, kTokenBytes> bytes;
    if (RAND_bytes(bytes.data(), int(bytes.size())) != 1) {
        return absl::InternalError("no random bytes from OpenSSL for a token");
    }
    return absl::StrCat(
        kTokenPrefix, absl::BytesToHexString(
                          std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size())));
}

int64_t NowMicros() { return absl::ToUnixMicros(absl::Now()); }

absl::Status NoSuchName(const std::string& name) {
    return absl::NotFoundError(absl::StrCat("no token named \"", absl::CHexEscape(name), "\""));
}

}  // namespace

const char* RoleName(Role role) {
    switch (role) {
        case Role::kSubmitter:
            return "submitter";
        case Role::kAdmin:
            return "admin";
        case Role::kWorker:
            return "worker";
    }
    return "?";
}

absl::StatusOr<Role> RoleFromName(std::string_view name) {
    for (Role r : kRoles) {
        if (name == RoleName(r)) return r;
    }
    return absl::InvalidArgumentError(absl::StrCat("unknown role \"", std::string(name),
                                                   "\": expected submitter, admin or worker"));
}

absl::Status CheckTokenName(std::string_view name) {
    const bool ok =
        !name.empty() && name.size() <= kMaxTokenNameBytes &&
        std::all_of(name.begin(), name.end(), [](char c) {
            return absl::ascii_isalnum(c) || c == '.' || c == '_' || c == '-' || c == '@';
        });
    if (ok) return absl::OkStatus();
    return absl::InvalidArgumentError(absl::StrCat(
        "token name \"", absl::CHexEscape(std::string(name.substr(0, kMaxTokenNameBytes))),
        "\": expected 1 to ", kMaxTokenNameBytes, " letters, digits or . _ - @"));
}

absl::StatusOr<std::unique_ptr<TokenStore>> TokenStore::Open(const std::string& data_dir) {
    if (std::error_code e; !std::filesystem::create_directories(data_dir, e) && e) {
        return absl::UnavailableError(
            absl::StrCat(data_dir, ": cannot make the data folder: ", e.message()));
    }
    const std::string path = data_dir + "/" + kFileName;
    sqlite3* db = nullptr;
    if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) !=
        SQLITE_OK) {
        absl::Status s = absl::UnavailableError(
            absl::StrCat(path, ": cannot open the token store: ", db ? sqlite3_errmsg(db) : "?"));
        sqlite3_close(db);
        return s;
    }
    std::unique_ptr<TokenStore> store(new TokenStore(db, path));
    // The server reads while `lightfarm-server token` writes: WAL lets both go on, and the busy
    // timeout covers a write in progress.
    absl::Status s = Exec(db,
                          "PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL;"
                          "PRAGMA busy_timeout=5000;"
                          "CREATE TABLE IF NOT EXISTS tokens (name TEXT PRIMARY KEY,"
                          "  role TEXT NOT NULL, hash TEXT NOT NULL UNIQUE,"
                          "  created INTEGER NOT NULL, revoked INTEGER);"
                          // Added with `token rotate`: a name's earlier tokens, refused as
                          // revoked. Files made before it gain it here; their tokens stay.
                          "CREATE TABLE IF NOT EXISTS retired_tokens (hash TEXT PRIMARY KEY,"
                          "  name TEXT NOT NULL, retired INTEGER NOT NULL);");
    if (!s.ok()) return absl::Status(s.code(), absl::StrCat(path, ": ", s.message()));
    return store;
}

TokenStore::~TokenStore() { sqlite3_close(db_); }

absl::StatusOr<std::string> TokenStore::Create(const std::string& name, Role role) {
    if (absl::Status s = CheckTokenName(name); !s.ok()) return s;
    absl::StatusOr<std::string> token = NewToken();
    if (!token.ok()) return token.status();
    Statement insert(db_, "INSERT INTO tokens (name, role, hash, created) VALUES (?1, ?2, ?3, ?4)");
    insert.Bind(1, name).Bind(2, RoleName(role)).Bind(3, Sha256Hex(*token));
    insert.Bind(4, NowMicros()).Step();
    if (absl::Status s = insert.status(); !s.ok()) {
        if (absl::IsAlreadyExists(s)) {
            return absl::AlreadyExistsError(
                absl::StrCat("a token named \"", name,
                             "\" exists (revoked ones keep their names, which own their jobs): "
                             "`token rotate --name ",
                             name, "` gives it a new token, or choose another name"));
        }
        return s;
    }
    return token;
}

absl::StatusOr<std::string> TokenStore::Rotate(const std::string& name) {
    absl::StatusOr<std::string> token = NewToken();
    if (!token.ok()) return token.status();
    if (absl::Status s = Exec(db_, "BEGIN IMMEDIATE"); !s.ok()) return s;
    Statement retire(db_,
                     "INSERT INTO retired_tokens (hash, name, retired) "
                     "SELECT hash, name, ?2 FROM tokens WHERE name = ?1");
    retire.Bind(1, name).Bind(2, NowMicros()).Step();
    absl::Status s = retire.status();
    if (s.ok() && sqlite3_changes(db_) == 0) s = NoSuchName(name);
    if (s.ok()) {
        Statement replace(db_, "UPDATE tokens SET hash = ?2, revoked = NULL WHERE name = ?1");
        replace.Bind(1, name).Bind(2, Sha256Hex(*token)).Step();
        s = replace.status();
    }
    if (!s.ok()) {
        Exec(db_, "ROLLBACK").IgnoreError();
        return s;
    }
    if (absl::Status c = Exec(db_, "COMMIT"); !c.ok()) return c;
    return token;
}

absl::Status TokenStore::Revoke(const std::string& name) {
    Statement revoke(db_, "UPDATE tokens SET revoked = coalesce(revoked, ?2) WHERE name = ?1");
    revoke.Bind(1, name).Bind(2, NowMicros()).Step();
    if (absl::Status s = revoke.status(); !s.ok()) return s;
    if (sqlite3_changes(db_) == 0) return NoSuchName(name);
    return absl::OkStatus();
}

namespace {

absl::StatusOr<TokenInfo> InfoOf(const Statement& row) {
    TokenInfo info;
    info.name = std::string(row.Column(0));
    absl::StatusOr<Role> role = RoleFromName(row.Column(1));
    if (!role.ok()) {
        return absl::DataLossError(
            absl::StrCat("token \"", info.name, "\": ", role.status().message()));
    }
    info.role = *role;
    info.created = absl::FromUnixMicros(row.ColumnInt(2));
    if (!row.IsNull(3)) info.revoked = absl::FromUnixMicros(row.ColumnInt(3));
    return info;
}

}  // namespace

absl::StatusOr<std::vector<TokenInfo>> TokenStore::List() const {
    std::vector<TokenInfo> tokens;
    Statement list(db_, "SELECT name, role, created, revoked FROM tokens ORDER BY name");
    while (list.Step()) {
        absl::StatusOr<TokenInfo> info = InfoOf(list);
        if (!info.ok()) return info.status();
        tokens.push_back(std::move(*info));
    }
    if (absl::Status s = list.status(); !s.ok()) return s;
    return tokens;
}

absl::StatusOr<std::optional<TokenInfo>> TokenStore::Find(std::string_view token) const {
    // A rotated-away token is its name's, revoked when it was replaced.
    Statement find(db_,
                   "SELECT name, role, created, revoked FROM tokens WHERE hash = ?1 "
                   "UNION ALL SELECT t.name, t.role, t.created, r.retired "
                   "FROM retired_tokens r JOIN tokens t ON t.name = r.name WHERE r.hash = ?1");
    if (find.Bind(1, Sha256Hex(token)).Step()) return InfoOf(find);
    if (absl::Status s = find.status(); !s.ok()) return s;
    return std::nullopt;
}

absl::StatusOr<bool> TokenStore::Any() const {
    Statement any(db_, "SELECT 1 FROM tokens LIMIT 1");
    if (any.Step()) return true;
    if (absl::Status s = any.status(); !s.ok()) return s;
    return false;
}

}  // namespace lf
