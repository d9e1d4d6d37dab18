#include "lf/server/token_command.h"

#include <cstdio>
#include <optional>

#include "absl/time/time.h"
#include "lf/server/token_store.h"

namespace lf {

namespace {

int Fail(const absl::Status& s) {
    std::fprintf(stderr, "lightfarm-server token: error: %s\n", std::string(s.message()).c_str());
    return 1;
}

}  // namespace

int TokenCommand::Create() {
    absl::StatusOr<Role> role = RoleFromName(role_);
    if (!role.ok()) return Fail(role.status());
    absl::StatusOr<bool> any = store_->Any();
    if (!any.ok()) return Fail(any.status());
    absl::StatusOr<std::string> token = store_->Create(name_, *role);
    if (!token.ok()) return Fail(token.status());
    std::fprintf(stderr,
                 "token \"%s\" (%s) created; it is shown once, here: keep it in a file only its "
                 "user reads (--token-file) or in LIGHTFARM_TOKEN\n",
                 name_.c_str(), RoleName(*role));
    if (!*any) {
        std::fprintf(stderr,
                     "warning: this is the farm's first token: within a second, a server on %s "
                     "refuses every call without a valid token, workers included. Running "
                     "workers are refused until each has a worker token: make one per worker with "
                     "`lightfarm-server token create --data-dir %s --name NODE --role worker` "
                     "and restart the worker with --token-file FILE (or LIGHTFARM_TOKEN); "
                     "clients need one too (a submitter or admin token)\n",
                     data_dir_.c_str(), data_dir_.c_str());
    }
    std::printf("%s\n", token->c_str());
    return 0;
}

int TokenCommand::Rotate() {
    absl::StatusOr<std::string> token = store_->Rotate(name_);
    if (!token.ok()) return Fail(token.status());
    std::fprintf(stderr,
                 "token \"%s\" rotated: its previous token is refused within a second; this "
                 "one, shown once, sees and manages the same jobs\n",
                 name_.c_str());
    std::printf("%s\n", token->c_str());
    return 0;
}

int TokenCommand::List() {
    absl::StatusOr<std::vector<TokenInfo>> tokens = store_->List();
    if (!tokens.ok()) return Fail(tokens.status());
    std::printf("%-24s %-10s %-20s %s\n", "NAME", "ROLE", "CREATED", "STATE");
    for (const TokenInfo& t : *tokens) {
        const std::string state =
            t.valid() ? "valid"
                      : "revoked " +
                            absl::FormatTime("%Y-%m-%d %H:%M:%S", t.revoked, absl::LocalTimeZone());
        std::printf("%-24s %-10s %-20s %s\n", t.name.c_str(), RoleName(t.role),
                    absl::FormatTime("%Y-%m-%d %H:%M:%S", t.created, absl::LocalTimeZone()).c_str(),
                    state.c_str());
    }
    return 0;
}

int TokenCommand::Revoke() {
    if (absl::Status s = store_->Revoke(name_); !s.ok()) return Fail(s);
    std::fprintf(stderr, "token \"%s\" revoked: servers refuse it within a second\n",
                 name_.c_str());
    return 0;
}

TokenCommand::TokenCommand(CLI::App& app) {
    token_ = app.add_subcommand(
        "token",
        "manage the farm's bearer tokens in DIR/tokens.db (also while a server runs there). "
        "Once a token exists, the server asks every call for one; see docs/farm.md, Security");
    token_->require_subcommand(1);
    create_ = token_->add_subcommand(
        "create", "make a token and print it as the last line (it is stored only hashed)");
    list_ = token_->add_subcommand("list", "list tokens: name, role, created, revoked");
    CLI::App* revoke = token_->add_subcommand("revoke", "revoke a token by name (kept, refused)");
    rotate_ = token_->add_subcommand(
        "rotate",
        "give a name a new token, revoked or not, and print it as the last line: its previous "
        "token is refused, its jobs stay its own (for a token that leaked)");
    for (CLI::App* cmd : {create_, list_, revoke, rotate_}) {
        cmd->add_option("--data-dir", data_dir_, "the server's data folder")->required();
    }
    create_->add_option("--name", name_, "who the token is for: 1-64 of A-Z a-z 0-9 . _ - @")
        ->required();
    create_
        ->add_option("--role", role_,
                     "submitter: submit and see, watch, fetch, cancel and delete its own jobs; "
                     "admin: everything, every job; worker: lease, heartbeat, complete tasks")
        ->required()
        ->check(CLI::IsMember({"submitter", "admin", "worker"}));
    for (CLI::App* cmd : {revoke, rotate_}) {
        cmd->add_option("--name", name_, "the token's name")->required();
    }
}

std::optional<int> TokenCommand::Run() {
    if (!token_->parsed()) return std::nullopt;
    absl::StatusOr<std::unique_ptr<TokenStore>> store = TokenStore::Open(data_dir_);
    if (!store.ok()) return Fail(store.status());
    store_ = std::move(*store);
    if (create_->parsed()) return Create();
    if (list_->parsed()) return List();
    if (rotate_->parsed()) return Rotate();
    return Revoke();
}

TokenCommand::~TokenCommand() = default;

}  // namespace lf
